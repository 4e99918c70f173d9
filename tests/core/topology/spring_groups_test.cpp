// The solver's sleep groups (core/tissue/spring_groups.hpp) follow topology changes through the
// surface's spring log instead of rereading every spring: after cuts, suction and tears they must
// be what a rebuild from every spring gives (the independent check), the physics must be the same
// bits as a world that rebuilds before every step, and no rebuild may be needed for them.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "core/scene/snapshot.hpp"
#include "core/topology/cut.hpp"
#include "core/topology/tear.hpp"
#include "core/topology/vitrector.hpp"

using namespace vitreo::core;

namespace {

RetinaCapScene small_retina() {
  RetinaCapOptions o;
  o.retina_vertices = 5000;
  o.detachment = false;
  o.retina.tear_strain = INFINITY;
  return build_retina_cap(o);
}

Vec3 on_globe(double theta, double phi, double r = 12.0) {
  return r * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -std::cos(theta));
}

// A radial blade (through the retina) swept from one point on it to another.
CutResult radial_stroke(Cutter& cutter, const Vec3& from, const Vec3& to) {
  return cutter.sweep({from * 0.9, from * 1.06}, {to * 0.9, to * 1.06});
}

// Operation i of a fixed sequence: blade strokes along meridians, the vitrector (its field and removal),
// and torn springs, at places that move around the retina.
void operate(RetinaCapScene& scene, Cutter& cutter, Vitrector& vitrector, int i) {
  Surface& s = scene.world.surface(scene.retina);
  const double phi = 0.37 * i;
  if (i % 3 == 0) {
    const Vec3 a = on_globe(0.4, phi), b = on_globe(0.4 + 2.0 / 12.0, phi + 0.05);
    ASSERT_TRUE(radial_stroke(cutter, a, b).status);
  } else if (i % 3 == 1) {
    const Vec3 p = on_globe(0.9, phi);
    ASSERT_TRUE(vitrector.set_pose(p * (1.0 - 0.15 / 12.0), p));
    ASSERT_TRUE(vitrector.apply(1e-3).status);
  } else {
    // The live spring nearest a point on the retina.
    const Vec3 p = on_globe(0.7, phi);
    std::uint32_t best = kNone;
    double best_d = INFINITY;
    for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
      if (!s.edge_alive(e) || s.edge_triangles(e)[1] == kNone) continue;
      const auto ev = s.edge_vertices(e);
      const double d = (0.5 * (s.position(ev[0]) + s.position(ev[1])) - p).norm();
      if (d < best_d) {
        best_d = d;
        best = e;
      }
    }
    ASSERT_NE(best, kNone);
    ASSERT_TRUE(tear_spring(s, s.edge_id(best)).status);
  }
}

}  // namespace

TEST(SpringGroups, FollowCutsSuctionAndTearsExactlyWithoutRebuilding) {
  RetinaCapScene followed = small_retina(), rebuilt = small_retina();
  Cutter cut_f(followed.world.surface(followed.retina)), cut_r(rebuilt.world.surface(rebuilt.retina));
  Vitrector vit_f(followed.world.surface(followed.retina)), vit_r(rebuilt.world.surface(rebuilt.retina));
  for (Vitrector* v : {&vit_f, &vit_r}) ASSERT_TRUE(v->set_cut_rate(5000.0));
  ASSERT_TRUE(followed.world.step(1e-3).ok);
  ASSERT_TRUE(rebuilt.world.step(1e-3).ok);
  const std::uint64_t rebuilds0 = followed.world.spring_group_rebuilds();
  ASSERT_GE(rebuilds0, 1u) << "the first step builds the groups";

  std::vector<std::uint8_t> bytes;
  const std::uint64_t log0 = followed.world.surface(followed.retina).spring_log_end();
  for (int i = 0; i < 45; ++i) {
    operate(followed, cut_f, vit_f, i);
    operate(rebuilt, cut_r, vit_r, i);
    ASSERT_FALSE(testing::Test::HasFatalFailure());
    // The control rebuilds its groups before every step: restoring its own snapshot drops them.
    encode_snapshot(rebuilt.world, "control", bytes);
    ASSERT_TRUE(decode_snapshot(rebuilt.world, bytes));
    const StepReport rf = followed.world.step(1e-3), rr = rebuilt.world.step(1e-3);
    ASSERT_TRUE(rf.ok && rr.ok) << rf.error << rr.error;
    const Status groups = followed.world.check_spring_groups();
    ASSERT_TRUE(groups) << "after operation " << i << ": " << groups.message();
    ASSERT_EQ(followed.world.state_hash(), rebuilt.world.state_hash()) << "after operation " << i;
  }
  EXPECT_GT(followed.world.surface(followed.retina).spring_log_end(), log0 + 1000) << "the operations changed springs";
  EXPECT_EQ(followed.world.spring_group_rebuilds(), rebuilds0) << "the log was enough for every change";
  EXPECT_GT(rebuilt.world.spring_group_rebuilds(), 45u);
}

