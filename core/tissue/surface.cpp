#include "core/tissue/surface.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <Eigen/LU>

#include "core/common/prefault.hpp"
#include "core/common/validate.hpp"

namespace vitreo::core {

namespace {

constexpr double kMinTraction = 0.2;
constexpr double kMaxTraction = 2.0;

std::uint32_t reserve_for(std::size_t n, const SurfaceCapacity& c) {
  return static_cast<std::uint32_t>(n + std::max<double>(c.minimum_extra, c.growth_fraction * static_cast<double>(n)));
}

}  // namespace

Surface::Surface(const SurfaceDescription& d)
    : material_(d.material), contained_by_globe_(d.contained_by_globe), pressurised_(d.pressurised) {
  material_.validate();
  const auto& mesh = d.mesh;
  const std::size_t nv = mesh.positions.size();
  if (nv == 0) throw InvalidArgument("surface '" + material_.name + "': no vertices");
  if (!d.extra_vertex_mass_g.empty() && d.extra_vertex_mass_g.size() != nv) {
    throw InvalidArgument("surface '" + material_.name + "': extra_vertex_mass_g needs one value per vertex");
  }
  require_range(d.capacity.growth_fraction, 0.0, 10.0, "capacity.growth_fraction");

  // Edge count of a triangulated surface is about 1.5 × triangles (+ boundary) + line springs.
  const std::size_t ne_est = mesh.triangles.size() * 3 / 2 + nv / 8 + d.line_springs.size() + 16;
  const std::uint32_t vcap = reserve_for(nv, d.capacity);
  const std::uint32_t ecap = reserve_for(ne_est, d.capacity) + 3 * (vcap - static_cast<std::uint32_t>(nv));
  const std::uint32_t tcap = reserve_for(mesh.triangles.size(), d.capacity) + 2 * (vcap - static_cast<std::uint32_t>(nv));

  auto reserve_all = [](std::uint32_t n, auto&... vecs) { (vecs.reserve(n), ...); };
  reserve_all(vcap, x_, v_, rest_, mass_, inverse_mass_, extra_mass_, vertex_area_, vertex_alive_, fixed_,
              vertex_generation_, first_corner_, free_vertices_);
  reserve_all(ecap, edge_v_, edge_t_, base_rest_vec_, rest_vec_, rest_len_, stiffness_, edge_traction_, bend_, bend_rest_,
              edge_alive_, edge_is_line_, edge_generation_, free_edges_);
  reserve_all(tcap, tri_v_, tri_e_, tri_rest_area_, tri_alive_, tri_generation_, free_triangles_);
  next_corner_.reserve(3 * static_cast<std::size_t>(tcap));
  // Touch the reserved memory now, so that a cut taking new slots during the simulation does not
  // pay the operating system's first-touch page faults (tens of µs per stroke otherwise).
  touch_reserved(x_, v_, rest_, mass_, inverse_mass_, extra_mass_, vertex_area_, vertex_alive_, fixed_,
                 vertex_generation_, first_corner_, free_vertices_, edge_v_, edge_t_, base_rest_vec_, rest_vec_,
                 rest_len_, stiffness_, edge_traction_, bend_, bend_rest_, edge_alive_,
                 edge_is_line_, edge_generation_, free_edges_,
                 tri_v_, tri_e_, tri_rest_area_, tri_alive_, tri_generation_, free_triangles_, next_corner_);
  block_awake_.assign((vcap + kSleepBlock - 1) / kSleepBlock, 1);
  block_quiet_steps_.assign(block_awake_.size(), 0);
  block_motion_.assign(block_awake_.size(), 0);
  block_drift_mm_.assign(block_awake_.size(), 0.0);
  vertex_noted_.assign(vcap, 0);
  edge_noted_.assign(ecap, 0);
  reserve_touched(noted_vertices_, vcap);
  reserve_touched(noted_edges_, ecap);

  for (std::size_t i = 0; i < nv; ++i) {
    require_finite(mesh.positions[i], "surface '" + material_.name + "': vertex position");
    const std::uint32_t v = allocate_vertex();
    x_[v] = rest_[v] = mesh.positions[i];
    if (!d.extra_vertex_mass_g.empty()) {
      require_non_negative(d.extra_vertex_mass_g[i], "extra_vertex_mass_g");
      extra_mass_[v] = d.extra_vertex_mass_g[i];
    }
  }

  for (const auto& t : mesh.triangles) {
    for (auto i : t) {
      if (i >= nv) throw InvalidArgument("surface '" + material_.name + "': triangle index out of range");
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      throw InvalidArgument("surface '" + material_.name + "': triangle repeats a vertex");
    }
    const Vec3& a = mesh.positions[t[0]];
    const double area = 0.5 * (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).norm();
    if (!(area > 1e-12)) throw InvalidArgument("surface '" + material_.name + "': degenerate (zero-area) triangle");
    const std::uint32_t tri = add_triangle(t, area);
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t va = t[k], vb = t[(k + 1) % 3];
      std::uint32_t e = find_edge(va, vb);
      if (e == kNone) {
        e = add_edge(va, vb, rest_[vb] - rest_[va], 1.0);
      } else if (edge_t_[e][1] != kNone) {
        throw InvalidArgument("surface '" + material_.name + "': non-manifold edge (shared by more than two triangles)");
      }
      tri_e_[tri][k] = e;
      attach_triangle_to_edge(e, tri);
    }
  }

