// Step stage 2: the implicit solve — Vertex Block Descent (Chen, Liu, Yang & Yuksel 2024, "Vertex
// Block Descent", ACM TOG 43(4)), Gauss–Seidel over the vertices in mesh order.
//
// A substep of implicit Euler is the minimiser of the incremental potential
//   G(y) = Σ_i ½ m̃_i |y_i − x̃_i|² / h² + E(y),
// x̃ the inertial target (position + h × velocity + h² × external acceleration, with the implicit
// drag folded into m̃: see Scratch::effective_inverse_mass) and E every elastic term: springs
// (½ k (|d| − L)²), bending stencils (½ k |Σ K x − h₀ n̂|², read as constant rows: build_bend_rows),
// attachments, grips and instrument contacts (½ k |p − target|², one-sided for contacts), and the
// springs' dashpots (Rayleigh damping, ½ (k τ / h) (n · Δd)² over the substep). A vertex's step holds
// its neighbours and takes one Newton step on its own terms: f = −∂G/∂y_i, H = ∂²G/∂y_i² (the
// spring's Hessian clamped to be positive semi-definite, as in VBD), y_i += H⁻¹ f, then the globe
// wall keeps it inside.
//
// Where the sweep starts decides what an unconverged sweep gives. It starts from y = x + h v (where
// inertia alone carries the tissue, without this substep's external forces): for tissue at rest in
// equilibrium that is already the minimiser, every f is zero and nothing moves — so the fixed point
// is the exact static equilibrium of the nominal material however few sweeps run, and sweeps that
// stop short leave the motion damped, not the tissue soft. (Starting from x̃, as XPBD must — its
// positions are x̃ plus the constraint corrections — a sweep that cannot carry the new h² g of
// weight through the whole mesh settles where the tissue has sagged enough to balance one partial
// sweep: tens of times softer than the material on a 20k retina at two substeps.)
#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/tissue/awake_vertices.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

namespace {

// Solves H Δ = f for a symmetric positive definite 3×3 H given by its upper triangle (xx, xy, xz,
// yy, yz, zz), by the adjugate: a few dozen flops and one division.
Vec3 solve_spd3(const std::array<double, 6>& m, const Vec3& f) {
  const double a = m[0], b = m[1], c = m[2], d = m[3], e = m[4], g = m[5];
  const double c00 = d * g - e * e, c01 = c * e - b * g, c02 = b * e - c * d;
  const double c11 = a * g - c * c, c12 = b * c - a * e, c22 = a * d - b * b;
  const double det = a * c00 + b * c01 + c * c02;
  if (!(det > 0.0)) return Vec3::Zero();
  const double inv = 1.0 / det;
  return Vec3((c00 * f.x() + c01 * f.y() + c02 * f.z()) * inv, (c01 * f.x() + c11 * f.y() + c12 * f.z()) * inv,
              (c02 * f.x() + c12 * f.y() + c22 * f.z()) * inv);
}

void add_outer(std::array<double, 6>& m, double s, const Vec3& n) {
  m[0] += s * n.x() * n.x();
  m[1] += s * n.x() * n.y();
  m[2] += s * n.x() * n.z();
  m[3] += s * n.y() * n.y();
  m[4] += s * n.y() * n.z();
  m[5] += s * n.z() * n.z();
}

// See sweep_vertices: the largest (stiffness h² / inertia) at which a vertex keeps its momentum.
constexpr double kMomentumStiffness = 100.0;

// Below this tangential motion per substep, wall friction sticks (see sweep_vertices).
constexpr double kStick_mm = 1e-7;

void add_diagonal(std::array<double, 6>& m, double s) {
  m[0] += s;
  m[3] += s;
  m[5] += s;
}

}  // namespace

