#pragma once
// The adapter between the instruments' cutting poses and removal requests and core/topology: each
// blade keeps an incision per surface it cuts (core/topology/incision.hpp), advanced to the blade's
// pose every step, so a cut made in thousands of 1 ms steps is the cut of the whole path; scissors
// keep a Scissors per surface (both jaws' incisions, cutting as they close). An instrument leaving
// the eye ends its incisions. The vitrector removes through Vitrector's guillotine; suction itself
// is applied by the solver (SuctionField); build the adapter with the instruments'
// VitrectorSettings (InstrumentSceneOptions::vitrector) so both use one model.
//
// Room for kMaxInstruments instruments is made at construction (no allocation in the step); an
// instrument index beyond it is refused with an error in last_error().
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/instruments/instrument_system.hpp"
#include "core/topology/blade_tools.hpp"
#include "core/topology/cut.hpp"
#include "core/topology/incision.hpp"
#include "core/topology/vitrector.hpp"

namespace vitreo::core {

class TopologyAdapter final : public TopologyActions {
 public:
  static constexpr std::uint32_t kMaxInstruments = 8;
  // cut_surfaces: surfaces blades and scissors cut; removal_surfaces: surfaces the vitrector removes
  // (gel, membranes); of those, aspirated_surface (the vitreous gel, or kNone) is aspirated as a
  // volume and the others are clipped (vitrector.hpp). Throws InvalidArgument for surfaces out of range.
  TopologyAdapter(TissueWorld& world, const std::vector<std::uint32_t>& cut_surfaces,
                  const std::vector<std::uint32_t>& removal_surfaces, CutSettings cut = {}, VitrectorSettings vitrector = {},
                  std::uint32_t aspirated_surface = kNone);

  void cut(TissueWorld& world, const CuttingPose& pose) override;
  void remove(TissueWorld& world, const RemovalRequest& request) override;

  std::uint32_t springs_opened() const { return springs_opened_; }
  // Pieces of cut an incision could not join to its crack (CutResult::gaps): 0 unless the mesh
  // changed under a crack in a way it could not follow.
  std::uint32_t gaps() const { return gaps_; }
  double removed_mass_g() const { return removed_mass_g_; }
  // Stalks (attachments between two layers) the instruments severed: the guillotine within its
  // reach, the scissors' jaws and the blades' edges wherever they swept while cutting.
  std::uint64_t stalks_cut() const { return stalks_cut_; }
  const Status& last_error() const { return last_error_; }

 private:
  void note(const CutResult& r);
  void sever_stalks_swept(TissueWorld& world, const CuttingPose& pose);
  // What one instrument cuts one surface with.
  struct Edges {
    Incision blade;
    Scissors scissors;
  };
  std::vector<std::unique_ptr<Cutter>> cutters_;
  std::vector<std::unique_ptr<Edges>> edges_;  // [instrument × cutters_.size() + surface]
  std::vector<std::unique_ptr<Vitrector>> vitrectors_;
  // Each instrument's cutting pose at the last step, for the area its edges swept since.
  struct LastPose {
    CuttingPose pose;
    bool valid = false;
  };
  std::array<LastPose, kMaxInstruments> last_pose_{};
  std::uint32_t springs_opened_ = 0, gaps_ = 0;
  double removed_mass_g_ = 0.0;
  std::uint64_t stalks_cut_ = 0;
  Status last_error_ = Status::ok();
};

}  // namespace vitreo::core
