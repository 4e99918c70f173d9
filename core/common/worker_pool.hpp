#pragma once
// The core's one source of threads: a fixed set of workers that the tissue step hands passes to
// whose items are independent of each other (a vertex's prediction, a stencil's curvature), so the
// result is the same bit for bit whatever the number of threads and however they are scheduled.
//
// A pass is split into threads() parts, part p always on thread p (part 0 on the caller): a fixed
// partition, never work stealing. Only passes where no item reads what another item writes may be
// run here, and any reduction must be one whose result does not depend on the split (a maximum, a
// logical and) — that is what keeps the bits independent of the thread count.
//
// The passes are tens of microseconds long and come every few hundred microseconds, so a worker
// waits for the next by spinning (a sleep and wake-up through the kernel costs about as much as the
// pass itself): kPauseRounds rounds of a pause instruction, then rounds that yield the core (so that
// more threads than cores — or a loaded machine — cost a context switch, not a time slice spent
// spinning against the thread being waited for), and after kSpinRounds rounds in all (the
// simulation stopped) it sleeps on a futex until the next pass. The caller waits for the workers'
// parts the same way, without the sleep.
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

namespace vitreo::core {

class WorkerPool {
 public:
  // threads ≥ 1: the calling thread and threads − 1 workers.
  explicit WorkerPool(unsigned threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  unsigned threads() const { return static_cast<unsigned>(workers_.size()) + 1; }

  // Calls part(p) for every p in [0, threads()), part 0 on the calling thread, and returns when
  // all have returned. `part` must not throw.
  template <class F>
  void run(F& part) {
    run_erased([](void* f, unsigned p) { (*static_cast<F*>(f))(p); }, &part);
  }

  // The slice [begin, end) of n items that part p of `parts` takes: contiguous, sizes within one.
  static std::uint32_t slice_begin(std::uint32_t n, unsigned p, unsigned parts) {
    return static_cast<std::uint32_t>(std::uint64_t{n} * p / parts);
  }

 private:
  static constexpr std::uint32_t kPauseRounds = 1u << 10;
  static constexpr std::uint32_t kSpinRounds = 1u << 16;
  void run_erased(void (*fn)(void*, unsigned), void* context);
  void work(unsigned part);

  std::vector<std::thread> workers_;
  // A new pass is published by bumping generation_ (release); fn_ and context_ are written before.
  std::atomic<std::uint32_t> generation_{0};
  std::atomic<std::uint32_t> remaining_{0};  // workers still running the current pass
  std::atomic<bool> stopping_{false};
  void (*fn_)(void*, unsigned) = nullptr;
  void* context_ = nullptr;
};

// Splits items [0, n) over the pool's threads (a null pool: one thread) and calls
// body(begin, end) for each part's slice.
template <class Body>
void run_sliced(WorkerPool* pool, std::uint32_t n, Body&& body) {
  if (pool == nullptr || pool->threads() == 1) {
    body(std::uint32_t{0}, n);
    return;
  }
  const unsigned parts = pool->threads();
  auto part = [&](unsigned p) { body(WorkerPool::slice_begin(n, p, parts), WorkerPool::slice_begin(n, p + 1, parts)); };
  pool->run(part);
}

}  // namespace vitreo::core