// Once per step, after the effective masses are known: the vertex sweep's input for each surface.
// Active vertices are the movable (w > 0) live vertices of awake blocks, in mesh order; each gets
// its springs (from the active spring groups, which hold every spring touching an awake block) and
// its bending stencils, laid out contiguously so the sweep streams through them. The layout stands
// while the surface's topology, its awake blocks and its movable vertices do: then only the values
// are refreshed (refresh_packed_values), the same bits as a fresh layout, in less time
// (core/tissue/MEASUREMENTS.md, 2026-11-28).
void TissueWorld::pack_terms(double h) {
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    Surface& s = *surfaces_[si];
    Scratch& sc = scratch_[si];
    auto view = s.solver_view();
    const double* w = sc.effective_inverse_mass.data();
    const Vec3* x = view.x.data();
    const auto* ev = view.edge_v.data();
    const double damping_per_k = s.material().internal_damping_s / h;

    // Active vertices; the slots of the last step's are cleared first. Listed again every step
    // (a vertex can become immovable without a topology change), noting whether the list changed.
    const std::uint32_t last_count = sc.active_count;
    for (std::uint32_t i = 0; i < sc.active_count; ++i) sc.slot[sc.active[i]] = kNone;
    std::uint32_t n = 0;
    bool same_vertices = true;
    for_each_awake_vertex(s, [&](std::uint32_t v) {
      if (!view.vertex_alive[v] || w[v] == 0.0) return;
      same_vertices = same_vertices && n < last_count && sc.active[n] == v;
      sc.slot[v] = n;
      sc.active[n++] = v;
    });
    sc.active_count = n;
    same_vertices = same_vertices && n == last_count;
    if (!relayout_every_step_ && sc.layout_valid && same_vertices && sc.layout_topology == s.topology_version() &&
        sc.layout_awake == s.awake_version() && refresh_packed_values(si, h)) {
      ++layouts_kept_;
      bend_rest_forces(si);
      continue;
    }

    // Count, then fill (CSR). Stencils are numbered as they are met in the counting pass.
    std::fill_n(sc.spring_begin.begin(), n + 1, 0u);
    std::fill_n(sc.stencil_begin.begin(), n + 1, 0u);
    std::uint32_t stencils = 0;
    for_each_active_edge(si, [&](std::uint32_t e) {
      const std::uint32_t a = ev[e][0], b = ev[e][1];
      const std::uint32_t sa = sc.slot[a], sb = sc.slot[b];
      if (sa != kNone) ++sc.spring_begin[sa + 1];
      if (sb != kNone) ++sc.spring_begin[sb + 1];
      const Surface::BendStencil& st = view.bend[e];
      if (st.stiffness == 0.0) return;
      const auto [t0, t1] = view.edge_t[e];
      const std::uint32_t c = view.tri_v[t0][0] + view.tri_v[t0][1] + view.tri_v[t0][2] - a - b;
      const std::uint32_t d = view.tri_v[t1][0] + view.tri_v[t1][1] + view.tri_v[t1][2] - a - b;
      const std::uint32_t sc_c = sc.slot[c], sc_d = sc.slot[d];
      if (sa == kNone && sb == kNone && sc_c == kNone && sc_d == kNone) return;
      sc.stencil_edge[stencils] = e;
      Stencil& out = sc.stencils[stencils++];
      out.v = {a, b, c, d};
      out.K = st.K;
      out.k = st.stiffness;
      out.target = view.bend_rest[e] * st.normal(x[a], x[b], x[c], x[d]);
      for (const std::uint32_t q : {sa, sb, sc_c, sc_d}) {
        if (q != kNone) ++sc.stencil_begin[q + 1];
      }
    });
    sc.stencil_count = stencils;
    for (std::uint32_t i = 0; i < n; ++i) {
      sc.spring_begin[i + 1] += sc.spring_begin[i];
      sc.stencil_begin[i + 1] += sc.stencil_begin[i];
    }

    std::copy_n(sc.spring_begin.begin(), n, sc.fill.begin());
    for_each_active_edge(si, [&](std::uint32_t e) {
      const std::uint32_t a = ev[e][0], b = ev[e][1];
      const double k = view.stiffness[e];
      for (int end = 0; end < 2; ++end) {
        const std::uint32_t me = end == 0 ? a : b, other = end == 0 ? b : a;
        const std::uint32_t q = sc.slot[me];
        if (q == kNone) continue;
        sc.spring_edge[sc.fill[q]] = e;
        SpringTerm& t = sc.spring_terms[sc.fill[q]++];
        t.other = other;
        t.k = k;
        t.rest_len = view.rest_len[e];
        t.damping = k * damping_per_k;
        t.wake_block = 0;
        t.wake_length = 0.0;
        if (w[other] == 0.0 && !s.vertex_awake(other)) {
          // A spring from an awake vertex to a sleeping block: when its length has changed since
          // that block fell asleep, the pull has changed, and the block wakes (sweep_vertices).
          const std::uint32_t block = other / Surface::kSleepBlock;
          const std::uint64_t key = (std::uint64_t{block} << 32) | sc.block_sleep_serial[block];
          if (sc.wake_key[e] != key) {  // the first step with this sleep of that block
            sc.wake_key[e] = key;
            sc.wake_length[e] = (x[b] - x[a]).norm();
          }
          t.wake_block = block + 1;
          t.wake_length = sc.wake_length[e];
        }
      }
    });

    std::copy_n(sc.stencil_begin.begin(), n, sc.fill.begin());
    for (std::uint32_t i = 0; i < stencils; ++i) {
      const Stencil& st = sc.stencils[i];
      for (std::uint32_t corner = 0; corner < 4; ++corner) {
        const std::uint32_t q = sc.slot[st.v[corner]];
        if (q != kNone) sc.stencil_refs[sc.fill[q]++] = {i, corner};
      }
    }
    sc.layout_valid = true;
    sc.layout_topology = s.topology_version();
    sc.layout_awake = s.awake_version();
    sc.layout_spring_values = s.spring_values_version();
    sc.layout_damping_per_k = damping_per_k;
    build_bend_rows(si);
    bend_rest_forces(si);
  }
}