  for (const auto& ls : d.line_springs) {
    if (ls.a >= nv || ls.b >= nv || ls.a == ls.b) throw InvalidArgument("line spring: bad vertex indices");
    require_positive(ls.stiffness_un_per_mm, "line spring stiffness");
    if (find_edge(ls.a, ls.b) != kNone) throw InvalidArgument("line spring duplicates a triangle edge");
    const Vec3 r = rest_[ls.b] - rest_[ls.a];
    if (!(r.norm() > 1e-9)) throw InvalidArgument("line spring has zero rest length");
    const std::uint32_t e = add_edge(ls.a, ls.b, r, 1.0);
    edge_is_line_[e] = 1;
    ++line_springs_;
    stiffness_[e] = ls.stiffness_un_per_mm;
    ++spring_values_version_;
  }
  // find_edge for line springs walks triangle fans, so it does not see them; line springs are
  // kept in a separate per-vertex search only at build time, which is all they need.

  // Every vertex and spring, including those without triangles; the notes the build took are
  // covered by this.
  for (std::uint32_t v : noted_vertices_) vertex_noted_[v] = 0;
  for (std::uint32_t e : noted_edges_) edge_noted_[e] = 0;
  noted_vertices_.clear();
  noted_edges_.clear();
  for (std::uint32_t v = 0; v < vertex_slots(); ++v) update_vertex_mass(v);
  for (std::uint32_t e = 0; e < edge_slots(); ++e) update_edge_stiffness(e);
  for (std::uint32_t v = 0; v < vertex_slots(); ++v) {
    if (!(mass_[v] > 0.0)) {
      throw InvalidArgument("surface '" + material_.name + "': vertex " + std::to_string(v) +
                            " has no mass (no triangle and no extra mass)");
    }
  }
}

// ---- Pools ----------------------------------------------------------------------------------

std::uint32_t Surface::allocate_vertex() {
  std::uint32_t v;
  if (!free_vertices_.empty()) {
    v = free_vertices_.back();
    free_vertices_.pop_back();
  } else {
    v = vertex_slots();
    x_.emplace_back(Vec3::Zero());
    v_.emplace_back(Vec3::Zero());
    rest_.emplace_back(Vec3::Zero());
    mass_.push_back(0.0);
    inverse_mass_.push_back(0.0);
    extra_mass_.push_back(0.0);
    vertex_area_.push_back(0.0);
    vertex_alive_.push_back(0);
    fixed_.push_back(0);
    vertex_generation_.push_back(0);
    first_corner_.push_back(kNone);
  }
  x_[v] = v_[v] = rest_[v] = Vec3::Zero();
  mass_[v] = inverse_mass_[v] = extra_mass_[v] = vertex_area_[v] = 0.0;
  vertex_alive_[v] = 1;
  ++block_motion_[v / kSleepBlock];  // the caller places it: spatial indexes must look again
  fixed_[v] = 0;
  first_corner_[v] = kNone;
  ++live_vertices_;
  ++topology_version_;
  if (!block_awake_.empty()) wake_vertex(v);
  return v;
}

std::uint32_t Surface::allocate_edge() {
  std::uint32_t e;
  if (!free_edges_.empty()) {
    e = free_edges_.back();
    free_edges_.pop_back();
  } else {
    e = edge_slots();
    edge_v_.push_back({kNone, kNone});
    edge_t_.push_back({kNone, kNone});
    base_rest_vec_.emplace_back(Vec3::Zero());
    rest_vec_.emplace_back(Vec3::Zero());
    rest_len_.push_back(0.0);
    stiffness_.push_back(0.0);
    edge_traction_.push_back(1.0);
    bend_.emplace_back();
    bend_rest_.push_back(0.0);
    edge_alive_.push_back(0);
    edge_is_line_.push_back(0);
    edge_generation_.push_back(0);
  }
  edge_t_[e] = {kNone, kNone};
  edge_alive_[e] = 1;
  edge_is_line_[e] = 0;
  bend_[e] = BendStencil{};
  bend_rest_[e] = 0.0;
  ++live_edges_;
  ++topology_version_;
  return e;
}

