#pragma once
// Foot pedals → surgical controls, from a mapping configuration.
//
// The vitrectomy pedal's travel sets vacuum (and, on dual-linear pedals, its side travel the cut
// rate); its switches fire the laser, reflux, change instrument, switch fluid–air and put the light
// pipe's pick out. The microscope pedal sets zoom,
// focus, the X–Y joystick and light. Which axis or switch does what is configuration, since rigs differ
// (rig/config/default-rig.toml).
#include <cstdint>
#include <string>
#include <vector>

namespace vitreo::rig {

// A pedal axis's calibrated travel (rig/calibration/pedal_range.hpp measures it): its potentiometer
// reads `lo` at rest and `hi` fully down, and jitters at rest within `dead_zone` of the travel.
struct AxisRange {
  int pedal_id = 0;
  int axis = 0;
  double lo = 0.0, hi = 1.0, dead_zone = 0.0;
  // The raw reading mapped onto 0..1 with the dead zone removed:
  // n = clamp((raw - lo) / (hi - lo), 0, 1); n <= dead_zone ? 0 : (n - dead_zone) / (1 - dead_zone).
  double apply(double raw) const;
};

struct PedalMapping {
  // Calibrated axes (from a calibration file); an axis not listed reads its raw 0..1 travel.
  std::vector<AxisRange> axis_ranges;
  int vitrectomy_pedal_id = 0;
  int vacuum_axis = 0;
  double vacuum_max_mmhg = 650.0;
  int cut_rate_axis = 1;  // -1: fixed cut rate
  double cut_rate_min_cpm = 1500.0;
  double cut_rate_max_cpm = 10000.0;
  int reflux_switch = 0;
  int laser_switch = 1;
  int instrument_switch = 2;
  int air_switch = 3;  // fluid–air exchange: each press switches the infusion between fluid and air
  int pick_switch = 4;  // the light pipe's pick (a lighted pick) is out while held; not the laser's switch

  int microscope_pedal_id = 1;
  int zoom_axis = 0;
  int focus_axis = 1;
  double zoom_min = 1.0;
  double zoom_max = 4.0;
  double focus_range_mm = 6.0;  // focus travels ±half of this about the fundus
  // The X–Y joystick: two axes, 0.5 = centred (a pedal without them leaves the microscope still),
  // deflection beyond the dead band moves the field at a speed (core::Microscope).
  int pan_x_axis = 2;
  int pan_y_axis = 3;
  double pan_deadband = 0.08;  // of the half travel
  int light_up_switch = 0;
  int light_down_switch = 1;
  double light_step = 0.1;
};

struct SurgicalControls {
  double vacuum_mmhg = 0.0;
  double cut_rate_cpm = 0.0;
  bool reflux = false;
  bool laser_fire = false;
  bool pick_out = false;  // the light pipe's pick, held out by pick_switch
  std::uint32_t instrument_changes = 0;  // rising edges of the instrument switch so far
  bool air_infusion = false;             // the infusion runs air (fluid–air exchange), toggled by air_switch
  double zoom = 1.0;
  double focus_offset_mm = 0.0;
  double pan_x = 0.0, pan_y = 0.0;  // joystick −1..1 (+x image right, +y image up), dead band removed
  double light_level = 0.7;  // 0..1 of the light source
  // Each pedal's axes as the mapping read them: 0..1 of their travel after the axis calibration
  // (axes the pedal does not have read 0). What the feet did, before it became vacuum, cut rate or
  // zoom; the debrief draws it.
  double vitrectomy_travel[4] = {};
  double microscope_travel[4] = {};
};

struct PedalReading {
  int pedal_id = 0;
  int axis_count = 0;
  double axes[4] = {};
  std::uint16_t switches = 0;
};

class PedalMapper {
 public:
  explicit PedalMapper(PedalMapping mapping = {}) : m_(mapping) {}
  // Applies a reading. Returns false (controls unchanged) for a non-finite or out-of-range axis:
  // a broken pedal must not open the vacuum.
  bool apply(const PedalReading& reading);
  const SurgicalControls& controls() const { return c_; }
  const PedalMapping& mapping() const { return m_; }

 private:
  PedalMapping m_;
  SurgicalControls c_;
  std::uint16_t last_switches_[2] = {0, 0};
};

// Reads a mapping from TOML text (section [pedals]); unknown keys and out-of-range values are
// errors reported as "<origin>:<line>: <key>: <reason>". Throws std::runtime_error.
PedalMapping parse_pedal_mapping(const std::string& toml_text, const std::string& origin);

}  // namespace vitreo::rig
