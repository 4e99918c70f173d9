#include "core/instruments/topology_adapter.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/topology/geometry.hpp"

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

namespace {

// What a cutting pose's edges are: a blade's one edge; a scissors' two jaws, hinge to tip.
struct EdgeSegments {
  std::array<Vec3, 2> from, to;
  int count = 0;
};

EdgeSegments edge_segments(const CuttingPose& p) {
  EdgeSegments e;
  if (p.kind != InstrumentKind::kScissors) {
    e.from[0] = p.a;
    e.to[0] = p.b;
    e.count = 1;
    return e;
  }
  // As Scissors::set_pose lays the jaws: at ± half the opening about the bisector, in the plane.
  const Vec3 n = p.normal.normalized();
  const Vec3 u = (p.bisector - p.bisector.dot(n) * n).normalized();
  const Vec3 w = n.cross(u);
  const double half = 0.5 * p.opening_rad;
  for (int k = 0; k < 2; ++k) {
    const double side = k == 0 ? 1.0 : -1.0;
    e.from[k] = p.hinge;
    e.to[k] = p.hinge + p.jaw_length_mm * (std::cos(half) * u + side * std::sin(half) * w);
  }
  e.count = 2;
  return e;
}

}  // namespace

void TopologyAdapter::sever_stalks_swept(TissueWorld& world, const CuttingPose& pose) {
  LastPose& last = last_pose_[pose.instrument];
  const bool had = last.valid;
  last.valid = pose.in_eye;
  if (!pose.in_eye) return;
  const CuttingPose before = last.pose;
  last.pose = pose;
  if (!had || before.kind != pose.kind) return;
  // Scissors cut only while they close; a blade cuts wherever its edge moves.
  if (pose.kind == InstrumentKind::kScissors && !(pose.opening_rad < before.opening_rad - 1e-9)) return;
  const EdgeSegments e0 = edge_segments(before), e1 = edge_segments(pose);
  // The area each edge swept this step: the quad between its old and new position, as two triangles.
  std::array<std::array<Vec3, 3>, 4> swept;
  int n = 0;
  for (int k = 0; k < e1.count; ++k) {
    swept[static_cast<std::size_t>(n++)] = {e0.from[k], e0.to[k], e1.to[k]};
    swept[static_cast<std::size_t>(n++)] = {e0.from[k], e1.to[k], e1.from[k]};
  }
  stalks_cut_ += world.cut_attachments_if([&](const Vec3& top, const Vec3& base) {
    double s = 0.0;
    std::array<double, 3> bary{};
    for (int t = 0; t < n; ++t) {
      const auto& tri = swept[static_cast<std::size_t>(t)];
      if (topology::segment_triangle(base, top, tri[0], tri[1], tri[2], s, bary)) return true;
    }
    return false;
  });
}

void TopologyAdapter::cut(TissueWorld& world, const CuttingPose& pose) {
  if (pose.instrument >= kMaxInstruments) {
    last_error_ = Status::error("topology adapter: more cutting instruments than it has room for");
    return;
  }
  // The edges cut the stalks that bridge two layers wherever they sweep: scissors slid between an
  // elevated membrane and the retina and closed there delaminate it (horizontal scissors).
  sever_stalks_swept(world, pose);
  if (cutters_.empty()) return;
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
