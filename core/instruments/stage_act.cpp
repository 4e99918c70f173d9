// Stage: the instruments act on the tissue. Forceps grasp and let go (a grip holds the grasped
// surface point to the jaws), the endolaser's aiming beam finds the retina and a trigger burns a
// spot (adhering the retina where it lies on the choroid), the vitrector's port draws tissue in (a
// suction field for the solver, a removal request for the topology stage), blades and closing
// scissors sweep their edges (cut requests). Colliders, contact candidates and suction fields go to
// the tissue world for its step.
#include "core/instruments/instrument_system.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vitreo::core {

namespace {
constexpr double kLaserRange_mm = 30.0;
}  // namespace

void InstrumentSystem::act(double dt, InstrumentEvents& events) {
  update_grasps(events);
  update_laser(events);
  draw_in_and_sweep(dt);
  (void)world_.set_suction_fields(suction_);
  (void)world_.set_colliders(colliders_);
  (void)world_.set_contact_candidates(candidates_);
}

void InstrumentSystem::update_grasps(InstrumentEvents& events) {
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    if (st.description.kind != InstrumentKind::kForceps) continue;
    const Vec3& h = st.tip.hinge;
    const InstrumentFrame& f = st.frame;
    if (st.grip != kNone) {
      if (!world_.grip_active(st.grip)) {
        st.grip = kNone;  // reported from the tissue events
      } else if (!st.inside || st.input.actuation < options_.release_actuation) {
        events.emit(InstrumentEventKind::kRelease, i, kNone, world_.grip_point(st.grip), 0.0);
        world_.release_grip(st.grip);
        st.grip = kNone;
      } else {
        const Vec3 target = h + st.grip_local.x() * f.u + st.grip_local.y() * f.v + st.grip_local.z() * f.w;
        (void)world_.set_grip_target(st.grip, target);
      }
    }
    const bool closing = st.input.actuation >= options_.grasp_close_actuation &&
                         previous_input_[i].actuation < options_.grasp_close_actuation;
    if (st.grip == kNone && st.inside && closing) {
      // Jaws closing on a membrane that lies on the retina close on the membrane: it is the layer
      // the jaws meet first. The nearest point of every other surface is tried before the retina's
      // (at equal distance the retina used to win, and a peel became a retinal tear).
      const std::uint32_t retina = options_.retina_surface;
      const std::uint32_t not_retina = retina < 32 ? ~(1u << retina) : ~0u;
      SurfacePoint sp = collision_->nearest_point(world_, st.tip.grasp_point, options_.grasp_radius_mm, not_retina);
      if (!sp.found && not_retina != ~0u) sp = collision_->nearest_point(world_, st.tip.grasp_point, options_.grasp_radius_mm);
      if (sp.found) {
        GripDescription g;
        g.surface = sp.surface;
        g.triangle = world_.surface(sp.surface).triangle_id(sp.triangle);
        g.bary = sp.bary;
        g.target_mm = sp.point;  // held where it is: no snap toward the jaws
        g.stiffness_un_per_mm = options_.grasp_stiffness_un_per_mm;
        g.break_force_un = options_.grasp_break_force_un;
        const std::uint32_t id = world_.add_grip(g);
        if (id != kNone) {
          st.grip = id;
          const Vec3 rel = sp.point - h;
          st.grip_local = {rel.dot(f.u), rel.dot(f.v), rel.dot(f.w)};
          events.emit(InstrumentEventKind::kGrasp, i, sp.surface, sp.point, sp.distance);
        }
      }
    }
    st.grip_force_un = st.grip != kNone ? world_.grip_force(st.grip) : 0.0;
  }
}

