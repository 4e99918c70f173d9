// Step stage: instruments acting inside the substeps — contact with kinematic capsules (tissue is
// pushed out, never crossed), grips (forceps grasps and laser adhesions at barycentric surface
// points), and their force estimates from the constraint multipliers. The broad phase that picks the
// candidate triangles lives in core/collision (FCL); here everything is exact and allocation-free.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/common/validate.hpp"
#include "core/tissue/contact_geometry.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

namespace {
// In a crossing, only this many radii of the axis beyond the crossing point count toward the depth
// (a long oblique shaft must not fling the triangle by its far end).
constexpr double kCrossingReachRadii = 3.0;
// A triangle this close to a capsule gets a contact term for the substep (it may move that far
// during the sweeps; instruments move ≤ 0.1 mm per 1 ms step).
constexpr double kContactReach_mm = 0.05;
// How deep the contact terms may let tissue into a capsule before the hard projection acts: their
// stiffness keeps a few mN of contact within a few µm.
constexpr double kContactSlack_mm = 0.02;
// The most the hard projection moves any corner of a triangle, in units of the depth it removes
// (project_contacts).
constexpr double kMaxLever = 2.0;
// A tip pressing tissue that lies on the wall (attached retina: its vertices are fixed) squeezes
// the tissue's thickness against the rigid choroid and sclera. A layer much thinner than the contact
// is an elastic foundation (Winkler; K. L. Johnson, Contact Mechanics, 1985): the pressure under
// each point is the confined modulus E(1−ν)/((1+ν)(1−2ν)) times the local squeeze over the
// thickness t. A spherical tip of radius R pressed δ deep touches a disc of area π·2Rδ, so the force
// is π E_c R δ² / t — gentle at first contact, 3000 µN (the excessive-force limit) at about
// 0.16 mm into a 0.25 mm retina with a 23 G tip. Past the whole thickness the tip is on the sclera:
// the contact stiffness of free tissue takes over. ν = 1/3, the spring network's.
double anchored_layer_force_un(const TissueMaterial& m, double radius_mm, double depth_mm, double rigid_un_per_mm) {
  if (!(m.thickness_mm > 0.0) || !(depth_mm > 0.0)) return 0.0;
  constexpr double nu = 1.0 / 3.0;
  const double confined_pa = m.membrane_modulus_pa_mm / m.thickness_mm * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double squeeze = std::min(depth_mm, m.thickness_mm);
  const double f = std::numbers::pi * confined_pa * radius_mm * squeeze * squeeze / m.thickness_mm;
  return f + rigid_un_per_mm * std::max(0.0, depth_mm - m.thickness_mm);
}
}  // namespace

double TissueWorld::local_pressure_on(std::uint32_t surface, std::uint32_t vertex) const {
  double p = 0.0;
  for (const auto& lf : local_forces_) {
    if (lf.d.surface != surface) continue;
    for (std::size_t i = 0; i < lf.d.vertices.size(); ++i) {
      if (lf.d.vertices[i] != vertex) continue;
      p += lf.d.pressure_pa * lf.d.scale * (lf.d.weights.empty() ? 1.0 : lf.d.weights[i]);
    }
  }
  return p;
}

Status TissueWorld::set_colliders(std::span<const ColliderCapsule> colliders) {
  if (colliders.size() > kMaxColliders) return Status::error("set_colliders: more than kMaxColliders");
  for (const auto& c : colliders) {
    if (!is_finite(c.a0) || !is_finite(c.b0) || !is_finite(c.a1) || !is_finite(c.b1) || !std::isfinite(c.radius_mm) ||
        c.radius_mm < 0.0 || c.radius_mm > 5.0) {
      return Status::error("set_colliders: non-finite or out-of-range capsule");
    }
  }
  std::copy(colliders.begin(), colliders.end(), colliders_.begin());
  collider_count_ = static_cast<std::uint32_t>(colliders.size());
  return Status::ok();
}

Status TissueWorld::set_contact_candidates(std::span<const ContactCandidate> candidates) {
  candidates_.clear();
  for (const auto& c : candidates) {
    if (candidates_.size() == candidates_.capacity()) return Status::error("set_contact_candidates: capacity exceeded");
    if (c.collider >= kMaxColliders || c.surface >= surfaces_.size() ||
        !surfaces_[c.surface]->triangle_alive(c.triangle)) {
      continue;  // stale after a topology change: dropped
    }
    candidates_.push_back(c);
  }
  return Status::ok();
}

