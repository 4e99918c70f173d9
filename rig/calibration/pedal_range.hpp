#pragma once
// Pedal travel: a real pedal's potentiometer neither reads 0 at rest nor 1 fully pressed, and it
// jitters about its rest reading. The technician leaves the pedal alone for a moment (rest), then
// presses it fully down and lets it up (travel); from the raw 0..1 readings we take the range
// actually reached and a dead zone wide enough that rest jitter never opens the vacuum.
//
// Applying it: n = clamp((raw - lo) / (hi - lo), 0, 1); out = n < dz ? 0 : (n - dz) / (1 - dz).
#include <string>
#include <vector>

#include "rig/input/controls.hpp"

namespace vitreo::rig::calibration {

using rig::AxisRange;

struct PedalRangeLimits {
  std::size_t min_rest_samples = 20;
  std::size_t min_travel_samples = 50;
  double min_range = 0.3;       // hi - lo: the pedal was really pressed
  double dead_zone_margin = 0.01;  // added to the rest jitter, of the range
};

// lo, hi: raw readings at rest and fully pressed; dead_zone: of the normalised travel. The rig's
// pedal mapping applies it (rig/input/controls.hpp), so the formula lives there once.
using PedalRange = AxisRange;

struct PedalRangeResult {
  bool ok = false;
  std::string error;
  PedalRange range;
  double rest_jitter = 0.0;     // max |rest - median(rest)|, raw units
};

PedalRangeResult measure_pedal_range(const std::vector<double>& rest, const std::vector<double>& travel,
                                     const PedalRangeLimits& limits = {});

}  // namespace vitreo::rig::calibration
