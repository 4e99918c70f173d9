// Stage: the light pipe's cone and the macular dose (light.hpp).
#include "core/sim/light.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vitreo::core {

LightModel::LightModel(const InstrumentSceneOptions& o)
    : half_angle_deg_(o.light_half_angle_deg),
      safe_distance_mm_(o.light_safe_distance_mm),
      dose_limit_j_cm2_(o.light_dose_limit_j_cm2),
      macula_mm_(o.macula_mm) {}

void LightModel::step(double dt, const InstrumentSystem& instruments, InstrumentEvents& events) {
  light_.active = false;
  for (std::uint32_t i = 0; i < instruments.instrument_count(); ++i) {
    const InstrumentState& st = instruments.instrument(i);
    if (st.description.kind != InstrumentKind::kLightPipe || !st.inside) continue;
    light_.active = true;
    light_.apex_mm = st.frame.tip;
    light_.axis = st.frame.u;
    light_.half_angle_rad = half_angle_deg_ * std::numbers::pi / 180.0;
    if (!macula_mm_) continue;
    const Vec3 to = *macula_mm_ - st.frame.tip;
    const double d = to.norm();
    light_.macula_distance_mm = d;
    if (d < safe_distance_mm_ && !close_reported_) {
      events.emit(InstrumentEventKind::kLightTooClose, i, kNone, st.frame.tip, d);
    }
    close_reported_ = d < safe_distance_mm_;
    if (d > 1e-6 && to.dot(st.frame.u) / d >= std::cos(light_.half_angle_rad)) {
      const double spot_r = std::max(d * std::tan(light_.half_angle_rad), 0.1);
      const double irradiance_mw_mm2 = st.input.light_power_mw / (std::numbers::pi * spot_r * spot_r);
      light_.macula_dose_j_cm2 += irradiance_mw_mm2 * 0.1 * dt;  // mW/mm² = 0.1 W/cm²
    }
    if (light_.macula_dose_j_cm2 > dose_limit_j_cm2_ && !dose_reported_) {
      dose_reported_ = true;
      events.emit(InstrumentEventKind::kLightToxicity, i, kNone, *macula_mm_, light_.macula_dose_j_cm2);
    }
  }
}

}  // namespace vitreo::core
