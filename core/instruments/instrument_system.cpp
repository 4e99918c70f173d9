#include "core/instruments/instrument_system.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/validate.hpp"

namespace vitreo::core {

namespace {
constexpr double kLaserRange_mm = 30.0;
constexpr std::uint32_t kPartsPerInstrument = TipGeometry::kMaxParts;

Quat quat_from_rotation_vector(const Vec3& r) {
  const double angle = r.norm();
  if (!(angle > 1e-15)) return Quat::Identity();
  return Quat(Eigen::AngleAxisd(angle, r / angle));
}

CapsuleShape shape(const Capsule& c) { return {c.a, c.b, c.radius_mm}; }
}  // namespace

const char* to_string(InstrumentEventKind k) {
  switch (k) {
    case InstrumentEventKind::kExcessiveRetinaForce: return "excessive retina force";
    case InstrumentEventKind::kUnintendedTear: return "unintended tear";
    case InstrumentEventKind::kLaserOnDetachedRetina: return "laser on detached retina";
    case InstrumentEventKind::kLightTooClose: return "light pipe too close to the macula";
    case InstrumentEventKind::kLightToxicity: return "macular light dose over the limit";
    case InstrumentEventKind::kInstrumentCollision: return "instrument collision";
    case InstrumentEventKind::kLensTouch: return "lens touch";
    case InstrumentEventKind::kWallContact: return "globe wall contact";
    case InstrumentEventKind::kGrasp: return "grasp";
    case InstrumentEventKind::kGraspLost: return "grasp lost";
    case InstrumentEventKind::kRelease: return "release";
    case InstrumentEventKind::kAttachmentBroken: return "attachment broken";
    case InstrumentEventKind::kLaserBurn: return "laser burn";
  }
  return "?";
}

Quat EyeRotation::rotation() const { return quat_from_rotation_vector(rotation_vector_rad); }

InstrumentSystem::InstrumentSystem(TissueWorld& world, InstrumentSceneOptions options, std::vector<InstrumentDescription> instruments)
    : world_(world), options_(std::move(options)) {
  if (instruments.size() * kPartsPerInstrument > TissueWorld::kMaxColliders) {
    throw InvalidArgument("instruments: too many instruments for the collider capacity");
  }
  for (const auto& p : options_.ports_mm) require_finite(p, "instruments: port");
  for (const auto& d : instruments) {
    if (d.port >= options_.ports_mm.size()) throw InvalidArgument("instruments: port index out of range");
  }
  if (options_.retina_surface != kNone && options_.retina_surface >= world.surface_count()) {
    throw InvalidArgument("instruments: retina surface out of range");
  }
  for (const auto& s : options_.drainage_sites) {
    if (s.local_force >= world.local_force_count()) throw InvalidArgument("instruments: drainage site's local force out of range");
  }
  require_range(options_.port_stiffness_un_per_mm, 0.0, 1e9, "instruments: port stiffness");
  require_range(options_.eye_rotation_stiffness_un_mm_per_rad, 1.0, 1e12, "instruments: eye rotation stiffness");
  collision_ = std::make_unique<CollisionScene>(world, options_.collision, options_.anatomy);
  const std::size_t n = instruments.size();
  state_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    state_[i].description = instruments[i];
    state_[i].input.present = false;
  }
  previous_input_.resize(n);
  for (auto& in : previous_input_) in.present = false;
  previous_tip_.resize(n);
  was_inside_.assign(n, 0);
  pair_touching_.assign(n * n, 0);
  lens_touching_.assign(n, 0);
  wall_touching_.assign(n, 0);
  retina_overloaded_.assign(n, 0);
  colliders_.reserve(TissueWorld::kMaxColliders);
  collider_owner_.reserve(TissueWorld::kMaxColliders);
  candidates_.reserve(TissueWorld::kMaxContactCandidates);
  suction_.reserve(TissueWorld::kMaxSuctionFields);
  events_.reserve(256);
  burns_.reserve(4096);
  sweeps_.reserve(n);
  poses_.reserve(n);
  removals_.reserve(n);
}

InstrumentSystem::~InstrumentSystem() = default;