// Each active vertex's row of the bending Hessian Q = Σ_stencils k K Kᵀ: its diagonal and one entry
// per other corner of its stencils (a vertex's own spring neighbours and the far corners of the
// stencils it is an opposite corner of: about twelve on a regular mesh), summed in the order of
// the vertex's stencils. Q is constant while the stencils' K and k are (they change with the
// topology and the springs' values, when the rows are built again), so the sweep reads one row
// instead of twelve stencils, and nothing has to follow a vertex's move.
void TissueWorld::build_bend_rows(std::uint32_t si) {
  Scratch& sc = scratch_[si];
  std::uint32_t end = 0;
  for (std::uint32_t q = 0; q < sc.active_count; ++q) {
    const std::uint32_t v = sc.active[q];
    const std::uint32_t begin = end;
    sc.bend_begin[q] = begin;
    double diagonal = 0.0;
    for (std::uint32_t k = sc.stencil_begin[q], stop = sc.stencil_begin[q + 1]; k < stop; ++k) {
      const StencilRef r = sc.stencil_refs[k];
      const Stencil& st = sc.stencils[r.stencil];
      const double k_mine = st.k * st.K[r.corner];
      for (std::uint32_t c = 0; c < 4; ++c) {
        const double coef = k_mine * st.K[c];
        const std::uint32_t j = st.v[c];
        if (j == v) {
          diagonal += coef;
          continue;
        }
        std::uint32_t at = begin;
        while (at < end && sc.bend_other[at] != j) ++at;
        if (at == end) {
          sc.bend_other[end] = j;
          sc.bend_coef[end++] = 0.0;
        }
        sc.bend_coef[at] += coef;
      }
    }
    sc.bend_diag[q] = diagonal;
  }
  sc.bend_begin[sc.active_count] = end;
}

