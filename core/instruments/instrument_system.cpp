#include "core/instruments/instrument_system.hpp"

#include <algorithm>
#include <cmath>

#include "core/common/validate.hpp"

namespace vitreo::core {

namespace {
constexpr std::uint32_t kPartsPerInstrument = TipGeometry::kMaxParts;
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
  if (options_.vitreous_surface != kNone) {
    if (options_.vitreous_surface >= 32) throw InvalidArgument("instruments: vitreous surface index beyond the pass-through mask");
    options_.collision.pass_through_mask |= 1u << options_.vitreous_surface;
  }
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
  burns_.reserve(4096);
  sweeps_.reserve(n);
  poses_.reserve(n);
  removals_.reserve(n);
}

InstrumentSystem::~InstrumentSystem() = default;

Status InstrumentSystem::set_input(std::uint32_t i, const InstrumentInput& in) {
  if (i >= state_.size()) return Status::error("set_input: no such instrument");
  if (!is_finite(in.tip_fixture_mm) || !is_finite(in.axis_fixture) || !(in.axis_fixture.norm() > 1e-9) ||
      !std::isfinite(in.twist_rad) || !std::isfinite(in.actuation) || !std::isfinite(in.pedal) || !std::isfinite(in.cut_rate_cpm) ||
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

void InstrumentSystem::begin_step() {
  sweeps_.clear();
  poses_.clear();
  removals_.clear();
  suction_.clear();
}

void InstrumentSystem::end_step() {
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    previous_input_[i] = state_[i].input;
    previous_tip_[i] = state_[i].tip;
    was_inside_[i] = state_[i].inside ? 1 : 0;
  }
}

Vec3 InstrumentSystem::burn_position(const BurnSpot& b) const {
  const Surface& s = world_.surface(b.surface);
  if (!s.triangle_alive(b.triangle.index) || s.triangle_id(b.triangle.index) != b.triangle) return b.position_mm;
  const auto tv = s.triangle_vertices(b.triangle.index);
  return b.bary[0] * s.position(tv[0]) + b.bary[1] * s.position(tv[1]) + b.bary[2] * s.position(tv[2]);
}

}  // namespace vitreo::core
