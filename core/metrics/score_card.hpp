#pragma once
// The session's scores, 0–100 per category and a weighted total, from what SessionMetrics
// accumulated and how far the case's criteria have got. Categories (names as in
// rig/telemetry/lcmtypes/score_t.lcm):
//   target_achievement   mean progress of the case's criteria (time limit excluded)
//   efficiency           simulated time and tip path per unit of progress, against half-score references
//   tissue_treatment     forces on the retina (time over the damage limit, impulse, peak) and
//                        iatrogenic events (tears, lens/wall touches, light toxicity, stray burns)
//   instrument_handling  instrument collisions, retinal touches, lost grasps, working tips in the light
//   microscope_handling  working tips in the microscope's field, near its centre, in focus, at a usable
//                        zoom (only when the metrics watch a microscope: SessionMetrics::watch_microscope)
// The formulas and their rationale: core/metrics/README.md.
#include <array>
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/instruments/instrument_system.hpp"
#include "core/metrics/case_progress.hpp"

namespace vitreo::core {

inline constexpr std::size_t kInstrumentEventKinds = static_cast<std::size_t>(InstrumentEventKind::kLaserBurn) + 1;

// What the scores are computed from (SessionMetrics fills it, step by step).
// The version of the formulas below and in compute_scores (README: Scores): raised whenever a
// formula, weight or reference changes, so a debrief says which formulas its numbers came from.
inline constexpr int kScoreFormulaVersion = 2;

struct SessionTotals {
  double elapsed_s = 0.0;
  std::uint64_t steps = 0;
  double path_length_mm = 0.0;               // all instrument tips, inside the eye
  std::uint32_t retina_contacts = 0;         // contact entries, all instruments
  double retina_contact_time_s = 0.0;        // instrument-seconds in contact
  double peak_retina_force_un = 0.0;
  double retina_force_impulse_un_s = 0.0;    // ∫ retina force dt, all instruments
  double time_over_force_limit_s = 0.0;      // instrument-seconds above the damage limit
  double force_limit_un = 0.0;               // the damage limit used
  std::array<std::uint32_t, kInstrumentEventKinds> events{};  // by InstrumentEventKind
  std::uint32_t burns_on_target = 0;         // within the target band of a laser-ring guide
  std::uint32_t burns_elsewhere = 0;
  std::uint32_t retina_tears = 0;            // tissue tear events on the retina
  std::uint32_t other_tears = 0;             // on gel and membranes
  bool illumination_measured = false;        // a light pipe is among the instruments
  double working_time_s = 0.0;               // instrument-seconds of non-light instruments inside
  double lit_working_time_s = 0.0;           // ... with the tip inside the light cone
  // Microscope handling, when the metrics watch the microscope: instrument-seconds of the working
  // (non-light) instruments' tips at work inside the eye (MetricsOptions::work_clearance_mm), and
  // of those the time out of the field of view,
  // ∫ c² dt, c = (min(r, 1) − r₀) / (1 − r₀) beyond r₀ = MetricsOptions::centre_radius, else 0 (r: the
  // tip's distance from the field's centre over the field's radius), the
  // time out of the depth of field and the time at an extreme zoom (MetricsOptions::extreme_zoom).
  bool microscope_measured = false;
  double microscope_working_time_s = 0.0;
  double out_of_field_s = 0.0;
  double off_centre_s = 0.0;
  double out_of_focus_s = 0.0;
  double extreme_zoom_s = 0.0;

  std::uint32_t count(InstrumentEventKind k) const { return events[static_cast<std::size_t>(k)]; }
  // Events that harm the eye or show loss of control: excessive retina force, unintended tears,
  // laser on detached retina, light too close / toxic, instrument collisions, lens and wall touches.
  std::uint32_t iatrogenic_events() const;
};

// Reference values and weights. The defaults are chosen, not calibrated: they make one serious
// iatrogenic event cost about a third of a category (one e-fold) and are to be fitted to recorded
// expert and novice sessions (README: validation).
struct ScoreOptions {
  double weight_target = 0.4;
  double weight_efficiency = 0.2;
  double weight_tissue = 0.25;
  double weight_instrument = 0.15;
  double weight_microscope = 0.1;

  // Efficiency: time / path per unit of progress at which that half of the category gives half credit.
  double reference_time_s = 300.0;   // used when the case has no time limit (else the limit)
  double reference_path_mm = 250.0;

  // Tissue treatment: penalties in e-folds (category = 100 · exp(−Σ)).
  double per_second_over_limit = 2.0;
  double per_limit_second = 0.1;      // per F_limit · 1 s of retina force impulse
  double per_peak_squared = 0.5;      // × (peak / F_limit)²
  double per_excessive_force = 0.5;   // per entry above the limit
  double per_retina_tear = 1.0;
  double per_lens_touch = 1.0;
  double per_wall_contact = 0.3;
  double per_light_toxicity = 1.0;
  double per_light_too_close = 0.2;
  double per_burn_on_detached = 0.2;
  double per_burn_off_target = 0.1;

  // Instrument handling: penalties in e-folds, and the share of the category that illumination
  // (working tips inside the light cone) decides when it is measured.
  double per_instrument_collision = 0.3;
  double per_retinal_contact = 0.05;
  double per_grasp_lost = 0.2;
  double illumination_share = 0.5;

  // Microscope handling: e-folds for the whole working time spent out of the field, at the field's
  // edge (∫ c² dt over the working time, SessionTotals::off_centre_s), out of focus and at an extreme zoom.
  double per_out_of_field = 2.0;
  double per_off_centre = 0.5;
  double per_out_of_focus = 1.0;
  double per_extreme_zoom = 1.0;

  void validate() const;  // throws InvalidArgument (negative or non-finite values, all weights 0)
};

struct ScoreEntry {
  const char* name = "";
  double value = 0.0;   // 0..100
  double weight = 0.0;  // in the total
};

struct ScoreCard {
  std::vector<ScoreEntry> categories;  // only the measurable ones, in a fixed order
  double total = 0.0;                  // weighted mean of the categories, 0..100
  const ScoreEntry* find(std::string_view name) const;
};

// Fills card (no allocation once it has room for five categories). time_limit_s: the case's limit,
// 0 when it has none.
void compute_scores(const SessionTotals& totals, const std::vector<CriterionProgress>& criteria, double time_limit_s,
                    const ScoreOptions& options, ScoreCard& card);

}  // namespace vitreo::core