// The constant part of each active vertex's bending force this step, Σ k K_i target over its
// stencils (their targets follow the stencils' normals at the step's start).
void TissueWorld::bend_rest_forces(std::uint32_t si) {
  Scratch& sc = scratch_[si];
  run_sliced(workers_.get(), sc.active_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t q = begin; q < end; ++q) {
      Vec3 b = Vec3::Zero();
      for (std::uint32_t k = sc.stencil_begin[q], stop = sc.stencil_begin[q + 1]; k < stop; ++k) {
        const StencilRef r = sc.stencil_refs[k];
        const Stencil& st = sc.stencils[r.stencil];
        b += (st.k * st.K[r.corner]) * st.target;
      }
      sc.bend_force[q] = b;
    }
  });
}

// The same layout as the last step's: each stencil and, where any spring's rest length or stiffness
// changed since they were filled (Surface::spring_values_version), each spring term takes its values
// afresh from its spring, exactly as a full pack would (the wake fields stand: no block woke or
// slept). Stencils always do: their target follows the stencil's current normal. False when a
// stencil's spring has lost its bending, which a full pack would leave out.
bool TissueWorld::refresh_packed_values(std::uint32_t si, double h) {
  Surface& s = *surfaces_[si];
  Scratch& sc = scratch_[si];
  auto view = s.solver_view();
  const Vec3* x = view.x.data();
  const double damping_per_k = s.material().internal_damping_s / h;
  std::atomic<bool> bending_kept{true};
  run_sliced(workers_.get(), sc.stencil_count, [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t e = sc.stencil_edge[i];
      const Surface::BendStencil& st = view.bend[e];
      if (st.stiffness == 0.0) {
        bending_kept.store(false, std::memory_order_relaxed);
        return;
      }
      Stencil& out = sc.stencils[i];
      out.K = st.K;
      out.k = st.stiffness;
      out.target = view.bend_rest[e] * st.normal(x[out.v[0]], x[out.v[1]], x[out.v[2]], x[out.v[3]]);
    }
  });
  if (!bending_kept.load(std::memory_order_relaxed)) {
    sc.layout_valid = false;
    return false;
  }
  if (sc.layout_spring_values == s.spring_values_version() && sc.layout_damping_per_k == damping_per_k) return true;
  const bool stencils_changed = sc.layout_spring_values != s.spring_values_version();  // their K and k follow the springs
  sc.layout_spring_values = s.spring_values_version();
  sc.layout_damping_per_k = damping_per_k;
  run_sliced(workers_.get(), sc.spring_begin[sc.active_count], [&](std::uint32_t begin, std::uint32_t end) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t e = sc.spring_edge[i];
      SpringTerm& t = sc.spring_terms[i];
      const double k = view.stiffness[e];
      t.k = k;
      t.rest_len = view.rest_len[e];
      t.damping = k * damping_per_k;
    }
  });
  if (stencils_changed) build_bend_rows(si);
  return true;
}

