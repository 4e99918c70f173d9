// Properties the solver must keep: energy never grows without input, tears at the configured
// strain, attachments break at their strength, the retina stays inside the globe, runs are
// deterministic, bad input is refused, and a step that would go non-finite is rolled back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/anatomy/retina_cap.hpp"
#include "core/scene/snapshot.hpp"
#include "core/tissue/surface_validity.hpp"
#include "core/tissue/tissue_world.hpp"
#include "test_meshes.hpp"

using namespace vitreo::core;

namespace {

GlobeWall far_wall() { return GlobeWall::sphere(Vec3::Zero(), 1e6); }

RetinaCapOptions small_retina() {
  RetinaCapOptions o;
  o.retina_vertices = 2000;
  return o;
}

}  // namespace

TEST(SolverBehaviour, EnergyNeverGrowsWithoutInput) {
  // A sheet pinned along one edge, perturbed randomly, under gravity, with no drag: the only
  // energy is what it starts with.
  SurfaceDescription d;
  d.mesh = test::rectangle(4.0, 4.0, 10, 10);
  d.material.drag_pa_s_per_mm = 0.0;
  d.material.tear_strain = INFINITY;
  d.contained_by_globe = false;
  Environment env;
  env.apply_pressure = false;
  TissueWorld world(far_wall(), env);
  Surface& s = world.surface(world.add_surface(d));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (s.rest_position(v).y() == 0.0) {
      ASSERT_TRUE(s.set_fixed(s.vertex_id(v), true));
    } else {
      const Vec3 jitter(u(rng), u(rng), u(rng));
      ASSERT_TRUE(s.set_position(s.vertex_id(v), s.position(v) + jitter));
    }
  }
  const double e0 = world.energy().total();
  double emax = e0;
  for (int i = 0; i < 2000; ++i) {
    ASSERT_TRUE(world.step(1e-3).ok);
    emax = std::max(emax, world.energy().total());
  }
  EXPECT_LE(emax, e0 + 1e-9 * std::abs(e0));
  EXPECT_LT(world.energy().total(), e0);
}

TEST(SolverBehaviour, ASpringTearsAtTheConfiguredStrain) {
  for (double tear : {0.35, 0.55}) {
    SurfaceDescription d;
    d.mesh = test::rectangle(6.0, 1.0, 12, 2);
    d.material.tear_strain = tear;
    d.material.bending_modulus_un_mm = 0.0;
    d.contained_by_globe = false;
    Environment env;
    env.gravity_mm_s2 = Vec3::Zero();
    env.apply_pressure = false;
    SolverSettings settings;
    settings.substeps = 4;
    settings.iterations = 4;
    TissueWorld world(far_wall(), env, settings);
    Surface& s = world.surface(world.add_surface(d));
    std::vector<std::uint32_t> pulled;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.rest_position(v).x() == 0.0) {
        ASSERT_TRUE(s.set_fixed(s.vertex_id(v), true));
      }
      if (s.rest_position(v).x() == 6.0) {
        ASSERT_TRUE(s.set_fixed(s.vertex_id(v), true));
        pulled.push_back(v);
      }
    }
    // Pull the right edge slowly (quasi-static: 6 mm/s) and watch the largest strain at the end
    // of each step (where tears are decided).
    double strain_before_tear = 0.0;
    double torn_at = -1.0;
    for (int i = 0; i < 4000 && torn_at < 0; ++i) {
      for (auto v : pulled) {
        ASSERT_TRUE(s.set_fixed_position(s.vertex_id(v), s.position(v) + Vec3(0.006, 0, 0)));
      }
      const auto r = world.step(1e-3);
      ASSERT_TRUE(r.ok);
      if (r.tears > 0) {
        torn_at = world.events().front().magnitude;
        EXPECT_EQ(world.events().front().kind, TissueEventKind::kTear);
      } else {
        for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
          if (s.edge_alive(e)) strain_before_tear = std::max(strain_before_tear, s.edge_strain(e));
        }
      }
    }
    ASSERT_GT(torn_at, 0.0) << "no tear for tear_strain " << tear;
    EXPECT_GE(torn_at, tear);
    EXPECT_LT(torn_at, tear * 1.05) << "torn well past the configured strain";
    EXPECT_LE(strain_before_tear, tear * 1.0001) << "a spring survived past its tolerance";
    EXPECT_TRUE(check_surface(s).ok()) << check_surface(s).summary();
  }
}

