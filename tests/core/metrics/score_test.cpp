// The score formulas: bounded, monotonic in the right direction for every input, and the
// categories the LCM score_t type names.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "core/metrics/score_card.hpp"

namespace vitreo::core {
namespace {

SessionTotals ordinary() {
  SessionTotals t;
  t.elapsed_s = 120.0;
  t.steps = 120000;
  t.path_length_mm = 180.0;
  t.retina_contacts = 4;
  t.retina_contact_time_s = 3.0;
  t.peak_retina_force_un = 900.0;
  t.retina_force_impulse_un_s = 1200.0;
  t.force_limit_un = 3000.0;
  t.illumination_measured = true;
  t.working_time_s = 100.0;
  t.lit_working_time_s = 80.0;
  return t;
}

std::vector<CriterionProgress> half_done() {
  std::vector<CriterionProgress> c(3);
  c[0].kind = CriterionKind::kMembraneReleased;
  c[0].progress = 0.5;
  c[1].kind = CriterionKind::kPathCut;
  c[1].progress = 0.25;
  c[2].kind = CriterionKind::kTimeLimit;
  c[2].progress = 0.0;  // a time limit never counts toward achievement
  return c;
}

double category(const SessionTotals& t, const char* name, const std::vector<CriterionProgress>& c = half_done()) {
  ScoreCard card;
  compute_scores(t, c, 600.0, ScoreOptions{}, card);
  const ScoreEntry* e = card.find(name);
  EXPECT_NE(e, nullptr) << name;
  return e ? e->value : -1.0;
}

TEST(Scores, CategoriesAreTheLcmNamesAndBounded) {
  ScoreCard card;
  compute_scores(ordinary(), half_done(), 600.0, ScoreOptions{}, card);
  std::vector<std::string> names;
  for (const auto& e : card.categories) {
    names.emplace_back(e.name);
    EXPECT_GE(e.value, 0.0);
    EXPECT_LE(e.value, 100.0);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"target_achievement", "efficiency", "tissue_treatment", "instrument_handling"}));
  // Mean progress of the two goals (the time limit excluded).
  EXPECT_NEAR(card.find("target_achievement")->value, 37.5, 1e-12);
  // The total is the weighted mean of the categories: between the smallest and the largest.
  double lo = 100.0, hi = 0.0;
  for (const auto& e : card.categories) {
    lo = std::min(lo, e.value);
    hi = std::max(hi, e.value);
  }
  EXPECT_GE(card.total, lo);
  EXPECT_LE(card.total, hi);
}

TEST(Scores, MoreDamageLowersTissueTreatment) {
  using Bump = std::function<void(SessionTotals&, int)>;
  const std::vector<std::pair<const char*, Bump>> damages = {
      {"time over limit", [](SessionTotals& t, int k) { t.time_over_force_limit_s += 0.2 * k; }},
      {"impulse", [](SessionTotals& t, int k) { t.retina_force_impulse_un_s += 5000.0 * k; }},
      {"peak", [](SessionTotals& t, int k) { t.peak_retina_force_un += 800.0 * k; }},
      {"retina tears", [](SessionTotals& t, int k) { t.retina_tears += static_cast<std::uint32_t>(k); }},
      {"lens touches", [](SessionTotals& t, int k) { t.events[static_cast<std::size_t>(InstrumentEventKind::kLensTouch)] += static_cast<std::uint32_t>(k); }},
      {"stray burns", [](SessionTotals& t, int k) { t.burns_elsewhere += static_cast<std::uint32_t>(k); }},
      {"light toxicity", [](SessionTotals& t, int k) { t.events[static_cast<std::size_t>(InstrumentEventKind::kLightToxicity)] += static_cast<std::uint32_t>(k); }},
  };
  for (const auto& [what, bump] : damages) {
    double last = category(ordinary(), "tissue_treatment");
    for (int k = 1; k <= 50; k *= 2) {
      SessionTotals t = ordinary();
      bump(t, k);
      const double now = category(t, "tissue_treatment");
      EXPECT_LT(now, last) << what << " ×" << k;
      EXPECT_GE(now, 0.0);
      last = now;
    }
  }
  SessionTotals t = ordinary();
  t.events[static_cast<std::size_t>(InstrumentEventKind::kLensTouch)] = 2;
  t.events[static_cast<std::size_t>(InstrumentEventKind::kUnintendedTear)] = 1;
  t.events[static_cast<std::size_t>(InstrumentEventKind::kGrasp)] = 5;  // not harm
  EXPECT_EQ(t.iatrogenic_events(), 3u);
  // Nothing but ordinary contact costs little; no contact at all is the full score of the work
  // done: care is earned in proportion to progress (half_done: P = 0.375).
  SessionTotals clean = ordinary();
  clean.peak_retina_force_un = clean.retina_force_impulse_un_s = 0.0;
  EXPECT_DOUBLE_EQ(category(clean, "tissue_treatment"), 37.5);
  std::vector<CriterionProgress> done = half_done();
  done[0].progress = done[1].progress = 1.0;
  EXPECT_DOUBLE_EQ(category(clean, "tissue_treatment", done), 100.0);
}

