#pragma once
// The fixed instrument poses the case golden test and the per-case frame benchmark share: tracker
// samples as the tracker driver delivers them, and the standard framing of a case — the light pipe
// 6 mm into its port aimed at the case's region of interest, the first tool through its own port
// aimed at that region with its tip 3 mm short of it (handle a third closed), settled for three
// steps; the microscope starts centred on the region of interest.
#include <memory>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "rig/session/case_switcher.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::rig::testing {

// The shipped cases: the *.toml files of scenes/ other than the materials library, by name, sorted.
std::vector<std::string> shipped_case_names();

// One case from scenes/ loaded the way a session loads it, with its look (visuals) for rendering;
// the loader owns the case's static meshes and textures, so it lives as long as the model.
struct CaseUnderTest {
  CaseUnderTest(const std::string& scene_file, int retina_vertices, const std::string& cache_dir);
  CaseSwitcher loader;
  SimulationModel model;
};

// A tracker sample for instrument `id` with its tip at `tip` (eye-fixture frame); the orientation
// is left to the port (the shaft is rebuilt from the port through the tip).
// `orientation`: the tracker's rotation (its x axis sets the instrument's roll about the shaft).
telemetry::RecordedInput tracker_sample(int id, const core::Vec3& tip, double actuation,
                                      const core::Quat& orientation = core::Quat::Identity());

// An operator command as the session records it (code: telemetry::CommandCode; b: pan's y).
telemetry::RecordedInput command_input(int code, double a = 0.0, double b = 0.0);
// A pedal reading: the microscope pedal (id 1) or the vitrectomy pedal (id 0), four axes, switches.
telemetry::RecordedInput pedal_input(int pedal, double a0, double a1, double a2, double a3, int switches = 0);

inline constexpr double kToolClearance_mm = 3.0;
inline constexpr double kToolActuation = 0.3;

// Applies the standard poses and steps three times; false if the model refused an input.
bool place_at_fixed_poses(SimulationModel& model);

}  // namespace vitreo::rig::testing
