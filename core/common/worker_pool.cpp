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
  claimed_ = std::make_unique<std::atomic<std::uint8_t>[]>(workers + 1);
  for (unsigned p = 0; p <= workers; ++p) claimed_[p].store(1, std::memory_order_relaxed);  // no pass yet
  workers_.reserve(workers);
  for (unsigned p = 1; p <= workers; ++p) workers_.emplace_back([this, p] { work(p); });
}

WorkerPool::~WorkerPool() {
  stopping_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (auto& t : workers_) t.join();
}

void WorkerPool::run_if_unclaimed(unsigned p) {
  if (claimed_[p].exchange(1, std::memory_order_acq_rel) != 0) return;
  fn_(context_, p);
  remaining_.fetch_sub(1, std::memory_order_release);
}

void WorkerPool::run_erased(void (*fn)(void*, unsigned), void* context) {
  if (workers_.empty()) {
    fn(context, 0);
    return;
  }
  const auto workers = static_cast<unsigned>(workers_.size());
  fn_ = fn;
  context_ = context;
  remaining_.store(workers, std::memory_order_relaxed);
  for (unsigned p = 1; p <= workers; ++p) claimed_[p].store(0, std::memory_order_release);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();  // cheap when no worker sleeps (the waiter count is checked first)
  fn(context, 0);
  for (unsigned p = 1; p <= workers; ++p) run_if_unclaimed(p);
  for (std::uint32_t round = 0; remaining_.load(std::memory_order_acquire) != 0; ++round) {
    if (round < kCallerPauseRounds) {
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
    // A worker late for a pass may find its part claimed (the caller ran it), or claim the part of
    // the next pass, which it then runs with that pass's function: either way each part runs once.
    run_if_unclaimed(part);
  }
}

}  // namespace vitreo::core
