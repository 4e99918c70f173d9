#pragma once
// The deterministic part of a session: the eye, and what the devices' inputs mean for it.
//
// Everything that changes the simulation enters through apply() as a recorded DeviceInput, and time
// only through step(): live sessions and replays run this same code on the same inputs, which is
// why a replay ends in the same state hash as the session it recorded.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "core/instruments/instrument_system.hpp"
#include "core/instruments/topology_adapter.hpp"
#include "rig/input/controls.hpp"
#include "rig/input/port_pivot.hpp"
#include "rig/session/device_inputs.hpp"

namespace vitreo::rig {

// A link's state as an input: a lost tracker must freeze its instrument in replay exactly when it
// did live, so link changes are recorded like samples (device_kind kLinkKind, values[0] = state).
inline constexpr std::int8_t kLinkKind = 4;
enum class LinkInput : int { Up = 1, Lost = 2 };
// The session's end, recorded at its last step (values[0] = steps run) so a replay knows its length.
inline constexpr std::int8_t kSessionEndKind = 5;
// An accepted operator command (values[0] = telemetry::CommandCode, values[1] = its value): pause,
// reset or zoom change the session, so they are recorded and replayed like device inputs.
inline constexpr std::int8_t kCommandKind = 6;

struct ModelConfig {
  core::RetinaCapOptions scene;
  double dt_s = 1e-3;
  PedalMapping pedals;
  TrackerCalibration calibration;
  std::vector<Port> ports;  // instrument i goes through port i (if present)
  // What each tracked instrument is (index = tracker's instrument id = port); the light pipe in the
  // second port, aimed at the posterior pole, stands in for the surgeon's other hand unless a
  // tracker drives it.
  std::vector<core::InstrumentKind> instruments = {core::InstrumentKind::kForceps, core::InstrumentKind::kLightPipe};
};

struct InstrumentSlot {
  bool present = false;
  bool frozen = false;  // its tracker is lost: held where it was
  int port = -1;
  int tool_type = 0;
  InstrumentPose pose;
};

class SimulationModel {
 public:
  explicit SimulationModel(const ModelConfig& config);

  // Applies one recorded input. Returns false for an input it refuses (unknown kind, non-finite
  // values, bad quaternion): the refusal is counted and the state is unchanged.
  bool apply(const telemetry::DeviceInput& in);
  // One physics step (skipped while paused). Returns the core's report.
  core::StepReport step();
  bool paused() const { return paused_; }
  // View state the operator sets (wireframe and labels toggles, microscope zoom override).
  bool wireframe() const { return wireframe_; }
  bool labels() const { return labels_; }
  double zoom_override() const { return zoom_override_; }
  std::uint64_t resets() const { return resets_; }

  core::TissueWorld& world() { return scene_.world; }
  const core::InstrumentSystem& instrument_system() const { return *system_; }
  const core::TissueWorld& world() const { return scene_.world; }
  const core::RetinaCapScene& scene() const { return scene_; }
  const SurgicalControls& controls() const { return pedals_.controls(); }
  const std::array<InstrumentSlot, 4>& instruments() const { return instruments_; }
  const core::Quat& eye_rotation() const { return eye_rotation_; }
  std::uint64_t inputs_applied() const { return applied_; }
  std::uint64_t inputs_refused() const { return refused_; }
  std::uint64_t steps() const { return steps_; }
  // World state plus the input-derived state, so a replay must agree on both.
  std::uint64_t state_hash() const;

 private:
  ModelConfig config_;
  void build_instruments();

  core::RetinaCapScene scene_;
  std::unique_ptr<core::TopologyAdapter> topology_;
  std::unique_ptr<core::InstrumentSystem> system_;
  bool eye_tracked_ = false;  // an eyeball fixture reports the eye's rotation
  PedalMapper pedals_;
  std::array<InstrumentSlot, 4> instruments_{};
  core::Quat eye_rotation_ = core::Quat::Identity();
  bool paused_ = false;
  bool wireframe_ = false, labels_ = false;
  double zoom_override_ = 0.0;  // 0: the pedal's zoom
  std::uint64_t applied_ = 0, refused_ = 0, steps_ = 0, resets_ = 0;
};

}  // namespace vitreo::rig
