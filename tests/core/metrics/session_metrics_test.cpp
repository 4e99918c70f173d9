// SessionMetrics on scripted instruments: the odometer against the analytic length of the path,
// retinal contacts against the script's known contact phases, refusals, determinism.
#include <gtest/gtest.h>

#include <random>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <tuple>
#include <vector>

#include "alloc_counter.hpp"
#include "core/metrics/session_metrics.hpp"
#include "test_meshes.hpp"

namespace vitreo::core {
namespace {

constexpr double kDt = 1e-3;
constexpr double kPi = std::numbers::pi;
const Vec3 kPort(0.0, 0.0, 10.0);

SurfaceDescription sheet(double size, int cells, double z) {
  SurfaceDescription d;
  d.mesh = test::rectangle(size, size, cells, cells);
  for (auto& p : d.mesh.positions) p += Vec3(-size / 2, -size / 2, z);
  d.contained_by_globe = false;
  d.material.membrane_modulus_pa_mm = 1e4;  // the stiffest shipped material (membrane.toml: ERM)
  d.material.tear_strain = INFINITY;
  return d;
}

// A flat "retina" (a sheet anchored at its border) under a port, and one blunt instrument.
struct Bench {
  TissueWorld world;
  std::uint32_t retina = 0;
  std::unique_ptr<Simulation> instruments;