Status TissueWorld::set_suction_fields(std::span<const SuctionField> fields) {
  if (fields.size() > kMaxSuctionFields) return Status::error("set_suction_fields: too many fields");
  suction_.clear();
  for (const auto& f : fields) {
    if (!is_finite(f.apex_mm) || !is_finite(f.axis) || !(f.axis.norm() > 0.0) || !std::isfinite(f.radius_mm) ||
        !std::isfinite(f.pressure_pa) || f.radius_mm < 0.0 || f.pressure_pa < 0.0 || f.pressure_pa > 1e5) {
      return Status::error("set_suction_fields: non-finite or out-of-range field");
    }
    SuctionField g = f;
    g.axis.normalize();
    suction_.push_back(g);
  }
  return Status::ok();
}

Vec3 TissueWorld::contact_force(std::uint32_t collider, std::uint32_t surface) const {
  if (collider >= kMaxColliders || surface >= surfaces_.size()) return Vec3::Zero();
  return contact_force_[collider * surfaces_.size() + surface];
}

Vec3 TissueWorld::contact_force(std::uint32_t collider) const {
  Vec3 f = Vec3::Zero();
  for (std::uint32_t s = 0; s < surfaces_.size(); ++s) f += contact_force(collider, s);
  return f;
}

double TissueWorld::max_contact_depth(std::uint32_t collider) const {
  return collider < kMaxColliders ? contact_depth_[collider] : 0.0;
}

std::uint32_t TissueWorld::add_grip(const GripDescription& g) {
  if (g.surface >= surfaces_.size()) return kNone;
  const Surface& s = *surfaces_[g.surface];
  if (!s.triangle_alive(g.triangle.index) || s.triangle_id(g.triangle.index) != g.triangle) return kNone;
  if (!is_finite(g.bary) || !is_finite(g.target_mm) || std::abs(g.bary.sum() - 1.0) > 1e-6 || g.bary.minCoeff() < -1e-9) {
    return kNone;
  }
  if (!(g.stiffness_un_per_mm > 0.0) || !std::isfinite(g.stiffness_un_per_mm) || !(g.break_force_un > 0.0)) return kNone;
  for (std::uint32_t i = 0; i < grips_.size(); ++i) {
    if (grips_[i].active) continue;
    grips_[i] = Grip{};
    grips_[i].d = g;
    grips_[i].previous_target = g.target_mm;
    grips_[i].active = true;
    grips_[i].vertices = s.triangle_vertices(g.triangle.index);
    grips_[i].last_point = g.bary[0] * s.position(grips_[i].vertices[0]) + g.bary[1] * s.position(grips_[i].vertices[1]) +
                           g.bary[2] * s.position(grips_[i].vertices[2]);
    grip_high_water_ = std::max(grip_high_water_, i + 1);
    for (auto v : s.triangle_vertices(g.triangle.index)) surfaces_[g.surface]->wake_vertex(v);
    return i;
  }
  return kNone;
}

Status TissueWorld::set_grip_target(std::uint32_t grip, const Vec3& target) {
  if (grip >= grips_.size() || !grips_[grip].active) return Status::error("set_grip_target: no such active grip");
  if (!is_finite(target)) return Status::error("set_grip_target: non-finite target");
  grips_[grip].d.target_mm = target;
  const Surface& s = *surfaces_[grips_[grip].d.surface];
  for (auto v : s.triangle_vertices(grips_[grip].d.triangle.index)) surfaces_[grips_[grip].d.surface]->wake_vertex(v);
  return Status::ok();
}

void TissueWorld::release_grip(std::uint32_t grip) {
  if (grip < grips_.size()) grips_[grip].active = false;
}

Vec3 TissueWorld::grip_point(std::uint32_t grip) const {
  const Grip& g = grips_.at(grip);
  const Surface& s = *surfaces_[g.d.surface];
  const auto tv = s.triangle_vertices(g.d.triangle.index);
  return g.d.bary[0] * s.position(tv[0]) + g.d.bary[1] * s.position(tv[1]) + g.d.bary[2] * s.position(tv[2]);
}