std::uint32_t Surface::allocate_triangle() {
  std::uint32_t t;
  if (!free_triangles_.empty()) {
    t = free_triangles_.back();
    free_triangles_.pop_back();
  } else {
    t = triangle_slots();
    tri_v_.push_back({kNone, kNone, kNone});
    tri_e_.push_back({kNone, kNone, kNone});
    tri_rest_area_.push_back(0.0);
    tri_alive_.push_back(0);
    tri_generation_.push_back(0);
    next_corner_.insert(next_corner_.end(), 3, kNone);
  }
  tri_alive_[t] = 1;
  ++live_triangles_;
  return t;
}

void Surface::free_edge(std::uint32_t e) {
  ++topology_version_;
  wake_vertex(edge_v_[e][0]);
  wake_vertex(edge_v_[e][1]);
  edge_alive_[e] = 0;
  log_spring(e);
  stiffness_[e] = 0.0;
  ++spring_values_version_;
  bend_[e] = BendStencil{};
  ++edge_generation_[e];
  free_edges_.push_back(e);
  --live_edges_;
}

void Surface::free_triangle(std::uint32_t t) {
  for (std::uint32_t k = 0; k < 3; ++k) {
    unlink_corner(t, k);
    detach_triangle_from_edge(tri_e_[t][k], t);
  }
  tri_alive_[t] = 0;
  ++tri_generation_[t];
  free_triangles_.push_back(t);
  --live_triangles_;
}

std::uint32_t Surface::add_edge(std::uint32_t a, std::uint32_t b, const Vec3& base_rest_vector, double traction) {
  const std::uint32_t e = allocate_edge();
  edge_v_[e] = {a, b};
  log_spring(e);
  base_rest_vec_[e] = base_rest_vector;
  edge_traction_[e] = traction;
  refresh_rest(e);
  return e;
}

std::uint32_t Surface::add_triangle(std::array<std::uint32_t, 3> v, double rest_area) {
  const std::uint32_t t = allocate_triangle();
  tri_v_[t] = v;
  tri_e_[t] = {kNone, kNone, kNone};
  tri_rest_area_[t] = rest_area;
  for (std::uint32_t k = 0; k < 3; ++k) link_corner(t, k);
  return t;
}

void Surface::link_corner(std::uint32_t t, std::uint32_t k) {
  const std::uint32_t c = 3 * t + k, v = tri_v_[t][k];
  next_corner_[c] = first_corner_[v];
  first_corner_[v] = c;
  note_vertex(v);
}

void Surface::unlink_corner(std::uint32_t t, std::uint32_t k) {
  const std::uint32_t c = 3 * t + k, v = tri_v_[t][k];
  std::uint32_t* link = &first_corner_[v];
  while (*link != kNone && *link != c) link = &next_corner_[*link];
  if (*link == c) *link = next_corner_[c];
  next_corner_[c] = kNone;
  note_vertex(v);
}

void Surface::attach_triangle_to_edge(std::uint32_t e, std::uint32_t t) {
  note_edge(e);
  if (edge_t_[e][0] == kNone) {
    edge_t_[e][0] = t;
  } else {
    edge_t_[e][1] = t;
  }
}

void Surface::detach_triangle_from_edge(std::uint32_t e, std::uint32_t t) {
  if (e == kNone) return;
  note_edge(e);
  auto& et = edge_t_[e];
  if (et[0] == t) {
    et[0] = et[1];
    et[1] = kNone;
  } else if (et[1] == t) {
    et[1] = kNone;
  }
}

std::uint32_t Surface::find_edge(std::uint32_t a, std::uint32_t b) const {
  for (std::uint32_t c = first_corner_[a]; c != kNone; c = next_corner_[c]) {
    const std::uint32_t t = c / 3;
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t e = tri_e_[t][k];
      if (e == kNone) continue;
      const auto ev = edge_v_[e];
      if ((ev[0] == a && ev[1] == b) || (ev[0] == b && ev[1] == a)) return e;
    }
  }
  return kNone;
}

// ---- Derived quantities ---------------------------------------------------------------------

void Surface::note_triangle_area(std::uint32_t t) {
  for (std::uint32_t k = 0; k < 3; ++k) {
    note_vertex(tri_v_[t][k]);
    note_edge(tri_e_[t][k]);
  }
}

void Surface::refresh_noted() {
  for (const std::uint32_t e : noted_edges_) {
    edge_noted_[e] = 0;
    update_edge_stiffness(e);  // nothing for a spring removed since
  }
  for (const std::uint32_t v : noted_vertices_) {
    vertex_noted_[v] = 0;
    if (!vertex_alive_[v]) continue;
    update_vertex_mass(v);
    wake_vertex(v);
  }
  noted_edges_.clear();
  noted_vertices_.clear();
}

