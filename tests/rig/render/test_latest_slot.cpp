#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

#include "vitreo/render/latest_slot.hpp"

namespace vr = vitreo::render;

TEST(LatestSlot, ConsumerGetsOnlyTheNewestAndCountsDrops) {
  vr::LatestSlot<int> slot;
  EXPECT_EQ(slot.take(), nullptr);
  slot.publish(1);
  slot.publish(2);
  slot.publish(3);
  const int* v = slot.take();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(*v, 3);
  EXPECT_EQ(slot.dropped(), 2u);
  EXPECT_EQ(slot.take(), nullptr);  // nothing new
  slot.publish(4);
  ASSERT_NE(slot.take(), nullptr);
  EXPECT_EQ(slot.published(), 4u);
}

namespace {
struct Pair {
  std::uint64_t a = 0, b = 0;  // always equal when published: a torn value would differ
};
}  // namespace

TEST(LatestSlot, ConcurrentValuesAreWholeAndIncreasing) {
  vr::LatestSlot<Pair> slot;
  constexpr std::uint64_t kCount = 200000;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (std::uint64_t i = 1; i <= kCount; ++i) slot.publish({i, i});
    done.store(true, std::memory_order_release);
  });
  std::uint64_t last = 0, takes = 0;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    if (const Pair* p = slot.take()) {
      ASSERT_EQ(p->a, p->b);
      ASSERT_GT(p->a, last);
      last = p->a;
      ++takes;
    } else if (finished) {
      break;
    }
  }
  producer.join();
  EXPECT_EQ(last, kCount);  // the final value is never lost
  EXPECT_EQ(takes + slot.dropped(), kCount);
}