// The point terms of a substep (stage_solve.cpp): intact attachments, active grips (their targets
// interpolated from the jaws' pose at the start of the step to the end) and instrument contacts.
// A contact term is made for each candidate triangle within reach of its capsule, linearised at the
// substep's start: the closest points of the triangle and the axis (at the capsule's pose at the
// end of the substep) give the point, the push direction and the axis point to keep the capsule's
// radius from. Triangles the axis crosses are left to the hard projection (project_contacts).
void TissueWorld::add_point_terms(double fraction) {
  clear_point_terms();
  for (std::uint32_t i = 0; i < attachments_.size(); ++i) {
    const Attachment& at = attachments_[i];
    if (!at.intact) continue;
    PointTerm t{};
    t.kind = PointKind::kAttachment;
    t.owner = i;
    t.k = at.d.stiffness_un_per_mm;
    t.surface[0] = at.d.surface_a;
    t.vertex[0] = at.a.index;
    t.b[0] = 1.0;
    t.count = 1;
    if (at.d.surface_b == AttachmentDescription::kWorld) {
      t.target = at.d.world_point_mm;
    } else {
      t.surface[1] = at.d.surface_b;
      t.vertex[1] = at.b.index;
      t.b[1] = -1.0;
      t.count = 2;
      if (at.d.rest_length_mm > 0.0) {
        // A stalk: surface_a's end is held at rest_length_mm inward of its base (toward the globe's
        // centre, fixed for the substep), so the stalk keeps the layers apart and passes shear on.
        const Vec3 inward = wall_.center() - surfaces_[at.d.surface_b]->position(at.b.index);
        const double n = inward.norm();
        if (n > 1e-9) t.target = inward * (at.d.rest_length_mm / n);
      }
    }
    add_point_term(t);
  }
  for (std::uint32_t i = 0; i < grip_high_water_; ++i) {
    const Grip& g = grips_[i];
    if (!g.active || !surfaces_[g.d.surface]->triangle_alive(g.d.triangle.index)) continue;
    PointTerm t{};
    t.kind = PointKind::kGrip;
    t.owner = i;
    t.k = g.d.stiffness_un_per_mm;
    t.count = 3;
    const auto tv = surfaces_[g.d.surface]->triangle_vertices(g.d.triangle.index);
    for (std::uint32_t j = 0; j < 3; ++j) {
      t.surface[j] = g.d.surface;
      t.vertex[j] = tv[j];
      t.b[j] = g.d.bary[static_cast<Eigen::Index>(j)];
    }
    t.target = g.previous_target + fraction * (g.d.target_mm - g.previous_target);
    add_point_term(t);
  }
  struct AnchoredPress {
    double depth = 0.0;
    Vec3 normal = Vec3::Zero();
    std::uint32_t surface = 0;
  };
  std::array<AnchoredPress, kMaxColliders> anchored{};
  for (const ContactCandidate& c : candidates_) {
    const ColliderCapsule& cap = colliders_[c.collider];
    const Vec3 a = cap.a0 + fraction * (cap.a1 - cap.a0);
    const Vec3 b = cap.b0 + fraction * (cap.b1 - cap.b0);
    const Surface& s = *surfaces_[c.surface];
    const auto tv = s.triangle_vertices(c.triangle);
    const Vec3 &x0 = s.position(tv[0]), &x1 = s.position(tv[1]), &x2 = s.position(tv[2]);
    const auto st = contact::closest_segment_triangle(a, b, x0, x1, x2);
    // Within reach: the triangle may move toward the capsule during the substep's sweeps.
    if (st.crossing || !(st.distance > 1e-9) || st.distance > cap.radius_mm + kContactReach_mm) continue;
    if (s.is_fixed(tv[0]) && s.is_fixed(tv[1]) && s.is_fixed(tv[2])) {
      // Attached retina: nothing to move, but the instrument presses into the tissue's thickness.
      // One press per instrument part, at its deepest (every triangle under the tip sees it).
      if (st.distance < cap.radius_mm && cap.radius_mm - st.distance > anchored[c.collider].depth) {
        anchored[c.collider] = {cap.radius_mm - st.distance, (st.on_triangle - st.on_segment) / st.distance, c.surface};
      }
      continue;
    }
    PointTerm t{};
    t.kind = PointKind::kContact;
    t.owner = c.collider;
    t.k = settings_.contact_stiffness_un_per_mm;
    t.count = 3;
    for (std::uint32_t j = 0; j < 3; ++j) {
      t.surface[j] = c.surface;
      t.vertex[j] = tv[j];
      t.b[j] = st.bary[static_cast<Eigen::Index>(j)];
    }
    t.normal = (st.on_triangle - st.on_segment) / st.distance;
    t.target = st.on_segment;
    t.offset = cap.radius_mm;
    add_point_term(t);
  }
  for (std::uint32_t k = 0; k < collider_count_; ++k) {
    const AnchoredPress& p = anchored[k];
    if (!(p.depth > 0.0)) continue;
    const double f = anchored_layer_force_un(surfaces_[p.surface]->material(), colliders_[k].radius_mm, p.depth,
                                             settings_.contact_stiffness_un_per_mm);
    contact_force_[k * surfaces_.size() + p.surface] -= p.normal * (f / settings_.substeps);
    contact_depth_[k] = std::max(contact_depth_[k], p.depth);
  }
}