void Surface::refresh_rest(std::uint32_t e) {
  ++spring_values_version_;
  rest_vec_[e] = base_rest_vec_[e] * (surface_traction_ * edge_traction_[e]);
  rest_len_[e] = rest_vec_[e].norm();
}

void Surface::update_vertex_mass(std::uint32_t v) {
  if (!vertex_alive_[v]) return;
  double area = 0.0;
  for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t) { area += tri_rest_area_[t] / 3.0; });
  vertex_area_[v] = area;
  mass_[v] = material_.areal_density_g_per_mm2() * area + extra_mass_[v];
  inverse_mass_[v] = (fixed_[v] || !(mass_[v] > 0.0)) ? 0.0 : 1.0 / mass_[v];
}

void Surface::update_edge_stiffness(std::uint32_t e) {
  if (!edge_alive_[e] || edge_is_line_[e]) return;
  const double len2 = base_rest_vec_[e].squaredNorm();
  double k = 0.0;
  for (const auto t : edge_t_[e]) {
    if (t != kNone && len2 > 0.0) k += triangle_spring_share(t, e) / len2;
  }
  stiffness_[e] = k;
  ++spring_values_version_;
  update_edge_bending(e);
}

// A triangle's share of the stiffness of its spring e (µN/mm × mm²: divided by the spring's rest
// length² by the caller).
//
// In linear elasticity a triangle's energy is a quadratic form in the strains of its three edges,
// W = ½ δᵀ G δ, δ_k = Δℓ_k / ℓ_k (the strain tensor is fixed by the three edge strains: δ_k =
// t_kᵀ ε t_k, t_k the edge's direction), with G = M⁻ᵀ C M⁻¹, C the plane-stress stiffness of the
// membrane (modulus E·t, Poisson ratio 1/3) times the rest area and M the map from the strain
// tensor to the edge strains. Springs carry the diagonal only. Each spring takes its row of G,
// summed (k_k ℓ_k² = Σ_l G_kl): a uniform expansion of any triangle then stores exactly its
// elastic energy (a pressurised membrane inflates as a continuum would, however the mesh is
// shaped), and on an equilateral triangle — where G is diagonal for ν = 1/3 — it is Van Gelder's
// k = E·t × area / ℓ² (Van Gelder 1998), which gives the network the modulus E·t and Poisson's
// ratio 1/3 (Lloyd, Székely & Harders 2007 discuss why no spring network matches other ratios).
// A very obtuse triangle can make a row negative; a spring's share is kept above a tenth of Van
// Gelder's, so a spring never pushes its ends apart when stretched.
double Surface::triangle_spring_share(std::uint32_t t, std::uint32_t e) const {
  const auto& te = tri_e_[t];
  // The triangle's edge directions in its own plane (rest vectors, any orientation: only t tᵀ
  // enters).
  std::array<Vec3, 3> r{base_rest_vec_[te[0]], base_rest_vec_[te[1]], base_rest_vec_[te[2]]};
  const Vec3 ex = r[0].normalized();
  const Vec3 ez = r[0].cross(r[1]).normalized();
  const Vec3 ey = ez.cross(ex);
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) {
    const double len = r[static_cast<std::size_t>(k)].norm();
    const double cx = r[static_cast<std::size_t>(k)].dot(ex) / len, cy = r[static_cast<std::size_t>(k)].dot(ey) / len;
    m.row(k) << cx * cx, cy * cy, 2.0 * cx * cy;  // δ_k = t_kᵀ ε t_k with ε = (εxx, εyy, εxy)
  }
  const double nu = 1.0 / 3.0;
  const double et = material_.membrane_modulus_pa_mm * tri_rest_area_[t];
  const double lambda = et * nu / (1.0 - nu * nu), mu = et / (2.0 * (1.0 + nu));
  Eigen::Matrix3d c;
  c << lambda + 2.0 * mu, lambda, 0.0, lambda, lambda + 2.0 * mu, 0.0, 0.0, 0.0, 4.0 * mu;
  const Eigen::Matrix3d m_inverse = m.inverse();
  const Eigen::Matrix3d g = m_inverse.transpose() * c * m_inverse;
  int k = 0;
  while (k < 3 && te[static_cast<std::size_t>(k)] != e) ++k;
  if (k == 3) return 0.0;
  const double van_gelder = et;  // × ℓ² / ℓ²
  return std::max(g.row(k).sum(), 0.1 * van_gelder);
}

Vec3 Surface::rest_vector_between(std::uint32_t t, std::uint32_t from, std::uint32_t to) const {
  for (const std::uint32_t e : tri_e_[t]) {
    if (e == kNone) continue;
    const auto ev = edge_v_[e];
    if (ev[0] == from && ev[1] == to) return rest_vec_[e];
    if (ev[0] == to && ev[1] == from) return -rest_vec_[e];
  }
  return Vec3::Zero();
}