void TissueWorld::sweep_vertices(double h) {
  const double inv_h2 = 1.0 / (h * h);
  const double wake_strain = settings_.wake_strain;
  const double offset = settings_.wall_offset_mm;
  const double friction = settings_.wall_friction;
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    Surface& s = *surfaces_[si];
    Scratch& sc = scratch_[si];
    Vec3* x = s.solver_view().x.data();
    const Vec3* prev = sc.previous.data();
    const double* w = sc.effective_inverse_mass.data();
    const bool walled = s.contained_by_globe();
    for (std::uint32_t q = 0; q < sc.active_count; ++q) {
      const std::uint32_t v = sc.active[q];
      const Vec3 y = x[v];
      const double inertia = inv_h2 / w[v];
      Vec3 f = inertia * (sc.target[v] - y);
      std::array<double, 6> H{inertia, 0.0, 0.0, inertia, 0.0, inertia};
      const Vec3 moved = y - prev[v];
      double stretch_stiffness = 0.0;  // the springs' elastic share of H's trace

      for (std::uint32_t k = sc.spring_begin[q], end = sc.spring_begin[q + 1]; k < end; ++k) {
        const SpringTerm& t = sc.spring_terms[k];
        const Vec3 d = y - x[t.other];
        const double len2 = d.squaredNorm();
        if (!(len2 > 0.0)) continue;
        const double len = std::sqrt(len2);
        const double inv_len = 1.0 / len;
        const Vec3 n = d * inv_len;
        if (t.wake_block != 0 && std::abs(len - t.wake_length) > wake_strain * t.rest_len) sc.wake_request[t.wake_block - 1] = 1;
        // Elastic: f = −k (len − L) n, H = k [s I + (1 − s) n nᵀ], s = max(0, 1 − L/len): the
        // transverse stiffness of a compressed spring is dropped, so H stays positive.
        f -= (t.k * (len - t.rest_len)) * n;
        const double transverse = std::max(0.0, 1.0 - t.rest_len * inv_len);
        add_diagonal(H, t.k * transverse);
        // Dashpot along the spring over the substep: f = −c n (n · (Δy_v − Δy_other)).
        const double rate = n.dot(moved - (x[t.other] - prev[t.other]));
        f -= (t.damping * rate) * n;
        add_outer(H, t.k * (1.0 - transverse) + t.damping, n);
        stretch_stiffness += t.k * (1.0 + 2.0 * transverse);
      }

      // Bending: −∂/∂y of Σ ½ k |Σ K x − target|², from the vertex's row of constant coefficients.
      Vec3 bend = sc.bend_force[q] - sc.bend_diag[q] * y;
      for (std::uint32_t k = sc.bend_begin[q], end = sc.bend_begin[q + 1]; k < end; ++k) bend -= sc.bend_coef[k] * x[sc.bend_other[k]];
      f += bend;
      add_diagonal(H, sc.bend_diag[q]);

      // Friction with the wall where the vertex lies on it pressed by a normal load N: up to μ N
      // against its tangential motion u in this substep, as a smoothed stick–slip force (the
      // friction of the incremental potential contact model, Li et al. 2020, as VBD uses it):
      // below kStick it holds the vertex like a stiff spring to where the substep started, beyond
      // it it resists with μ N. Without it the springs would slide attached retina over the wall
      // whenever a detachment or an instrument pulls on it.
      if (sc.contact_load[v] > 0.0) {
        const double limit = friction * sc.contact_load[v] * sc.velocity_keep[v] / w[v];
        const Vec3& n = sc.contact_normal[v];
        const Vec3 u = moved - n * n.dot(moved);
        const double slip = std::max(u.norm(), kStick_mm);
        f -= (limit / slip) * u;
        const double k_stick = limit / slip;
        add_diagonal(H, k_stick);
        add_outer(H, -k_stick, n);
      }

      bool touching = false;  // an instrument presses on the vertex
      for (std::uint32_t p = sc.point_head[v]; p != kNone; p = point_refs_[p].next) {
        const PointTerm& t = point_terms_[point_refs_[p].term];
        const double b = t.b[point_refs_[p].corner];
        const Vec3 off = t.point(*this) - t.target;
        if (t.kind == PointKind::kContact) {
          const double gap = t.normal.dot(off) - t.offset;
          if (gap >= 0.0) continue;
          touching = true;
          f -= (t.k * b * gap) * t.normal;
          add_outer(H, t.k * b * b, t.normal);
        } else {
          f -= (t.k * b) * off;
          add_diagonal(H, t.k * b * b);
        }
      }

      // The next substep may start from this vertex's motion continued undamped (see
      // integrate_and_predict) only where its springs' stiffness is within kMomentumStiffness of
      // its inertia (the retina's vertices are ~30 times theirs at the rig's settings): a vertex
      // held by springs much stiffer than its inertia (a sliver's corner after a cut, a fragment
      // left by random cuts and removals) is far from converged after one sweep, and momentum
      // carried into its start feeds the error back until it grows without bound (at a gate of
      // 1000, a sheet mangled by 400 random topology operations ran into a limit cycle at 1 m/s;
      // at 100 it settles). Nor where an instrument presses on it (a contact is a stiff one-sided
      // spring: tissue carried on by its momentum into or off the instrument bounces);
      // update_velocities and integrate_and_predict decide the rest.
      sc.momentum[v] = touching                                           ? Scratch::kStartDamped
                       : stretch_stiffness < kMomentumStiffness * inertia ? Scratch::kStartCarried
                                                                          : Scratch::kStartInertial;
      Vec3 next = y + solve_spd3(H, f);
      if (walled && wall_.project_inside(next, offset)) sc.wall_touched[v] = 1;
      x[v] = next;
    }
  }
}