TEST(SolverBehaviour, AnAttachmentCarriesItsLoadAndBreaksAtItsStrength) {
  // One triangle hanging from the eye wall by an attachment at each corner. Its buoyant weight is
  // m g (1 − ρ_fluid/ρ); each attachment carries a third.
  SurfaceDescription d;
  d.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  d.mesh.triangles = {{0, 1, 2}};
  d.contained_by_globe = false;
  TissueWorld world(far_wall());
  const auto sid = world.add_surface(d);
  const Surface& s = world.surface(sid);
  const Environment& env = world.environment();
  const double weight = s.total_mass() * env.gravity_mm_s2.norm() *
                        (1.0 - env.fluid_density_g_per_mm3 / s.material().density_g_per_mm3);
  std::vector<std::uint32_t> ids;
  for (std::uint32_t v = 0; v < 3; ++v) {
    AttachmentDescription a;
    a.surface_a = sid;
    a.vertex_a = v;
    a.world_point_mm = s.position(v);
    a.stiffness_un_per_mm = 1e5;
    a.break_force_un = 0.45 * weight;  // 35 % above its share
    ids.push_back(world.add_attachment(a));
  }
  for (int i = 0; i < 200; ++i) ASSERT_TRUE(world.step(1e-3).ok);
  double carried = 0.0;
  for (auto i : ids) {
    EXPECT_TRUE(world.attachment_intact(i));
    carried += world.attachment_force(i);
  }
  EXPECT_NEAR(carried, weight, 0.01 * weight) << "force estimate from the constraint multipliers";

  // Double gravity: each attachment must now carry 2/3 of the weight, past its strength.
  Environment heavy = env;
  heavy.gravity_mm_s2 *= 2.0;
  ASSERT_TRUE(world.set_environment(heavy));
  int broken = 0;
  for (int i = 0; i < 50; ++i) broken += static_cast<int>(world.step(1e-3).attachments_broken);
  EXPECT_EQ(broken, 3);
  for (auto i : ids) EXPECT_FALSE(world.attachment_intact(i));
}

TEST(SolverBehaviour, TheRetinaNeverLeavesTheGlobe) {
  RetinaCapOptions o = small_retina();
  o.environment.intraocular_pressure_pa = units::mmhg_to_pa(60.0);  // far above normal
  o.detachment_pressure_pa = o.environment.intraocular_pressure_pa + 2000.0;
  auto scene = build_retina_cap(o);
  for (int i = 0; i < 300; ++i) {
    ASSERT_TRUE(scene.world.step(1e-3).ok);
    const Surface& s = scene.world.surface(scene.retina);
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      ASSERT_GE(scene.world.wall().clearance(s.position(v)), -1e-9) << "vertex " << v << " step " << i;
    }
  }
  // The detachment force really lifted the retina off the wall somewhere.
  const Surface& s = scene.world.surface(scene.retina);
  double lift = 0.0;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) lift = std::max(lift, scene.world.wall().clearance(s.position(v)));
  EXPECT_GT(lift, 0.5);
}