void Surface::update_edge_bending(std::uint32_t e) {
  bend_[e] = BendStencil{};
  bend_rest_[e] = 0.0;
  const auto [t0, t1] = edge_t_[e];
  if (t0 == kNone || t1 == kNone || !(material_.bending_modulus_un_mm > 0.0)) return;
  const auto [a, b] = edge_v_[e];
  const auto [c, d] = edge_opposite_vertices(e);
  // The stencil's rest shape, from the springs' rest vectors (positions relative to a).
  const Vec3 xb = rest_vec_[e];  // rest vectors run from edge_v_[e][0] = a
  const Vec3 xc = rest_vector_between(t0, a, c);
  const Vec3 xd = rest_vector_between(t1, a, d);
  const Vec3 e0 = xb, e1 = xc, e2 = xd, e3 = xc - xb, e4 = xd - xb;
  // Cotangents of the four angles at a and b, bounded so a rest sliver cannot give a huge weight
  // (the topology layer keeps rest angles above 1°, cot 57).
  auto cot = [](const Vec3& u, const Vec3& v) {
    const double s = u.cross(v).norm();
    return std::clamp(u.dot(v) / std::max(s, 1e-300), -100.0, 100.0);
  };
  const double c01 = cot(e0, e1), c02 = cot(e0, e2), c03 = cot(-e0, e3), c04 = cot(-e0, e4);
  BendStencil& st = bend_[e];
  st.K = {c03 + c04, c01 + c02, -c01 - c03, -c02 - c04};
  st.stiffness = material_.bending_modulus_un_mm / (tri_rest_area_[t0] + tri_rest_area_[t1]);
  bool a_then_b = false;  // does triangle 0 run a → b?
  for (std::size_t k = 0; k < 3; ++k) a_then_b |= tri_v_[t0][k] == a && tri_v_[t0][(k + 1) % 3] == b;
  st.orientation = a_then_b ? 1.0 : -1.0;
  const Vec3 xa = Vec3::Zero();
  bend_rest_[e] = st.curvature(xa, xb, xc, xd).dot(st.normal(xa, xb, xc, xd));
}

double Surface::edge_force(std::uint32_t e) const {
  const auto [a, b] = edge_v_[e];
  return stiffness_[e] * ((x_[b] - x_[a]).norm() - rest_len_[e]);
}

double Surface::edge_strain(std::uint32_t e) const {
  const auto [a, b] = edge_v_[e];
  return rest_len_[e] > 0.0 ? (x_[b] - x_[a]).norm() / rest_len_[e] - 1.0 : 0.0;
}

double Surface::total_mass() const {
  double m = 0.0;
  for (std::uint32_t v = 0; v < vertex_slots(); ++v) {
    if (vertex_alive_[v]) m += mass_[v];
  }
  return m;
}

double Surface::total_rest_area() const {
  double a = 0.0;
  for (std::uint32_t t = 0; t < triangle_slots(); ++t) {
    if (tri_alive_[t]) a += tri_rest_area_[t];
  }
  return a;
}

// ---- Edits ------------------------------------------------------------------------------------

Status Surface::set_fixed(VertexId id, bool fixed) {
  if (!is_current(id)) return Status::error("set_fixed: stale or invalid vertex handle");
  fixed_[id.index] = fixed ? 1 : 0;
  if (fixed) v_[id.index] = Vec3::Zero();
  update_vertex_mass(id.index);
  wake_vertex(id.index);
  return Status::ok();
}

Status Surface::set_fixed_position(VertexId id, const Vec3& p) {
  if (!is_current(id)) return Status::error("set_fixed_position: stale or invalid vertex handle");
  if (!fixed_[id.index]) return Status::error("set_fixed_position: vertex is not fixed");
  if (!is_finite(p)) return Status::error("set_fixed_position: non-finite position");
  x_[id.index] = p;
  wake_vertex(id.index);
  ++block_motion_[id.index / kSleepBlock];  // moved by hand: spatial indexes must look again
  return Status::ok();
}

Status Surface::set_position(VertexId id, const Vec3& p) {
  if (!is_current(id)) return Status::error("set_position: stale or invalid vertex handle");
  if (!is_finite(p)) return Status::error("set_position: non-finite position");
  x_[id.index] = p;
  wake_vertex(id.index);
  ++block_motion_[id.index / kSleepBlock];  // moved by hand: spatial indexes must look again
  return Status::ok();
}

Status Surface::set_velocity(VertexId id, const Vec3& vel) {
  if (!is_current(id)) return Status::error("set_velocity: stale or invalid vertex handle");
  if (!is_finite(vel)) return Status::error("set_velocity: non-finite velocity");
  v_[id.index] = fixed_[id.index] ? Vec3::Zero() : vel;
  wake_vertex(id.index);
  return Status::ok();
}