// The hard guarantee behind the contact terms: after the sweeps, any candidate triangle still
// deeper inside a capsule than kContactSlack_mm, or crossed by its axis, is pushed out (the part
// beyond the slack; crossed triangles back to the side the instrument came from), so an instrument
// never passes through tissue however fast it moves. The push's force is added to the contact
// force as the momentum it took (m Δx / h²).
void TissueWorld::project_contacts(double h, double fraction) {
  const double inv_h2 = 1.0 / (h * h);
  const double share = 1.0 / settings_.substeps;  // forces are averaged over the substeps
  for (const ContactCandidate& c : candidates_) {
    const ColliderCapsule& cap = colliders_[c.collider];
    const Vec3 a = cap.a0 + fraction * (cap.a1 - cap.a0);
    const Vec3 b = cap.b0 + fraction * (cap.b1 - cap.b0);
    const double r = cap.radius_mm;
    Surface& s = *surfaces_[c.surface];
    auto view = s.solver_view();
    const double* w = scratch_[c.surface].effective_inverse_mass.data();
    const auto tv = view.tri_v[c.triangle];
    Vec3& x0 = view.x[tv[0]];
    Vec3& x1 = view.x[tv[1]];
    Vec3& x2 = view.x[tv[2]];
    // Cheap reject: the triangle's bounding sphere against the capsule.
    const Vec3 centroid = (x0 + x1 + x2) / 3.0;
    const double tri_r2 = std::max({(x0 - centroid).squaredNorm(), (x1 - centroid).squaredNorm(), (x2 - centroid).squaredNorm()});
    double sp = 0.0, tq = 0.0;
    const double axis_d2 = contact::closest_segment_segment(a, b, centroid, centroid, sp, tq);
    const double reach = r + std::sqrt(tri_r2);
    if (axis_d2 > reach * reach) continue;

    const auto st = contact::closest_segment_triangle(a, b, x0, x1, x2);
    if (!st.crossing && st.distance >= r - kContactSlack_mm) continue;
    Vec3 tri_n = (x1 - x0).cross(x2 - x0);
    const double tri_n_len = tri_n.norm();
    if (!(tri_n_len > 0.0)) continue;
    tri_n /= tri_n_len;
    Vec3 n;  // direction the tissue is pushed (from the instrument into the tissue)
    double depth;
    if (!st.crossing && st.distance > 1e-9) {
      n = (st.on_triangle - st.on_segment) / st.distance;
      depth = r - kContactSlack_mm - st.distance;
    } else {
      // The axis crosses the triangle: push it back to the side the instrument came from.
      n = -static_cast<double>(c.side) * tri_n;
      const Vec3 u = (b - a).norm() > 0.0 ? Vec3((b - a).normalized()) : Vec3(-n);
      double beyond = 0.0;
      for (const Vec3* e : {&a, &b}) {
        const double along = (*e - st.on_segment).dot(u);
        const double clipped = std::clamp(along, -kCrossingReachRadii * r, kCrossingReachRadii * r);
        beyond = std::max(beyond, (clipped * u).dot(n));
      }
      depth = r + beyond;
    }
    const Vec3& bc = st.bary;
    const double wsum = w[tv[0]] * bc[0] * bc[0] + w[tv[1]] * bc[1] * bc[1] + w[tv[2]] * bc[2] * bc[2];
    if (wsum == 0.0) continue;
    double& deepest = contact_depth_[c.collider];
    deepest = std::max(deepest, depth);
    // A point next to a fixed vertex (an anchored rim: the gel's at the vitreous base, a traction
    // plane's edge held by the vitreous) is a lever: pushing it out by `depth` moves the free corners
    // by depth·w·b/Σwb², without bound as the point nears the fixed corner — the tissue was flung
    // tens of millimetres by a shaft passing the rim. No corner moves more than kMaxLever·depth;
    // with equal masses the lever never exceeds (1+√3)/2 ≈ 1.37, so only anchored triangles are
    // limited (they stay partly inside for the substep and the contact terms push them on).
    double lambda = depth / wsum;
    const double lever = std::max({w[tv[0]] * bc[0], w[tv[1]] * bc[1], w[tv[2]] * bc[2]}) * lambda;
    if (lever > kMaxLever * depth) lambda *= kMaxLever * depth / lever;
    x0 += (w[tv[0]] * bc[0] * lambda) * n;
    x1 += (w[tv[1]] * bc[1] * lambda) * n;
    x2 += (w[tv[2]] * bc[2] * lambda) * n;
    // Pushed by the instrument: no momentum carried into the next substep (see sweep_vertices).
    for (const auto v : tv) scratch_[c.surface].momentum[v] = Scratch::kStartDamped;
    contact_force_[c.collider * surfaces_.size() + c.surface] -= n * (lambda * inv_h2 * share);
  }
}

