// The tissue step's worker pool: every part runs once per pass, slices cover the items exactly once, and — what the pool is for — the tissue world's state is the same bit for
// bit at any thread count, through tears, changed rest lengths, suction, snapshots and a rolled-back
// step. Run under ThreadSanitizer by the tsan preset (label `threads`).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <thread>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "core/common/worker_pool.hpp"
#include "core/scene/snapshot.hpp"
#include "core/tissue/tissue_world.hpp"

using namespace vitreo::core;

TEST(WorkerPool, EveryPartRunsOncePerPass) {
  // 8 threads on this 2-core machine too: workers the kernel has not scheduled yet leave their
  // parts to the caller, and a worker late for one pass must not run a part twice in the next.
  for (unsigned threads : {1u, 2u, 3u, 5u, 8u}) {
    WorkerPool pool(threads);
    ASSERT_EQ(pool.threads(), threads);
    std::set<std::thread::id> helpers;
    for (int pass = 0; pass < 2000; ++pass) {
      std::vector<std::atomic<int>> calls(threads);
      std::vector<std::thread::id> ran_on(threads);
      auto part = [&](unsigned p) {
        calls[p].fetch_add(1, std::memory_order_relaxed);
        ran_on[p] = std::this_thread::get_id();
      };
      pool.run(part);
      for (unsigned p = 0; p < threads; ++p) ASSERT_EQ(calls[p].load(), 1) << threads << " threads, pass " << pass << ", part " << p;
      EXPECT_EQ(ran_on[0], std::this_thread::get_id()) << "part 0 runs on the caller";
      helpers.insert(ran_on.begin(), ran_on.end());
    }
    EXPECT_LE(helpers.size(), threads) << "the pool's own threads only";
  }
}

TEST(WorkerPool, AWorkerRunsItsPartBesideTheCaller) {
  // The caller's part waits (up to 5 s) for the worker's to start: it can only see it start if the
  // two run at the same time, which is what the pool is for (and what TSan then watches).
  WorkerPool pool(2);
  std::atomic<bool> started{false};
  bool seen = false;
  std::thread::id worker;
  auto part = [&](unsigned p) {
    if (p == 1) {
      worker = std::this_thread::get_id();
      started.store(true, std::memory_order_release);
      return;
    }
    for (int i = 0; i < 5000 && !seen; ++i) {
      seen = started.load(std::memory_order_acquire);
      if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  };
  pool.run(part);
  EXPECT_TRUE(seen) << "the worker never started its part while the caller ran its own";
  EXPECT_NE(worker, std::this_thread::get_id());
}

TEST(WorkerPool, SlicesCoverTheItemsExactlyOnce) {
  for (unsigned threads : {1u, 2u, 3u, 4u}) {
    WorkerPool pool(threads);
    for (std::uint32_t n : {0u, 1u, 2u, 3u, 7u, 64u, 1000u, 4097u}) {
      std::vector<std::atomic<int>> seen(n);
      std::atomic<std::uint32_t> largest{0}, smallest{~0u};
      run_sliced(&pool, n, [&](std::uint32_t begin, std::uint32_t end) {
        ASSERT_LE(begin, end);
        for (std::uint32_t i = begin; i < end; ++i) seen[i].fetch_add(1, std::memory_order_relaxed);
        largest.store(std::max(largest.load(), end - begin));
        smallest.store(std::min(smallest.load(), end - begin));
      });
      for (std::uint32_t i = 0; i < n; ++i) ASSERT_EQ(seen[i].load(), 1) << threads << " threads, item " << i << " of " << n;
      EXPECT_LE(largest.load() - smallest.load(), 1u) << "slices differ by at most one item";
    }
  }
}

TEST(WorkerPool, WorkersThatFellAsleepWakeForTheNextPassAndStopCleanly) {
  WorkerPool pool(3);
  std::atomic<int> calls{0};
  auto part = [&](unsigned) { calls.fetch_add(1, std::memory_order_relaxed); };
  pool.run(part);
  // Long enough that every worker has given up spinning and sleeps on the futex.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  pool.run(part);
  EXPECT_EQ(calls.load(), 6);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  // The destructor joins sleeping workers.
}

namespace {

RetinaCapScene working_cap(unsigned threads) {
  RetinaCapOptions o;
  o.retina_vertices = 3000;
  o.membrane = true;
  RetinaCapScene scene = build_retina_cap(o);
  scene.world.set_worker_threads(threads);
  return scene;
}

// A movable, awake retina vertex at the middle of the detachment (the most displaced one).
std::uint32_t lifted_vertex(const RetinaCapScene& scene) {
  const Surface& s = scene.world.surface(scene.retina);
  std::uint32_t best = 0;
  double lift = -1.0;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (!s.vertex_alive(v) || s.inverse_mass(v) == 0.0 || !s.vertex_awake(v)) continue;
    const double d = (s.rest_position(v) - s.position(v)).norm();
    if (d > lift) lift = d, best = v;
  }
  return best;
}

}  // namespace

