#pragma once
// Latest-value mailbox between exactly one writer thread and one reader thread. Neither side ever
// blocks or spins: the writer always has a private slot to fill, the reader always has a private slot
// to read, and the third slot is swapped atomically between them. This is the thesis' double-buffered
// vertex state (ch. 2.3.2) made wait-free: a slow reader sees fewer updates, never a torn one, and
// never holds back the writer. Same idea as PX4 uORB's "latest sample" topics and the classic
// triple-buffering of graphics swap chains. The one latest-value mailbox of the rig: device samples
// to physics, view snapshots to the picture, scenes to the render thread, command context to the
// telemetry thread.
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>
#include <utility>

namespace vitreo::runtime {

template <class T>
class TripleBuffer {
  static_assert(std::is_copy_assignable_v<T>, "TripleBuffer holds values that can be copied in");

 public:
  explicit TripleBuffer(const T& initial = T{}) : slots_{Slot{initial}, Slot{initial}, Slot{initial}} {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // ---- writer side (one thread) ----
  // Fill the returned slot in place (no copy for large states), then publish().
  T& write_slot() noexcept { return slots_[back_].value; }
  // Makes the filled slot the latest; the writer gets the previously shared slot back.
  void publish() noexcept {
    const std::uint8_t previous =
        middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    if (previous & kFresh) dropped_.fetch_add(1, std::memory_order_relaxed);  // the reader never took it
    back_ = static_cast<std::uint8_t>(previous & kIndexMask);
    publishes_.fetch_add(1, std::memory_order_relaxed);
  }
  // Copies (or moves) a whole value in and publishes it.
  void write(T v) {
    write_slot() = std::move(v);
    publish();
  }

  // ---- reader side (one thread) ----
  // Takes the latest published value if there is a new one; returns whether it did.
  bool update() noexcept {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    front_ = static_cast<std::uint8_t>(middle_.exchange(front_, std::memory_order_acq_rel) & kIndexMask);
    return true;
  }
  // The reader's current value (stable until the next update()).
  const T& read_slot() const noexcept { return slots_[front_].value; }
  const T& read() noexcept {
    update();
    return read_slot();
  }
  // The latest value if it is new since the last take()/update() (valid until the next one), else nullptr.
  const T* take() noexcept { return update() ? &read_slot() : nullptr; }

  // Total publishes so far (any thread; for statistics only).
  std::uint64_t publishes() const noexcept { return publishes_.load(std::memory_order_relaxed); }
  // Values overwritten before the reader took them (any thread; statistics).
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;  // the shared slot holds a value the reader has not taken
  // Each slot on its own cache lines so writer and reader never false-share.
  struct alignas(64) Slot {
    T value;
  };
  std::array<Slot, 3> slots_;
  alignas(64) std::atomic<std::uint8_t> middle_{1};
  alignas(64) std::uint8_t back_ = 0;   // writer-owned
  alignas(64) std::uint8_t front_ = 2;  // reader-owned
  alignas(64) std::atomic<std::uint64_t> publishes_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace vitreo::runtime