  explicit Bench(InstrumentKind kind = InstrumentKind::kDrainageNeedle, double sheet_z = 0.0)
      : world(GlobeWall::sphere(Vec3::Zero(), 12.0), no_pressure(), no_sleep()) {
    retina = world.add_surface(sheet(4.0, 16, sheet_z));
    Surface& s = world.surface(retina);
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      const Vec3 p = s.rest_position(v);
      if (std::abs(std::abs(p.x()) - 2.0) < 1e-9 || std::abs(std::abs(p.y()) - 2.0) < 1e-9) {
        EXPECT_TRUE(s.set_fixed(s.vertex_id(v), true));
      }
    }
    InstrumentSceneOptions o;
    o.ports_mm = {kPort};
    o.retina_surface = retina;
    instruments = std::make_unique<Simulation>(world, o, std::vector<InstrumentDescription>{{kind, Gauge::k23, 0, {}}});
    // The rig's measured eye rotation: none, so the eye frame is the fixture frame exactly.
    instruments->set_eye_fixture_rotation(Quat::Identity());
  }
  MetricsCase metrics_case() const {
    MetricsCase c;
    c.retina = retina;
    return c;
  }
  static Environment no_pressure() {
    Environment e;
    e.apply_pressure = false;
    return e;
  }
  static SolverSettings no_sleep() {
    SolverSettings s;
    s.sleeping = false;
    return s;
  }
  // Tip at p, the shaft through the port.
  void step_at(const Vec3& p, bool present = true) {
    InstrumentInput in;
    in.tip_fixture_mm = p;
    in.axis_fixture = (p - kPort).normalized();
    in.present = present;
    ASSERT_TRUE(instruments->set_input(0, in));
    instruments->step(kDt);
  }
};

void step_and_observe(Bench& b, SessionMetrics& m, const Vec3& p, bool present = true) {
  b.step_at(p, present);
  ASSERT_TRUE(m.observe(kDt));
}

TEST(SessionMetrics, OdometerMeasuresTheTipPathOfACircleAndNothingOutsideTheEye) {
  Bench b(InstrumentKind::kPick, -11.0);
  SessionMetrics m(b.world, b.metrics_case(), b.instruments.get());
  const double r = 3.0;
  const int n = 200;  // 0.094 mm a step: above the odometer's 0.05 mm stride, so every step counts
  const Vec3 c(0.0, 0.0, 2.0);
  const auto on_circle = [&](int k) { return Vec3(c + r * Vec3(std::cos(2 * kPi * k / n), std::sin(2 * kPi * k / n), 0.0)); };
  for (int k = 0; k <= n; ++k) step_and_observe(b, m, on_circle(k));
  ASSERT_TRUE(b.instruments->instrument(0).inside);
  // An inscribed n-gon: 2·n·r·sin(π/n), within r·π³/(3n²) of the circle's 2πr.
  const double polygon = 2.0 * n * r * std::sin(kPi / n);
  EXPECT_NEAR(m.instrument(0).path_length_mm, polygon, 1e-9);
  EXPECT_NEAR(m.totals().path_length_mm, 2 * kPi * r, 1.01 * r * kPi * kPi * kPi / (3.0 * n * n));

  // Out of the eye (not tracked), moved far away, back in at the start: the jumps are not path.
  step_and_observe(b, m, Vec3(5.0, 5.0, 30.0), false);
  EXPECT_FALSE(b.instruments->instrument(0).inside);
  step_and_observe(b, m, Vec3(0.0, 0.0, 20.0), false);
  for (int k = 0; k <= n; ++k) step_and_observe(b, m, on_circle(k));
  EXPECT_NEAR(m.totals().path_length_mm, 2.0 * polygon, 1e-9);
  EXPECT_EQ(m.totals().steps, static_cast<std::uint64_t>(2 * (n + 1) + 2));
  EXPECT_NEAR(m.totals().elapsed_s, (2 * (n + 1) + 2) * kDt, 1e-12);
  EXPECT_EQ(m.totals().retina_contacts, 0u);  // the sheet lies far below the circle
}

// A hand held still with a tracker's jitter (5 µm, 1 σ, each step) travels nothing; 1000 steps of
// it used to add up to several millimetres.
TEST(SessionMetrics, OdometerIgnoresSensorJitter) {
  Bench b(InstrumentKind::kPick, -11.0);
  SessionMetrics m(b.world, b.metrics_case(), b.instruments.get());
  std::mt19937_64 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.005);
  const Vec3 c(0.0, 0.0, 2.0);
  for (int k = 0; k < 1000; ++k) step_and_observe(b, m, Vec3(c + Vec3(jitter(rng), jitter(rng), jitter(rng))));
  ASSERT_TRUE(b.instruments->instrument(0).inside);
  EXPECT_LT(m.totals().path_length_mm, 0.05);
  // and a real 2 mm move after it counts within one stride
  for (int k = 1; k <= 100; ++k) step_and_observe(b, m, Vec3(c + Vec3(0.02 * k, 0.0, 0.0)));
  EXPECT_NEAR(m.totals().path_length_mm, 2.0, 0.1);
}

// Presses the sheet twice, held `first` and `second` steps at depth `depth` below its rest surface,
// apart. The tip comes down from 1 mm above and goes back up at `speed_mm_s`, a quick surgeon's
// move: a tip that jumps onto the sheet in one step flings it off (it comes back and is touched
// again), and one lifted slower than the sheet springs back is caught up and bounced on — each a
// second contact in this undamped bench (core/tissue/MEASUREMENTS.md, 2026-11-28 eighteenth
// session: 20 mm/s gave two contacts 0–0.5 mm off the centre, a jump or 5–10 mm/s 3–9).
struct ContactScript {
  int first = 200, second = 120;
  int third = 0;  // a third press of this many steps when > 0
  double depth = 0.3;
  double speed_mm_s = 20.0;
  // The tip's height at each step.
  std::vector<double> heights() const {
    std::vector<double> z;
    const double step = speed_mm_s * kDt;
    const auto press = [&](int hold) {
      for (double h = 1.0 - step; h > -depth; h -= step) z.push_back(h);
      z.insert(z.end(), hold, -depth);
      for (double h = -depth + step; h < 1.0; h += step) z.push_back(h);
      z.insert(z.end(), 100, 1.0);
    };
    z.assign(50, 1.0);
    press(first);
    press(second);
    if (third > 0) press(third);
    return z;
  }
};

