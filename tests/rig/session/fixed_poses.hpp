#pragma once
// The fixed instrument poses the case golden test and the per-case frame benchmark share: tracker
// samples as the tracker driver delivers them, and the standard framing of a case — the light pipe
// 6 mm into its port and the first tool 5 mm into its own, both aimed at the case's region of
// interest, jaws open, settled for three steps.
#include "core/common/types.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::rig::testing {

// A tracker sample for instrument `id` with its tip at `tip` (eye-fixture frame); the orientation
// is left to the port (the shaft is rebuilt from the port through the tip).
telemetry::DeviceInput tracker_sample(int id, const core::Vec3& tip, double actuation);

// Applies the standard poses and steps three times; false if the model refused an input.
bool place_at_fixed_poses(SimulationModel& model);

}  // namespace vitreo::rig::testing