// A tear (or cut) that splits a gripped triangle frees its slot: the grip follows the tissue to the
// new triangle around the old one's vertices that holds the gripped point, so the jaws keep their
// hold while the tissue tears at the grasp.
void TissueWorld::rebind_grips() {
  for (std::uint32_t i = 0; i < grip_high_water_; ++i) {
    Grip& g = grips_[i];
    if (!g.active) continue;
    Surface& s = *surfaces_[g.d.surface];
    const bool current = s.triangle_alive(g.d.triangle.index) && s.triangle_id(g.d.triangle.index) == g.d.triangle;
    if (current) {
      const auto tv = s.triangle_vertices(g.d.triangle.index);
      g.last_point = g.d.bary[0] * s.position(tv[0]) + g.d.bary[1] * s.position(tv[1]) + g.d.bary[2] * s.position(tv[2]);
      continue;
    }
    double best = std::numeric_limits<double>::infinity();
    std::uint32_t best_t = kNone;
    Vec3 best_bary = Vec3::Zero();
    for (auto v : g.vertices) {
      if (!s.vertex_alive(v)) continue;
      s.for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) {
        const auto tv = s.triangle_vertices(t);
        Vec3 bary;
        const Vec3 q = contact::closest_on_triangle(g.last_point, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), bary);
        const double d = (q - g.last_point).squaredNorm();
        if (d < best) {
          best = d;
          best_t = t;
          best_bary = bary;
        }
      });
    }
    if (best_t == kNone) continue;  // break_grips reports it next step
    g.d.triangle = s.triangle_id(best_t);
    g.d.bary = best_bary;
    g.vertices = s.triangle_vertices(best_t);
  }
}

void TissueWorld::break_grips() {
  for (std::uint32_t i = 0; i < grip_high_water_; ++i) {
    Grip& g = grips_[i];
    if (!g.active) continue;
    const bool stale = !surfaces_[g.d.surface]->triangle_alive(g.d.triangle.index) ||
                       surfaces_[g.d.surface]->triangle_id(g.d.triangle.index) != g.d.triangle;
    if (stale || g.peak_force_un > g.d.break_force_un) {
      g.active = false;
      if (events_.size() < events_.capacity()) {
        events_.push_back({TissueEventKind::kGripBroken, g.d.surface, i, g.d.target_mm, g.peak_force_un});
      }
    }
  }
}

}  // namespace vitreo::core
