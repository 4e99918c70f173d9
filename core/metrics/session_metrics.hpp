#pragma once
// Session metrics: observes a running case once per physics step and keeps what a debriefing (and
// the rig's score_t telemetry channel) needs — the tip path inside the eye ("odometer"), retinal
// contacts and the force on the retina, iatrogenic events, laser spots on and off target, tears —
// and, on demand, the case's criteria and the scores (case_progress.hpp, score_card.hpp).
//
//   core::Scene scene = core::build_scene(description);
//   core::Simulation sim(scene.world, options, tools);
//   core::SessionMetrics metrics(scene, &sim);
//   sim.set_observer(&metrics);            // the step's last stage observes (or call observe(dt))
//   loop: sim.set_input(...); sim.step(dt);
//   metrics.criteria(), metrics.score()   // at a lower rate (each scans the world)
//
// Like the rest of core: no clock (dt is given), no allocation in observe() after construction,
// the same observations give the same numbers bit for bit.
#include <cstdint>
#include <vector>

#include "core/common/status.hpp"
#include "core/sim/simulation.hpp"
#include "core/metrics/case_progress.hpp"
#include "core/metrics/score_card.hpp"
#include "core/scene/microscope.hpp"
#include "core/scene/scene_builder.hpp"

namespace vitreo::core {

struct MetricsOptions {
  // An instrument touches the retina while the retina's contact force on it exceeds this (µN).
  double contact_force_un = 1.0;
  // Every this many observed steps the metrics check whether the case is over: every criterion met
  // (complete) or its time limit passed. From then on the score stands: nothing more is counted,
  // criteria() and score() return what they were at that step (EyeSi ends a module the same way).
  std::uint32_t completion_check_steps = 100;
  // The odometer counts the tip's path in strides of at least this (mm): above sensor jitter.
  double odometer_stride_mm = 0.05;
  // Force above which the retina is damaged (µN); ≤ 0: the instruments' retina_force_limit_un.
  double retina_force_limit_un = 0.0;
  // A burn counts as on target within this distance (along the wall) of a laser-ring guide.
  double laser_target_band_mm = 0.5;
  // Microscope handling: a zoom above this is extreme while working (24× total at the default 4×
  // at zoom 1, the top of an ophthalmic microscope's range: a field of about 2.4 mm on the fundus
  // in the contact-lens view, which a working tip keeps leaving).
  double extreme_zoom = 6.0;
  // A working tip is at work — and judged in the microscope's view — while it acts on tissue
  // (holds it, touches the retina, aspirates, fires) or is within this of the retina (mm from the wall,
  // behind the ora serrata): not while it travels from its port through the periphery to the work.
  double work_clearance_mm = 2.0;
  // The work is centred while within this share of the field's radius; beyond it, off centre
  // counts up to 1 at the edge (see SessionTotals::off_centre_s).
  double centre_radius = 0.5;
  ProgressOptions progress;
  ScoreOptions scores;
  void validate() const;  // throws InvalidArgument
};

struct InstrumentMetrics {
  InstrumentKind kind = InstrumentKind::kLightPipe;
  double path_length_mm = 0.0;            // tip path while inside the eye (eye frame)
  std::uint32_t retina_contacts = 0;      // entries into contact
  double retina_contact_time_s = 0.0;
  double peak_retina_force_un = 0.0;
  double retina_force_impulse_un_s = 0.0;
  double time_over_force_limit_s = 0.0;
  bool touching_retina = false;           // now
};

// What the microscope showed of the work at the last observed step (the instructor's overlay):
// the working tip farthest off the field's centre and the one farthest from the focal plane.
struct MicroscopeGlance {
  bool judged = false;            // a working tip was inside the eye
  double field_radius = 0.0;      // largest: 0 centre, 1 the field's edge
  double defocus_mm = 0.0;        // largest |distance from the focal plane|
  double depth_of_field_mm = 0.0; // total
};

class SessionMetrics final : public StepObserver {
 public:
  // From a built scene; sim may be null (tissue-only metrics). The metrics keep references to the
  // world and the simulation: both must outlive them. Throws InvalidArgument on bad options or
  // criteria that name what the case lacks.
  SessionMetrics(const Scene& scene, const Simulation* sim, MetricsOptions options = {});
  // From a world built another way (core/anatomy/retina_cap), described by hand.
  SessionMetrics(const TissueWorld& world, MetricsCase c, const Simulation* sim, MetricsOptions options = {});

  // The microscope whose view the working tips are judged in (microscope_handling), on this eye;
  // both must outlive the metrics (or be replaced). Without one that category is not scored. Call
  // before the first observe(), or the time before it goes unjudged.
  void watch_microscope(const Microscope* microscope, const EyeModel* eye);

  // Once after each physics step (Simulation::step or TissueWorld::step) of dt_s seconds.
  // Refuses (changing nothing) a dt that is not finite and in (0, 0.02], and a second call without a
  // world step in between (it would count the step's events twice).
  Status observe(double dt_s);
  // The simulation's last stage, when registered with Simulation::set_observer.
  void after_step(double dt_s) override { (void)observe(dt_s); }

  const SessionTotals& totals() const { return totals_; }
  const MicroscopeGlance& microscope_glance() const { return glance_; }
  const InstrumentMetrics& instrument(std::uint32_t i) const { return per_instrument_.at(i); }
  std::uint32_t instrument_count() const { return static_cast<std::uint32_t>(per_instrument_.size()); }
  TissueProgress tissue() const { return progress_.tissue(world_); }

  // The case's criteria measured now (scans the world; no allocation).
  const std::vector<CriterionProgress>& criteria();
  // All criteria except the time limit met (false when the case has none).
  bool complete();
  // Criteria, then the scores (no allocation).
  const ScoreCard& score();
  // What the last score() / criteria() found, without measuring again (the picture shows these).
  const ScoreCard& last_score() const { return card_; }
  // The case is over (see MetricsOptions::completion_check_steps): completed, or out of time.
  bool finished() const { return finished_; }
  bool completed() const { return completed_; }
  double finished_at_s() const { return finished_at_s_; }
  const CaseProgress& progress() const { return progress_; }

 private:
  void accumulate(double dt);
  // A working tip at work (MetricsOptions::work_clearance_mm); needs the watched eye.
  bool at_work(const InstrumentState& st) const;

  const TissueWorld& world_;
  const Simulation* sim_;
  const Microscope* microscope_ = nullptr;
  const EyeModel* eye_ = nullptr;
  MicroscopeGlance glance_;
  MetricsOptions options_;
  CaseProgress progress_;
  SessionTotals totals_;
  std::vector<InstrumentMetrics> per_instrument_;
  std::vector<Vec3> last_tip_;
  std::vector<std::uint8_t> was_inside_;
  std::size_t burns_seen_ = 0;
  std::uint64_t last_world_step_ = 0;
  double time_limit_s_ = 0.0;
  ScoreCard card_;
  std::uint32_t steps_since_check_ = 0;
  bool finished_ = false, completed_ = false;
  double finished_at_s_ = 0.0;
};

}  // namespace vitreo::core