Status Surface::set_surface_traction(double scale) {
  if (!std::isfinite(scale) || scale < kMinTraction || scale > kMaxTraction) {
    return Status::error("set_surface_traction: scale must be finite and in [0.2, 2]");
  }
  surface_traction_ = scale;
  for (std::uint32_t e = 0; e < edge_slots(); ++e) {
    if (edge_alive_[e]) refresh_rest(e);
  }
  wake_all();
  return Status::ok();
}

Status Surface::set_edge_traction(EdgeId id, double scale) {
  if (!is_current(id)) return Status::error("set_edge_traction: stale or invalid edge handle");
  if (!std::isfinite(scale) || scale < kMinTraction || scale > kMaxTraction) {
    return Status::error("set_edge_traction: scale must be finite and in [0.2, 2]");
  }
  edge_traction_[id.index] = scale;
  refresh_rest(id.index);
  wake_vertex(edge_v_[id.index][0]);
  wake_vertex(edge_v_[id.index][1]);
  return Status::ok();
}

void Surface::apply_plasticity(double dt_s, double floor_mm, std::vector<std::uint32_t>* crept_short) {
  const double rate = material_.plastic_rate_per_s;
  if (!(rate > 0.0)) return;
  const double yield = material_.plastic_yield_strain;
  const double alpha = std::min(1.0, rate * dt_s);
  for (std::uint32_t e = 0; e < edge_slots(); ++e) {
    if (!edge_alive_[e]) continue;
    const auto [a, b] = edge_v_[e];
    if (!vertex_awake(a) && !vertex_awake(b)) continue;  // asleep: nothing changed
    // Length: the rest length creeps by the part of the strain beyond the yield, so small elastic
    // deformations still spring back; the rest vector keeps its direction.
    const double length = (x_[b] - x_[a]).norm();
    const double base_len = base_rest_vec_[e].norm();
    const double scale = surface_traction_ * edge_traction_[e];
    const double strain = base_len > 0.0 ? length / (scale * base_len) - 1.0 : 0.0;
    if (std::abs(strain) > yield) {
      const double excess = strain - std::copysign(yield, strain);
      base_rest_vec_[e] *= 1.0 + alpha * excess;
      const double before = rest_len_[e];
      refresh_rest(e);
      if (crept_short && before >= floor_mm && rest_len_[e] < floor_mm && crept_short->size() + 2 <= crept_short->capacity()) {
        crept_short->push_back(a);
        crept_short->push_back(b);
      }
    }
    // Curvature: beyond a bend of `yield` radians across the spring (h ≈ θ × the spring's length
    // for this stencil), the rest curvature creeps toward the current one.
    const BendStencil& st = bend_[e];
    if (st.stiffness == 0.0) continue;
    const auto [c, d] = edge_opposite_vertices(e);
    const double h = st.curvature(x_[a], x_[b], x_[c], x_[d]).dot(st.normal(x_[a], x_[b], x_[c], x_[d]));
    const double diff = h - bend_rest_[e];
    const double allowed = yield * rest_len_[e];
    if (std::abs(diff) > allowed) bend_rest_[e] += alpha * (diff - std::copysign(allowed, diff));
  }
}

void Surface::wake_all() {
  std::fill(block_awake_.begin(), block_awake_.end(), std::uint8_t{1});
  std::fill(block_quiet_steps_.begin(), block_quiet_steps_.end(), std::uint16_t{0});
  ++awake_version_;
  note_all_blocks_moved();
}

void Surface::note_awake_blocks_moved(std::span<const double> step_drift_mm) {
  for (std::uint32_t b = 0; b < block_count(); ++b) block_drift_mm_[b] += step_drift_mm[b];
}

void Surface::note_all_blocks_moved() {
  for (auto& m : block_motion_) ++m;
}

void Surface::update_sleep(std::span<const double> block_max_speed2, double sleep_speed2, std::uint32_t steps_to_sleep) {
  for (std::uint32_t b = 0; b < block_count(); ++b) {
    if (!block_awake_[b]) continue;
    if (block_max_speed2[b] >= sleep_speed2) {
      block_quiet_steps_[b] = 0;
      continue;
    }
    if (++block_quiet_steps_[b] < steps_to_sleep) continue;
    block_awake_[b] = 0;
    ++awake_version_;
    const std::uint32_t end = std::min(vertex_slots(), (b + 1) * kSleepBlock);
    for (std::uint32_t v = b * kSleepBlock; v < end; ++v) v_[v] = Vec3::Zero();
  }
}

std::uint32_t Surface::awake_block_count() const {
  return static_cast<std::uint32_t>(std::count(block_awake_.begin(), block_awake_.end(), std::uint8_t{1}));
}