TEST(SolverBehaviour, ADetachmentComesToRest) {
  // A bullous detachment held by the retina's tension is a static equilibrium: once it has
  // inflated, nothing may keep moving. (The rim where it meets the attached retina used to flip
  // on and off the wall every step at ~5 mm/s, so the detachment never slept.) Every vertex is
  // simulated (no sleeping), and the speed is real displacement over one step, which a vertex
  // flipping between two places cannot hide.
  RetinaCapOptions o = small_retina();
  o.solver.sleeping = false;
  auto scene = build_retina_cap(o);
  for (int i = 0; i < 1500; ++i) ASSERT_TRUE(scene.world.step(1e-3).ok);
  const Surface& s = scene.world.surface(scene.retina);
  std::vector<Vec3> before(s.vertex_slots());
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) before[v] = s.position(v);
  ASSERT_TRUE(scene.world.step(1e-3).ok);
  double fastest = 0.0, lift = 0.0;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
    if (!s.vertex_alive(v)) continue;
    fastest = std::max(fastest, (s.position(v) - before[v]).norm() / 1e-3);
    lift = std::max(lift, scene.world.wall().clearance(s.position(v)));
  }
  EXPECT_GT(lift, 0.5) << "the detachment force lifted the retina";
  EXPECT_LT(fastest, scene.world.settings().sleep_speed_mm_s) << "mm/s: resting tissue still moves";
}

TEST(SolverBehaviour, TheSameInputsGiveTheSameBits) {
  auto run = [](double detachment_pa) {
    RetinaCapOptions o = small_retina();
    o.detachment_pressure_pa = detachment_pa;
    o.membrane = true;
    auto scene = build_retina_cap(o);
    for (int i = 0; i < 300; ++i) {
      if (i == 150) {
        EXPECT_TRUE(scene.world.set_local_force_scale(scene.detachment_force, 0.5));
      }
      EXPECT_TRUE(scene.world.step(1e-3).ok);
    }
    return scene.world.state_hash();
  };
  const auto a = run(3000.0), b = run(3000.0), c = run(3000.0000001);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c) << "the hash must see a change in the inputs";
}

TEST(SolverBehaviour, MassIsConservedThroughTears) {
  RetinaCapOptions o = small_retina();
  o.retina.tear_strain = 0.1;  // fragile, so the detachment tears it
  o.detachment_pressure_pa = 9000.0;
  auto scene = build_retina_cap(o);
  const double m0 = scene.world.total_mass();
  std::uint32_t tears = 0;
  for (int i = 0; i < 400; ++i) {
    const auto r = scene.world.step(1e-3);
    ASSERT_TRUE(r.ok);
    tears += r.tears;
  }
  EXPECT_GT(tears, 0u);
  // Exact: what the tears' cleanup removed as lone sliver fragments is reported (clean_topology.hpp).
  EXPECT_NEAR(scene.world.total_mass(), m0 - scene.world.cleanup_removed_mass_g(), 1e-12 * m0);
  const auto report = check_surface(scene.world.surface(scene.retina));
  EXPECT_TRUE(report.ok()) << report.summary();
}

TEST(SolverBehaviour, StableAtOneMillisecondAcrossTheDocumentedStiffnessRange) {
  for (double modulus : {0.0, 1.0, 1e2, 1e4, 1e5}) {
    RetinaCapOptions o = small_retina();
    o.retina.membrane_modulus_pa_mm = modulus;
    o.retina.tear_strain = INFINITY;
    auto scene = build_retina_cap(o);
    double vmax = 0.0;
    for (int i = 0; i < 300; ++i) {
      ASSERT_TRUE(scene.world.step(1e-3).ok) << "modulus " << modulus;
      const Surface& s = scene.world.surface(scene.retina);
      for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) vmax = std::max(vmax, s.velocity(v).norm());
    }
    // Nothing in an eye moves at 1 m/s; an instability quickly would.
    EXPECT_LT(vmax, 1e3) << "modulus " << modulus;
    // Released, the tissue comes to rest.
    ASSERT_TRUE(scene.world.set_local_force_scale(scene.detachment_force, 0.0));
    for (int i = 0; i < 1500; ++i) ASSERT_TRUE(scene.world.step(1e-3).ok);
    // Released, it comes to rest: rms speed below 1 mm/s (stiff membranes keep a faint flutter
    // of a few µm where the direction term meets the wall; see project_springs).
    const double rms = std::sqrt(2.0 * scene.world.energy().kinetic / scene.world.total_mass());
    EXPECT_LT(rms, 1.0) << "modulus " << modulus;
  }
}

