#pragma once
// The light in the eye: the light pipe's cone, and the light dose on the macula. Endoillumination
// close to the macula for long is phototoxic; the dose is the irradiance of the cone's spot
// (source power over the spot's area at the macula's distance) integrated while the macula lies in
// the cone. Events: the pipe closer than the safe distance (each time it comes closer), the dose
// past its limit (once).
#include <limits>
#include <optional>

#include "core/instruments/instrument_system.hpp"

namespace vitreo::core {

struct LightExposure {
  bool active = false;
  Vec3 apex_mm = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();
  double half_angle_rad = 0.0;
  double macula_distance_mm = std::numeric_limits<double>::infinity();
  double macula_dose_j_cm2 = 0.0;
};

class LightModel {
 public:
  // The cone, the safe distance, the dose limit and the macula from InstrumentSceneOptions.
  explicit LightModel(const InstrumentSceneOptions& options);
  // This step's cone and dose from the light pipes among the instruments.
  void step(double dt_s, const InstrumentSystem& instruments, InstrumentEvents& events);
  const LightExposure& exposure() const { return light_; }

 private:
  double half_angle_deg_, safe_distance_mm_, dose_limit_j_cm2_;
  std::optional<Vec3> macula_mm_;
  LightExposure light_;
  bool close_reported_ = false;
  bool dose_reported_ = false;
};

}  // namespace vitreo::core
