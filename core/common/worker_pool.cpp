#include "core/common/worker_pool.hpp"

namespace vitreo::core {

namespace {
inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}
}  // namespace

WorkerPool::WorkerPool(unsigned threads) {
  const unsigned workers = threads > 1 ? threads - 1 : 0;
  workers_.reserve(workers);
  for (unsigned p = 1; p <= workers; ++p) workers_.emplace_back([this, p] { work(p); });
}

WorkerPool::~WorkerPool() {
  stopping_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (auto& t : workers_) t.join();
}

void WorkerPool::run_erased(void (*fn)(void*, unsigned), void* context) {
  if (workers_.empty()) {
    fn(context, 0);
    return;
  }
  fn_ = fn;
  context_ = context;
  remaining_.store(static_cast<std::uint32_t>(workers_.size()), std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();  // cheap when no worker sleeps (the waiter count is checked first)
  fn(context, 0);
  for (std::uint32_t round = 0; remaining_.load(std::memory_order_acquire) != 0; ++round) {
    if (round < kPauseRounds) {
      cpu_relax();
    } else {
      std::this_thread::yield();
    }
  }
}

void WorkerPool::work(unsigned part) {
  std::uint32_t seen = 0;
  for (;;) {
    std::uint32_t now = generation_.load(std::memory_order_acquire);
    for (std::uint32_t round = 0; now == seen; now = generation_.load(std::memory_order_acquire)) {
      if (++round < kPauseRounds) {
        cpu_relax();
      } else if (round < kSpinRounds) {
        std::this_thread::yield();
      } else {
        generation_.wait(seen, std::memory_order_acquire);
      }
    }
    seen = now;
    if (stopping_.load(std::memory_order_relaxed)) return;
    fn_(context_, part);
    remaining_.fetch_sub(1, std::memory_order_release);
  }
}

}  // namespace vitreo::core
