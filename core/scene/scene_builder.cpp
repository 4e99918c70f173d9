#include "core/scene/scene_builder.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>
#include <utility>

#include "core/common/validate.hpp"
#include "core/topology/clean_topology.hpp"
#include "core/common/units.hpp"

namespace vitreo::core {

namespace {

using units::kDeg;
using units::kPi;

// Tangent frame on the wall at a fundus location: e_merid points anterior (increasing polar angle),
// e_circ along increasing azimuth, inward toward the globe centre.
struct Frame {
  Vec3 c, e_merid, e_circ, inward;
};

Frame frame_at(const EyeModel& eye, const FundusLocation& l) {
  const double th = l.polar_deg * kDeg, ph = l.azimuth_deg * kDeg;
  Frame f;
  f.c = eye.wall_point(th, ph);
  f.inward = -f.c.normalized();
  f.e_merid = (eye.wall_point(th + 1e-4, ph) - eye.wall_point(th - 1e-4, ph)).normalized();
  f.e_circ = f.inward.cross(f.e_merid).normalized();
  // Right-handed so that e_circ points toward increasing azimuth.
  const Vec3 toward_phi(-std::sin(ph), std::cos(ph), 0.0);
  if (f.e_circ.dot(toward_phi) < 0.0) f.e_circ = -f.e_circ;
  return f;
}

Vec3 on_wall(const EyeModel& eye, const Frame& f, double u, double w) {
  const Vec3 d = (f.c + u * f.e_circ + w * f.e_merid).normalized();
  return d * eye.wall.radius_toward(d);
}

Vec2 local(const Frame& f, const Vec3& p) { return {(p - f.c).dot(f.e_circ), (p - f.c).dot(f.e_merid)}; }

bool inside_polygon(const std::vector<Vec2>& poly, const Vec2& p) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) in = !in;
  }
  return in;
}

// Nearest-point queries over a fixed point set (a uniform hash grid).
class PointGrid {
 public:
  PointGrid(const std::vector<Vec3>& points, double cell) : points_(points), cell_(cell) {
    for (std::uint32_t i = 0; i < points.size(); ++i) cells_[key(index(points[i]))].push_back(i);
  }
  std::uint32_t nearest(const Vec3& p, double* distance = nullptr) const {
    const auto c = index(p);
    std::uint32_t best = kNone;
    double best_d2 = 1e300;
    for (int r = 1; r <= 64; ++r) {
      for (int dx = -r; dx <= r; ++dx) {
        for (int dy = -r; dy <= r; ++dy) {
          for (int dz = -r; dz <= r; ++dz) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r && r > 1) continue;
            const auto it = cells_.find(key({c[0] + dx, c[1] + dy, c[2] + dz}));
            if (it == cells_.end()) continue;
            for (auto i : it->second) {
              const double d2 = (points_[i] - p).squaredNorm();
              if (d2 < best_d2 || (d2 == best_d2 && i < best)) {
                best_d2 = d2;
                best = i;
              }
            }
          }
        }
      }
      // Anything in a further ring is at least (r)·cell away.
      if (best != kNone && std::sqrt(best_d2) <= r * cell_) break;
    }
    if (distance) *distance = std::sqrt(best_d2);
    return best;
  }

 private:
  std::array<std::int64_t, 3> index(const Vec3& p) const {
    return {static_cast<std::int64_t>(std::floor(p.x() / cell_)), static_cast<std::int64_t>(std::floor(p.y() / cell_)),
            static_cast<std::int64_t>(std::floor(p.z() / cell_))};
  }
  static std::uint64_t key(const std::array<std::int64_t, 3>& c) {
    return (static_cast<std::uint64_t>(c[0] + 4096) << 26) ^ (static_cast<std::uint64_t>(c[1] + 4096) << 13) ^
           static_cast<std::uint64_t>(c[2] + 4096);
  }
  const std::vector<Vec3>& points_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
};

double mean_edge(const TriangleMesh& m) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      sum += (m.positions[t[static_cast<std::size_t>(k)]] - m.positions[t[static_cast<std::size_t>((k + 1) % 3)]]).norm();
      ++n;
    }
  }
  return n ? sum / static_cast<double>(n) : 1.0;
}

