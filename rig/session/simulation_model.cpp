#include "rig/session/simulation_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "core/common/state_hasher.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/input_codec.hpp"

namespace vitreo::rig {

// ---- The model ------------------------------------------------------------------------------------

SimulationModel::SimulationModel(const ModelConfig& config)
    : SimulationModel(config, prepare_case(config.cases, config.first_case, config.load)) {}

SimulationModel::SimulationModel(const ModelConfig& config, std::unique_ptr<PreparedCase> first)
    : config_(config), pedals_(config.pedals), laser_(config.laser) {
  if (!first) throw std::invalid_argument("SimulationModel: no case");
  install(std::move(first));
  case_loads_ = 0;  // the first case is the start, not a switch
}

void SimulationModel::install(std::unique_ptr<PreparedCase> c) {
  retired_ = std::move(case_);
  case_ = std::move(c);
  // A case starts with the instruments out, the pedals released and the eye at rest.
  pedals_ = PedalMapper(config_.pedals);
  for (auto& slot : instruments_) {  // instruments out; a lost tracker stays lost
    const bool frozen = slot.frozen;
    slot = InstrumentSlot{};
    slot.frozen = frozen;
  }
  eye_rotation_ = core::Quat::Identity();
  eye_tracked_ = false;
  paused_ = false;
  // The microscope starts centred on the case's region of interest.
  microscope_ = core::Microscope(config_.microscope, case_->scene->eye.fundus_coords(case_->focus_mm),
                                 case_->scene->description.view.wide_angle);
  // The case's metrics judge the work in this microscope's view (microscope_handling).
  case_->metrics->watch_microscope(&microscope_, &case_->scene->eye);
  ++case_loads_;
}

int SimulationModel::selected_tool() const {
  const auto n = case_->tools.size();
  if (n == 0) return -1;
  // A handpiece that names its tool (the tracker's tool type) puts that tool in the working hand
  // when the case offers it: a blade cannot be switched into forceps. A universal handpiece (tool
  // type 0), or one naming a tool the case lacks, leaves the choice to the instrument switch.
  if (core::InstrumentKind named; instrument_kind_of_tool_type(instruments_[kToolTracker].tool_type, named)) {
    const auto it = std::find(case_->tools.begin(), case_->tools.end(), named);
    if (it != case_->tools.end()) return static_cast<int>(it - case_->tools.begin());
  }
  return static_cast<int>(pedals_.controls().instrument_changes % n);
}

bool SimulationModel::apply(const telemetry::RecordedInput& in) {
  // A value that is not a finite number changes nothing (a recording's reader refuses one outright;
  // a live device's driver range-checks its frames, so none should arrive).
  double values[telemetry::kMaxInputValues];
  const std::size_t n = telemetry::input_values(in.what, values);
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(values[i])) {
      ++refused_;
      return false;
    }
  }
  const bool ok = std::visit(
      [&](const auto& r) {
        using T = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<T, telemetry::TrackerSample>) return apply_tracker(r);
        else if constexpr (std::is_same_v<T, telemetry::EyeFixtureSample>) return apply_fixture(r);
        else if constexpr (std::is_same_v<T, telemetry::PedalSample>) return apply_pedal(r);
        else if constexpr (std::is_same_v<T, telemetry::LinkChange>) return apply_link(in.channel, r);
        else if constexpr (std::is_same_v<T, telemetry::OperatorCommand>) return apply_command(r);
        else if constexpr (std::is_same_v<T, telemetry::CaseSwitch>) return apply_case_switch(r);
        else return std::is_same_v<T, telemetry::SessionEnd>;  // marks the length; changes nothing
      },
      in.what);
  ok ? ++applied_ : ++refused_;
  return ok;
}

bool SimulationModel::apply_case_switch(const telemetry::CaseSwitch& c) {
  if (c.index < 0 || c.index >= case_count()) return false;
  if (staged_ && staged_->index == c.index) {
    install(std::move(staged_));
  } else {
    install(prepare_case(config_.cases, c.index, config_.load));
  }
  return true;
}