// Steps at which the tip's end (radius r) is below the sheet's rest surface (z = 0): the longest
// the presses can touch.
int steps_below_rest_surface(const std::vector<double>& heights, double tip_radius_mm) {
  return static_cast<int>(std::count_if(heights.begin(), heights.end(), [&](double h) { return h - tip_radius_mm < 0.0; }));
}

void run_contacts(Bench& b, SessionMetrics& m, const ContactScript& s, double* impulse = nullptr, double* peak = nullptr) {
  double sum = 0.0, max = 0.0;
  for (const double z : s.heights()) {
    step_and_observe(b, m, Vec3(0.0, 0.0, z));
    sum += b.instruments->instrument(0).retina_force_un * kDt;
    max = std::max(max, b.instruments->instrument(0).retina_force_un);
  }
  if (impulse) *impulse = sum;
  if (peak) *peak = max;
}

TEST(SessionMetrics, ScriptedContactsGiveTheirCountAndDuration) {
  Bench b;
  MetricsOptions o;
  o.retina_force_limit_un = 1e9;  // no damage in this test
  SessionMetrics m(b.world, b.metrics_case(), b.instruments.get(), o);
  double impulse = 0.0, peak = 0.0;
  const ContactScript s;
  run_contacts(b, m, s, &impulse, &peak);
  EXPECT_EQ(m.totals().retina_contacts, 2u);
  // Each contact lasts at least as long as the script holds the tip down, and at most while the
  // tip's end is below the sheet's rest surface (the sheet, pushed down, springs back after it).
  const int below = steps_below_rest_surface(s.heights(), shaft_radius_mm(Gauge::k23));
  EXPECT_GE(m.totals().retina_contact_time_s, (s.first + s.second) * kDt - 1e-12);
  EXPECT_LE(m.totals().retina_contact_time_s, below * kDt + 1e-12);
  EXPECT_EQ(m.instrument(0).retina_contacts, 2u);
  EXPECT_GT(peak, 10.0);
  EXPECT_DOUBLE_EQ(m.totals().peak_retina_force_un, peak);
  EXPECT_NEAR(m.totals().retina_force_impulse_un_s, impulse, 1e-9 * impulse);
  EXPECT_EQ(m.totals().time_over_force_limit_s, 0.0);
  EXPECT_FALSE(m.instrument(0).touching_retina);
}

TEST(SessionMetrics, TimeAboveTheDamageLimitIsCounted) {
  // A limit below the force of a held press (the sheet's tension on the tip, about 1000 µN here):
  // the time above it is at least the time the script holds the tip down and at most the contact
  // time; the script's force trace, counted here, is the exact reference.
  Bench b;
  MetricsOptions o;
  o.retina_force_limit_un = 300.0;
  SessionMetrics m(b.world, b.metrics_case(), b.instruments.get(), o);
  const ContactScript s;
  int over = 0;
  for (const double z : s.heights()) {
    step_and_observe(b, m, Vec3(0.0, 0.0, z));
    if (b.instruments->instrument(0).retina_force_un > o.retina_force_limit_un) ++over;
  }
  EXPECT_NEAR(m.totals().time_over_force_limit_s, over * kDt, 1e-12);  // summed step by step
  EXPECT_GE(m.totals().time_over_force_limit_s, (s.first + s.second) * kDt);
  EXPECT_LE(m.totals().time_over_force_limit_s, m.totals().retina_contact_time_s + 1e-12);  // both sums of the same steps
  EXPECT_EQ(m.totals().force_limit_un, 300.0);
  // With the instruments' own limit (3000 µN) the same press made slowly (5 mm/s down, held, back
  // up) never damages the sheet.
  const Vec3 down(0.0, 0.0, -s.depth);
  Bench b2;
  SessionMetrics m2(b2.world, b2.metrics_case(), b2.instruments.get());
  double held = 0.0;
  for (int i = 0; i <= 260; ++i) step_and_observe(b2, m2, Vec3(0.0, 0.0, 1.0 - 0.005 * i));
  for (int i = 0; i < s.first; ++i) {
    step_and_observe(b2, m2, down);
    held = b2.instruments->instrument(0).retina_force_un;
  }
  for (int i = 260; i >= 0; --i) step_and_observe(b2, m2, Vec3(0.0, 0.0, 1.0 - 0.005 * i));
  EXPECT_GT(held, o.retina_force_limit_un) << "the held press must be a real load";
  EXPECT_EQ(m2.totals().force_limit_un, b2.instruments->options().retina_force_limit_un);
  EXPECT_EQ(m2.totals().time_over_force_limit_s, 0.0);
  EXPECT_EQ(m2.totals().count(InstrumentEventKind::kExcessiveRetinaForce), 0u);
}