TEST(SolverBehaviour, RestingTissueSleepsAndWakesWhenPulled) {
  // An attached retina with no detachment comes to rest and sleeps; moving the optic-disc anchors
  // wakes the tissue around them, and the result matches a run without sleeping.
  struct Outcome {
    std::uint32_t awake_before = 0, awake_during = 0;
    Vec3 start = Vec3::Zero(), end = Vec3::Zero();
  };
  auto run = [](bool sleeping) {
    RetinaCapOptions o = small_retina();
    o.detachment = false;
    o.solver.sleeping = sleeping;
    auto scene = build_retina_cap(o);
    for (int i = 0; i < 600; ++i) EXPECT_TRUE(scene.world.step(1e-3).ok);
    Outcome out;
    out.awake_before = scene.world.awake_blocks();
    Surface& s = scene.world.surface(scene.retina);
    // The free vertex nearest the disc's anchored rim: the tissue the pull reaches first.
    Vec3 disc = Vec3::Zero();
    int anchors = 0;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.is_fixed(v) && s.position(v).z() < -10.0) {
        disc += s.position(v);
        ++anchors;
      }
    }
    disc /= anchors;
    std::uint32_t watched = 0;
    double best = 1e9;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      const double d = (s.position(v) - disc).norm();
      if (!s.is_fixed(v) && d < best) {
        best = d;
        watched = v;
      }
    }
    out.start = s.position(watched);
    // Lift the disc anchors 0.3 mm toward the centre over 0.3 s (a jump would tear the retina
    // around them), then let it settle.
    for (int i = 0; i < 300; ++i) {
      for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
        if (s.is_fixed(v) && s.position(v).z() < -10.0) {
          EXPECT_TRUE(s.set_fixed_position(s.vertex_id(v), s.position(v) * (1.0 - 0.001 / 12.0)));
        }
      }
      EXPECT_TRUE(scene.world.step(1e-3).ok);
      out.awake_during = std::max(out.awake_during, scene.world.awake_blocks());
    }
    for (int i = 0; i < 200; ++i) EXPECT_TRUE(scene.world.step(1e-3).ok);
    out.end = s.position(watched);
    return out;
  };
  const Outcome sleeping = run(true);
  const Outcome reference = run(false);
  const std::uint32_t blocks = (static_cast<std::uint32_t>(small_retina().retina_vertices) + Surface::kSleepBlock - 1) / Surface::kSleepBlock;
  EXPECT_LE(sleeping.awake_before, blocks / 20) << "a retina at rest on the choroid should (almost all) sleep";
  EXPECT_GT(sleeping.awake_during, sleeping.awake_before) << "pulling the anchors must wake the tissue around them";
  // Intraocular pressure holds the attached retina on the wall (the wall takes the pressure only
  // as far as the springs leave it to), so the lift stretches the tissue by the disc more than it
  // lifts it: ~0.02 mm of motion at the retina's nominal stiffness, and sleeping must reproduce it
  // to a third of that.
  const double moved = (reference.end - reference.start).norm();
  EXPECT_GT(moved, 0.015) << "the pull moved the tissue next to the disc";
  EXPECT_LT((sleeping.end - reference.end).norm(), moved / 3.0) << "sleeping must not change the outcome";
}

TEST(SolverBehaviour, TinyTrianglesStayStable) {
  // A sliver triangle 1e-4 of the others' size next to normal ones, with a stiff material.
  SurfaceDescription d;
  d.mesh = test::rectangle(2.0, 2.0, 4, 4);
  const std::uint32_t n = static_cast<std::uint32_t>(d.mesh.positions.size());
  d.mesh.positions.emplace_back(2.0 + 1e-3, 2.0 - 5e-4, 0.0);  // hangs off the corner (4,4)=24 and (4,3)=19
  d.mesh.triangles.push_back({19, n, 24});
  d.material.membrane_modulus_pa_mm = 1e5;
  d.contained_by_globe = false;
  TissueWorld world(far_wall());
  Surface& s = world.surface(world.add_surface(d));
  ASSERT_TRUE(s.set_fixed(s.vertex_id(0), true));
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(world.step(1e-3).ok);
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) EXPECT_LT(s.velocity(v).norm(), 1e3);
}