// Cuts a U-shaped slit into the retina mesh along mesh edges and curls the flap inward (3-D flap).
BuiltTear cut_u_tear(TriangleMesh& mesh, const EyeModel& eye, const TearSpec& t) {
  const std::string what = "tear '" + t.name + "'";
  const Frame f = frame_at(eye, t.center);
  const double W = t.width_mm, L = t.length_mm;
  const double anterior_end = t.center.polar_deg * kDeg + 0.5 * L / (eye.fundus_extent_mm / eye.ora_polar_rad);
  if (anterior_end > eye.ora_polar_rad - 0.02) throw InvalidArgument(what + ": reaches the ora serrata");

  // The U, from the left hinge corner down, round the apex (posterior) and up to the right corner.
  std::vector<Vec2> curve;
  const double wc = -0.5 * L + 0.5 * W;
  const double step = 0.02;
  for (double w = 0.5 * L; w > wc; w -= step) curve.emplace_back(-0.5 * W, w);
  for (double a = kPi; a <= 2.0 * kPi + 1e-9; a += step / (0.5 * W)) curve.emplace_back(0.5 * W * std::cos(a), wc + 0.5 * W * std::sin(a));
  for (double w = wc; w <= 0.5 * L + 1e-9; w += step) curve.emplace_back(0.5 * W, w);

  // Candidate vertices near the tear.
  const double reach = L + W + 1.0;
  std::vector<std::uint32_t> near;
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
    if ((mesh.positions[v] - f.c).norm() < reach) near.push_back(v);
  }
  std::vector<std::vector<std::uint32_t>> tris_of(mesh.positions.size());
  std::vector<std::vector<std::uint32_t>> nbr(mesh.positions.size());
  for (std::uint32_t ti = 0; ti < mesh.triangles.size(); ++ti) {
    const auto& tr = mesh.triangles[ti];
    for (int k = 0; k < 3; ++k) {
      const auto a = tr[static_cast<std::size_t>(k)], b = tr[static_cast<std::size_t>((k + 1) % 3)];
      tris_of[a].push_back(ti);
      if (std::find(nbr[a].begin(), nbr[a].end(), b) == nbr[a].end()) nbr[a].push_back(b);
      if (std::find(nbr[b].begin(), nbr[b].end(), a) == nbr[b].end()) nbr[b].push_back(a);
    }
  }
  const auto nearest = [&](const Vec3& p) {
    std::uint32_t best = kNone;
    double bd = 1e300;
    for (auto v : near) {
      const double d = (mesh.positions[v] - p).squaredNorm();
      if (d < bd) {
        bd = d;
        best = v;
      }
    }
    return best;
  };
  std::vector<std::uint32_t> path;
  for (const auto& q : curve) {
    const Vec3 target = on_wall(eye, f, q.x(), q.y());
    const std::uint32_t goal = nearest(target);
    if (goal == kNone) throw InvalidArgument(what + ": outside the retina");
    if (path.empty()) {
      path.push_back(goal);
      continue;
    }
    // Walk along mesh edges to the goal so the slit follows edges.
    for (int guard = 0; path.back() != goal && guard < 64; ++guard) {
      const auto cur = path.back();
      std::uint32_t next = kNone;
      double nd = (mesh.positions[cur] - mesh.positions[goal]).norm();
      for (auto n : nbr[cur]) {
        const double d = (mesh.positions[n] - mesh.positions[goal]).norm();
        if (d < nd) {
          nd = d;
          next = n;
        }
      }
      if (next == kNone) break;
      path.push_back(next);
    }
    // Remove loops: a vertex met again closes a loop that is cut away.
    const auto last = path.back();
    const auto first = std::find(path.begin(), path.end() - 1, last);
    if (first != path.end() - 1) path.erase(first + 1, path.end());
  }
  if (path.size() < 4) throw InvalidArgument(what + ": too small for the mesh resolution (raise retina_vertices or the size)");

  std::vector<Vec2> poly;
  for (auto v : path) poly.push_back(local(f, mesh.positions[v]));
  std::vector<std::uint8_t> on_path(mesh.positions.size(), 0);
  for (auto v : path) on_path[v] = 1;

  BuiltTear out;
  out.name = t.name;
  std::vector<std::uint32_t> flap;
  for (std::size_t i = 1; i + 1 < path.size(); ++i) {
    const auto v = path[i];
    std::vector<std::uint32_t> inside;
    for (auto ti : tris_of[v]) {
      const auto& tr = mesh.triangles[ti];
      const Vec3 centroid = (mesh.positions[tr[0]] + mesh.positions[tr[1]] + mesh.positions[tr[2]]) / 3.0;
      if (inside_polygon(poly, local(f, centroid))) inside.push_back(ti);
    }
    if (inside.empty() || inside.size() == tris_of[v].size()) continue;
    const auto dup = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.push_back(mesh.positions[v]);
    if (!mesh.surface_coords.empty()) mesh.surface_coords.push_back(mesh.surface_coords[v]);
    for (auto ti : inside) {
      for (auto& c : mesh.triangles[ti]) {
        if (c == v) c = dup;
      }
    }
    flap.push_back(dup);
    ++out.cut_vertices;
  }
  if (out.cut_vertices < 2) throw InvalidArgument(what + ": too small for the mesh resolution (raise retina_vertices or the size)");
  for (auto v : near) {
    if (!on_path[v] && inside_polygon(poly, local(f, mesh.positions[v]))) flap.push_back(v);
  }
  // Curl: lift grows from the hinge (anterior) to the apex (posterior).
  for (auto v : flap) {
    const Vec2 q = local(f, mesh.positions[v]);
    const double s = std::clamp((0.5 * L - q.y()) / L, 0.0, 1.0);
    mesh.positions[v] += -mesh.positions[v].normalized() * (t.lift_mm * s * s);
  }
  std::sort(flap.begin(), flap.end());
  out.flap_vertices = std::move(flap);
  return out;
}