bool SimulationModel::apply_command(const telemetry::OperatorCommand& c) {
  // Case changes, reset and snapshots are carried out by the session (a case is loaded off the
  // physics thread; its arrival is a CaseSwitch).
  using telemetry::CommandCode;
  switch (static_cast<CommandCode>(c.code)) {
    case CommandCode::Pause: paused_ = true; break;
    case CommandCode::Resume: paused_ = false; break;
    case CommandCode::Reset: ++resets_; break;  // requested here, the reload arrives as a CaseSwitch
    case CommandCode::ToggleWireframe: wireframe_ = !wireframe_; break;
    case CommandCode::ToggleLabels: labels_ = !labels_; break;
    case CommandCode::Zoom: microscope_.set_zoom(c.value); break;
    case CommandCode::Pan: microscope_.pan_to(core::Vec2(c.value, c.pan_y_mm)); break;
    case CommandCode::Focus: microscope_.set_focus(c.value); break;
    case CommandCode::ToggleShading: flat_shading_ = !flat_shading_; break;
    case CommandCode::ToggleWideAngle: microscope_.toggle_wide_angle(); break;
    case CommandCode::ToggleReinverter: microscope_.toggle_reinverter(); break;
    // The laser's settings, held to the commands' ranges here too (a recording could say anything).
    case CommandCode::LaserPower:
      if (!laser_power_in_range(c.value)) return false;
      laser_.power_mw = c.value;
      break;
    case CommandCode::LaserDuration:
      if (!laser_duration_in_range(c.value)) return false;
      laser_.duration_ms = c.value;
      break;
    default: break;
  }
  return true;
}

bool SimulationModel::apply_link(std::int32_t channel, const telemetry::LinkChange& link) {
  // Which instrument a tracker link carries is its channel; the pedals' and the fixture's links
  // freeze no instrument.
  constexpr std::uint8_t kTrackerDevice = 1;  // PROTOCOL.md's device type of a tracker
  if (link.device_type == kTrackerDevice && channel >= 0 && channel < static_cast<int>(instruments_.size())) {
    instruments_[static_cast<std::size_t>(channel)].frozen =
        link.event == telemetry::LinkEvent::Lost || link.event == telemetry::LinkEvent::Stuck;
  }
  return true;
}

bool SimulationModel::apply_tracker(const telemetry::TrackerSample& t) {
  if (t.instrument_id >= kTrackedInstruments) return false;
  InstrumentSlot& slot = instruments_[t.instrument_id];
  if (slot.frozen) return true;  // a frozen instrument ignores its (late) samples
  InstrumentPose pose;
  // In the fixture frame: the instrument system applies the eye's rotation itself. The port is where
  // the turned eye carries it (the ports are known with the eye at rest), so the shaft's axis runs
  // through the cannula the instrument is in.
  const std::size_t i = t.instrument_id;
  Port port = config_.measured_ports[i] ? *config_.measured_ports[i] : case_->tracker_ports[i];
  if (eye_tracked_) {
    port.position_mm = eye_rotation_ * port.position_mm;
    port.outward = eye_rotation_ * port.outward;
  }
  if (!map_through_port(tracked_pose(t), port, core::Quat::Identity(), config_.calibration[i], pose)) return false;
  slot.present = true;
  slot.port = case_->tracker_port_ids[i];  // the eye's port: 0 infusion, 1 working_1, 2 working_2
  slot.tool_type = t.tool_type;
  slot.pose = pose;
  return true;
}

bool SimulationModel::apply_pedal(const telemetry::PedalSample& p) {
  const SurgicalControls before = pedals_.controls();
  const bool ok = pedals_.apply(pedal_reading(p));
  // The pedal's zoom and focus are targets for the microscope's motors when they move (a command
  // holds until the pedal moves again).
  if (ok && pedals_.controls().zoom != before.zoom) microscope_.set_zoom(pedals_.controls().zoom);
  if (ok && pedals_.controls().focus_offset_mm != before.focus_offset_mm) microscope_.set_focus(pedals_.controls().focus_offset_mm);
  return ok;
}

bool SimulationModel::apply_fixture(const telemetry::EyeFixtureSample& e) {
  const core::Quat orientation = fixture_orientation(e);
  if (!(std::abs(orientation.coeffs().norm() - 1.0) < 1e-3)) return false;
  // Relative to the calibrated rest reading; skipped when there is none, so uncalibrated sessions
  // keep their bits.
  eye_rotation_ = config_.eye_zero.coeffs() == core::Quat::Identity().coeffs()
                      ? orientation.normalized()
                      : (config_.eye_zero.conjugate() * orientation.normalized()).normalized();
  eye_tracked_ = true;
  return true;
}

