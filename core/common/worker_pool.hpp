#pragma once
// The core's one source of threads: a fixed set of workers that the tissue step hands passes to
// whose items are independent of each other (a vertex's prediction, a stencil's curvature), so the
// result is the same bit for bit whatever the number of threads and however they are scheduled.
//
// A pass is split into threads() parts, a fixed partition of its items (run_sliced: contiguous
// slices). Part p is meant for thread p (part 0 for the caller), but any thread may run it: a part
// is claimed once, and the caller, done with its own, claims and runs every part no worker has
// started — so a worker that the kernel has not scheduled yet (a loaded machine, more threads than
// cores) delays nothing. Which thread runs a part cannot change what it computes: only passes where
// no item reads what another item writes may be run here, and any reduction must be one whose result
// does not depend on the split (per block, a maximum, a logical and) — that is what keeps the bits
// independent of the thread count and of the scheduling.
//
// The passes are tens of microseconds long and come every few hundred microseconds, so a worker
// waits for the next by spinning (a sleep and wake-up through the kernel costs about as much as the
// pass itself): kPauseRounds rounds of a pause instruction, then rounds that yield the core, and
// after kSpinRounds rounds in all (the simulation stopped) it sleeps on a futex until the next
// pass. The caller waits for parts that workers are running the same way, without the sleep.
// Spinning means a worker holds a core while the simulation runs: give the pool the cores there
// are to spare, no more.
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

  // Calls part(p) once for every p in [0, threads()) — part 0 on the calling thread, the others on
  // their workers or, where a worker has not started its part by then, on the calling thread — and
  // returns when all have returned. `part` must not throw.
  template <class F>
  void run(F& part) {
    run_erased([](void* f, unsigned p) { (*static_cast<F*>(f))(p); }, &part);
  }

  // The slice [begin, end) of n items that part p of `parts` takes: contiguous, sizes within one.
  static std::uint32_t slice_begin(std::uint32_t n, unsigned p, unsigned parts) {
    return static_cast<std::uint32_t>(std::uint64_t{n} * p / parts);
  }

 private:
  // Rounds of a ~25 ns pause (measured here): a worker pauses ~1.6 ms, then yields until ~0.1 s,
  // then sleeps; the caller waits for running parts pausing ~0.1 ms, then yielding.
  static constexpr std::uint32_t kPauseRounds = 1u << 16;
  static constexpr std::uint32_t kSpinRounds = 1u << 18;
  static constexpr std::uint32_t kCallerPauseRounds = 1u << 12;
  void run_erased(void (*fn)(void*, unsigned), void* context);
  void work(unsigned part);
  // Runs part p if nobody has claimed it this pass.
  void run_if_unclaimed(unsigned p);

  std::vector<std::thread> workers_;
  // Per part (index 0 unused): 0 until a thread claims it in the current pass. The caller resets
  // them (release) after writing fn_ and context_, so whoever claims a part sees the pass it is of.
  std::unique_ptr<std::atomic<std::uint8_t>[]> claimed_;
  // A new pass is announced by bumping generation_ (release), after the claims were reset.
  std::atomic<std::uint32_t> generation_{0};
  std::atomic<std::uint32_t> remaining_{0};  // parts 1.. not finished in the current pass
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