// A case gives an attachment's stiffness and break force as they are at the resolution the cases are
// written for (kReferenceRetinaVertices, the rig's 5k). An attachment stands for the tissue around
// it, stride vertices' worth; at N retina vertices a vertex covers 5000/N of the area it covers at
// 5k, and so does each attachment (membranes and the gel's cortex are meshed at the retina's
// resolution). Springs in parallel: the stiffness and break force per attachment scale by that
// share, so the adhesion per mm² — the tissue's property — and the force a peel takes are the same
// at any resolution. At 5k the factor is exactly 1.
constexpr double kReferenceRetinaVertices = 5000.0;
double attachment_area_scale(const EyeModel& eye) { return kReferenceRetinaVertices / eye.parameters.retina_vertices; }

bool is_strong(const MembraneSpec& m, std::uint32_t index) {
  switch (m.strength) {
    case AttachmentStrength::kWeak: return false;
    case AttachmentStrength::kStrong: return true;
    case AttachmentStrength::kMixed: {
      if (m.strong_fraction <= 0.0) return false;
      const auto every = static_cast<std::uint32_t>(std::max(1.0, std::round(1.0 / m.strong_fraction)));
      return index % every == 0;
    }
  }
  return false;
}

// Under a traction membrane the subretinal fluid carries this share of the intraocular pressure
// at most: the traction holds the retina up against the rest, and once it is cut the retina settles
// back onto the pigment epithelium, whose pump draws the fluid away (a share of 1 would leave a cut
// detachment standing wherever it was, with nothing to bring it down).
constexpr double kSubretinalSupport = 0.9;

