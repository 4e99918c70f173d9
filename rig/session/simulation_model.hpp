#pragma once
// The deterministic part of a session: the eye, and what the devices' inputs mean for it.
//
// Everything that changes the simulation enters through apply() as a RecordedInput, and time
// only through step(): live sessions and replays run this same code on the same inputs, which is
// why a replay ends in the same state hash as the session it recorded.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <string>

#include "core/sim/simulation.hpp"
#include "core/scene/microscope.hpp"
#include "rig/input/controls.hpp"
#include "rig/input/port_pivot.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/session/case_runtime.hpp"
#include "rig/session/device_inputs.hpp"
#include "rig/session/laser_settings.hpp"

namespace vitreo::rig {

struct ModelConfig {
  // The session's cases (scenes/*.toml as text, so a recording can carry them); first_case starts.
  std::vector<scene_io::CaseText> cases;
  int first_case = 0;
  scene_io::CaseLoadOptions load;  // cache folder, resolution overrides
  double dt_s = 1e-3;
  PedalMapping pedals;
  // The rig's sensor calibration (rig/session/calibration_in_force.hpp): per tracked instrument its
  // tracker calibration and, when measured on the fixture, its port. calibration_text is the file in
  // force (empty: none), carried by the recording so a replay maps the inputs the same way.
  std::array<TrackerCalibration, kTrackedInstruments> calibration{};
  std::array<std::optional<Port>, kTrackedInstruments> measured_ports{};
  core::Quat eye_zero = core::Quat::Identity();  // the fixture's reading with the eye at rest
  std::string calibration_text;
  core::MicroscopeSettings microscope;
  // The endolaser's settings at the start (the rig file's [laser]); commands change them later.
  LaserSettings laser;
};

// The case list and overrides as one text (stored in a recording's header), and back. decode throws
// std::runtime_error for a text that is not one.
std::string encode_case_list(const ModelConfig& config);
void decode_case_list(const std::string& text, ModelConfig& config);

struct InstrumentSlot {
  bool present = false;
  bool frozen = false;  // its tracker is lost: held where it was
  int port = -1;
  int tool_type = 0;
  InstrumentPose pose;
};

class SimulationModel {
 public:
  // Loads config.first_case in place (allocates, may settle), or starts from one already prepared.
  explicit SimulationModel(const ModelConfig& config);
  SimulationModel(const ModelConfig& config, std::unique_ptr<PreparedCase> first);
  // The case's metrics hold a pointer to the microscope: the model stays where it was built.
  SimulationModel(SimulationModel&&) = delete;
  SimulationModel& operator=(SimulationModel&&) = delete;

  // Applies one recorded input. Returns false for an input it refuses (non-finite values, bad
  // quaternion, a case or setting out of range): the refusal is counted and the state is unchanged.
  // A CaseSwitch installs the staged case when it is the one named, else loads it in place
  // (a replay), so both reach the same state.
  bool apply(const telemetry::RecordedInput& in);
  // Live sessions: a case prepared on another thread, installed by the next CaseSwitch for its
  // index (wait-free: a pointer move). take_retired() hands back the case it replaced, so its memory
  // is freed off the physics thread.
  void stage(std::unique_ptr<PreparedCase> prepared) { staged_ = std::move(prepared); }
  bool has_staged() const { return staged_ != nullptr; }
  std::unique_ptr<PreparedCase> take_retired() { return std::move(retired_); }
  // Maps the inputs onto the case's instruments and runs one core::Simulation step, metrics
  // included (skipped while paused). Returns the tissue's report.
  core::StepReport step();
  bool paused() const { return paused_; }
  // View state the operator sets: wireframe, labels (the case's guides and the structures' names,
  // shown at the start) and flat shading toggles; the microscope (pedal and commands drive it).
  bool wireframe() const { return wireframe_; }
  bool labels() const { return labels_; }
  bool flat_shading() const { return flat_shading_; }
  const core::Microscope& microscope() const { return microscope_; }
  // The endolaser's power and pulse duration now: a console setting, kept across case changes.
  const LaserSettings& laser() const { return laser_; }
  std::uint64_t resets() const { return resets_; }

  core::TissueWorld& world() { return case_->scene->world; }
  const core::Simulation& simulation() const { return *case_->sim; }
  const core::TissueWorld& world() const { return case_->scene->world; }
  const core::Scene& scene() const { return *case_->scene; }
  const PreparedCase& current_case() const { return *case_; }
  // The current case's metrics; score()/criteria() scan the world, so callers ask at a low rate.
  core::SessionMetrics& metrics() { return *case_->metrics; }
  // The view-snapshot spares of the current case (capture_view swaps them in; nothing else).
  PreparedCase& mutable_case() { return *case_; }
  int case_index() const { return case_->index; }
  int case_count() const { return static_cast<int>(config_.cases.size()); }
  const ModelConfig& config() const { return config_; }
  std::uint64_t case_loads() const { return case_loads_; }
  // The hand-held tool tracker 0 drives now (index into current_case().tools; -1: none): the tool
  // its handpiece names (tool type) when the case offers it, else the instrument switch's choice.
  int selected_tool() const;
  const SurgicalControls& controls() const { return pedals_.controls(); }
  const std::array<InstrumentSlot, 4>& instruments() const { return instruments_; }
  const core::Quat& eye_rotation() const { return eye_rotation_; }
  std::uint64_t inputs_applied() const { return applied_; }
  std::uint64_t inputs_refused() const { return refused_; }
  std::uint64_t steps() const { return steps_; }
  // World state plus the input-derived state, so a replay must agree on both.
  std::uint64_t state_hash() const;

 private:
  // One per kind of input (apply() has checked that every value is finite).
  bool apply_tracker(const telemetry::TrackerSample& t);
  bool apply_fixture(const telemetry::EyeFixtureSample& e);
  bool apply_pedal(const telemetry::PedalSample& p);
  bool apply_link(std::int32_t channel, const telemetry::LinkChange& link);
  bool apply_command(const telemetry::OperatorCommand& c);
  bool apply_case_switch(const telemetry::CaseSwitch& c);
  ModelConfig config_;
  void install(std::unique_ptr<PreparedCase> c);

  std::unique_ptr<PreparedCase> case_, staged_, retired_;
  std::uint64_t case_loads_ = 0;
  bool eye_tracked_ = false;  // an eyeball fixture reports the eye's rotation
  PedalMapper pedals_;
  std::array<InstrumentSlot, 4> instruments_{};
  core::Quat eye_rotation_ = core::Quat::Identity();
  bool paused_ = false;
  bool wireframe_ = false, labels_ = true, flat_shading_ = false;
  core::Microscope microscope_{core::MicroscopeSettings{}, core::Vec2::Zero()};
  LaserSettings laser_;
  std::uint64_t applied_ = 0, refused_ = 0, steps_ = 0, resets_ = 0;
};

}  // namespace vitreo::rig