Status InstrumentSystem::set_input(std::uint32_t i, const InstrumentInput& in) {
  if (i >= state_.size()) return Status::error("set_input: no such instrument");
  if (!is_finite(in.tip_fixture_mm) || !is_finite(in.axis_fixture) || !(in.axis_fixture.norm() > 1e-9) ||
      !std::isfinite(in.twist_rad) || !std::isfinite(in.actuation) || !std::isfinite(in.pedal) ||
      !std::isfinite(in.laser_power_mw) || !std::isfinite(in.laser_duration_s) || !std::isfinite(in.light_power_mw) ||
      in.laser_power_mw < 0.0 || in.laser_duration_s < 0.0 || in.light_power_mw < 0.0) {
    return Status::error("set_input: non-finite or negative value");
  }
  InstrumentInput c = in;
  c.axis_fixture.normalize();
  c.actuation = std::clamp(c.actuation, 0.0, 1.0);
  c.pedal = std::clamp(c.pedal, 0.0, 1.0);
  state_[i].input = c;
  return Status::ok();
}

void InstrumentSystem::set_eye_fixture_rotation(std::optional<Quat> rotation) { rig_rotation_ = rotation; }

void InstrumentSystem::emit(InstrumentEventKind kind, std::uint32_t instrument, std::uint32_t other, const Vec3& p, double m) {
  if (events_.size() < events_.capacity()) events_.push_back({kind, instrument, other, p, m});
}

// Quasi-static eye rotation: each inserted shaft holds its port on its line with the sclera's
// stiffness; the orbit resists with a torsional stiffness. Solved by a few preconditioned fixed-point
// iterations, warm-started from the last step.
void InstrumentSystem::solve_eye_rotation() {
  if (rig_rotation_) {
    const Eigen::AngleAxisd aa(*rig_rotation_);
    eye_.rotation_vector_rad = aa.angle() * aa.axis();
    eye_.from_rig = true;
  } else {
    eye_.from_rig = false;
  }
  const double kp = options_.port_stiffness_un_per_mm;
  const double ke = options_.eye_rotation_stiffness_un_mm_per_rad;
  auto torque_at = [&](const Vec3& theta) {
    const Quat r = quat_from_rotation_vector(theta);
    Vec3 torque = Vec3::Zero();
    double lever2 = 0.0;
    for (const auto& st : state_) {
      if (!st.input.present) continue;
      const Vec3 port = r * options_.ports_mm[st.description.port];
      const Vec3& a = st.input.axis_fixture;
      const Vec3 rel = port - st.input.tip_fixture_mm;
      if (rel.dot(-a) <= 0.0) continue;  // tip not past the port: not inserted
      const Vec3 offset = rel - rel.dot(a) * a;
      torque += port.cross(-kp * offset);
      lever2 += port.squaredNorm();
    }
    return std::pair{torque, lever2};
  };
  Vec3 theta = eye_.rotation_vector_rad;
  if (!eye_.from_rig) {
    for (int it = 0; it < 8; ++it) {
      const auto [tq, lever2] = torque_at(theta);
      theta += (tq - ke * theta) / (ke + kp * lever2);
    }
    eye_.rotation_vector_rad = theta;
  }
  eye_.torque_un_mm = torque_at(theta).first;
}

void InstrumentSystem::place_instruments() {
  const Quat rt = eye_.rotation().conjugate();  // fixture → eye
  colliders_.clear();
  collider_owner_.clear();
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    const Vec3 tip = rt * st.input.tip_fixture_mm;
    const Vec3 axis = rt * st.input.axis_fixture;
    st.frame = make_frame(tip, axis, st.input.twist_rad, options_.ports_mm[st.description.port]);
    st.inside = st.input.present && st.frame.inserted_mm > 0.0;
    st.tip = st.inside ? tip_geometry(st.description.kind, st.description.gauge, st.frame, st.input, st.description.dimensions)
                       : TipGeometry{};
    if (!st.inside) continue;
    const bool had = was_inside_[i] != 0;
    for (int k = 0; k < st.tip.count; ++k) {
      const Capsule& c = st.tip.parts[static_cast<std::size_t>(k)];
      if (!c.pushes_tissue || c.radius_mm <= 0.0) continue;
      ColliderCapsule cc;
      cc.a1 = c.a;
      cc.b1 = c.b;
      cc.radius_mm = c.radius_mm;
      const Capsule& prev = previous_tip_[i].parts[static_cast<std::size_t>(k)];
      const bool same = had && k < previous_tip_[i].count && prev.pushes_tissue;
      cc.a0 = same ? prev.a : c.a;
      cc.b0 = same ? prev.b : c.b;
      colliders_.push_back(cc);
      collider_owner_.push_back(i);
    }
  }
}