// A hand that does nothing earns nothing: no progress, no care, no efficiency — whatever it did not
// damage. (Before the care categories were scaled by progress an idle run scored 77.)
TEST(Scores, NoProgressScoresZeroInEveryCategory) {
  SessionTotals idle;
  idle.elapsed_s = 10.0;
  idle.steps = 10000;
  std::vector<CriterionProgress> none = half_done();
  none[0].progress = none[1].progress = 0.0;
  ScoreCard card;
  compute_scores(idle, none, 600.0, ScoreOptions{}, card);
  for (const auto& e : card.categories) EXPECT_EQ(e.value, 0.0) << e.name;
  EXPECT_EQ(card.total, 0.0);
  // Equal progress: the one with a retinal tear scores lower in tissue treatment and in total.
  std::vector<CriterionProgress> some = half_done();
  SessionTotals careful = ordinary(), careless = ordinary();
  careless.retina_tears = 1;
  ScoreCard a, b;
  compute_scores(careful, some, 600.0, ScoreOptions{}, a);
  compute_scores(careless, some, 600.0, ScoreOptions{}, b);
  EXPECT_GT(a.find("tissue_treatment")->value, b.find("tissue_treatment")->value);
  EXPECT_GT(a.total, b.total);
}

TEST(Scores, LongerPathsAndTimesLowerEfficiencyProgressRaisesIt) {
  double last = category(ordinary(), "efficiency");
  for (double extra : {10.0, 100.0, 1000.0, 1e5}) {
    SessionTotals t = ordinary();
    t.path_length_mm += extra;
    const double now = category(t, "efficiency");
    EXPECT_LT(now, last) << extra;
    EXPECT_GT(now, 0.0);
    last = now;
  }
  last = category(ordinary(), "efficiency");
  for (double extra : {1.0, 60.0, 600.0, 1e5}) {
    SessionTotals t = ordinary();
    t.elapsed_s += extra;
    const double now = category(t, "efficiency");
    EXPECT_LT(now, last) << extra;
    last = now;
  }
  // The same resources for more of the task are more efficient; none of it, no efficiency.
  auto more = half_done();
  more[0].progress = 1.0;
  EXPECT_GT(category(ordinary(), "efficiency", more), category(ordinary(), "efficiency"));
  auto none = half_done();
  none[0].progress = none[1].progress = 0.0;
  EXPECT_EQ(category(ordinary(), "efficiency", none), 0.0);
}

TEST(Scores, ClumsinessAndWorkingInTheDarkLowerInstrumentHandling) {
  const double base = category(ordinary(), "instrument_handling");
  SessionTotals t = ordinary();
  t.events[static_cast<std::size_t>(InstrumentEventKind::kInstrumentCollision)] = 3;
  EXPECT_LT(category(t, "instrument_handling"), base);
  t = ordinary();
  t.retina_contacts += 10;
  EXPECT_LT(category(t, "instrument_handling"), base);
  t = ordinary();
  t.lit_working_time_s = 20.0;
  EXPECT_LT(category(t, "instrument_handling"), base);
  // Without a light pipe the light is not judged.
  t.illumination_measured = false;
  EXPECT_GT(category(t, "instrument_handling"), base);
}