// ---- Tearing ----------------------------------------------------------------------------------

Surface::TearResult Surface::tear_edge(EdgeId id) {
  TearResult result;
  if (!is_current(id)) {
    result.status = Status::error("tear_edge: stale or invalid edge handle");
    return result;
  }
  const std::uint32_t e = id.index;
  if (edge_is_line_[e]) {
    result.status = Status::error("tear_edge: line springs have no surface to tear");
    return result;
  }
  const auto tris = edge_t_[e];
  const int ntri = (tris[0] != kNone) + (tris[1] != kNone);
  // Worst case: 2 midpoint vertices + 2 vertices un-pinched at the crack's ends; 6 new springs +
  // up to 4 replaced by un-pinching; 4 triangles for 2 removed.
  if (vertex_slots() + 4 > x_.capacity() && free_vertices_.size() < 4) {
    result.status = Status::error("tear_edge: vertex pool full (raise the surface capacity)");
    return result;
  }
  if (edge_slots() + 8 > edge_v_.capacity() && free_edges_.size() < 8) {
    result.status = Status::error("tear_edge: spring pool full (raise the surface capacity)");
    return result;
  }
  if (triangle_slots() + 4 > tri_v_.capacity() && free_triangles_.size() < 4) {
    result.status = Status::error("tear_edge: triangle pool full (raise the surface capacity)");
    return result;
  }

  const EditBatch edit(*this);
  const auto [a, b] = edge_v_[e];
  const Vec3 r_ab = base_rest_vec_[e];
  const double traction = edge_traction_[e];

  // Two fracture vertices at the spring's midpoint: one stays with a's side, one with b's.
  const std::uint32_t ma = allocate_vertex();
  const std::uint32_t mb = allocate_vertex();
  for (std::uint32_t m : {ma, mb}) {
    x_[m] = 0.5 * (x_[a] + x_[b]);
    v_[m] = 0.5 * (v_[a] + v_[b]);
    rest_[m] = 0.5 * (rest_[a] + rest_[b]);
  }
  fixed_[ma] = fixed_[a] && fixed_[b];
  fixed_[mb] = fixed_[ma];

  // Remember, per adjacent triangle, the opposite vertex, its springs to a and b, and the rest
  // vector a → opposite, before the triangle goes.
  struct Side {
    std::uint32_t opposite = kNone;
    std::uint32_t e_ao = kNone, e_bo = kNone;
    Vec3 r_a_opp = Vec3::Zero();
    double area = 0.0;
    bool a_first = false;  // triangle order is (a, b, opp) rather than (b, a, opp)
  };
  std::array<Side, 2> sides{};
  for (int i = 0; i < ntri; ++i) {
    const std::uint32_t t = tris[static_cast<std::size_t>(i)];
    const auto tv = tri_v_[t];
    Side& s = sides[static_cast<std::size_t>(i)];
    for (std::uint32_t k = 0; k < 3; ++k) {
      if (tv[k] != a && tv[k] != b) s.opposite = tv[k];
      if (tv[k] == a && tv[(k + 1) % 3] == b) s.a_first = true;
    }
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::uint32_t te = tri_e_[t][k];
      const auto ev = edge_v_[te];
      const bool has_o = ev[0] == s.opposite || ev[1] == s.opposite;
      if (has_o && (ev[0] == a || ev[1] == a)) s.e_ao = te;
      if (has_o && (ev[0] == b || ev[1] == b)) s.e_bo = te;
    }
    // Rest vectors live on springs, which may have crept plastically away from the rest positions;
    // new springs are built from them by vector addition (thesis ch. 2.6.2.1.1).
    s.r_a_opp = edge_v_[s.e_ao][0] == a ? base_rest_vec_[s.e_ao] : Vec3(-base_rest_vec_[s.e_ao]);
    s.area = tri_rest_area_[t];
  }
  for (int i = 0; i < ntri; ++i) free_triangle(tris[static_cast<std::size_t>(i)]);
  free_edge(e);

  const std::uint32_t e_a = add_edge(a, ma, 0.5 * r_ab, traction);
  const std::uint32_t e_b = add_edge(mb, b, 0.5 * r_ab, traction);
  auto make_triangle = [&](std::array<std::uint32_t, 3> v, std::array<std::uint32_t, 3> edges, double area) {
    const std::uint32_t t = add_triangle(v, area);
    tri_e_[t] = edges;
    for (auto e2 : edges) attach_triangle_to_edge(e2, t);
  };
  for (int i = 0; i < ntri; ++i) {
    const Side& s = sides[static_cast<std::size_t>(i)];
    const std::uint32_t o = s.opposite;
    const Vec3 r_m_o = s.r_a_opp - 0.5 * r_ab;  // both fracture vertices rest at the midpoint
    const std::uint32_t e_mao = add_edge(ma, o, r_m_o, traction);
    const std::uint32_t e_mbo = add_edge(mb, o, r_m_o, traction);
    const double half = 0.5 * s.area;
    if (s.a_first) {  // (a, b, o) → (a, ma, o) and (mb, b, o)
      make_triangle({a, ma, o}, {e_a, e_mao, s.e_ao}, half);
      make_triangle({mb, b, o}, {e_b, s.e_bo, e_mbo}, half);
    } else {  // (b, a, o) → (b, mb, o) and (ma, a, o)
      make_triangle({b, mb, o}, {e_b, e_mbo, s.e_bo}, half);
      make_triangle({ma, a, o}, {e_a, s.e_ao, e_mao}, half);
    }
  }

  // An opposite vertex that was already on a boundary would now join two separate fans (a
  // "bow-tie"); give each fan its own vertex so the surface stays manifold.
  for (int i = 0; i < ntri; ++i) separate_fans(sides[static_cast<std::size_t>(i)].opposite);

  result.vertex_a_side = ma;
  result.vertex_b_side = mb;
  return result;
}

