// VertexIndex (the spatial query the cutter and the vitrector use) against a brute-force scan of
// every slot: it must report exactly the live vertices in the box, in slot order, while the
// solver moves the tissue (awake and sleeping blocks), vertices are moved by hand, the mesh is cut
// and material removed, and a snapshot puts every vertex back somewhere else.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "core/tissue/tissue_world.hpp"
#include "core/topology/cut.hpp"
#include "core/topology/vertex_index.hpp"
#include "core/topology/vitrector.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {

std::vector<std::uint32_t> brute_force(const Surface& s, const Vec3& lo, const Vec3& hi) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (!s.vertex_alive(v)) continue;
    const Vec3& x = s.position(v);
    if ((x.array() >= lo.array()).all() && (x.array() <= hi.array()).all()) out.push_back(v);
  }
  return out;
}

// Random boxes of several sizes around the sheet; every query must equal the brute-force answer.
// Returns how many blocks the first query refitted.
std::uint32_t expect_exact(VertexIndex& index, const Surface& s, std::mt19937& rng, const char* when) {
  std::uint32_t refits = 0;
  std::uniform_real_distribution<double> u(-0.5, 4.5), size(0.01, 2.0), z(-1.0, 1.0);
  for (int q = 0; q < 40; ++q) {
    const Vec3 c(u(rng), 0.75 * u(rng), 0.2 * z(rng));
    const Vec3 half(size(rng), size(rng), 0.5 * size(rng));
    const Vec3 lo = c - half, hi = c + half;
    std::vector<std::uint32_t> got;
    index.for_each_in_box(lo, hi, [&](std::uint32_t v) { got.push_back(v); });
    if (q == 0) refits = index.last_refits();
    EXPECT_EQ(got, brute_force(s, lo, hi)) << when << ", query " << q;
  }
  return refits;
}

// A sheet sagging under gravity from its pinned edge x = 0, in a world with the given settings.
struct SaggingSheet {
  TissueWorld world;
  Surface& s;
  SaggingSheet(const SurfaceDescription& d, const SolverSettings& settings)
      : world(GlobeWall::sphere(Vec3::Zero(), 1e6), gravity_only(), settings), s(world.surface(world.add_surface(d))) {
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.rest_position(v).x() == 0.0) (void)s.set_fixed(s.vertex_id(v), true);
    }
  }
  static Environment gravity_only() {
    Environment env;
    env.apply_pressure = false;
    env.gravity_mm_s2 = Vec3(0.0, 0.0, -9810.0);
    return env;
  }
};

}  // namespace

TEST(VertexIndex, ReportsExactlyTheVerticesInTheBoxWhileTheTissueMovesSleepsAndChanges) {
  SolverSettings settings;
  settings.sleep_after_steps = 5;  // so blocks fall asleep (and wake) within the test
  settings.sleep_speed_mm_s = 2.0;
  SaggingSheet sagging(sheet(4.0, 3.0, 24, 18, 0.3, 3), settings);
  TissueWorld& world = sagging.world;
  Surface& s = sagging.s;
  VertexIndex index(s);
  Cutter cutter(s);
  Vitrector vit(s);
  std::mt19937 rng(11);
  expect_exact(index, s, rng, "at rest");
  std::vector<std::uint8_t> saved;
  std::uint32_t min_refits = 1u << 30, max_refits = 0;
  for (int step = 0; step < 400; ++step) {
    ASSERT_TRUE(world.step(1e-3).ok);
    if (step == 50) world.write_state(saved);
    if (step % 40 == 7) {  // a hand-placed vertex, asleep or not
      const std::uint32_t v = std::uniform_int_distribution<std::uint32_t>(0, s.vertex_slots() - 1)(rng);
      if (s.vertex_alive(v)) {
        ASSERT_TRUE(s.set_position(s.vertex_id(v), s.position(v) + Vec3(0.3, -0.2, 0.5)));
      }
    }
    if (step == 120) {  // a cut across the sagging sheet and a suction bite
      ASSERT_TRUE(cutter.sweep({Vec3(1.0, 0.5, -2.0), Vec3(1.0, 0.5, 2.0)}, {Vec3(3.0, 2.5, -2.0), Vec3(3.0, 2.5, 2.0)}).status);
      ASSERT_TRUE(vit.set_pose(s.position(100) + Vec3(0, 0, 0.1), Vec3(0, 0, -1)));
      ASSERT_TRUE(vit.cut_now().status);
    }
    if (step % 10 == 0) {
      const std::uint32_t refits = expect_exact(index, s, rng, "while simulating");
      min_refits = std::min(min_refits, refits);
      max_refits = std::max(max_refits, refits);
    }
  }
  // Some blocks slept: the index refitted fewer than all of them at some point (the point of it).
  EXPECT_LT(world.awake_blocks(), s.block_count());
  EXPECT_LT(min_refits, index.patches_in_use());
  EXPECT_GT(max_refits, 0u);
  // A snapshot restore moves every vertex (sleeping ones too) without waking anything.
  ASSERT_TRUE(world.read_state(saved.data(), saved.size()));
  expect_exact(index, s, rng, "after a snapshot restore");
}

// The drift bound: with every block awake and sagging, a small query re-reads only the patches
// whose grown box reaches it, not the whole sheet; waking moves nothing and forces no re-read;
// a vertex placed by hand is found where it now is.
TEST(VertexIndex, RereadsOnlyThePatchesTheDriftBoundBringsNearTheQuery) {
  SolverSettings settings;
  settings.sleeping = false;  // every block moves every step
  SaggingSheet sagging(sheet(4.0, 3.0, 48, 36, 0.0, 5), settings);
  TissueWorld& world = sagging.world;
  Surface& s = sagging.s;
  VertexIndex index(s);
  for (int step = 0; step < 3; ++step) ASSERT_TRUE(world.step(1e-3).ok);
  EXPECT_GT(s.block_drift_mm(0), 0.0);
  // A box around one vertex far from the pinned edge.
  const std::uint32_t probe = s.vertex_slots() - 1;
  const Vec3 lo = s.position(probe).array() - 0.05, hi = s.position(probe).array() + 0.05;
  std::vector<std::uint32_t> got;
  index.for_each_in_box(lo, hi, [&](std::uint32_t v) { got.push_back(v); });
  EXPECT_EQ(got, brute_force(s, lo, hi));
  EXPECT_GT(index.last_refits(), 0u);                          // the sheet moved: the boxes there are read again
  EXPECT_LT(index.last_refits(), index.patches_in_use() / 4);  // but only there
  // Waking every block moves nothing: a query elsewhere re-reads only what drifted near it.
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) s.wake_vertex(v);
  const Vec3 lo2 = s.position(0).array() - 0.05, hi2 = s.position(0).array() + 0.05;
  got.clear();
  index.for_each_in_box(lo2, hi2, [&](std::uint32_t v) { got.push_back(v); });
  EXPECT_EQ(got, brute_force(s, lo2, hi2));
  EXPECT_LT(index.last_refits(), index.patches_in_use() / 4);
  // A vertex placed by hand far from everything is found there, and only its block is re-read.
  const Vec3 away(10.0, 10.0, 10.0);
  ASSERT_TRUE(s.set_position(s.vertex_id(probe), away));
  got.clear();
  index.for_each_in_box(away.array() - 0.01, away.array() + 0.01, [&](std::uint32_t v) { got.push_back(v); });
  EXPECT_EQ(got, std::vector<std::uint32_t>{probe});
  EXPECT_LE(index.last_refits(), Surface::kSleepBlock / VertexIndex::kPatch);
}