BuiltMembrane build_membrane(Scene& scene, const TriangleMesh& retina_mesh, const MembraneSpec& spec) {
  const EyeModel& eye = scene.eye;
  TissueWorld& world = scene.world;
  const std::string what = "membrane '" + spec.name + "'";
  BuiltMembrane out;
  out.name = spec.name;
  const Frame f = frame_at(eye, spec.center);
  const Vec2 cf = eye.fundus_coords(f.c);
  const double sc = cf.norm();
  const double phc = spec.center.azimuth_deg * kDeg;
  const double disc_reach = eye.parameters.optic_disc_radius_mm + 0.6;

  // The membrane's region in fundus coordinates (the epiretinal membrane also covers the disc rim:
  // see in_region below).
  const double ring_r = eye.fundus_extent_mm / eye.ora_polar_rad;
  const auto in_region_q = [&](const Vec2& q) {
    const double s = q.norm();
    const double phi = std::atan2(q.y(), q.x());
    const double dphi = std::abs(std::remainder(phi - phc, 2.0 * kPi));
    const double circ_len = dphi * ring_r * std::sin(std::max(1e-3, s / ring_r));
    switch (spec.kind) {
      case MembraneKind::kEpiretinal: return (q - cf).norm() < spec.size_mm;
      case MembraneKind::kCircumferential: return std::abs(s - sc) < 0.5 * spec.width_mm && circ_len < 0.5 * spec.size_mm;
      case MembraneKind::kAnteroposterior:
        return s > sc && s < std::min(sc + spec.size_mm, eye.fundus_extent_mm - 0.3) && circ_len < 0.5 * spec.width_mm;
      case MembraneKind::kPerpendicular: return false;
    }
    return false;
  };

  SurfaceDescription d;
  d.material = scene.description.materials.membrane;
  d.material.name = spec.name;
  d.contained_by_globe = true;
  std::vector<std::uint32_t> from_retina;  // per membrane vertex, kNone for the perpendicular sheet
  std::vector<std::uint8_t> near_disc, fixed;

  if (spec.kind == MembraneKind::kPerpendicular) {
    // A plane standing on the retina along the circumferential direction, its far edge held by the
    // (condensed) vitreous: contraction pulls the retina toward the centre.
    const double h = std::max(0.3, mean_edge(retina_mesh));
    const int nu = std::max(2, static_cast<int>(std::ceil(spec.size_mm / h))) + 1;
    const int nh = std::max(2, static_cast<int>(std::ceil(spec.height_mm / h))) + 1;
    PointGrid grid(retina_mesh.positions, 1.0);
    std::vector<std::uint8_t> used(retina_mesh.positions.size(), 0);
    for (int j = 0; j < nh; ++j) {
      for (int i = 0; i < nu; ++i) {
        const double u = -0.5 * spec.size_mm + spec.size_mm * i / (nu - 1);
        Vec3 base = on_wall(eye, f, u, 0.0);
        std::uint32_t r = kNone;
        if (j == 0) {
          r = grid.nearest(base);
          if (used[r]) {
            r = kNone;
          } else {
            used[r] = 1;
            base = retina_mesh.positions[r];
          }
        }
        d.mesh.positions.push_back(base + (-base.normalized()) * (spec.height_mm * j / (nh - 1)));
        from_retina.push_back(r);
        near_disc.push_back(0);
        fixed.push_back(j == nh - 1 ? 1 : 0);
      }
    }
    for (int j = 0; j + 1 < nh; ++j) {
      for (int i = 0; i + 1 < nu; ++i) {
        const auto a = static_cast<std::uint32_t>(j * nu + i), b = a + 1, c = a + static_cast<std::uint32_t>(nu), e = c + 1;
        d.mesh.triangles.push_back({a, b, e});
        d.mesh.triangles.push_back({a, e, c});
      }
    }
  } else {
    const auto in_region = [&](const Vec3& p) {
      return in_region_q(eye.fundus_coords(p)) ||
             (spec.kind == MembraneKind::kEpiretinal && (p - eye.optic_disc_mm).norm() < disc_reach);
    };
    std::vector<std::uint32_t> to_m(retina_mesh.positions.size(), kNone);
    for (const auto& t : retina_mesh.triangles) {
      if (!(in_region(retina_mesh.positions[t[0]]) && in_region(retina_mesh.positions[t[1]]) &&
            in_region(retina_mesh.positions[t[2]]))) {
        continue;
      }
      std::array<std::uint32_t, 3> mt{};
      for (std::size_t k = 0; k < 3; ++k) {
        if (to_m[t[k]] == kNone) {
          to_m[t[k]] = static_cast<std::uint32_t>(d.mesh.positions.size());
          const Vec3& p = retina_mesh.positions[t[k]];
          from_retina.push_back(t[k]);
          near_disc.push_back((p - eye.optic_disc_mm).norm() < disc_reach ? 1 : 0);
          const bool at_base = spec.kind == MembraneKind::kAnteroposterior &&
                               eye.fundus_coords(p).norm() > eye.fundus_extent_mm - eye.parameters.vitreous_base_mm;
          fixed.push_back(at_base ? 1 : 0);
          // Anteroposterior traction: the band's anterior end is held by the vitreous base, standing
          // inward of the retina (anterior PVR), so contraction pulls the retina forward and inward.
          // Elsewhere the band stands spec.elevation_mm off the retina on its stalks (0: on it).
          d.mesh.positions.push_back(p - p.normalized() * (at_base ? spec.height_mm : spec.elevation_mm));
          if (at_base) from_retina.back() = kNone;
        }
        mt[k] = to_m[t[k]];
      }
      d.mesh.triangles.push_back(mt);
    }
  }
  if (d.mesh.triangles.empty()) throw InvalidArgument(what + ": covers no retina (check centre and size)");
  out.surface = world.add_surface(d);
  Surface& ms = world.surface(out.surface);
  for (std::uint32_t v = 0; v < fixed.size(); ++v) {
    if (fixed[v]) (void)ms.set_fixed(ms.vertex_id(v), true);
  }

  // Instance-vertex attachments. The perpendicular plane is attached at every base vertex, and an
  // epiretinal membrane at every vertex over the disc rim (strong unless the case makes them all
  // weak: a membrane is cut off the disc, not peeled off it); each of
  // those stands for its vertex's share of the tissue (attachment_area_scale). Everywhere else a
  // membrane is attached at the sites of a square lattice of pitch attachment_spacing_mm in fundus
  // coordinates, centred on the membrane's centre, each site on the free membrane vertex nearest it:
  // the number, place, strength and numbering of the attachments — a band's stalks — are then the
  // same at every mesh resolution, so the pegs a script cuts at 5k are the pegs of the case's 20k,
  // and each carries the force the case gives (it stands for spacing² of tissue at any mesh).
  out.first_attachment = world.attachment_count();
  const Surface& retina = world.surface(scene.retina);
  auto attach = [&](std::uint32_t v, bool strong, double scale) {
    AttachmentDescription a;
    a.surface_a = out.surface;
    a.vertex_a = v;
    a.surface_b = scene.retina;
    a.vertex_b = from_retina[v];
    a.stiffness_un_per_mm = 2e3 * scale;
    a.break_force_un = (strong ? spec.strong_break_force_un : spec.weak_break_force_un) * scale;
    a.rest_length_mm = spec.elevation_mm;
    world.add_attachment(a);
    ++out.attachment_count;
    if (strong) ++out.strong_attachments;
    return world.attachment_count() - 1;
  };
  std::vector<std::uint8_t> taken(from_retina.size(), 0);
  const auto free_vertex = [&](std::uint32_t v) { return from_retina[v] != kNone && !fixed[v] && !retina.is_fixed(from_retina[v]); };
  if (spec.kind == MembraneKind::kPerpendicular) {
    for (std::uint32_t v = 0; v < from_retina.size(); ++v) {
      if (free_vertex(v)) (void)attach(v, is_strong(spec, out.attachment_count), attachment_area_scale(eye));
    }
  } else {
    const auto disc_site = [&](const Vec2& q) {
      return spec.kind == MembraneKind::kEpiretinal && (q - eye.optic_disc_fundus_mm).norm() < disc_reach;
    };
    const auto on_disc_rim = [&](std::uint32_t v) { return spec.kind == MembraneKind::kEpiretinal && near_disc[v] != 0; };
    // The sites: every lattice point in the membrane's region (the anterior end a band's base holds
    // and the disc rim excluded), numbered row by row — from the description alone, not the mesh.
    const double a = spec.attachment_spacing_mm;
    const int reach = static_cast<int>(std::ceil((spec.size_mm + spec.width_mm + 1.0) / a));
    const double base_s = eye.fundus_extent_mm - eye.parameters.vitreous_base_mm;
    std::vector<Vec2> sites;
    for (int j = -reach; j <= reach; ++j) {
      for (int i = -reach; i <= reach; ++i) {
        const Vec2 q = cf + a * Vec2(i, j);
        if (!in_region_q(q) || disc_site(q)) continue;
        if (spec.kind == MembraneKind::kAnteroposterior && q.norm() > base_s) continue;
        sites.push_back(q);
      }
    }
    std::vector<Vec2> where(from_retina.size());
    for (std::uint32_t v = 0; v < from_retina.size(); ++v) {
      if (from_retina[v] != kNone) where[v] = eye.fundus_coords(retina_mesh.positions[from_retina[v]]);
    }
    out.sites.assign(sites.size(), kNone);
    for (std::size_t k = 0; k < sites.size(); ++k) {
      // The nearest free vertex not already holding a site, within the site's cell and a bit.
      std::uint32_t best = kNone;
      double best_d = 0.75 * a;
      for (std::uint32_t v = 0; v < from_retina.size(); ++v) {
        if (taken[v] || !free_vertex(v) || on_disc_rim(v)) continue;
        const double dist = (where[v] - sites[k]).norm();
        if (dist < best_d) best_d = dist, best = v;
      }
      if (best == kNone) continue;  // no vertex of this mesh near the site (a coarse mesh's edge)
      taken[best] = 1;
      const bool strong = is_strong(spec, static_cast<std::uint32_t>(k));
      out.sites[k] = attach(best, strong, 1.0);
    }
    if (spec.kind == MembraneKind::kEpiretinal) {
      for (std::uint32_t v = 0; v < from_retina.size(); ++v) {
        if (from_retina[v] != kNone && !fixed[v] && on_disc_rim(v)) {
          (void)attach(v, spec.strength != AttachmentStrength::kWeak, attachment_area_scale(eye));
        }
      }
    }
  }
  if (out.attachment_count == 0) throw InvalidArgument(what + ": no attachment to the retina (raise its size)");

  if (spec.detach_radius_mm > 0.0) {
    std::vector<Vec3> pts;
    for (std::uint32_t v = 0; v < from_retina.size(); ++v) pts.push_back(ms.position(v));
    PointGrid grid(pts, 1.0);
    const Surface& rs = world.surface(scene.retina);
    LocalForceDescription lf;
    lf.name = spec.name + ".subretinal";
    lf.surface = scene.retina;
    lf.pressure_pa = world.environment().intraocular_pressure_pa;
    for (std::uint32_t v = 0; v < rs.vertex_slots(); ++v) {
      if (!rs.vertex_alive(v) || rs.is_fixed(v)) continue;
      double dist = 0.0;
      (void)grid.nearest(rs.position(v), &dist);
      if (dist < spec.detach_radius_mm) {
        const double u = dist / spec.detach_radius_mm;
        lf.vertices.push_back(v);
        lf.weights.push_back(std::clamp(1.5 * (1.0 - u * u), 0.0, kSubretinalSupport));
      }
    }
    if (!lf.vertices.empty()) out.detachment_force = world.add_local_force(lf);
  }

  // Contraction (thesis ch. 2.4: rest lengths scaled down).
  // An epiretinal membrane contracts in its own plane, every way. The traction bands and the
  // perpendicular plane contract along their fibres: circumferential bands along the circle,
  // anteroposterior bands along the meridian, and the plane of condensed vitreous toward the
  // globe's centre (its height), which lifts the retina without puckering it along the plane's base.
  if (spec.kind == MembraneKind::kEpiretinal) {
    const Status st = ms.set_surface_traction(spec.rest_length_scale);
    if (!st) throw InvalidArgument(what + ": " + st.message());
  } else {
    for (std::uint32_t e = 0; e < ms.edge_slots(); ++e) {
      if (!ms.edge_alive(e)) continue;
      const auto [a, b] = ms.edge_vertices(e);
      const Vec3 mid = 0.5 * (ms.position(a) + ms.position(b));
      const Vec3 dir = (ms.position(b) - ms.position(a)).normalized();
      const Vec3 e_phi = Vec3(-mid.y(), mid.x(), 0.0).normalized();
      const double along_circ = std::abs(dir.dot(e_phi));
      const double along_radius = std::abs(dir.dot((mid - eye.wall.center()).normalized()));
      const bool aligned = spec.kind == MembraneKind::kCircumferential ? along_circ > 0.7
                           : spec.kind == MembraneKind::kPerpendicular ? along_radius > 0.7
                                                                       : along_circ < 0.5;
      if (aligned) {
        const Status st = ms.set_edge_traction(ms.edge_id(e), spec.rest_length_scale);
        if (!st) throw InvalidArgument(what + ": " + st.message());
      }
    }
  }
  return out;
}