TEST(SolverBehaviour, BadStepInputIsRefusedAndChangesNothing) {
  auto scene = build_retina_cap(small_retina());
  const auto h = scene.world.state_hash();
  for (double dt : {0.0, -1e-3, std::nan(""), double{INFINITY}, 0.5}) {
    const auto r = scene.world.step(dt);
    EXPECT_FALSE(r.ok) << dt;
    EXPECT_NE(r.error.find("dt"), std::string::npos);
  }
  EXPECT_EQ(scene.world.state_hash(), h);
  EXPECT_FALSE(scene.world.set_local_force_scale(scene.detachment_force, std::nan("")));
  EXPECT_FALSE(scene.world.set_local_force_scale(scene.detachment_force, 2.0));
  EXPECT_FALSE(scene.world.set_local_force_scale(99, 0.5));
  Environment env;
  env.intraocular_pressure_pa = std::nan("");
  EXPECT_FALSE(scene.world.set_environment(env));
  EXPECT_EQ(scene.world.state_hash(), h);
}

TEST(SolverBehaviour, AStepThatWouldGoNonFiniteIsRolledBack) {
  auto scene = build_retina_cap(small_retina());
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(scene.world.step(1e-3).ok);
  Surface& s = scene.world.surface(scene.retina);
  // A finite but absurd position (a corrupted device value that got through) overflows a spring.
  std::uint32_t v = 0;
  while (s.is_fixed(v)) ++v;
  ASSERT_TRUE(s.set_position(s.vertex_id(v), Vec3(1e300, -1e300, 1e300)));
  const auto before = scene.world.state_hash();
  const auto r = scene.world.step(1e-3);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("rolled back"), std::string::npos);
  EXPECT_EQ(scene.world.state_hash(), before);
  ASSERT_FALSE(scene.world.events().empty());
  EXPECT_EQ(scene.world.events().back().kind, TissueEventKind::kRolledBack);
  // Restoring the vertex lets the simulation carry on.
  ASSERT_TRUE(s.set_position(s.vertex_id(v), s.rest_position(v)));
  EXPECT_TRUE(scene.world.step(1e-3).ok);
}

TEST(SolverBehaviour, PlasticityKeepsAReleasedMembraneNearWhereItWasLeft) {
  auto run = [](double plastic_rate) -> double {
    SurfaceDescription d;
    d.mesh = test::rectangle(4.0, 4.0, 8, 8);
    d.material.plastic_rate_per_s = plastic_rate;
    d.material.tear_strain = INFINITY;
    // In a thin fluid (1/20 of vitreous' drag, no entrained mass), so that bending alone returns
    // the elastic sheet within the test's seconds: a 4 mm cantilever relaxes with τ ≈ c L⁴ /
    // (3.5² D) ≈ 0.7 s here, ~14 s in vitreous.
    d.material.drag_pa_s_per_mm = 1.0;
    d.material.entrained_fluid_mm = 0.0;
    d.contained_by_globe = false;
    Environment env;
    env.gravity_mm_s2 = Vec3::Zero();
    env.apply_pressure = false;
    TissueWorld world(far_wall(), env);
    Surface& s = world.surface(world.add_surface(d));
    // Clamped (two columns held, so the sheet cannot simply hinge about its edge: a rigid turn
    // stores no energy and would stay).
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.rest_position(v).x() <= 0.5 + 1e-9) {
        EXPECT_TRUE(s.set_fixed(s.vertex_id(v), true));
      }
    }
    const std::uint32_t grip = 4 * 9 + 8;  // middle of the free edge (row 4, column 8)
    EXPECT_TRUE(s.set_fixed(s.vertex_id(grip), true));
    // Lift the free edge's middle 2 mm out of plane over 1 s, hold 1 s, release, wait 3 s.
    bool ok = true;
    for (int i = 0; i < 1000; ++i) {
      ok &= s.set_fixed_position(s.vertex_id(grip), s.rest_position(grip) + Vec3(0, 0, 2.0 * (i + 1) / 1000)).is_ok();
      ok &= world.step(1e-3).ok;
    }
    for (int i = 0; i < 1000; ++i) ok &= world.step(1e-3).ok;
    ok &= s.set_fixed(s.vertex_id(grip), false).is_ok();
    for (int i = 0; i < 3000; ++i) ok &= world.step(1e-3).ok;
    EXPECT_TRUE(ok);
    return s.position(grip).z();
  };
  const double elastic = run(0.0), plastic = run(5.0);
  EXPECT_LT(elastic, 0.3) << "without plasticity the membrane springs back";
  EXPECT_GT(plastic, 1.0) << "with plasticity it stays roughly where it was left";
}

