// Triple buffer and SPSC ring: single-thread semantics, then real threads hammering them (these are
// the tests TSan must see clean).
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "rig/runtime/spsc_ring.hpp"
#include "rig/runtime/triple_buffer.hpp"

using vitreo::runtime::SpscRing;
using vitreo::runtime::TripleBuffer;

namespace {
// A value whose fields must all agree: a torn read (half old, half new) breaks the invariant.
struct Stamp {
  std::uint64_t seq = 0;
  std::array<std::uint64_t, 15> copy{};  // 128 bytes: spans cache lines
  bool consistent() const {
    for (auto c : copy)
      if (c != seq * 2654435761u) return false;
    return true;
  }
  static Stamp make(std::uint64_t s) {
    Stamp v;
    v.seq = s;
    v.copy.fill(s * 2654435761u);
    return v;
  }
};
}  // namespace

TEST(TripleBuffer, ReaderSeesLatestValueAndOnlyWhenFresh) {
  TripleBuffer<int> tb(-1);
  EXPECT_FALSE(tb.update());
  EXPECT_EQ(tb.read_slot(), -1);
  tb.write(1);
  tb.write(2);
  tb.write(3);  // the writer never waits: older values are simply overwritten
  EXPECT_TRUE(tb.update());
  EXPECT_EQ(tb.read_slot(), 3);
  EXPECT_FALSE(tb.update());
  EXPECT_EQ(tb.read_slot(), 3);
  tb.write_slot() = 4;
  tb.publish();
  EXPECT_EQ(tb.read(), 4);
  EXPECT_EQ(tb.publishes(), 4u);
}

TEST(TripleBuffer, ConcurrentWriterReaderNeverTearsAndSequenceIsMonotonic) {
  TripleBuffer<Stamp> tb(Stamp::make(0));
  constexpr std::uint64_t kWrites = 200000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t s = 1; s <= kWrites; ++s) tb.write(Stamp::make(s));
    done.store(true, std::memory_order_release);
  });
  std::uint64_t last = 0, updates = 0, torn = 0, backwards = 0;
  while (true) {
    const bool finished = done.load(std::memory_order_acquire);
    if (tb.update()) {
      ++updates;
      const Stamp& v = tb.read_slot();
      if (!v.consistent()) ++torn;
      if (v.seq <= last) ++backwards;
      last = v.seq;
    }
    if (finished && !tb.update()) break;
  }
  writer.join();
  if (tb.update()) last = tb.read_slot().seq;
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kWrites) << "the reader must end on the final value";
  EXPECT_GT(updates, 0u);
}

// take(): only what is new, and every value the reader never saw is counted as dropped (the render
// thread reports them as scenes it skipped).
TEST(TripleBuffer, TakeHandsOverOnlyNewValuesAndCountsTheOnesOverwritten) {
  TripleBuffer<int> tb(0);
  EXPECT_EQ(tb.take(), nullptr);
  tb.write(1);
  tb.write(2);
  tb.write(3);
  const int* v = tb.take();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(*v, 3);
  EXPECT_EQ(tb.dropped(), 2u);
  EXPECT_EQ(tb.take(), nullptr) << "nothing new";
  tb.write(4);
  ASSERT_NE(tb.take(), nullptr);
  EXPECT_EQ(tb.dropped(), 2u);
  EXPECT_EQ(tb.publishes(), 4u);
}

TEST(TripleBuffer, ConcurrentlyEveryValueIsTakenOrCountedAsDropped) {
  TripleBuffer<Stamp> tb(Stamp::make(0));
  constexpr std::uint64_t kWrites = 200000;
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::uint64_t s = 1; s <= kWrites; ++s) tb.write(Stamp::make(s));
    done.store(true, std::memory_order_release);
  });
  std::uint64_t last = 0, takes = 0;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    if (const Stamp* p = tb.take()) {
      ASSERT_TRUE(p->consistent());
      ASSERT_GT(p->seq, last);
      last = p->seq;
      ++takes;
    } else if (finished) {
      break;
    }
  }
  writer.join();
  EXPECT_EQ(last, kWrites) << "the final value is never lost";
  EXPECT_EQ(takes + tb.dropped(), kWrites);
}

TEST(SpscRing, FifoOrderAndDropWhenFullIsCounted) {
  SpscRing<int> ring(5);  // rounded up to 8
  ASSERT_EQ(ring.capacity(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(100));
  EXPECT_FALSE(ring.try_push(101));
  EXPECT_EQ(ring.dropped(), 2u);
  EXPECT_EQ(ring.size_approx(), 8u);
  int v = -1;
  for (int i = 0; i < 8; ++i) {
    ASSERT_TRUE(ring.try_pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(ring.try_pop(v));
  EXPECT_TRUE(ring.try_push(8));  // space again after draining; wrap-around
  ASSERT_TRUE(ring.try_pop(v));
  EXPECT_EQ(v, 8);
  EXPECT_EQ(ring.pushed(), 9u);
  EXPECT_EQ(ring.popped(), 9u);
}

TEST(SpscRing, ConcurrentProducerConsumerDeliversInOrderAndAccountsForEveryItem) {
  SpscRing<Stamp> ring(64);  // small, so the producer overruns the consumer often
  constexpr std::uint64_t kItems = 300000;
  std::atomic<bool> done{false};
  std::uint64_t accepted = 0;
  std::thread producer([&] {
    for (std::uint64_t s = 1; s <= kItems; ++s)
      if (ring.try_push(Stamp::make(s))) ++accepted;
    done.store(true, std::memory_order_release);
  });
  std::uint64_t received = 0, last = 0, torn = 0, out_of_order = 0;
  Stamp v;
  while (true) {
    const bool finished = done.load(std::memory_order_acquire);
    bool got = false;
    while (ring.try_pop(v)) {
      got = true;
      ++received;
      if (!v.consistent()) ++torn;
      if (v.seq <= last) ++out_of_order;
      last = v.seq;
    }
    if (finished && !got && ring.size_approx() == 0) break;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(received, accepted);
  EXPECT_EQ(accepted + ring.dropped(), kItems) << "every item is either delivered or counted as dropped";
}