void InstrumentSystem::update_grasps() {
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    if (st.description.kind != InstrumentKind::kForceps) continue;
    const Vec3& h = st.tip.hinge;
    const InstrumentFrame& f = st.frame;
    if (st.grip != kNone) {
      if (!world_.grip_active(st.grip)) {
        st.grip = kNone;  // reported from the tissue events
      } else if (!st.inside || st.input.actuation < options_.release_actuation) {
        emit(InstrumentEventKind::kRelease, i, kNone, world_.grip_point(st.grip), 0.0);
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
      const SurfacePoint sp = collision_->nearest_point(world_, st.tip.grasp_point, options_.grasp_radius_mm);
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
          emit(InstrumentEventKind::kGrasp, i, sp.surface, sp.point, sp.distance);
        }
      }
    }
    st.grip_force_un = st.grip != kNone ? world_.grip_force(st.grip) : 0.0;
  }
}

void InstrumentSystem::update_laser(double /*dt*/) {
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    if (st.description.kind != InstrumentKind::kEndolaser) continue;
    st.aim_hit = false;
    if (!st.inside) continue;
    const RayHit hit = collision_->raycast(world_, st.frame.tip, st.frame.u, kLaserRange_mm);
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
        emit(InstrumentEventKind::kLaserOnDetachedRetina, i, hit.surface, hit.point, clearance);
      }
    }
    if (burns_.size() < burns_.capacity()) burns_.push_back(b);
    emit(InstrumentEventKind::kLaserBurn, i, hit.surface, hit.point, b.diameter_mm);
  }
}

void InstrumentSystem::update_fluid(double dt) {
  Environment env = world_.environment();
  // The world's level may have been set directly (a scene loaded mid-exchange): never above it.
  if (env.fluid_level_z_mm < fluid_level_ - 0.05 || !std::isfinite(env.fluid_level_z_mm)) fluid_level_ = env.fluid_level_z_mm;
  double level = fluid_level_;
  if (air_infusion_) {
    const Vec3& c = world_.wall().center();
    const double top = c.z() + world_.wall().radius_toward(Vec3::UnitZ());
    if (!(level < top)) level = top;
    // The aspirating needle takes fluid from its tip: the level falls toward it while air comes in.
    for (const auto& st : state_) {
      if (st.description.kind != InstrumentKind::kDrainageNeedle || !st.inside || st.input.pedal <= 0.0) continue;
      const double z = st.frame.tip.z();
      if (z < level) level = std::max(z, level - options_.aspiration_level_rate_mm_s * st.input.pedal * dt);
    }
  }
  fluid_level_ = level;
  constexpr double kPushStep_mm = 0.05;
  if (level != env.fluid_level_z_mm &&
      (!std::isfinite(env.fluid_level_z_mm) || !std::isfinite(level) || std::abs(level - env.fluid_level_z_mm) >= kPushStep_mm)) {
    env.fluid_level_z_mm = level;
    (void)world_.set_environment(env);
  }
  // Subretinal fluid drains through a break only while the break is under gas (thesis 2.6.2.4).
  const double now_level = fluid_level_;
  for (const auto& site : options_.drainage_sites) {
    if (!(site.break_point_mm.z() > now_level)) continue;
    for (const auto& st : state_) {
      if (st.description.kind != InstrumentKind::kDrainageNeedle || !st.inside || st.input.pedal <= 0.0) continue;
      if ((st.frame.tip - site.break_point_mm).norm() > site.reach_mm) continue;
      const double scale = world_.local_force_scale(site.local_force);
      (void)world_.set_local_force_scale(site.local_force, std::max(0.0, scale - options_.drainage_rate_per_s * st.input.pedal * dt));
    }
  }
}

