#include "core/metrics/score_card.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::core {

namespace {

// Credit for a cost x against the cost x_half that earns half: 1 at zero, ½ at x_half, falling
// smoothly and strictly, never below 0 (so every extra second or millimetre costs something, and
// there is no cliff at a threshold).
double half_credit(double x, double x_half) { return 1.0 / (1.0 + std::max(0.0, x) / x_half); }

double bounded(double score) { return std::clamp(score, 0.0, 100.0); }

}  // namespace

void ScoreOptions::validate() const {
  const double all[] = {weight_target,       weight_efficiency,   weight_tissue,        weight_instrument,
                        per_second_over_limit, per_limit_second,  per_peak_squared,     per_excessive_force,
                        per_retina_tear,     per_lens_touch,      per_wall_contact,     per_light_toxicity,
                        per_light_too_close, per_burn_on_detached, per_burn_off_target, per_instrument_collision,
                        per_retinal_contact, per_grasp_lost,      weight_microscope,    per_out_of_field,
                        per_off_centre,      per_out_of_focus,    per_extreme_zoom};
  for (double v : all) require_range(v, 0.0, 1e6, "scores: weights and penalties");
  require_range(illumination_share, 0.0, 1.0, "scores: illumination_share");
  require_range(reference_time_s, 1e-3, 1e6, "scores: reference_time_s");
  require_range(reference_path_mm, 1e-3, 1e7, "scores: reference_path_mm");
  if (!(weight_target + weight_efficiency + weight_tissue + weight_instrument + weight_microscope > 0.0)) {
    throw InvalidArgument("scores: all category weights are zero");
  }
}

std::uint32_t SessionTotals::iatrogenic_events() const {
  using K = InstrumentEventKind;
  std::uint32_t n = 0;
  for (K k : {K::kExcessiveRetinaForce, K::kUnintendedTear, K::kLaserOnDetachedRetina, K::kLightTooClose, K::kLightToxicity,
              K::kInstrumentCollision, K::kLensTouch, K::kWallContact}) {
    n += count(k);
  }
  return n;
}

const ScoreEntry* ScoreCard::find(std::string_view name) const {
  for (const auto& c : categories) {
    if (name == c.name) return &c;
  }
  return nullptr;
}

void compute_scores(const SessionTotals& t, const std::vector<CriterionProgress>& criteria, double time_limit_s,
                    const ScoreOptions& o, ScoreCard& card) {
  card.categories.clear();

  // Target achievement: the mean progress of the goals (the time limit is a constraint, scored
  // through efficiency).
  double progress = 0.0;
  int goals = 0;
  for (const auto& c : criteria) {
    if (c.kind == CriterionKind::kTimeLimit) continue;
    progress += c.progress;
    ++goals;
  }
  progress = goals ? progress / goals : 1.0;
  if (goals) card.categories.push_back({"target_achievement", bounded(100.0 * progress), o.weight_target});

  // Efficiency: resources per unit of progress, so idling or stopping early is not efficient.
  // Earned by the work like care below (× P): a hand that barely moves got half the path credit for
  // free however little it achieved.
  double efficiency = 0.0;
  if (progress > 0.0) {
    const double t_half = time_limit_s > 0.0 ? time_limit_s : o.reference_time_s;
    efficiency = 100.0 * progress *
                 (0.5 * half_credit(t.elapsed_s / progress, t_half) + 0.5 * half_credit(t.path_length_mm / progress, o.reference_path_mm));
  }
  card.categories.push_back({"efficiency", bounded(efficiency), o.weight_efficiency});

  // Tissue treatment: force on the retina and iatrogenic events, as e-folds of damage.
  const double limit = t.force_limit_un > 0.0 ? t.force_limit_un : 1.0;
  const double peak = t.peak_retina_force_un / limit;
  const double damage =
      o.per_second_over_limit * t.time_over_force_limit_s + o.per_limit_second * t.retina_force_impulse_un_s / limit +
      o.per_peak_squared * peak * peak + o.per_excessive_force * t.count(InstrumentEventKind::kExcessiveRetinaForce) +
      o.per_retina_tear * t.retina_tears + o.per_lens_touch * t.count(InstrumentEventKind::kLensTouch) +
      o.per_wall_contact * t.count(InstrumentEventKind::kWallContact) +
      o.per_light_toxicity * t.count(InstrumentEventKind::kLightToxicity) +
      o.per_light_too_close * t.count(InstrumentEventKind::kLightTooClose) +
      o.per_burn_on_detached * t.count(InstrumentEventKind::kLaserOnDetachedRetina) +
      o.per_burn_off_target * t.burns_elsewhere;
  // Care is earned by doing the work: the quality categories count in proportion to the progress
  // made, so a hand that never enters the eye scores no care (an idle run scored 77 before).
  card.categories.push_back({"tissue_treatment", bounded(100.0 * progress * std::exp(-damage)), o.weight_tissue});

  // Instrument handling: clumsiness as e-folds, and (with a light pipe) how much of the work was lit.
  const double clumsy = o.per_instrument_collision * t.count(InstrumentEventKind::kInstrumentCollision) +
                        o.per_retinal_contact * t.retina_contacts +
                        o.per_grasp_lost * t.count(InstrumentEventKind::kGraspLost);
  double handling = std::exp(-clumsy);
  if (t.illumination_measured && t.working_time_s > 0.0) {
    const double lit = std::clamp(t.lit_working_time_s / t.working_time_s, 0.0, 1.0);
    handling *= (1.0 - o.illumination_share) + o.illumination_share * lit;
  }
  card.categories.push_back({"instrument_handling", bounded(100.0 * progress * handling), o.weight_instrument});

  // Microscope handling (EyeSi's fifth category: the work centred in the field, in focus, at a
  // sensible zoom): shares of the working time as e-folds, earned by the work like care above. Only
  // the time a working tip was inside the eye is judged; none judged gives the factor 1.
  if (t.microscope_measured) {
    double view = 1.0;
    if (t.microscope_working_time_s > 0.0) {
      const double w = t.microscope_working_time_s;
      auto share = [w](double s) { return std::clamp(s / w, 0.0, 1.0); };
      view = std::exp(-(o.per_out_of_field * share(t.out_of_field_s) + o.per_off_centre * share(t.off_centre_s) +
                        o.per_out_of_focus * share(t.out_of_focus_s) + o.per_extreme_zoom * share(t.extreme_zoom_s)));
    }
    card.categories.push_back({"microscope_handling", bounded(100.0 * progress * view), o.weight_microscope});
  }

  double sum = 0.0, weights = 0.0;
  for (const auto& c : card.categories) {
    sum += c.weight * c.value;
    weights += c.weight;
  }
  card.total = weights > 0.0 ? bounded(sum / weights) : 0.0;
}

}  // namespace vitreo::core
