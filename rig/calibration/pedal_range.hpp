#pragma once
// Pedal travel: a real pedal's potentiometer neither reads 0 at rest nor 1 fully pressed, and it
// jitters about its rest reading. The technician leaves the pedal alone for a moment (rest), then
// presses it fully down and lets it up (travel); from the raw 0..1 readings we take the range
// actually reached and a dead zone wide enough that rest jitter never opens the vacuum.
//
// Applying it: n = clamp((raw - lo) / (hi - lo), 0, 1); out = n < dz ? 0 : (n - dz) / (1 - dz).
#include <string>
#include <vector>

namespace vitreo::rig::calibration {

struct PedalRangeLimits {
  std::size_t min_rest_samples = 20;
  std::size_t min_travel_samples = 50;
  double min_range = 0.3;       // hi - lo: the pedal was really pressed
  double dead_zone_margin = 0.01;  // added to the rest jitter, of the range
};

struct PedalRange {
  double lo = 0.0, hi = 1.0;    // raw readings at rest and fully pressed
  double dead_zone = 0.0;       // of the normalised travel
  // The raw reading mapped onto 0..1 with the dead zone removed.
  double apply(double raw) const;
};

struct PedalRangeResult {
  bool ok = false;
  std::string error;
  PedalRange range;
  double rest_jitter = 0.0;     // max |rest - median(rest)|, raw units
};

PedalRangeResult measure_pedal_range(const std::vector<double>& rest, const std::vector<double>& travel,
                                     const PedalRangeLimits& limits = {});

}  // namespace vitreo::rig::calibration