void InstrumentSystem::update_light(double dt) {
  light_.active = false;
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    const InstrumentState& st = state_[i];
    if (st.description.kind != InstrumentKind::kLightPipe || !st.inside) continue;
    light_.active = true;
    light_.apex_mm = st.frame.tip;
    light_.axis = st.frame.u;
    light_.half_angle_rad = options_.light_half_angle_deg * std::numbers::pi / 180.0;
    if (!options_.macula_mm) continue;
    const Vec3 to = *options_.macula_mm - st.frame.tip;
    const double d = to.norm();
    light_.macula_distance_mm = d;
    if (d < options_.light_safe_distance_mm && !light_close_reported_) {
      emit(InstrumentEventKind::kLightTooClose, i, kNone, st.frame.tip, d);
    }
    light_close_reported_ = d < options_.light_safe_distance_mm;
    if (d > 1e-6 && to.dot(st.frame.u) / d >= std::cos(light_.half_angle_rad)) {
      const double spot_r = std::max(d * std::tan(light_.half_angle_rad), 0.1);
      const double irradiance_mw_mm2 = st.input.light_power_mw / (std::numbers::pi * spot_r * spot_r);
      light_.macula_dose_j_cm2 += irradiance_mw_mm2 * 0.1 * dt;  // mW/mm² = 0.1 W/cm²
    }
    if (light_.macula_dose_j_cm2 > options_.light_dose_limit_j_cm2 && !light_dose_reported_) {
      light_dose_reported_ = true;
      emit(InstrumentEventKind::kLightToxicity, i, kNone, *options_.macula_mm, light_.macula_dose_j_cm2);
    }
  }
}

void InstrumentSystem::rigid_contacts() {
  const std::uint32_t n = static_cast<std::uint32_t>(state_.size());
  for (std::uint32_t i = 0; i < n; ++i) {
    const InstrumentState& a = state_[i];
    // Lens and globe wall.
    double lens = std::numeric_limits<double>::infinity();
    if (a.inside && options_.anatomy.has_lens) {
      for (int k = 0; k < a.tip.count; ++k) lens = std::min(lens, collision_->lens_distance(shape(a.tip.parts[static_cast<std::size_t>(k)])));
    }
    const bool touching_lens = lens <= 0.0;
    if (touching_lens && !lens_touching_[i]) emit(InstrumentEventKind::kLensTouch, i, kNone, a.frame.tip, -lens);
    lens_touching_[i] = touching_lens;
    const double wall = a.inside ? world_.wall().clearance(a.frame.tip) - shaft_radius_mm(a.description.gauge)
                                 : std::numeric_limits<double>::infinity();
    if (wall < 0.0 && !wall_touching_[i]) emit(InstrumentEventKind::kWallContact, i, kNone, a.frame.tip, -wall);
    wall_touching_[i] = wall < 0.0;
    // Other instruments (FCL capsule–capsule).
    for (std::uint32_t j = i + 1; j < n; ++j) {
      const InstrumentState& b = state_[j];
      double best = std::numeric_limits<double>::infinity();
      Vec3 where = Vec3::Zero();
      if (a.inside && b.inside) {
        for (int k = 0; k < a.tip.count; ++k) {
          for (int l = 0; l < b.tip.count; ++l) {
            Vec3 w;
            const double d = collision_->capsule_distance(shape(a.tip.parts[static_cast<std::size_t>(k)]),
                                                          shape(b.tip.parts[static_cast<std::size_t>(l)]), &w);
            if (d < best) {
              best = d;
              where = w;
            }
          }
        }
      }
      std::uint8_t& touching = pair_touching_[i * n + j];
      if (best <= 0.0 && !touching) emit(InstrumentEventKind::kInstrumentCollision, i, j, where, -best);
      touching = best <= 0.0;
    }
  }
}