core::StepReport SimulationModel::step() {
  if (paused_) return {};
  const SurgicalControls& c = pedals_.controls();
  core::Simulation& sys = *case_->sim;
  const int tool = selected_tool();
  const double vacuum = pedals_.mapping().vacuum_max_mmhg > 0.0 ? c.vacuum_mmhg / pedals_.mapping().vacuum_max_mmhg : 0.0;
  auto tracked = [&](const InstrumentSlot& slot) {
    // A frozen instrument (tracker lost) holds its last pose and lets go of nothing it holds.
    core::InstrumentInput in;
    in.present = slot.pose.inserted;
    in.tip_fixture_mm = slot.pose.tip_mm;
    in.axis_fixture = slot.pose.axis;
    in.twist_rad = slot.pose.roll_rad;
    in.actuation = slot.pose.actuation;
    return in;
  };
  for (std::uint32_t i = 0; i < sys.instrument_count(); ++i) {
    core::InstrumentInput in;
    if (static_cast<int>(i) == case_->second_hand) {
      const InstrumentSlot& slot = instruments_[kSecondHandTracker];
      if (slot.present) {
        in = tracked(slot);
      } else if (case_->second_hand_is_light_pipe()) {
        // Untracked light pipe: held 6 mm into its port, aimed at the case's region of interest.
        const core::Vec3 port = case_->tracker_ports[kSecondHandTracker].position_mm;
        in = core::InstrumentInput::through_port(port, (case_->focus_mm - port).normalized(), 6.0);
        if (eye_tracked_) {  // held in the eye's port, it turns with the eye
          in.tip_fixture_mm = eye_rotation_ * in.tip_fixture_mm;
          in.axis_fixture = eye_rotation_ * in.axis_fixture;
        }
      } else {
        in.present = false;  // an untracked second-hand tool stays outside the eye
      }
    } else if (static_cast<int>(i) == tool && instruments_[kToolTracker].present) {
      in = tracked(instruments_[kToolTracker]);
    } else {
      in.present = false;  // the tools not in the hand are outside the eye
    }
    in.pedal = std::clamp(vacuum, 0.0, 1.0);
    in.cut_rate_cpm = c.cut_rate_cpm;  // the vitrector's cutter, from the pedal (controls.hpp)
    // The laser switch fires the tool in the working hand; the light pipe's pick has its own switch
    // (it used to stick out at every shot, then not at all).
    in.trigger = static_cast<int>(i) == case_->second_hand ? case_->second_hand_is_light_pipe() && c.pick_out
                                                           : static_cast<int>(i) == tool && c.laser_fire;
    in.laser_power_mw = laser_.power_mw;  // the console's settings: each shot one pulse of these
    in.laser_duration_s = 1e-3 * laser_.duration_ms;
    in.light_power_mw = 5.0 + 10.0 * c.light_level;
    (void)sys.set_input(i, in);  // refused input (non-finite) leaves the last one in place
  }
  sys.set_air_infusion(c.air_infusion);
  microscope_.step(config_.dt_s, core::MicroscopeInput{core::Vec2(c.pan_x, c.pan_y)});
  sys.set_eye_fixture_rotation(eye_tracked_ ? std::optional<core::Quat>(eye_rotation_) : std::nullopt);
  ++steps_;
  // The case's metrics observe the step as its last stage, so a replay measures the same session.
  return sys.step(config_.dt_s).tissue;
}

std::uint64_t SimulationModel::state_hash() const {
  core::StateHasher h;
  h.add_u64(world().state_hash());
  h.add_u64(static_cast<std::uint64_t>(case_->index));
  h.add_u64(case_loads_);
  h.add_u64(steps_);
  h.add_u64(applied_);
  h.add_u64(resets_);
  h.add_u64((paused_ ? 1u : 0u) | (wireframe_ ? 2u : 0u) | (labels_ ? 4u : 0u) | (flat_shading_ ? 8u : 0u));
  microscope_.hash_into(h);
  h.add_u64(refused_);
  for (const auto& slot : instruments_) {
    h.add_u64((slot.present ? 1u : 0u) | (slot.frozen ? 2u : 0u) | (slot.pose.inserted ? 4u : 0u));
    h.add_u64(static_cast<std::uint64_t>(slot.tool_type));  // it picks the working hand's tool
    h.add_vec3(slot.pose.tip_mm);
    h.add_vec3(slot.pose.axis);
    h.add_double(slot.pose.roll_rad);
    h.add_double(slot.pose.actuation);
  }
  const auto& c = pedals_.controls();
  h.add_double(c.vacuum_mmhg);
  h.add_double(c.cut_rate_cpm);
  h.add_double(c.zoom);
  h.add_double(c.focus_offset_mm);
  h.add_double(c.pan_x);
  h.add_double(c.pan_y);
  h.add_double(c.light_level);
  h.add_u64(c.instrument_changes);
  h.add_u64(c.air_infusion ? 1u : 0u);
  h.add_u64((c.laser_fire ? 1u : 0u) | (c.pick_out ? 2u : 0u) | (c.reflux ? 4u : 0u));
  h.add_double(laser_.power_mw);
  h.add_double(laser_.duration_ms);
  h.add_double(eye_rotation_.w());
  h.add_double(eye_rotation_.x());
  h.add_double(eye_rotation_.y());
  h.add_double(eye_rotation_.z());
  return h.value();
}

}  // namespace vitreo::rig