std::uint32_t Surface::separate_fans(std::uint32_t v, std::vector<std::uint32_t>* out) {
  // v's triangles, with the corner v sits at (its two springs at v are tri_e_[t][corner] and
  // tri_e_[t][corner + 2], so no spring needs reading to find them).
  constexpr std::size_t kMax = 64;
  std::array<std::uint32_t, kMax> tris;
  std::array<std::uint8_t, kMax> corner, fan, stack;
  std::size_t n = 0;
  bool overflow = false;
  for_each_triangle_of(v, [&](std::uint32_t t, std::uint32_t c) {
    if (n == kMax) {
      overflow = true;
      return;
    }
    tris[n] = t;
    corner[n++] = static_cast<std::uint8_t>(c);
  });
  if (n < 2 || overflow) return 0;
  // Fans: triangles joined through a spring at v (edge_t_ names its other triangle), found by a
  // flood from each triangle not yet reached, in corner-list order. So fans are numbered by their
  // first triangle in the corner list: the first keeps v, the others get copies in a fixed order.
  std::fill_n(fan.begin(), n, std::uint8_t{0});
  std::uint8_t fans = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (fan[i] != 0) continue;
    fan[i] = ++fans;
    std::size_t top = 0;
    stack[top++] = static_cast<std::uint8_t>(i);
    while (top > 0) {
      const std::size_t x = stack[--top];
      const auto& te = tri_e_[tris[x]];
      for (const std::uint32_t e : {te[corner[x]], te[(corner[x] + 2u) % 3u]}) {
        if (e == kNone) continue;
        const std::uint32_t other = edge_t_[e][0] == tris[x] ? edge_t_[e][1] : edge_t_[e][0];
        if (other == kNone) continue;
        for (std::size_t j = 0; j < n; ++j) {
          if (tris[j] != other) continue;
          if (fan[j] == 0) {
            fan[j] = fans;
            stack[top++] = static_cast<std::uint8_t>(j);
          }
          break;
        }
      }
    }
  }
  if (fans < 2) return 0;
  std::uint32_t copies = 0;
  // Every fan after the first moves to a new copy of v.
  for (std::uint8_t g = 2; g <= fans; ++g) {
    if (free_vertices_.empty() && vertex_slots() >= x_.capacity()) break;  // pool full: leave as is
    ++copies;
    const std::uint32_t nv = allocate_vertex();
    if (out && out->size() < out->capacity()) out->push_back(nv);
    x_[nv] = x_[v];
    v_[nv] = v_[v];
    rest_[nv] = rest_[v];
    fixed_[nv] = fixed_[v];
    for (std::size_t i = 0; i < n; ++i) {
      if (fan[i] != g) continue;
      const std::uint32_t t = tris[i], k = corner[i];
      unlink_corner(t, k);
      tri_v_[t][k] = nv;
      link_corner(t, k);
      // Its two springs at v move to nv (a spring shared with a triangle of another fan cannot
      // exist, or the fans would be joined).
      for (const std::uint32_t e : {tri_e_[t][k], tri_e_[t][(k + 2u) % 3u]}) {
        if (e == kNone) continue;
        auto& ev = edge_v_[e];
        if (ev[0] != v && ev[1] != v) continue;  // moved already, with the fan's other triangle
        (ev[0] == v ? ev[0] : ev[1]) = nv;
        log_spring(e);
      }
    }
  }
  // v's and the copies' masses are noted (their corners moved); the springs' triangles and
  // areas are unchanged, and so are their stiffnesses.
  return copies;
}

}  // namespace vitreo::core