SessionTotals watched() {
  SessionTotals t = ordinary();
  t.microscope_measured = true;
  t.microscope_working_time_s = 100.0;
  t.out_of_field_s = 10.0;
  t.off_centre_s = 20.0;
  t.out_of_focus_s = 5.0;
  t.extreme_zoom_s = 0.0;
  return t;
}

// Microscope handling (README: Scores), worked by hand: shares of the 100 s working time out of the
// field 0.1, mean min(r,1)² 0.2, out of focus 0.05 → 2·0.1 + 0.5·0.2 + 1·0.05 = 0.35 e-folds, times
// the progress 0.375.
TEST(Scores, MicroscopeHandlingJudgesTheWorkInTheFieldAndInFocus) {
  EXPECT_NEAR(category(watched(), "microscope_handling"), 37.5 * std::exp(-0.35), 1e-9);
  ScoreCard card;
  compute_scores(watched(), half_done(), 600.0, ScoreOptions{}, card);
  ASSERT_EQ(card.categories.size(), 5u);
  EXPECT_STREQ(card.categories.back().name, "microscope_handling");
  double sum = 0.0, weights = 0.0;
  for (const auto& e : card.categories) {
    sum += e.weight * e.value;
    weights += e.weight;
  }
  EXPECT_NEAR(weights, 0.4 + 0.2 + 0.25 + 0.15 + 0.1, 1e-12);
  EXPECT_NEAR(card.total, sum / weights, 1e-9);

  // Every input strictly lowers it: each of the four kinds of time.
  const double base = category(watched(), "microscope_handling");
  for (double SessionTotals::*field : {&SessionTotals::out_of_field_s, &SessionTotals::off_centre_s, &SessionTotals::out_of_focus_s,
                                       &SessionTotals::extreme_zoom_s}) {
    SessionTotals t = watched();
    t.*field += 1.0;
    EXPECT_LT(category(t, "microscope_handling"), base);
  }
  // Out of the field for the whole working time: at most e⁻² of the progress.
  SessionTotals lost = watched();
  lost.out_of_field_s = lost.off_centre_s = 100.0;
  lost.out_of_focus_s = 0.0;
  EXPECT_NEAR(category(lost, "microscope_handling"), 37.5 * std::exp(-2.5), 1e-9);
  // Earned by the work: no progress, no score, however well the field was held.
  auto none = half_done();
  none[0].progress = none[1].progress = 0.0;
  SessionTotals perfect = watched();
  perfect.out_of_field_s = perfect.off_centre_s = perfect.out_of_focus_s = 0.0;
  EXPECT_EQ(category(perfect, "microscope_handling", none), 0.0);
  EXPECT_NEAR(category(perfect, "microscope_handling"), 37.5, 1e-12);
  // No microscope watched: the category is not scored at all.
  compute_scores(ordinary(), half_done(), 600.0, ScoreOptions{}, card);
  EXPECT_EQ(card.find("microscope_handling"), nullptr);
}

TEST(Scores, BadOptionsAreRefused) {
  ScoreOptions o;
  o.per_retina_tear = -1.0;
  EXPECT_THROW(o.validate(), InvalidArgument);
  o = ScoreOptions{};
  o.weight_target = o.weight_efficiency = o.weight_tissue = o.weight_instrument = o.weight_microscope = 0.0;
  EXPECT_THROW(o.validate(), InvalidArgument);
  o = ScoreOptions{};
  o.per_out_of_field = -0.5;
  EXPECT_THROW(o.validate(), InvalidArgument);
  o = ScoreOptions{};
  o.reference_path_mm = std::nan("");
  EXPECT_THROW(o.validate(), InvalidArgument);
  EXPECT_NO_THROW(ScoreOptions{}.validate());
}

}  // namespace
}  // namespace vitreo::core