namespace {

// Two triangles 1 mm on a side, the lower one fixed at z = 0, the upper one free above it at
// `start_gap_mm`, joined corner to corner by stalks of `stalk_mm` (k = 1000 µN/mm); no gravity, no
// pressure; the globe's centre 100 mm up, so "inward" is +z (within 0.6°). The upper triangle is
// pulled up by a local force of `pull_un` in all.
struct StalkedLayers {
  TissueWorld world{GlobeWall::sphere(Vec3(0, 0, 100), 101), [] {
                      Environment env;
                      env.gravity_mm_s2 = Vec3::Zero();
                      env.apply_pressure = false;
                      return env;
                    }()};
  std::uint32_t lower = 0, upper = 0;
  std::vector<std::uint32_t> stalks;
  static constexpr double kStiffness = 1000.0;

  StalkedLayers(double start_gap_mm, double stalk_mm, double pull_un) {
    SurfaceDescription d;
    d.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    d.mesh.triangles = {{0, 1, 2}};
    d.contained_by_globe = false;
    lower = world.add_surface(d);
    for (auto& p : d.mesh.positions) p.z() = start_gap_mm;
    upper = world.add_surface(d);
    Surface& l = world.surface(lower);
    for (std::uint32_t v = 0; v < 3; ++v) EXPECT_TRUE(l.set_fixed(l.vertex_id(v), true));
    for (std::uint32_t v = 0; v < 3; ++v) {
      AttachmentDescription a;
      a.surface_a = upper;
      a.vertex_a = v;
      a.surface_b = lower;
      a.vertex_b = v;
      a.stiffness_un_per_mm = kStiffness;
      a.rest_length_mm = stalk_mm;
      stalks.push_back(world.add_attachment(a));
    }
    if (pull_un > 0.0) {
      LocalForceDescription f;
      f.name = "pull";
      f.surface = upper;
      f.vertices = {0, 1, 2};
      f.toward_point_mm = Vec3(1.0 / 3.0, 1.0 / 3.0, 1e9);
      f.pressure_pa = pull_un / 0.5;  // over the triangle's 0.5 mm²: µN / mm² = Pa
      world.add_local_force(f);
    }
  }
  double gap(std::uint32_t v) const { return world.surface(upper).position(v).z() - world.surface(lower).position(v).z(); }
};

}  // namespace

TEST(SolverBehaviour, AStalkHoldsTwoLayersApartAtItsLengthAndStretchesByHookesLaw) {
  // Started compressed (0.2 mm on 0.5 mm stalks), the upper layer is pushed back out to the stalks'
  // length; pulled by 300 µN, each of the three stalks carries 100 µN and stretches F/k = 0.1 mm.
  StalkedLayers free_layers(0.2, 0.5, 0.0);
  for (int i = 0; i < 2000; ++i) ASSERT_TRUE(free_layers.world.step(1e-3).ok);
  for (std::uint32_t v = 0; v < 3; ++v) EXPECT_NEAR(free_layers.gap(v), 0.5, 1e-3) << "corner " << v;

  // A stalk resists shear as a coincident attachment does: the upper layer pushed 0.2 mm sideways
  // comes back over its base.
  Surface& up = free_layers.world.surface(free_layers.upper);
  for (std::uint32_t v = 0; v < 3; ++v) ASSERT_TRUE(up.set_position(up.vertex_id(v), up.position(v) + Vec3(0.2, 0, 0)));
  for (int i = 0; i < 2000; ++i) ASSERT_TRUE(free_layers.world.step(1e-3).ok);
  for (std::uint32_t v = 0; v < 3; ++v) {
    const Vec3 d = up.position(v) - free_layers.world.surface(free_layers.lower).position(v);
    // Over its base up to the stalk's lean toward the globe's centre (0.5 mm × 1/100 at corner 1).
    EXPECT_LT(std::abs(d.x()), 0.01) << "corner " << v;
    EXPECT_LT(std::abs(d.y()), 0.01) << "corner " << v;
  }

  StalkedLayers pulled(0.5, 0.5, 300.0);
  for (int i = 0; i < 3000; ++i) ASSERT_TRUE(pulled.world.step(1e-3).ok);
  for (std::uint32_t v = 0; v < 3; ++v) {
    EXPECT_NEAR(pulled.gap(v), 0.5 + 100.0 / StalkedLayers::kStiffness, 2e-3) << "corner " << v;
    EXPECT_NEAR(pulled.world.attachment_force(pulled.stalks[v]), 100.0, 2.0) << "corner " << v;
  }
}

