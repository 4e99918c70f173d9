#include "core/instruments/topology_adapter.hpp"

#include <algorithm>

namespace vitreo::core {

TopologyAdapter::TopologyAdapter(TissueWorld& world, const std::vector<std::uint32_t>& cut_surfaces,
                                 const std::vector<std::uint32_t>& removal_surfaces, CutSettings cut, VitrectorSettings vitrector,
                                 std::uint32_t aspirated_surface) {
  for (auto s : cut_surfaces) {
    if (s >= world.surface_count()) throw InvalidArgument("topology adapter: cut surface out of range");
    cutters_.push_back(std::make_unique<Cutter>(world.surface(s), cut));
  }
  for (std::uint32_t i = 0; i < kMaxInstruments; ++i) {
    for (auto& c : cutters_) edges_.push_back(std::make_unique<Edges>(Edges{Incision(*c), Scissors(*c, 1.0)}));
  }
  vitrector.removal_radius_mm = std::max(vitrector.removal_radius_mm, 1e-3);
  for (auto s : removal_surfaces) {
    if (s >= world.surface_count()) throw InvalidArgument("topology adapter: removal surface out of range");
    const RemovalModel model = s == aspirated_surface ? RemovalModel::kAspirate : RemovalModel::kClip;
    vitrectors_.push_back(std::make_unique<Vitrector>(world.surface(s), vitrector, model));
  }
}

void TopologyAdapter::note(const CutResult& r) {
  if (!r.status) last_error_ = r.status;
  springs_opened_ += r.springs_opened;
  gaps_ += r.gaps;
}

void TopologyAdapter::cut(TissueWorld& /*world*/, const CuttingPose& pose) {
  if (cutters_.empty()) return;
  if (pose.instrument >= kMaxInstruments) {
    last_error_ = Status::error("topology adapter: more cutting instruments than it has room for");
    return;
  }
  for (std::size_t k = 0; k < cutters_.size(); ++k) {
    Edges& e = *edges_[pose.instrument * cutters_.size() + k];
    if (!pose.in_eye) {  // the instrument left the eye: its cuts end where it last was
      note(e.blade.end());
      note(e.scissors.release());
      continue;
    }
    if (pose.kind == InstrumentKind::kScissors) {
      if (const Status s = e.scissors.set_blade_length(pose.jaw_length_mm); !s) {
        last_error_ = s;
        continue;
      }
      note(e.scissors.set_pose(pose.hinge, pose.bisector, pose.normal, pose.opening_rad));
    } else {
      // A blade moved along its own edge (plunging straight in) sweeps no area: the incision
      // records the pose and cuts nothing new.
      note(e.blade.advance({pose.a, pose.b}));
    }
  }
}

void TopologyAdapter::remove(TissueWorld& world, const RemovalRequest& request) {
  bool cut = false;
  double reach_mm = 0.0;
  for (auto& v : vitrectors_) {
    Status s = v->set_pose(request.port_center_mm, request.port_normal);
    if (s) s = v->set_cut_rate(std::min(request.cut_rate_cpm, v->settings().max_cut_rate_cpm));
    if (s) s = v->set_vacuum(std::clamp(request.vacuum, 0.0, 1.0));
    if (!s) {
      last_error_ = s;
      continue;
    }
    const VitrectorStepResult r = v->apply(request.dt_s);
    if (!r.status) last_error_ = r.status;
    removed_mass_g_ += r.removed_mass_g;
    cut = cut || r.cut;
    reach_mm = std::max(reach_mm, v->settings().removal_radius_mm);
  }
  // The guillotine also cuts the stalks (pegs) that bridge two layers within its reach: a
  // vitrector slid between an elevated membrane and the retina delaminates it.
  if (cut) stalks_cut_ += world.cut_attachments_in(request.port_center_mm, request.port_normal, reach_mm);
}

}  // namespace vitreo::core