TEST(SessionMetrics, RefusesBadDtAndASecondObserveOfTheSameStep) {
  Bench b;
  SessionMetrics m(b.world, b.metrics_case(), b.instruments.get());
  // Before any step there is nothing to observe.
  EXPECT_FALSE(m.observe(kDt));
  b.step_at(Vec3(0, 0, 1));
  EXPECT_FALSE(m.observe(0.0));
  EXPECT_FALSE(m.observe(-kDt));
  EXPECT_FALSE(m.observe(std::nan("")));
  EXPECT_FALSE(m.observe(0.5));
  EXPECT_EQ(m.totals().steps, 0u);
  EXPECT_TRUE(m.observe(kDt));
  EXPECT_FALSE(m.observe(kDt));
  EXPECT_EQ(m.totals().steps, 1u);
  EXPECT_DOUBLE_EQ(m.totals().elapsed_s, kDt);
  MetricsOptions bad;
  bad.contact_force_un = -1.0;
  EXPECT_THROW(SessionMetrics(b.world, b.metrics_case(), b.instruments.get(), bad), InvalidArgument);
  MetricsCase wrong = b.metrics_case();
  wrong.criteria.push_back({CriterionKind::kMembraneRemoved, "none", 0.5});
  EXPECT_THROW(SessionMetrics(b.world, wrong, b.instruments.get()), InvalidArgument);
}

TEST(SessionMetrics, ObserveCriteriaAndScoreDoNotAllocate) {
  Bench b;
  MetricsCase c = b.metrics_case();
  c.criteria = {{CriterionKind::kRetinaFlat, "", 0.3}, {CriterionKind::kTimeLimit, "", 10.0}};
  SessionMetrics m(b.world, c, b.instruments.get());
  (void)m.score();
  // The counter itself counts.
  test::AllocationCounter::counting = true;
  std::vector<double>* probe = new std::vector<double>(8);
  test::AllocationCounter::counting = false;
  delete probe;
  ASSERT_EQ(test::AllocationCounter::allocations, 2);
  test::AllocationCounter::allocations = 0;
  ContactScript presses;  // three presses of 50 steps
  presses.first = presses.second = presses.third = 50;
  const std::vector<double> heights = presses.heights();
  for (const double z : heights) {
    b.step_at(Vec3(0.0, 0.0, z));
    test::AllocationCounter::counting = true;
    const Status st = m.observe(kDt);
    const ScoreCard& card = m.score();
    test::AllocationCounter::counting = false;
    ASSERT_TRUE(st);
    ASSERT_EQ(card.categories.size(), 4u);
  }
  EXPECT_EQ(test::AllocationCounter::allocations, 0);
  EXPECT_EQ(m.totals().retina_contacts, 3u);
}

