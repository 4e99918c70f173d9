#pragma once
// One case ready to step: the built and settled core::Scene (a scenes/*.toml case), the instruments
// the case offers going through its sclerotomy ports, and how the rig's trackers map onto them.
//
// Preparing one allocates and may take a second (parse, build, settle or restore from the cache), so
// a live session does it on a loader thread and hands the result to physics at a step boundary
// (rig_session.cpp); a replay does it in place when it reaches the recorded switch.
//
// Tracker mapping (the surgeon's two hands):
//   tracker instrument 0 → the hand-held tool: the case's instruments other than the light pipe and
//                          the infusion, in the order the case lists them, through port "working_1"
//                          (or "working_2" when the case's instruments.working_port says so);
//                          the pedal's instrument-change switch cycles through them
//   tracker instrument 1 → the other hand's instrument through the other working port: the light pipe
//                          (when no tracker drives it, it is held there aimed at the case's region of
//                          interest), or the case's instruments.second_hand (forceps, pick or scissors:
//                          bimanual work under a chandelier)
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/instruments/topology_adapter.hpp"
#include "core/metrics/session_metrics.hpp"
#include "core/sim/simulation.hpp"
#include "core/scene/scene_builder.hpp"
#include "rig/input/port_pivot.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/session/view_snapshot.hpp"

namespace vitreo::rig {

inline constexpr int kToolTracker = 0;
inline constexpr int kSecondHandTracker = 1;
inline constexpr int kTrackedInstruments = 2;

struct PreparedCase {
  int index = 0;  // in the session's case list
  std::unique_ptr<core::Scene> scene;
  std::unique_ptr<core::TopologyAdapter> topology;
  std::unique_ptr<core::Simulation> sim;
  // The case's metrics, criteria and scores (core/metrics), the simulation step's last stage; built
  // with the case so a switch swaps them with it and nothing allocates on the physics thread.
  std::unique_ptr<core::SessionMetrics> metrics;
  std::vector<core::InstrumentKind> tools;  // simulation instruments 0..tools.size()-1
  int second_hand = -1;                     // simulation instrument index of tracker 1's instrument (-1: none)
  core::InstrumentKind second_hand_kind = core::InstrumentKind::kLightPipe;  // what it is
  bool second_hand_is_light_pipe() const { return second_hand >= 0 && second_hand_kind == core::InstrumentKind::kLightPipe; }
  Port tracker_ports[kTrackedInstruments];  // pivot of each tracked instrument
  std::string tracker_port_names[kTrackedInstruments];  // the eye's port each goes through
  int tracker_port_ids[kTrackedInstruments] = {1, 2};   // its index: 0 infusion, 1 working_1, 2 working_2
  core::Vec3 focus_mm = core::Vec3::Zero(); // the case's region of interest (light, microscope)
  std::uint64_t start_hash = 0;             // world state hash at the settled start
  bool from_cache = false;

  // For the picture (live sessions with rendering; replays leave them empty): a serial unique per
  // load, the case's static meshes and textures (owned by the session), and three view snapshots
  // sized for this case's surfaces, swapped into the view triple buffer by physics (frame_source).
  std::uint64_t serial = 0;
  const CaseVisuals* visuals = nullptr;
  std::vector<ViewSnapshot> spare_views;
  std::size_t spare_views_used = 0;
  double view_measured_at_s = -1e300;  // case time capture_view last measured the criteria for the picture
};

// The instrument kind of a scene file's instrument name; false for those that are not tracked
// instruments ("infusion").
bool instrument_kind(const std::string& name, core::InstrumentKind& out);

// The instrument kind a tracker's tool type names (firmware-protocol/PROTOCOL.md, POSE_SAMPLE); false
// for 0 (a universal handpiece that names no tool), 8 (the infusion is no held instrument) and codes
// past the last.
bool instrument_kind_of_tool_type(int tool_type, core::InstrumentKind& out);

// The tool type a handpiece of this kind reports (PROTOCOL.md, POSE_SAMPLE): the inverse of
// instrument_kind_of_tool_type.
int tool_type_of(core::InstrumentKind kind);

// Loads case `index` of `cases` and builds its instruments. Throws like scene_io::load_case.
std::unique_ptr<PreparedCase> prepare_case(const std::vector<scene_io::CaseText>& cases, int index,
                                           const scene_io::CaseLoadOptions& options);

// One line describing the case's instruments and their ports/trackers, for summaries and --help.
std::string describe_instruments(const PreparedCase& c);

}  // namespace vitreo::rig
