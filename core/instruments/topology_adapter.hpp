#pragma once
// The adapter between the instruments' cut and removal requests and core/topology: blades and
// scissors cut through Cutter (the swept-quad cut), the vitrector removes through Vitrector's
// guillotine. Suction itself is applied by the solver (SuctionField); build the adapter with the
// instruments' VitrectorSettings (InstrumentSceneOptions::vitrector) so both use one model.
#include <cstdint>
#include <memory>
#include <vector>

#include "core/instruments/instrument_system.hpp"
#include "core/topology/cut.hpp"
#include "core/topology/vitrector.hpp"

namespace vitreo::core {

class TopologyAdapter final : public TopologyActions {
 public:
  // cut_surfaces: surfaces blades and scissors cut; removal_surfaces: surfaces the vitrector removes
  // (gel, membranes). Throws InvalidArgument for surfaces out of range.
  TopologyAdapter(TissueWorld& world, const std::vector<std::uint32_t>& cut_surfaces,
                  const std::vector<std::uint32_t>& removal_surfaces, CutSettings cut = {}, VitrectorSettings vitrector = {});

  void cut(TissueWorld& world, const BladeSweep& sweep) override;
  void remove(TissueWorld& world, const RemovalRequest& request) override;

  std::uint32_t springs_opened() const { return springs_opened_; }
  double removed_mass_g() const { return removed_mass_g_; }
  const Status& last_error() const { return last_error_; }

 private:
  std::vector<std::unique_ptr<Cutter>> cutters_;
  std::vector<std::unique_ptr<Vitrector>> vitrectors_;
  std::uint32_t springs_opened_ = 0;
  double removed_mass_g_ = 0.0;
  Status last_error_ = Status::ok();
};

}  // namespace vitreo::core
