#include "rig/session/simulation_model.hpp"

#include <cmath>

#include "core/common/state_hasher.hpp"

namespace vitreo::rig {

SimulationModel::SimulationModel(const ModelConfig& config)
    : config_(config), scene_(core::build_retina_cap(config.scene)), pedals_(config.pedals) {}

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
        scene_ = core::build_retina_cap(config_.scene);
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
        ok = map_through_port(t.pose, config_.ports[static_cast<std::size_t>(port)], eye_rotation_, config_.calibration, pose);
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
      ok = true;
    }
  }
  ok ? ++applied_ : ++refused_;
  return ok;
}

core::StepReport SimulationModel::step() {
  if (paused_) return {};
  // Instruments wake the tissue where they are, so sleeping tissue responds to them.
  for (const auto& slot : instruments_) {
    if (slot.present && slot.pose.inserted) scene_.world.wake_sphere(slot.pose.tip_mm, 2.0);
  }
  ++steps_;
  return scene_.world.step(config_.dt_s);
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