TEST(SessionMetrics, SameSessionSameNumbers) {
  const auto run = [] {
    Bench b;
    SessionMetrics m(b.world, b.metrics_case(), b.instruments.get());
    run_contacts(b, m, ContactScript{});
    const SessionTotals t = m.totals();
    const ScoreCard s = m.score();
    return std::make_tuple(t, s, b.world.state_hash());
  };
  const auto [ta, sa, ha] = run();
  const auto [tb, sb, hb] = run();
  EXPECT_EQ(ha, hb);
  EXPECT_EQ(ta.path_length_mm, tb.path_length_mm);
  EXPECT_EQ(ta.retina_force_impulse_un_s, tb.retina_force_impulse_un_s);
  EXPECT_EQ(ta.peak_retina_force_un, tb.peak_retina_force_un);
  EXPECT_EQ(ta.retina_contact_time_s, tb.retina_contact_time_s);
  EXPECT_EQ(ta.events, tb.events);
  ASSERT_EQ(sa.categories.size(), sb.categories.size());
  for (std::size_t i = 0; i < sa.categories.size(); ++i) EXPECT_EQ(sa.categories[i].value, sb.categories[i].value);
  EXPECT_EQ(sa.total, sb.total);
}

TEST(SessionMetrics, PressingLongerLowersTissueTreatmentAndLongerPathsLowerEfficiency) {
  const auto session = [](int press_steps, int circles) {
    Bench b;
    SessionMetrics m(b.world, b.metrics_case(), b.instruments.get());
    ContactScript s;
    s.first = s.second = press_steps;
    run_contacts(b, m, s);
    for (int c = 0; c < circles; ++c) {
      for (int k = 0; k <= 200; ++k) {
        step_and_observe(b, m, Vec3(1.5 * std::cos(2 * kPi * k / 200), 1.5 * std::sin(2 * kPi * k / 200), 2.0));
      }
    }
    return m.score();
  };
  const ScoreCard gentle = session(100, 1), rough = session(600, 1), wandering = session(100, 3);
  const auto value = [](const ScoreCard& c, const char* name) {
    const ScoreEntry* e = c.find(name);
    EXPECT_NE(e, nullptr) << name;
    return e ? e->value : -1.0;
  };
  EXPECT_LT(value(rough, "tissue_treatment"), value(gentle, "tissue_treatment"));
  EXPECT_LT(value(wandering, "efficiency"), value(gentle, "efficiency"));
  EXPECT_EQ(value(wandering, "tissue_treatment"), value(gentle, "tissue_treatment"));
  for (const ScoreCard* c : {&gentle, &rough, &wandering}) {
    for (const auto& e : c->categories) {
      EXPECT_GE(e.value, 0.0);
      EXPECT_LE(e.value, 100.0);
    }
    // No criteria: nothing to achieve, so no target_achievement; no microscope watched, no microscope score.
    EXPECT_EQ(c->find("target_achievement"), nullptr);
    EXPECT_EQ(c->find("microscope_handling"), nullptr);
  }
}

