#pragma once
// Instrument geometry and kinematics: shafts of standard gauges pivoting at their sclerotomy port,
// the tip of each instrument type, handle actuation, and the capsules that stand for them in
// collision (thesis ch. 2.6.1, Figure 13: extension along the shaft, rotation about the incision
// point, twist about the shaft).
//
// Frames: the rig tracks instruments in the eye-fixture frame (the mock eye at rest); the simulated
// eye may be rotated about the globe centre (the origin) by R, so a point p_f of the fixture is at
// Rᵀ p_f in the eye frame, where the tissue lives. Everything below this file's kinematics works in
// the eye frame.
#include <array>
#include <cstdint>

#include "core/common/types.hpp"

namespace vitreo::core {

enum class Gauge : std::uint8_t { k20, k23, k25 };
// Outer shaft radius (mm): 20 G 0.908 mm, 23 G 0.642 mm, 25 G 0.514 mm outer diameter.
double shaft_radius_mm(Gauge g);

enum class InstrumentKind : std::uint8_t {
  kLightPipe,       // endoillumination, with a pick on its tip
  kForceps,         // grasping jaws, closed by the handle
  kPick,            // bent hook: lifts and separates, never grabs
  kBlade,           // straight (MVR) blade: cuts along its edge
  kSidewaysBlade,   // blade bent 90° from the shaft: cuts sideways
  kScissors,        // two blades closing about a hinge, by the handle
  kVitrector,       // side port, suction and cutting from the pedal
  kEndolaser,       // laser ray along the shaft, with an aiming beam
  kDrainageNeedle,  // flute / soft-tip needle: aspiration from the pedal
};
const char* to_string(InstrumentKind k);

// What the rig feeds for one instrument each step.
struct InstrumentInput {
  // The tracked pose in the eye-fixture frame: the tip and the shaft axis (unit, pointing into the
  // eye, from the handle toward the tip), and the roll about it (radians). The wand's port-relative
  // form (port, direction, insertion depth, twist) converts with through_port().
  Vec3 tip_fixture_mm = Vec3::Zero();
  Vec3 axis_fixture = -Vec3::UnitZ();
  double twist_rad = 0.0;
  double actuation = 0.0;  // handle: 0 open .. 1 closed (forceps, scissors)
  double pedal = 0.0;      // 0..1: vitrector vacuum, needle aspiration, laser fire gate
  // Vitrector: the console's cut rate (cuts per minute) set by the pedal; negative: the instrument's
  // own VitrectorSettings::cut_rate_cpm. Clamped to its max_cut_rate_cpm.
  double cut_rate_cpm = -1.0;
  bool trigger = false;    // light pipe: its pick is out; endolaser: fire a pulse on the rising edge
  double laser_power_mw = 200.0;
  double laser_duration_s = 0.1;
  double light_power_mw = 10.0;  // light pipe output
  bool present = true;           // false: the instrument is out of the eye (not tracked)

  static InstrumentInput through_port(const Vec3& port_fixture_mm, const Vec3& direction, double insertion_mm,
                                      double twist_rad = 0.0);
};

// The instrument's frame in the eye: tip, shaft axis u (into the eye), `up` v ⊥ u set by the twist
// (jaw opening direction, vitrector port facing, bent-tip direction), side w = u × v.
struct InstrumentFrame {
  Vec3 tip = Vec3::Zero();
  Vec3 u = -Vec3::UnitZ();
  Vec3 v = Vec3::UnitX();
  Vec3 w = Vec3::UnitY();
  double inserted_mm = 0.0;  // shaft length inside the eye (port to tip along the axis); ≤ 0: outside
  Vec3 port = Vec3::Zero();  // where the shaft passes the sclera (nearest point of the axis to the port)
};

// Frame from a tracked pose already in the eye frame and the port it goes through.
InstrumentFrame make_frame(const Vec3& tip, const Vec3& axis, double twist_rad, const Vec3& port);

struct Capsule {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  double radius_mm = 0.0;
  bool pushes_tissue = true;  // false: collides with instruments/anatomy only (forceps jaws, blades)
};

struct TipGeometry {
  static constexpr int kMaxParts = 4;
  std::array<Capsule, kMaxParts> parts{};
  int count = 0;
  // Forceps/scissors: the jaws' hinge and the point midway between the jaw tips.
  Vec3 hinge = Vec3::Zero();
  Vec3 grasp_point = Vec3::Zero();
  double jaw_gap_mm = 0.0;
  // Blades and scissors: the sharp edge (a segment).
  Vec3 edge_a = Vec3::Zero(), edge_b = Vec3::Zero();
  // Vitrector: the port's centre and facing (outward normal).
  Vec3 port_center = Vec3::Zero();
  Vec3 port_normal = Vec3::Zero();
};

struct InstrumentDimensions {
  double jaw_length_mm = 1.0;       // forceps, scissors
  double jaw_open_deg = 25.0;       // half opening at actuation 0
  double jaw_radius_mm = 0.06;
  double pick_length_mm = 0.3;      // bent pick / light-pipe pick
  double pick_radius_mm = 0.05;
  double blade_length_mm = 1.0;
  double sideways_blade_mm = 0.6;
  double vitrector_port_setback_mm = 0.3;  // port centre behind the tip
};

// The collision capsules and functional points of an instrument in its frame.
TipGeometry tip_geometry(InstrumentKind kind, Gauge gauge, const InstrumentFrame& f, const InstrumentInput& in,
                         const InstrumentDimensions& dim = {});

}  // namespace vitreo::core