Guide build_guide(const Scene& scene, const GuideSpec& g) {
  const EyeModel& eye = scene.eye;
  Guide out{g.name, g.kind, {}};
  if (g.kind == GuideKind::kLaserRing) {
    FundusLocation c = g.center;
    if (!g.around.empty()) {
      for (const auto& t : scene.description.tears) {
        if (t.name == g.around) c = t.center;
      }
    }
    const Frame f = frame_at(eye, c);
    for (int i = 0; i <= 64; ++i) {
      const double a = 2.0 * kPi * i / 64;
      out.polyline_mm.push_back(on_wall(eye, f, g.radius_mm * std::cos(a), g.radius_mm * std::sin(a)));
    }
  } else if (g.kind == GuideKind::kTarget) {
    // Targets are points, one per listed location, in order (no line between them).
    for (const auto& p : g.points) out.polyline_mm.push_back(wall_point_at(eye, p));
  } else {
    for (std::size_t i = 0; i + 1 < g.points.size(); ++i) {
      const auto& a = g.points[i];
      const auto& b = g.points[i + 1];
      for (int k = 0; k < 16; ++k) {
        const double s = k / 16.0;
        out.polyline_mm.push_back(eye.wall_point((a.polar_deg + s * (b.polar_deg - a.polar_deg)) * kDeg,
                                                 (a.azimuth_deg + s * (b.azimuth_deg - a.azimuth_deg)) * kDeg));
      }
    }
    out.polyline_mm.push_back(wall_point_at(eye, g.points.back()));
  }
  // Lift off the wall by half a retina so the line lies on the retina's surface.
  for (auto& p : out.polyline_mm) p -= p.normalized() * (0.5 * eye.parameters.retina_thickness_mm);
  return out;
}