void InstrumentSystem::update_laser(InstrumentEvents& events) {
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    if (st.description.kind != InstrumentKind::kEndolaser) continue;
    st.aim_hit = false;
    if (!st.inside) continue;
    std::uint32_t opaque = ~0u;
    if (options_.vitreous_surface < 32) opaque &= ~(1u << options_.vitreous_surface);
    const RayHit hit = collision_->raycast(world_, st.frame.tip, st.frame.u, kLaserRange_mm, opaque);
    st.aim_hit = hit.hit;
    st.aim_point_mm = hit.hit ? hit.point : Vec3(st.frame.tip + kLaserRange_mm * st.frame.u);
    const bool fire = st.input.trigger && !previous_input_[i].trigger;
    if (!fire || !hit.hit) continue;
    BurnSpot b;
    b.instrument = i;
    b.surface = hit.surface;
    b.triangle = world_.surface(hit.surface).triangle_id(hit.triangle);
    b.bary = hit.bary;
    b.position_mm = hit.point;
    b.power_mw = st.input.laser_power_mw;
    b.duration_s = st.input.laser_duration_s;
    const double energy_mj = b.power_mw * b.duration_s;
    b.diameter_mm = options_.laser_spot_mm * std::clamp(std::sqrt(energy_mj / options_.laser_reference_energy_mj), 0.25, 3.0);
    b.time_s = world_.time_s();
    if (hit.surface == options_.retina_surface && energy_mj > 0.0) {
      const Surface& s = world_.surface(hit.surface);
      const double clearance = world_.wall().clearance(hit.point) - world_.settings().wall_offset_mm;
      double pressure = 0.0;
      for (auto v : s.triangle_vertices(hit.triangle)) pressure = std::max(pressure, world_.local_pressure_on(hit.surface, v));
      if (clearance <= options_.adhesion_gap_mm && pressure <= options_.adhesion_max_pressure_pa) {
        GripDescription g;
        g.surface = hit.surface;
        g.triangle = b.triangle;
        g.bary = hit.bary;
        g.target_mm = hit.point;
        g.stiffness_un_per_mm = options_.adhesion_stiffness_un_per_mm;
        b.adhered = world_.add_grip(g) != kNone;
      } else {
        events.emit(InstrumentEventKind::kLaserOnDetachedRetina, i, hit.surface, hit.point, clearance);
      }
    }
    if (burns_.size() < burns_.capacity()) burns_.push_back(b);
    events.emit(InstrumentEventKind::kLaserBurn, i, hit.surface, hit.point, b.diameter_mm);
  }
}

// The vitrector's suction and removal, the blades' and closing scissors' sweeps.
void InstrumentSystem::draw_in_and_sweep(double dt) {
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    const InstrumentState& st = state_[i];
    const auto kind = st.description.kind;
    const bool cuts = kind == InstrumentKind::kBlade || kind == InstrumentKind::kSidewaysBlade || kind == InstrumentKind::kScissors;
    if (cuts && (st.inside || was_inside_[i])) poses_.push_back(cutting_pose(i));
    if (!st.inside) continue;
    if (kind == InstrumentKind::kVitrector && st.input.pedal > 0.0) {
      const VitrectorSettings& v = options_.vitrector;
      const double field = std::max(v.field_radius_mm * st.input.pedal, v.removal_radius_mm);
      suction_.push_back({st.tip.port_center, st.tip.port_normal, field, v.suction_pa * st.input.pedal});
      collision_->wake_near(world_, st.tip.port_center, field);
      const double cut_rate = st.input.cut_rate_cpm >= 0.0 ? std::min(st.input.cut_rate_cpm, v.max_cut_rate_cpm) : v.cut_rate_cpm;
      removals_.push_back({i, st.tip.port_center, st.tip.port_normal, v.removal_radius_mm, field, st.input.pedal, cut_rate, dt});
    }
    const bool blade = kind == InstrumentKind::kBlade || kind == InstrumentKind::kSidewaysBlade;
    const bool scissors = kind == InstrumentKind::kScissors && st.input.actuation > previous_input_[i].actuation;
    if ((blade || scissors) && was_inside_[i]) {
      const TipGeometry& p = previous_tip_[i];
      BladeSweep sw{i, kind, p.edge_a, p.edge_b, st.tip.edge_a, st.tip.edge_b};
      if ((sw.a1 - sw.a0).norm() + (sw.b1 - sw.b0).norm() > 1e-9) sweeps_.push_back(sw);
    }
  }
  (void)world_.set_suction_fields(suction_);
  (void)world_.set_colliders(colliders_);
  (void)world_.set_contact_candidates(candidates_);
}

CuttingPose InstrumentSystem::cutting_pose(std::uint32_t i) const {
  const InstrumentState& st = state_[i];
  CuttingPose p;
  p.instrument = i;
  p.kind = st.description.kind;
  p.in_eye = st.inside;
  p.a = st.tip.edge_a;
  p.b = st.tip.edge_b;
  if (p.kind == InstrumentKind::kScissors) {
    // The jaws lie in the (u, v) plane of the frame, at ± half the opening about u (tip_geometry).
    const InstrumentDimensions& dim = st.description.dimensions;
    p.hinge = st.tip.hinge;
    p.bisector = st.frame.u;
    p.normal = st.frame.u.cross(st.frame.v);
    p.opening_rad = 2.0 * dim.jaw_open_deg * std::numbers::pi / 180.0 * (1.0 - std::clamp(st.input.actuation, 0.0, 1.0));
    p.jaw_length_mm = dim.jaw_length_mm;
  }
  return p;
}

}  // namespace vitreo::core