// Microscope handling on a scripted tip: the view centred on the posterior pole of a (small) eye
// model, at zoom 2, looks down −z from just behind its lens, so where a tip lies in the field and in
// the depth of field follows from its position by hand (field half-angle tan 20° / 2; Berek's depth
// of field 1.336 · (0.44 + 1.7) = 2.859 mm, microscope_test.cpp). A tip is judged while at work:
// near the retina (within 2 mm), or acting (here: the flute needle aspirating). Phases, 1 mm above
// the retina unless said: 100 steps at 0.4 field radii (centred: within half the radius); 100 at
// 0.75 (off centre (0.75 − 0.5) / 0.5 = 0.5, squared 0.25); 200 at 1.5 (out of the field, in
// focus); 100 steps on the axis 3 mm above the retina aspirating (in the field, out of focus); 100
// steps there not aspirating (travelling: not judged); 50 steps out of the eye.
TEST(SessionMetrics, MicroscopeHandlingTimesTheWorkOutOfTheFieldAndOutOfFocus) {
  EyeParameters p;
  p.retina_vertices = 500;
  p.gel_shells = 0;
  const EyeModel eye = build_eye_model(p);
  Microscope scope(MicroscopeSettings{}, Vec2::Zero());
  scope.set_zoom(2.0);
  for (int i = 0; i < 1000; ++i) scope.step(kDt, {});
  ASSERT_EQ(scope.zoom(), 2.0);
  const double eye_z = eye.lens_center_z_mm - 0.5 * p.lens_thickness_mm - 0.5;
  const double retina_z = -eye.wall.radius_toward(-Vec3::UnitZ()) + p.retina_thickness_mm;
  const double half_tan = std::tan(20.0 * kPi / 180.0) / 2.0;
  const double near_z = retina_z + 1.0, high_z = retina_z + 3.0;
  const auto at_radius = [&](double r) { return Vec3(r * half_tan * (eye_z - near_z), 0.0, near_z); };
  const Vec3 centre = at_radius(0.4), off = at_radius(0.75), aside = at_radius(1.5), high(0.0, 0.0, high_z);
  ASSERT_LE(eye.wall.clearance(aside), 2.0) << "the tip beside the field still works near the retina";
  ASSERT_GT(eye.wall.clearance(high), 2.0);

  Bench b(InstrumentKind::kDrainageNeedle, -11.5);  // the bench's sheet lies below the eye model's retina
  SessionMetrics m(b.world, b.metrics_case(), b.instruments.get());
  m.watch_microscope(&scope, &eye);
  const auto step = [&](const Vec3& at, double pedal, bool present = true) {
    InstrumentInput in;
    in.tip_fixture_mm = at;
    in.axis_fixture = (at - kPort).normalized();
    in.pedal = pedal;
    in.present = present;
    ASSERT_TRUE(b.instruments->set_input(0, in));
    b.instruments->step(kDt);
    ASSERT_TRUE(m.observe(kDt));
  };
  for (int k = 0; k < 100; ++k) step(centre, 0.0);
  EXPECT_TRUE(m.microscope_glance().judged);
  EXPECT_NEAR(m.microscope_glance().field_radius, 0.4, 1e-9);
  EXPECT_NEAR(m.microscope_glance().defocus_mm, 1.0, 1e-9);
  EXPECT_EQ(m.totals().off_centre_s, 0.0);
  for (int k = 0; k < 100; ++k) step(off, 0.0);
  for (int k = 0; k < 200; ++k) step(aside, 0.0);
  EXPECT_NEAR(m.microscope_glance().field_radius, 1.5, 1e-9);
  for (int k = 0; k < 100; ++k) step(high, 0.5);
  EXPECT_NEAR(m.microscope_glance().defocus_mm, 3.0, 1e-9);
  for (int k = 0; k < 100; ++k) step(high, 0.0);
  EXPECT_FALSE(m.microscope_glance().judged) << "travelling, not at work";
  for (int k = 0; k < 50; ++k) step(Vec3(0.0, 0.0, 20.0), 0.0, false);
  EXPECT_FALSE(m.microscope_glance().judged);

  const SessionTotals& t = m.totals();
  ASSERT_TRUE(t.microscope_measured);
  EXPECT_NEAR(t.microscope_working_time_s, 0.5, 1e-9);
  EXPECT_NEAR(t.out_of_field_s, 0.2, 1e-9);
  EXPECT_NEAR(t.off_centre_s, 0.1 * 0.25 + 0.2, 1e-9);
  EXPECT_NEAR(t.out_of_focus_s, 0.1, 1e-9);
  EXPECT_EQ(t.extreme_zoom_s, 0.0);
  // No criteria (P = 1): 100 · exp(−(2 · 0.4 + 0.5 · 0.45 + 1 · 0.2)).
  const ScoreEntry* e = m.score().find("microscope_handling");
  ASSERT_NE(e, nullptr);
  EXPECT_NEAR(e->value, 100.0 * std::exp(-1.225), 1e-9);
}

}  // namespace
}  // namespace vitreo::core
