#include "fixed_poses.hpp"

#include <algorithm>
#include <filesystem>

namespace vitreo::rig::testing {

namespace {
scene_io::CaseLoadOptions load_options(int retina_vertices, const std::string& cache_dir) {
  scene_io::CaseLoadOptions o;
  o.retina_vertices = retina_vertices;
  o.cache_dir = cache_dir;
  return o;  // the case's own texture size: peripheral vessels vanish below 1024 px
}
ModelConfig model_config(const std::vector<scene_io::CaseText>& cases, const scene_io::CaseLoadOptions& load) {
  ModelConfig m;
  m.cases = cases;
  m.load = load;
  return m;
}
}  // namespace

CaseUnderTest::CaseUnderTest(const std::string& scene_file, int retina_vertices, const std::string& cache_dir)
    : loader({scene_io::read_case_text(scene_file)}, load_options(retina_vertices, cache_dir), /*visuals=*/true),
      model(model_config({scene_io::read_case_text(scene_file)}, load_options(retina_vertices, cache_dir)), loader.load_now(0)) {}

std::vector<std::string> shipped_case_names() {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(std::string(VITREO_SOURCE_DIR) + "/scenes")) {
    if (e.path().extension() == ".toml" && e.path().filename() != "materials.toml") out.push_back(e.path().stem().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

telemetry::RecordedInput tracker_sample(int id, const core::Vec3& tip, double actuation, const core::Quat& orientation) {
  telemetry::TrackerSample s;
  s.tip_mm = {tip.x(), tip.y(), tip.z()};
  // Orientation: the shaft is rebuilt from the port through the tip; the x axis gives the roll.
  s.q_wxyz = {orientation.w(), orientation.x(), orientation.y(), orientation.z()};
  s.actuation = actuation;
  s.quality = 1.0;
  s.instrument_id = static_cast<std::uint8_t>(id);
  // Tool type (PROTOCOL.md): the light pipe's hand holds a light pipe (1); the tool hand a universal
  // handpiece (0), so the case's first tool is in it, as golden/README.md says.
  s.tool_type = id == kSecondHandTracker ? 1 : 0;
  telemetry::RecordedInput in;
  in.what = s;
  return in;
}

telemetry::RecordedInput command_input(int code, double a, double b) {
  telemetry::RecordedInput in;
  in.what = telemetry::OperatorCommand{static_cast<std::int8_t>(code), a, b};
  return in;
}

telemetry::RecordedInput pedal_input(int pedal, double a0, double a1, double a2, double a3, int switches) {
  telemetry::PedalSample s;
  s.pedal_id = static_cast<std::uint8_t>(pedal);
  s.axis_count = 4;
  s.axes = {a0, a1, a2, a3};
  s.switches = static_cast<std::uint16_t>(switches);
  telemetry::RecordedInput in;
  in.what = s;
  return in;
}

bool place_at_fixed_poses(SimulationModel& model) {
  const PreparedCase& c = model.current_case();
  const core::Vec3 lp = c.tracker_ports[kSecondHandTracker].position_mm;
  const core::Vec3 tp = c.tracker_ports[kToolTracker].position_mm;
  if (!model.apply(tracker_sample(kSecondHandTracker, lp + 6.0 * (c.focus_mm - lp).normalized(), 0.0))) return false;
  // The tool aimed at the region of interest from its port, its tip short of it (its handle a
  // third closed): working tips, the laser's aiming spot and the shadows all lie in the field.
  const core::Vec3 tool_tip = c.focus_mm - kToolClearance_mm * (c.focus_mm - tp).normalized();
  if (!model.apply(tracker_sample(kToolTracker, tool_tip, kToolActuation))) return false;
  for (int i = 0; i < 3; ++i) model.step();
  return true;
}

}  // namespace vitreo::rig::testing
