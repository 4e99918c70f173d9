// Stage: the fluid level and the drainage (fluid.hpp).
#include "core/sim/fluid.hpp"

#include <algorithm>
#include <cmath>

namespace vitreo::core {

namespace {
bool aspirating(const InstrumentState& st) {
  return st.description.kind == InstrumentKind::kDrainageNeedle && st.inside && st.input.pedal > 0.0;
}
}  // namespace

FluidModel::FluidModel(TissueWorld& world, const InstrumentSceneOptions& options)
    : world_(world),
      sites_(options.drainage_sites),
      aspiration_level_rate_mm_s_(options.aspiration_level_rate_mm_s),
      drainage_rate_per_s_(options.drainage_rate_per_s) {}

void FluidModel::step(double dt, const InstrumentSystem& instruments) {
  Environment env = world_.environment();
  // The world's level may have been set directly (a scene loaded mid-exchange): never above it.
  if (env.fluid_level_z_mm < level_ - 0.05 || !std::isfinite(env.fluid_level_z_mm)) level_ = env.fluid_level_z_mm;
  double level = level_;
  if (air_infusion_) {
    const Vec3& c = world_.wall().center();
    const double top = c.z() + world_.wall().radius_toward(Vec3::UnitZ());
    if (!(level < top)) level = top;
    // The aspirating needle takes fluid from its tip: the level falls toward it while air comes in.
    for (std::uint32_t i = 0; i < instruments.instrument_count(); ++i) {
      const InstrumentState& st = instruments.instrument(i);
      if (!aspirating(st)) continue;
      const double z = st.frame.tip.z();
      if (z < level) level = std::max(z, level - aspiration_level_rate_mm_s_ * st.input.pedal * dt);
    }
  }
  level_ = level;
  constexpr double kPushStep_mm = 0.05;
  if (level != env.fluid_level_z_mm &&
      (!std::isfinite(env.fluid_level_z_mm) || !std::isfinite(level) || std::abs(level - env.fluid_level_z_mm) >= kPushStep_mm)) {
    env.fluid_level_z_mm = level;
    (void)world_.set_environment(env);
  }
  for (const auto& site : sites_) {
    if (!(site.break_point_mm.z() > level_)) continue;
    for (std::uint32_t i = 0; i < instruments.instrument_count(); ++i) {
      const InstrumentState& st = instruments.instrument(i);
      if (!aspirating(st)) continue;
      if ((st.frame.tip - site.break_point_mm).norm() > site.reach_mm) continue;
      const double scale = world_.local_force_scale(site.local_force);
      (void)world_.set_local_force_scale(site.local_force, std::max(0.0, scale - drainage_rate_per_s_ * st.input.pedal * dt));
    }
  }
}

}  // namespace vitreo::core
