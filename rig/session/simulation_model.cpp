#include "rig/session/simulation_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/state_hasher.hpp"

namespace vitreo::rig {

SimulationModel::SimulationModel(const ModelConfig& config)
    : config_(config), scene_(core::build_retina_cap(config.scene)), pedals_(config.pedals) {
  build_instruments();
}

void SimulationModel::build_instruments() {
  core::InstrumentSceneOptions options;
  for (const Port& p : config_.ports) options.ports_mm.push_back(p.position_mm);
  options.retina_surface = scene_.retina;
  options.macula_mm = core::Vec3(0.0, 0.0, -config_.scene.globe_radius_mm);
  if (scene_.detachment_force != core::kNone) {
    // The detachment drains through its centre (a break there), under gas.
    core::DrainageSite site;
    site.local_force = scene_.detachment_force;
    const double c = config_.scene.detachment_center_deg * std::numbers::pi / 180.0;
    site.break_point_mm = config_.scene.globe_radius_mm * core::Vec3(-std::sin(c), 0.0, -std::cos(c));
    options.drainage_sites.push_back(site);
  }
  std::vector<core::InstrumentDescription> instruments;
  for (std::size_t i = 0; i < config_.instruments.size() && i < config_.ports.size(); ++i) {
    core::InstrumentDescription d;
    d.kind = config_.instruments[i];
    d.port = static_cast<std::uint32_t>(i);
    instruments.push_back(d);
  }
  std::vector<std::uint32_t> surfaces;
  for (std::uint32_t s = 0; s < scene_.world.surface_count(); ++s) surfaces.push_back(s);
  system_.reset();
  topology_ = std::make_unique<core::TopologyAdapter>(scene_.world, surfaces, surfaces);
  system_ = std::make_unique<core::InstrumentSystem>(scene_.world, options, instruments);
  system_->set_topology(topology_.get());
}

bool SimulationModel::apply(const telemetry::DeviceInput& in) {
  for (std::uint8_t i = 0; i < in.n_values && i < telemetry::DeviceInput::kMaxValues; ++i) {
    if (!std::isfinite(in.values[i])) {
      ++refused_;
      return false;
    }
  }
  bool ok = false;
  if (in.device_kind == kSessionEndKind) {
    ok = true;
  } else if (in.device_kind == kCommandKind && in.n_values >= 2) {
    // Codes follow telemetry::CommandCode; case changes and snapshots are the session's business.
    switch (static_cast<int>(in.values[0])) {
      case 3: paused_ = true; break;   // Pause
      case 4: paused_ = false; break;  // Resume
      case 5:                          // Reset: the case as it was loaded, instruments out
        system_.reset();
        topology_.reset();
        scene_ = core::build_retina_cap(config_.scene);
        build_instruments();
        pedals_ = PedalMapper(config_.pedals);
        instruments_ = {};
        eye_rotation_ = core::Quat::Identity();
        ++resets_;
        break;
      case 7: wireframe_ = !wireframe_; break;
      case 8: labels_ = !labels_; break;
      case 9: zoom_override_ = in.values[1]; break;
      default: break;
    }
    ok = true;
  } else if (in.device_kind == kLinkKind && in.n_values >= 1) {
    // Which instrument a tracker link carries is its channel.
    if (in.channel >= 0 && in.channel < static_cast<int>(instruments_.size())) {
      instruments_[static_cast<std::size_t>(in.channel)].frozen = static_cast<int>(in.values[0]) == static_cast<int>(LinkInput::Lost);
    }
    ok = true;
  } else if (DecodedTracker t; decode_tracker(in, t)) {
    if (t.instrument_id >= 0 && t.instrument_id < static_cast<int>(instruments_.size())) {
      InstrumentSlot& slot = instruments_[static_cast<std::size_t>(t.instrument_id)];
      const int port = t.instrument_id < static_cast<int>(config_.ports.size()) ? t.instrument_id : -1;
      if (port >= 0 && !slot.frozen) {
        InstrumentPose pose;
        // In the fixture frame: the instrument system applies the eye's rotation itself.
        ok = map_through_port(t.pose, config_.ports[static_cast<std::size_t>(port)], core::Quat::Identity(),
                              config_.calibration, pose);
        if (ok) {
          slot.present = true;
          slot.port = port;
          slot.tool_type = t.tool_type;
          slot.pose = pose;
        }
      } else {
        ok = port >= 0;  // a frozen instrument ignores its (late) samples
      }
    }
  } else if (PedalReading p; decode_pedals(in, p)) {
    ok = pedals_.apply(p);
  } else if (DecodedEyeball e; decode_eyeball(in, e)) {
    const double n = e.orientation.coeffs().norm();
    if (std::abs(n - 1.0) < 1e-3) {
      eye_rotation_ = e.orientation.normalized();
      eye_tracked_ = true;
      ok = true;
    }
  }
  ok ? ++applied_ : ++refused_;
  return ok;
}

core::StepReport SimulationModel::step() {
  if (paused_) return {};
  const SurgicalControls& c = pedals_.controls();
  for (std::uint32_t i = 0; i < system_->instrument_count(); ++i) {
    const InstrumentSlot& slot = instruments_[i];
    core::InstrumentInput in;
    if (slot.present) {
      // A frozen instrument (tracker lost) holds its last pose and lets go of nothing it holds.
      in.present = slot.pose.inserted;
      in.tip_fixture_mm = slot.pose.tip_mm;
      in.axis_fixture = slot.pose.axis;
      in.twist_rad = slot.pose.roll_rad;
      in.actuation = slot.pose.actuation;
    } else if (config_.instruments[i] == core::InstrumentKind::kLightPipe) {
      // Untracked light pipe: held through its port, 6 mm in, toward the posterior pole.
      const core::Vec3 port = config_.ports[i].position_mm;
      const core::Vec3 target(0.0, 0.0, -0.6 * config_.scene.globe_radius_mm);
      in = core::InstrumentInput::through_port(port, (target - port).normalized(), 6.0);
    } else {
      in.present = false;
    }
    const double vacuum = pedals_.mapping().vacuum_max_mmhg > 0.0 ? c.vacuum_mmhg / pedals_.mapping().vacuum_max_mmhg : 0.0;
    in.pedal = std::clamp(vacuum, 0.0, 1.0);
    in.trigger = c.laser_fire;
    in.light_power_mw = 5.0 + 10.0 * c.light_level;
    (void)system_->set_input(i, in);  // refused input (non-finite) leaves the last one in place
  }
  system_->set_eye_fixture_rotation(eye_tracked_ ? std::optional<core::Quat>(eye_rotation_) : std::nullopt);
  ++steps_;
  return system_->step(config_.dt_s).tissue;
}

std::uint64_t SimulationModel::state_hash() const {
  core::StateHasher h;
  h.add_u64(scene_.world.state_hash());
  h.add_u64(steps_);
  h.add_u64(applied_);
  h.add_u64(resets_);
  h.add_u64((paused_ ? 1u : 0u) | (wireframe_ ? 2u : 0u) | (labels_ ? 4u : 0u));
  h.add_double(zoom_override_);
  h.add_u64(refused_);
  for (const auto& slot : instruments_) {
    h.add_u64((slot.present ? 1u : 0u) | (slot.frozen ? 2u : 0u) | (slot.pose.inserted ? 4u : 0u));
    h.add_vec3(slot.pose.tip_mm);
    h.add_vec3(slot.pose.axis);
    h.add_double(slot.pose.roll_rad);
    h.add_double(slot.pose.actuation);
  }
  const auto& c = pedals_.controls();
  h.add_double(c.vacuum_mmhg);
  h.add_double(c.cut_rate_cpm);
  h.add_double(c.zoom);
  h.add_double(c.light_level);
  h.add_u64(c.instrument_changes);
  h.add_double(eye_rotation_.w());
  h.add_double(eye_rotation_.x());
  h.add_double(eye_rotation_.y());
  h.add_double(eye_rotation_.z());
  return h.value();
}

}  // namespace vitreo::rig