TEST(SpringGroups, MoreChangesThanTheLogHoldsRebuildFromEverySpring) {
  RetinaCapScene scene = small_retina();
  ASSERT_TRUE(scene.world.step(1e-3).ok);  // builds the groups
  const std::uint64_t rebuilds0 = scene.world.spring_group_rebuilds();
  Surface& s = scene.world.surface(scene.retina);
  Cutter cutter(s);
  // Many strokes between two steps: more springs change than the log keeps.
  const std::uint64_t log0 = s.spring_log_end();
  for (int i = 0; s.spring_log_end() - log0 <= Surface::kSpringLogSize && i < 200; ++i) {
    const double phi = 0.11 * i;
    const Vec3 a = on_globe(0.3, phi), b = on_globe(0.3 + 3.0 / 12.0, phi);
    ASSERT_TRUE(radial_stroke(cutter, a, b).status);
  }
  ASSERT_TRUE(s.spring_log_lost(log0));
  ASSERT_TRUE(scene.world.step(1e-3).ok);
  EXPECT_EQ(scene.world.spring_group_rebuilds(), rebuilds0 + 1);
  const Status groups = scene.world.check_spring_groups();
  EXPECT_TRUE(groups) << groups.message();
}

TEST(SpringGroups, AGroupThatOutgrowsItsRoomIsRebuiltAndStaysExact) {
  RetinaCapScene scene = small_retina();
  ASSERT_TRUE(scene.world.step(1e-3).ok);
  const std::uint64_t rebuilds0 = scene.world.spring_group_rebuilds();
  Surface& s = scene.world.surface(scene.retina);
  Cutter cutter(s);
  // A cross-hatch of 1 mm strokes through the same few blocks, a step after each: their groups
  // gain springs with every stroke until one outgrows the room it was given. (With 1.5 mm strokes
  // the retina's vertex pool was within 2 % of full when that happened.)
  constexpr double kStroke = 1.0 / 12.0;
  int i = 0;
  for (; i < 300 && scene.world.spring_group_rebuilds() == rebuilds0; ++i) {
    const double along = 0.5 + 0.03 * (i / 2);
    Vec3 a, b;
    if (i % 2 == 0) {  // along a meridian
      a = on_globe(0.5, along);
      b = on_globe(0.5 + kStroke, along);
    } else {  // along a parallel
      a = on_globe(0.5 + 0.03 * (i / 2), 0.45);
      b = on_globe(0.5 + 0.03 * (i / 2), 0.45 + kStroke / std::sin(0.5));
    }
    const CutResult cut = radial_stroke(cutter, a, b);
    ASSERT_TRUE(cut.status) << "stroke " << i << ": " << cut.status.message();
    ASSERT_TRUE(scene.world.step(1e-3).ok);
    const Status groups = scene.world.check_spring_groups();
    ASSERT_TRUE(groups) << "after stroke " << i << ": " << groups.message();
  }
  EXPECT_GT(scene.world.spring_group_rebuilds(), rebuilds0) << "no group outgrew its room in " << i << " strokes";
  // And after the rebuild, following the log again.
  const std::uint64_t rebuilds1 = scene.world.spring_group_rebuilds();
  const Vec3 a = on_globe(1.0, 2.0), b = on_globe(1.0 + 1.5 / 12.0, 2.0);
  ASSERT_TRUE(radial_stroke(cutter, a, b).status);
  ASSERT_TRUE(scene.world.step(1e-3).ok);
  EXPECT_TRUE(scene.world.check_spring_groups());
  EXPECT_EQ(scene.world.spring_group_rebuilds(), rebuilds1);
}