TEST(WorkerPool, TheTissueStateIsTheSameBitForBitAtAnyThreadCount) {
  std::vector<RetinaCapScene> worlds;
  for (unsigned t : {1u, 2u, 3u}) worlds.push_back(working_cap(t));
  ASSERT_EQ(worlds[1].world.worker_threads(), 2u);
  std::vector<std::uint8_t> midway;
  for (int i = 0; i < 400; ++i) {
    const double scale = 0.9 + 0.1 * std::sin(2.0 * 3.141592653589793 * 1e-3 * i);
    for (RetinaCapScene& w : worlds) {
      Surface& s = w.world.surface(w.retina);
      ASSERT_TRUE(w.world.set_local_force_scale(w.detachment_force, scale));
      if (i == 100) {  // suction over the detachment: the suction pass runs split too
        const std::uint32_t v = lifted_vertex(w);
        const Vec3 inward = -s.position(v).normalized();
        const SuctionField f{s.position(v) + 0.4 * inward, -inward, 1.0, 400.0};
        ASSERT_TRUE(w.world.set_suction_fields({&f, 1}));
      }
      if (i == 250) {
        ASSERT_TRUE(w.world.set_suction_fields({}));
      }
      if (i % 100 == 50) {  // a topology change: tear an interior spring by hand
        std::uint32_t e = 0;
        while (e < s.edge_slots() && !(s.edge_alive(e) && s.edge_triangles(e)[1] != kNone && s.vertex_awake(s.edge_vertices(e)[0]))) ++e;
        ASSERT_LT(e, s.edge_slots());
        (void)s.tear_edge(s.edge_id(e));
      }
      if (i % 100 == 80) {  // rest lengths changed in place: the packed springs' values are refreshed split
        std::uint32_t e = 0;
        while (e < s.edge_slots() && !(s.edge_alive(e) && s.vertex_awake(s.edge_vertices(e)[0]) && s.vertex_awake(s.edge_vertices(e)[1])))
          ++e;
        ASSERT_LT(e, s.edge_slots());
        ASSERT_TRUE(s.set_edge_traction(s.edge_id(e), 0.9));
      }
      if (i == 300) {
        encode_snapshot(w.world, "midway", midway);
        ASSERT_TRUE(decode_snapshot(w.world, midway));
      }
      const StepReport r = w.world.step(1e-3);
      ASSERT_TRUE(r.ok) << r.error;
    }
    ASSERT_EQ(worlds[1].world.state_hash(), worlds[0].world.state_hash()) << "2 threads, step " << i;
    ASSERT_EQ(worlds[2].world.state_hash(), worlds[0].world.state_hash()) << "3 threads, step " << i;
  }
  // The run did what it was meant to exercise: the detachment and the suction kept much awake.
  EXPECT_GT(worlds[0].world.awake_blocks(), 4u);
}

TEST(WorkerPool, ANonFiniteStepIsRolledBackAtAnyThreadCount) {
  for (unsigned threads : {2u, 3u}) {
    RetinaCapScene a = working_cap(1), b = working_cap(threads);
    for (RetinaCapScene* w : {&a, &b}) {
      for (int i = 0; i < 20; ++i) ASSERT_TRUE(w->world.step(1e-3).ok);
      Surface& s = w->world.surface(w->retina);
      const std::uint32_t v = lifted_vertex(*w);
      ASSERT_TRUE(s.set_position(s.vertex_id(v), Vec3(1e300, -1e300, 1e300)));
      const auto before = w->world.state_hash();
      const StepReport r = w->world.step(1e-3);
      EXPECT_FALSE(r.ok) << threads << " threads";
      EXPECT_EQ(w->world.state_hash(), before) << "rolled back, " << threads << " threads";
      ASSERT_TRUE(s.set_position(s.vertex_id(v), s.rest_position(v)));
      for (int i = 0; i < 20; ++i) ASSERT_TRUE(w->world.step(1e-3).ok);
    }
    EXPECT_EQ(a.world.state_hash(), b.world.state_hash()) << threads << " threads";
  }
}

TEST(WorkerPool, AThreadCountOutsideOneToSixtyFourIsRefused) {
  RetinaCapScene scene = working_cap(1);
  EXPECT_THROW(scene.world.set_worker_threads(0), InvalidArgument);
  EXPECT_THROW(scene.world.set_worker_threads(65), InvalidArgument);
  EXPECT_EQ(scene.world.worker_threads(), 1u);
  scene.world.set_worker_threads(4);
  EXPECT_EQ(scene.world.worker_threads(), 4u);
  scene.world.set_worker_threads(1);
  EXPECT_EQ(scene.world.worker_threads(), 1u);
}