InstrumentStepReport InstrumentSystem::step(double dt) {
  InstrumentStepReport report;
  if (probe_) probe_(0, probe_user_);
  events_.clear();
  sweeps_.clear();
  poses_.clear();
  removals_.clear();
  suction_.clear();
  solve_eye_rotation();
  place_instruments();
  collision_->update(world_, colliders_, candidates_);
  // Whatever an instrument may touch this step must be simulated.
  for (const auto& c : candidates_) {
    Surface& s = world_.surface(c.surface);
    for (auto v : s.triangle_vertices(c.triangle)) {
      if (!s.vertex_awake(v)) s.wake_vertex(v);
    }
  }
  update_grasps();
  update_laser(dt);
  update_fluid(dt);
  update_light(dt);
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    const InstrumentState& st = state_[i];
    const auto kind = st.description.kind;
    const bool cuts = kind == InstrumentKind::kBlade || kind == InstrumentKind::kSidewaysBlade || kind == InstrumentKind::kScissors;
    if (cuts && (st.inside || was_inside_[i])) poses_.push_back(cutting_pose(i));
    if (!st.inside) continue;
    if (kind == InstrumentKind::kVitrector && st.input.pedal > 0.0) {
      const double field = std::max(options_.vitrector_field_mm * st.input.pedal, options_.vitrector_removal_mm);
      suction_.push_back({st.tip.port_center, st.tip.port_normal, field, options_.vitrector_suction_pa * st.input.pedal});
      collision_->wake_near(world_, st.tip.port_center, field);
      removals_.push_back({i, st.tip.port_center, st.tip.port_normal, options_.vitrector_removal_mm, field, st.input.pedal,
                           options_.vitrector_cut_rate_hz, dt});
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
  report.candidates = collision_->stats().candidates;
  report.patches_refit = collision_->stats().patches_refit;

  if (probe_) probe_(1, probe_user_);
  report.tissue = world_.step(dt);
  if (probe_) probe_(2, probe_user_);
  after_step(report.tissue, dt);
  if (probe_) probe_(3, probe_user_);
  return report;
}

void InstrumentSystem::after_step(const StepReport& report, double dt) {
  (void)dt;
  const std::uint32_t retina = options_.retina_surface;
  for (auto& st : state_) {
    st.contact_force_un = Vec3::Zero();
    st.retina_force_un = 0.0;
  }
  for (std::uint32_t c = 0; c < colliders_.size(); ++c) {
    InstrumentState& st = state_[collider_owner_[c]];
    st.contact_force_un += world_.contact_force(c);
    if (retina != kNone) st.retina_force_un += world_.contact_force(c, retina).norm();
  }
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    const bool over = st.retina_force_un > options_.retina_force_limit_un;
    if (over && !retina_overloaded_[i]) emit(InstrumentEventKind::kExcessiveRetinaForce, i, retina, st.frame.tip, st.retina_force_un);
    retina_overloaded_[i] = over;
    if (st.grip != kNone) st.grip_force_un = world_.grip_force(st.grip);
  }
  if (report.ok) {
    for (const TissueEvent& e : world_.events()) {
      if (e.kind == TissueEventKind::kTear && e.surface == retina) {
        // Attributed to the nearest instrument tip.
        std::uint32_t who = kNone;
        double best = std::numeric_limits<double>::infinity();
        for (std::uint32_t i = 0; i < state_.size(); ++i) {
          if (!state_[i].inside) continue;
          const double d = (state_[i].frame.tip - e.position_mm).norm();
          if (d < best) {
            best = d;
            who = i;
          }
        }
        emit(InstrumentEventKind::kUnintendedTear, who, e.surface, e.position_mm, e.magnitude);
      } else if (e.kind == TissueEventKind::kGripBroken) {
        for (std::uint32_t i = 0; i < state_.size(); ++i) {
          if (state_[i].grip == e.item) {
            emit(InstrumentEventKind::kGraspLost, i, e.surface, e.position_mm, e.magnitude);
            state_[i].grip = kNone;
          }
        }
      } else if (e.kind == TissueEventKind::kAttachmentBroken) {
        emit(InstrumentEventKind::kAttachmentBroken, kNone, e.surface, e.position_mm, e.magnitude);
      }
    }
  }
  rigid_contacts();
  if (topology_) {
    for (const auto& p : poses_) topology_->cut(world_, p);
    for (const auto& r : removals_) topology_->remove(world_, r);
  }
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    previous_input_[i] = state_[i].input;
    previous_tip_[i] = state_[i].tip;
    was_inside_[i] = state_[i].inside ? 1 : 0;
  }
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

Vec3 InstrumentSystem::burn_position(const BurnSpot& b) const {
  const Surface& s = world_.surface(b.surface);
  if (!s.triangle_alive(b.triangle.index) || s.triangle_id(b.triangle.index) != b.triangle) return b.position_mm;
  const auto tv = s.triangle_vertices(b.triangle.index);
  return b.bary[0] * s.position(tv[0]) + b.bary[1] * s.position(tv[1]) + b.bary[2] * s.position(tv[2]);
}

}  // namespace vitreo::core