Vec3 TissueWorld::PointTerm::point(const TissueWorld& w) const {
  Vec3 p = Vec3::Zero();
  for (std::uint32_t j = 0; j < count; ++j) p += b[j] * w.surfaces_[surface[j]]->position(vertex[j]);
  return p;
}

void TissueWorld::clear_point_terms() {
  for (const auto& [si, v] : point_vertices_) scratch_[si].point_head[v] = kNone;
  point_vertices_.clear();
  point_terms_.clear();
  point_refs_.clear();
}

// Adds a term and links it into the chains of its movable vertices (terms on immovable vertices
// only are dropped: they cannot change anything this substep).
void TissueWorld::add_point_term(const PointTerm& term) {
  if (point_terms_.size() == point_terms_.capacity() || point_refs_.size() + term.count > point_refs_.capacity()) return;
  bool movable = false;
  for (std::uint32_t j = 0; j < term.count; ++j) movable |= scratch_[term.surface[j]].slot[term.vertex[j]] != kNone;
  if (!movable) return;
  const auto index = static_cast<std::uint32_t>(point_terms_.size());
  point_terms_.push_back(term);
  for (std::uint32_t j = 0; j < term.count; ++j) {
    Scratch& sc = scratch_[term.surface[j]];
    const std::uint32_t v = term.vertex[j];
    if (sc.slot[v] == kNone) continue;
    if (sc.point_head[v] == kNone) point_vertices_.emplace_back(term.surface[j], v);
    point_refs_.push_back({index, j, sc.point_head[v]});
    sc.point_head[v] = static_cast<std::uint32_t>(point_refs_.size() - 1);
  }
}

// The forces the point terms carry after a substep's sweeps: attachments and grips remember their
// largest (for breaking), contacts add to the instrument's force, averaged over the substeps.
void TissueWorld::measure_point_forces(double fraction_of_step) {
  for (const PointTerm& t : point_terms_) {
    const Vec3 off = t.point(*this) - t.target;
    switch (t.kind) {
      case PointKind::kAttachment: {
        Attachment& at = attachments_[t.owner];
        at.last_force_un = t.k * off.norm();
        at.peak_force_un = std::max(at.peak_force_un, at.last_force_un);
        break;
      }
      case PointKind::kGrip: {
        Grip& g = grips_[t.owner];
        g.last_force_un = t.k * off.norm();
        g.peak_force_un = std::max(g.peak_force_un, g.last_force_un);
        break;
      }
      case PointKind::kContact: {
        const double gap = t.normal.dot(off) - t.offset;
        if (gap >= 0.0) break;
        contact_force_[t.owner * surfaces_.size() + t.surface[0]] += t.normal * (t.k * gap * fraction_of_step);
        contact_depth_[t.owner] = std::max(contact_depth_[t.owner], -gap);
        break;
      }
    }
  }
}

}  // namespace vitreo::core