// Tissue taken away under an attachment (the vitrector removing a membrane's triangles) lets the
// attachment go where it stood: the event is placed at its base, which is still there (it used to
// be placed at the origin, and the debrief drew those at the centre of the eye).
TEST(SolverBehaviour, AnAttachmentWhoseTissueIsRemovedBreaksWhereItStood) {
  StalkedLayers layers(0.5, 0.5, 0.0);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(layers.world.step(1e-3).ok);
  Surface& up = layers.world.surface(layers.upper);
  ASSERT_TRUE(up.remove_triangle(up.triangle_id(0)).status);
  ASSERT_EQ(up.vertex_count(), 0u);
  const StepReport r = layers.world.step(1e-3);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.attachments_broken, 3u);
  const Surface& low = layers.world.surface(layers.lower);
  std::size_t seen = 0;
  for (const TissueEvent& e : layers.world.events()) {
    if (e.kind != TissueEventKind::kAttachmentBroken) continue;
    const auto it = std::find(layers.stalks.begin(), layers.stalks.end(), e.item);
    ASSERT_NE(it, layers.stalks.end());
    const auto corner = static_cast<std::uint32_t>(it - layers.stalks.begin());  // added corner by corner
    EXPECT_LT((e.position_mm - low.position(corner)).norm(), 1e-12) << "stalk " << corner;
    ++seen;
  }
  EXPECT_EQ(seen, 3u);
}

TEST(SolverBehaviour, ACutSeversTheStalksInItsReachAndNothingElse) {
  StalkedLayers layers(0.5, 0.5, 0.0);
  // A coincident attachment (a membrane lying on the retina) at corner 0 beside the stalk.
  AttachmentDescription coincident;
  coincident.surface_a = layers.upper;
  coincident.vertex_a = 0;
  coincident.surface_b = layers.lower;
  coincident.vertex_b = 1;  // any vertex: it is the rest length that makes a stalk
  coincident.stiffness_un_per_mm = 1.0;
  const std::uint32_t flat = layers.world.add_attachment(coincident);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(layers.world.step(1e-3).ok);

  // A hemisphere of 0.3 mm about a point 0.1 mm beside corner 0's stalk, at its mid-height, facing
  // it: the stalk's midpoint (0, 0, 0.25) is inside; corners 1 and 2 are 1 mm away.
  EXPECT_EQ(layers.world.cut_attachments_in({-0.1, 0.0, 0.25}, {1, 0, 0}, 0.3), 1u);
  // Facing away, the same point reaches nothing; a second call does not count the cut one again.
  EXPECT_EQ(layers.world.cut_attachments_in({0.1, 0.0, 0.25}, {1, 0, 0}, 0.3), 0u);
  EXPECT_EQ(layers.world.cut_attachments_in({-0.1, 0.0, 0.25}, {1, 0, 0}, 0.3), 0u);
  EXPECT_TRUE(layers.world.attachment_intact(layers.stalks[0])) << "it breaks at the step boundary";

  const StepReport r = layers.world.step(1e-3);
  ASSERT_TRUE(r.ok);
  EXPECT_EQ(r.attachments_broken, 1u);
  EXPECT_FALSE(layers.world.attachment_holds(layers.stalks[0]));
  EXPECT_TRUE(layers.world.attachment_holds(layers.stalks[1]));
  EXPECT_TRUE(layers.world.attachment_holds(layers.stalks[2]));
  EXPECT_TRUE(layers.world.attachment_holds(flat)) << "a coincident attachment goes only with its tissue";

  // Refused: a stalk to a world point, a negative length.
  AttachmentDescription bad;
  bad.surface_a = layers.upper;
  bad.vertex_a = 1;
  bad.rest_length_mm = 0.5;
  EXPECT_THROW(layers.world.add_attachment(bad), InvalidArgument);
  bad.surface_b = layers.lower;
  bad.rest_length_mm = -0.1;
  EXPECT_THROW(layers.world.add_attachment(bad), InvalidArgument);
}

