#pragma once
// The fluid the eye is filled with: the fluid–gas boundary during a fluid–air exchange, and the
// subretinal fluid drained through a break. With the infusion running air, the level falls toward
// the tip of an aspirating needle (the flute takes fluid from where it is); subretinal fluid drains
// through a break only while the break lies under gas (thesis 2.6.2.4), lowering the detachment's
// force. The tissue world's environment follows the level in 0.05 mm increments (each change
// re-evaluates buoyancy everywhere, so it is not pushed every step).
#include <limits>
#include <vector>

#include "core/instruments/instrument_system.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

class FluidModel {
 public:
  // drainage sites, aspiration_level_rate_mm_s and drainage_rate_per_s from InstrumentSceneOptions.
  FluidModel(TissueWorld& world, const InstrumentSceneOptions& options);
  void set_air_infusion(bool on) { air_infusion_ = on; }
  // This step's level and drainage, from the aspirating needles among the instruments.
  void step(double dt_s, const InstrumentSystem& instruments);
  // The fluid–gas boundary (+infinity: all fluid).
  double level_z_mm() const { return level_; }

 private:
  TissueWorld& world_;
  std::vector<DrainageSite> sites_;
  double aspiration_level_rate_mm_s_, drainage_rate_per_s_;
  bool air_infusion_ = false;
  double level_ = std::numeric_limits<double>::infinity();
};

}  // namespace vitreo::core