TissueWorld make_world(const SceneDescription& d, const EyeModel& eye) {
  Environment env;
  env.intraocular_pressure_pa = units::mmhg_to_pa(d.intraocular_pressure_mmhg);
  SolverSettings s;
  s.substeps = d.substeps;
  return TissueWorld(eye.wall, env, s);
}

}  // namespace

Scene::Scene(SceneDescription d, EyeModel e, TissueWorld w)
    : description(std::move(d)), eye(std::move(e)), world(std::move(w)) {}

Scene build_scene(const SceneDescription& description, const BuildOptions& options) {
  description.validate();
  EyeModel eye = build_eye_model(description.anatomy);
  TissueWorld world = make_world(description, eye);
  Scene scene(description, std::move(eye), std::move(world));
  const EyeModel& e = scene.eye;
  const EyeParameters& ap = e.parameters;
  TissueWorld& w = scene.world;

  // ---- Retina (with its tears cut in) ----------------------------------------------------------
  TriangleMesh retina_mesh = e.retina_mesh;
  double ora_arc = 0.0;
  for (const auto& c : retina_mesh.surface_coords) ora_arc = std::max(ora_arc, c.x());
  for (const auto& t : description.tears) scene.tears.push_back(cut_u_tear(retina_mesh, e, t));
  {
    SurfaceDescription rd;
    rd.material = description.materials.retina;
    rd.material.thickness_mm = ap.retina_thickness_mm;
    rd.mesh = retina_mesh;
    rd.pressurised = true;
    rd.contained_by_globe = true;
    scene.retina = w.add_surface(rd);
  }
  Surface& rs = w.surface(scene.retina);
  for (std::uint32_t v = 0; v < retina_mesh.positions.size(); ++v) {
    const bool at_ora = retina_mesh.surface_coords[v].x() > ora_arc - 1e-6;
    const bool at_disc = (retina_mesh.positions[v] - e.optic_disc_mm).norm() <= ap.optic_disc_radius_mm;
    if (at_ora || at_disc) {
      (void)rs.set_fixed(rs.vertex_id(v), true);
      ++scene.anchored_retina_vertices;
    }
  }

  // ---- Vitreous gel: nested shells joined by line springs, anchored at the vitreous base, the
  // cortex tied to the retina by weak adhesions. ------------------------------------------------
  if (ap.gel_shells > 0) {
    SurfaceDescription gd;
    gd.material = description.materials.gel;
    gd.mesh = e.gel_mesh;
    gd.contained_by_globe = true;
    gd.pressurised = false;
    const std::size_t ng = gd.mesh.positions.size();
    std::vector<double> shell_end(static_cast<std::size_t>(ap.gel_shells), 0.0);
    for (std::size_t v = 0; v < ng; ++v) {
      auto& se = shell_end[e.gel_shell_of_vertex[v]];
      se = std::max(se, gd.mesh.surface_coords[v].x());
    }
    const auto anchored = [&](std::size_t v) {
      return gd.mesh.surface_coords[v].x() > shell_end[e.gel_shell_of_vertex[v]] - ap.vitreous_base_mm;
    };
    // Cortex adhesions: snap the cortex vertex onto its retina partner (instance vertices).
    const double gel_edge = mean_edge(gd.mesh);
    PointGrid retina_grid(retina_mesh.positions, 1.0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> adhesions;
    std::vector<std::uint8_t> retina_used(retina_mesh.positions.size(), 0);
    std::uint32_t counter = 0;
    for (std::uint32_t v = 0; v < ng; ++v) {
      if (e.gel_shell_of_vertex[v] != 0 || anchored(v)) continue;
      if (counter++ % static_cast<std::uint32_t>(description.gel_adhesion_stride) != 0) continue;
      double dist = 0.0;
      const std::uint32_t r = retina_grid.nearest(gd.mesh.positions[v], &dist);
      if (r == kNone || dist > 0.3 * gel_edge || retina_used[r] || rs.is_fixed(r)) continue;
      retina_used[r] = 1;
      gd.mesh.positions[v] = retina_mesh.positions[r];
      adhesions.emplace_back(v, r);
    }
    // Springs between shells: each vertex of a deeper shell to the nearest of the shell outside it.
    std::vector<std::vector<Vec3>> shell_points(static_cast<std::size_t>(ap.gel_shells));
    std::vector<std::vector<std::uint32_t>> shell_index(static_cast<std::size_t>(ap.gel_shells));
    for (std::uint32_t v = 0; v < ng; ++v) {
      shell_points[e.gel_shell_of_vertex[v]].push_back(gd.mesh.positions[v]);
      shell_index[e.gel_shell_of_vertex[v]].push_back(v);
    }
    const double gel_modulus_pa = description.materials.gel.membrane_modulus_pa_mm / description.materials.gel.thickness_mm;
    for (int k = 1; k < ap.gel_shells; ++k) {
      PointGrid outer(shell_points[static_cast<std::size_t>(k - 1)], 1.5);
      for (auto v : shell_index[static_cast<std::size_t>(k)]) {
        if (anchored(v)) continue;
        const std::uint32_t o = shell_index[static_cast<std::size_t>(k - 1)][outer.nearest(gd.mesh.positions[v])];
        const double len = (gd.mesh.positions[o] - gd.mesh.positions[v]).norm();
        if (!(len > 1e-6)) continue;
        gd.line_springs.push_back({v, o, gel_modulus_pa * gel_edge * gel_edge / len});
      }
    }
    scene.gel = w.add_surface(gd);
    Surface& gs = w.surface(scene.gel);
    for (std::uint32_t v = 0; v < ng; ++v) {
      if (anchored(v)) (void)gs.set_fixed(gs.vertex_id(v), true);
    }
    for (const auto& [g, r] : adhesions) {
      AttachmentDescription a;
      a.surface_a = scene.gel;
      a.vertex_a = g;
      a.surface_b = scene.retina;
      a.vertex_b = r;
      a.stiffness_un_per_mm = 2e2 * attachment_area_scale(scene.eye);
      a.break_force_un = description.gel_adhesion_break_force_un * attachment_area_scale(scene.eye);
      w.add_attachment(a);
      ++scene.gel_attachments;
    }
  }

  // ---- Membranes, detachments, guides ------------------------------------------------------------
  for (const auto& m : description.membranes) scene.membranes.push_back(build_membrane(scene, retina_mesh, m));

  for (const auto& d : description.detachments) {
    LocalForceDescription f;
    f.name = d.name;
    f.surface = scene.retina;
    f.toward_point_mm = Vec3::Zero();
    f.pressure_pa = w.environment().intraocular_pressure_pa + d.pressure_pa;
    const Vec3 center = wall_point_at(e, d.center).normalized();
    const double radius = d.radius_deg * kDeg;
    for (std::uint32_t v = 0; v < rs.vertex_slots(); ++v) {
      if (!rs.vertex_alive(v) || rs.is_fixed(v)) continue;
      const Vec3 p = rs.position(v);
      const double ang = std::atan2(p.cross(center).norm(), p.dot(center));
      if (ang < radius) {
        const double u = ang / radius;
        f.vertices.push_back(v);
        f.weights.push_back(std::clamp(1.5 * (1.0 - u * u), 0.0, 1.0));
      }
    }
    if (f.vertices.empty()) throw InvalidArgument("detachment '" + d.name + "': covers no free retina");
    scene.detachment_forces.push_back(w.add_local_force(f));
  }
  for (const auto& g : description.guides) scene.guides.push_back(build_guide(scene, g));

  if (options.textures) {
    scene.textures = generate_fundus(e, {description.texture_seed, description.texture_size_px});
  }
  // The solver's tears and creep clean up after themselves like the tools' cuts (clean_topology.hpp).
  install_clean_topology(w);
  if (options.settle) scene.settle = settle_world(w, description.settle);
  return scene;
}

SettleReport settle_world(TissueWorld& world, const SettleSpec& spec) {
  SettleReport r;
  const SolverSettings surgery = world.settings();
  SolverSettings settling = surgery;
  settling.settling_damping_per_s = spec.damping_per_s;
  // Let still regions (most of the retina, lying on the wall) fall asleep early: settling only has
  // to follow what still moves.
  settling.sleep_after_steps = std::min(surgery.sleep_after_steps, 20);
  world.replace_settings(settling);
  world.set_breaking(false);
  // Speed measured as real displacement over the check interval of the fastest free vertex: most
  // of the retina lies still on the wall, so an average would call a rising detachment settled, and
  // a vertex held against the wall can carry a velocity it never travels.
  constexpr int kInterval = 10;
  std::vector<std::vector<Vec3>> last(world.surface_count());
  const auto speed = [&] {
    double d2 = 0.0;
    for (std::uint32_t s = 0; s < world.surface_count(); ++s) {
      const Surface& sf = world.surface(s);
      auto& prev = last[s];
      const bool have = prev.size() == sf.vertex_slots();
      prev.resize(sf.vertex_slots());
      for (std::uint32_t v = 0; v < sf.vertex_slots(); ++v) {
        if (!sf.vertex_alive(v) || sf.is_fixed(v)) continue;
        d2 = std::max(d2, have ? (sf.position(v) - prev[v]).squaredNorm() : 1e300);
        prev[v] = sf.position(v);
      }
    }
    return std::sqrt(d2) / (kInterval * spec.dt_s);
  };
  while (r.steps < spec.max_steps) {
    if (r.steps >= spec.min_steps - kInterval && r.steps % kInterval == 0) {
      r.max_speed_mm_s = speed();
      if (r.steps >= spec.min_steps && r.max_speed_mm_s < spec.max_speed_mm_s) {
        r.settled = true;
        break;
      }
    }
    const StepReport s = world.step(spec.dt_s);
    ++r.steps;
    if (!s.ok) {
      r.ok = false;
      break;
    }
  }
  world.replace_settings(surgery);
  world.set_breaking(true);
  world.reset_clock();
  return r;
}

double max_retina_lift_mm(const Scene& scene) {
  const Surface& rs = scene.world.surface(scene.retina);
  double lift = 0.0;
  for (std::uint32_t v = 0; v < rs.vertex_slots(); ++v) {
    if (rs.vertex_alive(v)) lift = std::max(lift, scene.eye.wall.clearance(rs.position(v)));
  }
  return lift;
}

}  // namespace vitreo::core