// The vertex sweep's layout is kept from step to step while a surface's topology and awake region
// stand, and only its values refreshed: the result must be the bits of a world that lays it out
// afresh every step — through a breathing detachment (blocks waking and sleeping), torn springs, a
// spring's rest length changed in place and a snapshot restored midway — and the layout must really
// have been kept most of the time.
TEST(SolverBehaviour, KeepingTheSweepLayoutGivesTheBitsOfLayingItOutEveryStep) {
  RetinaCapScene kept = build_retina_cap(small_retina()), fresh = build_retina_cap(small_retina());
  fresh.world.set_relayout_every_step(true);
  std::vector<std::uint8_t> midway;
  for (int i = 0; i < 300; ++i) {
    const double scale = 0.9 + 0.1 * std::sin(2.0 * 3.141592653589793 * 1e-3 * i);
    for (RetinaCapScene* w : {&kept, &fresh}) {
      ASSERT_TRUE(w->world.set_local_force_scale(w->detachment_force, scale));
      if (i % 100 == 50) {  // a topology change: tear the interior spring of the lowest index
        Surface& s = w->world.surface(w->retina);
        std::uint32_t e = 0;
        while (e < s.edge_slots() && !(s.edge_alive(e) && s.edge_triangles(e)[1] != kNone)) ++e;
        ASSERT_LT(e, s.edge_slots());
        const std::uint64_t before = s.topology_version();
        (void)s.tear_edge(s.edge_id(e));
        ASSERT_GT(s.topology_version(), before);
      }
      if (i % 100 == 80) {  // a rest length changed in place (as creep and traction do): same layout, new values
        Surface& s = w->world.surface(w->retina);
        // A spring the sweep has packed: both ends awake, one of them free to move.
        const auto packed = [&](std::uint32_t e) {
          const auto [a, b] = s.edge_vertices(e);
          return s.edge_alive(e) && s.vertex_awake(a) && s.vertex_awake(b) && (s.inverse_mass(a) > 0.0 || s.inverse_mass(b) > 0.0);
        };
        std::uint32_t e = 0;
        while (e < s.edge_slots() && !packed(e)) ++e;
        ASSERT_LT(e, s.edge_slots());
        const std::uint64_t awake_before = s.awake_version(), values_before = s.spring_values_version();
        ASSERT_TRUE(s.set_edge_traction(s.edge_id(e), 0.9));
        ASSERT_EQ(s.awake_version(), awake_before) << "the layout stands";
        ASSERT_GT(s.spring_values_version(), values_before);
      }
      if (i == 150) {  // a snapshot taken and restored: the layout is laid out again after it
        encode_snapshot(w->world, "midway", midway);
        ASSERT_TRUE(decode_snapshot(w->world, midway));
      }
      ASSERT_TRUE(w->world.step(1e-3).ok);
    }
    ASSERT_EQ(kept.world.state_hash(), fresh.world.state_hash()) << "step " << i;
  }
  EXPECT_EQ(fresh.world.layouts_kept(), 0u);
  EXPECT_GT(kept.world.layouts_kept(), 200u) << "the layout was kept on most of the 300 steps";
}
