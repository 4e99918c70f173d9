#include "core/metrics/session_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/common/validate.hpp"

namespace vitreo::core {

void MetricsOptions::validate() const {
  require_range(contact_force_un, 0.0, 1e6, "metrics: contact_force_un");
  require_range(retina_force_limit_un, -1e12, 1e12, "metrics: retina_force_limit_un");
  require_range(laser_target_band_mm, 0.0, 10.0, "metrics: laser_target_band_mm");
  require_range(odometer_stride_mm, 0.0, 1.0, "metrics: odometer_stride_mm");
  require_range(extreme_zoom, 1.0, 1e3, "metrics: extreme_zoom");
  require_range(work_clearance_mm, 0.0, 30.0, "metrics: work_clearance_mm");
  require_range(centre_radius, 0.0, 0.99, "metrics: centre_radius");
  require_range(static_cast<double>(completion_check_steps), 1.0, 1e6, "metrics: completion_check_steps");
  progress.validate();
  scores.validate();
}

SessionMetrics::SessionMetrics(const Scene& scene, const Simulation* sim, MetricsOptions options)
    : SessionMetrics(scene.world, MetricsCase::from_scene(scene), sim, std::move(options)) {}

SessionMetrics::SessionMetrics(const TissueWorld& world, MetricsCase c, const Simulation* sim,
                               MetricsOptions options)
    : world_(world),
      sim_(sim),
      options_((options.validate(), std::move(options))),
      progress_(world, std::move(c), options_.progress) {
  for (const auto& spec : progress_.description().criteria) {
    if (spec.kind == CriterionKind::kTimeLimit) time_limit_s_ = time_limit_s_ > 0.0 ? std::min(time_limit_s_, spec.threshold) : spec.threshold;
  }
  totals_.force_limit_un = options_.retina_force_limit_un;
  if (sim_) {
    if (!(totals_.force_limit_un > 0.0)) totals_.force_limit_un = sim_->options().retina_force_limit_un;
    const std::uint32_t n = sim_->instrument_count();
    per_instrument_.resize(n);
    last_tip_.assign(n, Vec3::Zero());
    was_inside_.assign(n, 0);
    for (std::uint32_t i = 0; i < n; ++i) {
      const InstrumentState& st = sim_->instrument(i);
      per_instrument_[i].kind = st.description.kind;
      last_tip_[i] = st.frame.tip;
      was_inside_[i] = st.inside ? 1 : 0;
      if (st.description.kind == InstrumentKind::kLightPipe) totals_.illumination_measured = true;
    }
    burns_seen_ = sim_->burns().size();
  }
  if (!(totals_.force_limit_un > 0.0)) totals_.force_limit_un = InstrumentSceneOptions{}.retina_force_limit_un;
  last_world_step_ = world_.step_count();
  card_.categories.reserve(5);
}

void SessionMetrics::watch_microscope(const Microscope* microscope, const EyeModel* eye) {
  microscope_ = microscope && eye ? microscope : nullptr;
  eye_ = microscope_ ? eye : nullptr;
  totals_.microscope_measured = microscope_ != nullptr;
}

Status SessionMetrics::observe(double dt) {
  if (!std::isfinite(dt) || !(dt > 0.0) || dt > 0.02) return Status::error("metrics: dt must be in (0, 0.02] s");
  const auto& world_events = world_.events();
  const bool rolled_back = std::any_of(world_events.begin(), world_events.end(),
                                       [](const TissueEvent& e) { return e.kind == TissueEventKind::kRolledBack; });
  if (world_.step_count() == last_world_step_ && !rolled_back) {
    return Status::error("metrics: no physics step since the last observe()");
  }
  last_world_step_ = world_.step_count();
  if (finished_) return Status::ok();  // the case is over: its score stands as it was
  accumulate(dt);
  if (++steps_since_check_ >= options_.completion_check_steps) {
    steps_since_check_ = 0;
    completed_ = complete();  // measures the criteria now
    if (completed_ || (time_limit_s_ > 0.0 && totals_.elapsed_s >= time_limit_s_)) {
      // The card as it stands now: criteria() and score() return it from here on.
      compute_scores(totals_, progress_.criteria(), time_limit_s_, options_.scores, card_);
      finished_ = true;
      finished_at_s_ = totals_.elapsed_s;
    }
  }
  return Status::ok();
}

void SessionMetrics::accumulate(double dt) {
  const auto& world_events = world_.events();
  totals_.elapsed_s += dt;
  ++totals_.steps;

  for (const TissueEvent& e : world_events) {
    if (e.kind != TissueEventKind::kTear) continue;
    if (e.surface == progress_.description().retina) {
      ++totals_.retina_tears;
    } else {
      ++totals_.other_tears;
    }
  }
  if (!sim_) return;

  const double limit = totals_.force_limit_un;
  const LightExposure& light = sim_->light();
  const double cos_cone = std::cos(light.half_angle_rad);
  // The microscope's view, worked out once this step, when a working tip is there to be judged.
  MicroscopeView view;
  bool have_view = false;
  glance_ = MicroscopeGlance{};
  for (std::uint32_t i = 0; i < per_instrument_.size(); ++i) {
    const InstrumentState& st = sim_->instrument(i);
    InstrumentMetrics& m = per_instrument_[i];
    // Odometer: only the path while the tip is inside the eye, counted in strides of at least
    // odometer_stride_mm from the last counted point — a tracker's jitter (5 µm at 1 kHz) would
    // otherwise add 5 mm a second to a hand held still; a real motion loses under a stride.
    if (st.inside && was_inside_[i]) {
      const double d = (st.frame.tip - last_tip_[i]).norm();
      if (d >= options_.odometer_stride_mm) {
        m.path_length_mm += d;
        totals_.path_length_mm += d;
        last_tip_[i] = st.frame.tip;
      }
    } else {
      last_tip_[i] = st.frame.tip;
    }
    was_inside_[i] = st.inside ? 1 : 0;
    // Navigation targets are reached by a working tip (the light pipe only lights them).
    if (st.inside && st.description.kind != InstrumentKind::kLightPipe) progress_.observe_tip(world_, st.frame.tip);

    const double f = st.retina_force_un;
    const bool touching = f > options_.contact_force_un;
    if (touching && !m.touching_retina) {
      ++m.retina_contacts;
      ++totals_.retina_contacts;
    }
    m.touching_retina = touching;
    if (touching) {
      m.retina_contact_time_s += dt;
      totals_.retina_contact_time_s += dt;
    }
    m.peak_retina_force_un = std::max(m.peak_retina_force_un, f);
    totals_.peak_retina_force_un = std::max(totals_.peak_retina_force_un, f);
    m.retina_force_impulse_un_s += f * dt;
    totals_.retina_force_impulse_un_s += f * dt;
    if (f > limit) {
      m.time_over_force_limit_s += dt;
      totals_.time_over_force_limit_s += dt;
    }

    // Illumination: a working tip (not the light pipe itself) inside the eye and inside the cone.
    if (totals_.illumination_measured && st.inside && st.description.kind != InstrumentKind::kLightPipe) {
      totals_.working_time_s += dt;
      if (light.active) {
        const Vec3 to = st.frame.tip - light.apex_mm;
        const double d = to.norm();
        if (d > 0.0 && to.dot(light.axis) >= cos_cone * d) totals_.lit_working_time_s += dt;
      }
    }

    // Microscope handling: a working tip at work is what the field should hold — in the field,
    // near its centre, within the depth of field, at a usable zoom.
    if (microscope_ && st.inside && st.description.kind != InstrumentKind::kLightPipe && at_work(st)) {
      if (!have_view) {
        view = microscope_->view(*eye_);
        have_view = true;
        glance_.judged = true;
        glance_.depth_of_field_mm = view.depth_of_field_mm;
      }
      const double r = view.field_radius(st.frame.tip);
      glance_.field_radius = std::max(glance_.field_radius, r);
      glance_.defocus_mm = std::max(glance_.defocus_mm, std::abs(view.defocus_mm(st.frame.tip)));
      totals_.microscope_working_time_s += dt;
      if (!(r <= 1.0)) totals_.out_of_field_s += dt;
      // Off centre: 0 within the central part of the field, rising as the square to 1 at its edge.
      const double c = std::max(0.0, std::min(r, 1.0) - options_.centre_radius) / (1.0 - options_.centre_radius);
      totals_.off_centre_s += c * c * dt;
      if (!view.in_focus(st.frame.tip)) totals_.out_of_focus_s += dt;
      if (microscope_->zoom() > options_.extreme_zoom) totals_.extreme_zoom_s += dt;
    }
  }

  for (const InstrumentEvent& e : sim_->events()) {
    const auto k = static_cast<std::size_t>(e.kind);
    if (k < totals_.events.size()) ++totals_.events[k];
  }
  const auto& burns = sim_->burns();
  for (; burns_seen_ < burns.size(); ++burns_seen_) {
    const BurnSpot& b = burns[burns_seen_];
    if (progress_.distance_to_laser_ring(b.position_mm) <= options_.laser_target_band_mm) {
      ++totals_.burns_on_target;
    } else {
      ++totals_.burns_elsewhere;
    }
  }
  return;
}

bool SessionMetrics::at_work(const InstrumentState& st) const {
  using K = InstrumentKind;
  const K k = st.description.kind;
  // Holding tissue or touching the retina (not brushing through the gel on the way).
  if (st.grip != kNone || st.retina_force_un > options_.contact_force_un) return true;
  if ((k == K::kVitrector || k == K::kDrainageNeedle) && st.input.pedal > 0.0) return true;      // aspirating, cutting
  if (k == K::kEndolaser && st.input.trigger) return true;                                      // firing
  // Near the retina: close to the wall behind the ora serrata (the ports lie in front of it, so
  // entering the eye is not work).
  const Vec3 from_centre = st.frame.tip - eye_->wall.center();
  const double polar = std::atan2(Vec2(from_centre.x(), from_centre.y()).norm(), -from_centre.z());
  return polar < eye_->ora_polar_rad && eye_->wall.clearance(st.frame.tip) <= options_.work_clearance_mm;
}

const std::vector<CriterionProgress>& SessionMetrics::criteria() {
  if (!finished_) progress_.evaluate(world_, sim_ ? &sim_->instruments() : nullptr, totals_.elapsed_s);
  return progress_.criteria();
}

bool SessionMetrics::complete() {
  bool any = false;
  for (const auto& c : criteria()) {
    if (c.kind == CriterionKind::kTimeLimit) continue;
    if (!c.met) return false;
    any = true;
  }
  return any;
}

const ScoreCard& SessionMetrics::score() {
  if (finished_ && !card_.categories.empty()) return card_;
  compute_scores(totals_, criteria(), time_limit_s_, options_.scores, card_);
  return card_;
}

}  // namespace vitreo::core
