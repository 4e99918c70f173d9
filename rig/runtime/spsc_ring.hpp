#pragma once
// Bounded single-producer/single-consumer queue that never blocks the producer: when full, the item
// is dropped and counted (a slow consumer is dropped, never waited for — design guide). Storage is
// allocated once in the constructor, so pushing never allocates. Lamport's ring with each side
// caching the other's index (as in Rigtorp's SPSCQueue) so the common case touches no shared line.
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <type_traits>

namespace vitreo::runtime {

template <class T>
class SpscRing {
  static_assert(std::is_nothrow_copy_assignable_v<T> && std::is_default_constructible_v<T>,
                "SpscRing items are copied in and out without throwing");

 public:
  // capacity is rounded up to a power of two (at least 2).
  explicit SpscRing(std::size_t capacity)
      : mask_(std::bit_ceil(capacity < 2 ? std::size_t{2} : capacity) - 1),
        items_(std::make_unique<T[]>(mask_ + 1)) {}
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  std::size_t capacity() const noexcept { return mask_ + 1; }

  // ---- producer side (one thread) ----
  // Wait-free. Returns false (and counts a drop) when the ring is full.
  bool try_push(const T& item) noexcept {
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - cached_tail_ > mask_) {
      cached_tail_ = tail_.load(std::memory_order_acquire);
      if (head - cached_tail_ > mask_) {
        dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        return false;
      }
    }
    items_[head & mask_] = item;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // ---- consumer side (one thread) ----
  bool try_pop(T& out) noexcept {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == cached_head_) {
      cached_head_ = head_.load(std::memory_order_acquire);
      if (tail == cached_head_) return false;
    }
    out = items_[tail & mask_];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // ---- statistics (any thread) ----
  std::uint64_t pushed() const noexcept { return head_.load(std::memory_order_relaxed); }
  std::uint64_t popped() const noexcept { return tail_.load(std::memory_order_relaxed); }
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  std::size_t size_approx() const noexcept {
    const std::uint64_t h = head_.load(std::memory_order_acquire);
    const std::uint64_t t = tail_.load(std::memory_order_acquire);
    return h >= t ? static_cast<std::size_t>(h - t) : 0;
  }

 private:
  const std::size_t mask_;
  std::unique_ptr<T[]> items_;
  alignas(64) std::atomic<std::uint64_t> head_{0};  // next slot to write (producer)
  std::uint64_t cached_tail_ = 0;                    // producer's view of tail_
  std::atomic<std::uint64_t> dropped_{0};            // written by the producer only
  alignas(64) std::atomic<std::uint64_t> tail_{0};  // next slot to read (consumer)
  std::uint64_t cached_head_ = 0;                    // consumer's view of head_
};

}  // namespace vitreo::runtime
