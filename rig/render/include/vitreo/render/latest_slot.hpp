#pragma once
// LatestSlot<T>: a single-producer, single-consumer "latest value" mailbox (triple buffer).
//
// The physics thread publishes a FrameScene per step; the render thread takes the newest one at its
// own rate. Neither ever waits for the other: publish() and take() are each one atomic exchange,
// older unread values are overwritten (counted as dropped), and the three buffers mean the writer
// always has a buffer the reader is not looking at. Kept small and local to rig/render; the general
// runtime mailboxes live in rig/runtime/ and may replace it.
#include <array>
#include <atomic>
#include <cstdint>
#include <utility>

namespace vitreo::render {

template <typename T>
class LatestSlot {
 public:
  /// Producer: makes `value` the latest. Wait-free.
  void publish(T value) {
    buffers_[back_] = std::move(value);
    const std::uint32_t prev = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    if (prev & kFresh) dropped_.fetch_add(1, std::memory_order_relaxed);
    back_ = prev & kIndexMask;
    published_.fetch_add(1, std::memory_order_release);
  }

  /// Consumer: if a value newer than the last take() exists, returns a pointer to it (valid until
  /// the next take()); otherwise nullptr. Wait-free.
  const T* take() {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return nullptr;
    const std::uint32_t prev = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = prev & kIndexMask;
    return &buffers_[front_];
  }

  /// Number of publish() calls so far.
  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  /// Values overwritten before the consumer took them.
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::uint32_t kFresh = 4;
  static constexpr std::uint32_t kIndexMask = 3;
  std::array<T, 3> buffers_{};
  std::uint32_t back_ = 0;                  // producer-owned
  std::atomic<std::uint32_t> middle_{1};    // shared: index | kFresh
  std::uint32_t front_ = 2;                 // consumer-owned
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace vitreo::render
