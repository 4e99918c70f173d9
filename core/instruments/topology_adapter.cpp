#include "core/instruments/topology_adapter.hpp"

namespace vitreo::core {

TopologyAdapter::TopologyAdapter(TissueWorld& world, const std::vector<std::uint32_t>& cut_surfaces,
                                 const std::vector<std::uint32_t>& removal_surfaces, CutSettings cut, VitrectorSettings vitrector) {
  for (auto s : cut_surfaces) {
    if (s >= world.surface_count()) throw InvalidArgument("topology adapter: cut surface out of range");
    cutters_.push_back(std::make_unique<Cutter>(world.surface(s), cut));
  }
  vitrector.removal_radius_mm = std::max(vitrector.removal_radius_mm, 1e-3);
  for (auto s : removal_surfaces) {
    if (s >= world.surface_count()) throw InvalidArgument("topology adapter: removal surface out of range");
    vitrectors_.push_back(std::make_unique<Vitrector>(world.surface(s), vitrector));
  }
}

void TopologyAdapter::cut(TissueWorld& /*world*/, const BladeSweep& sweep) {
  // A blade moved along its own edge (plunging straight in) sweeps no area and cuts nothing new.
  const double area = 0.5 * (sweep.b1 - sweep.a0).cross(sweep.a1 - sweep.b0).norm();
  if (cutters_.empty() || !(area > 1e-9)) return;
  for (auto& c : cutters_) {
    const CutResult r = c->sweep({sweep.a0, sweep.b0}, {sweep.a1, sweep.b1});
    if (!r.status) last_error_ = r.status;
    springs_opened_ += r.springs_opened;
  }
}

void TopologyAdapter::remove(TissueWorld& /*world*/, const RemovalRequest& request) {
  for (auto& v : vitrectors_) {
    Status s = v->set_pose(request.port_center_mm, request.port_normal);
    if (s) s = v->set_cut_rate(std::min(request.cut_rate_cpm, v->settings().max_cut_rate_cpm));
    if (!s) {
      last_error_ = s;
      continue;
    }
    const VitrectorStepResult r = v->apply(request.dt_s);
    if (!r.status) last_error_ = r.status;
    removed_mass_g_ += r.removed_mass_g;
  }
}

}  // namespace vitreo::core
