// Step stage 2: constraint projection (XPBD, one Gauss–Seidel sweep in mesh order per iteration).
//
// The XPBD update of a constraint C with stiffness k over a substep h is
// Δλ = (−C − λ/(k h²)) / (Σw|∇C|² + 1/(k h²)); multiplied through by k h² it needs no division by a
// zero compliance. The multiplier λ starts at zero every substep; with one iteration per substep
// (Small Steps, Macklin et al. 2019 — the real-time default) it is never needed again, so it is only
// stored when several iterations must accumulate it, as XPBD requires to converge to the implicit
// solution rather than to an over-stiff one.
#include <algorithm>
#include <cmath>

#include "core/tissue/awake_vertices.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

namespace {
// An attachment stretched further than this by an awake side wakes its sleeping side.
constexpr double kAttachmentWake_mm = 5e-3;
// See the direction term in project_springs.
constexpr double kMaxDirectionFraction = 0.25;

}  // namespace

// Once per step, after the effective masses are known: everything a spring's projection needs
// that does not change between substeps and iterations, packed in sweep order. Springs whose ends
// are both immovable this step (asleep, anchored, dead) are left out; they would change nothing.
void TissueWorld::pack_springs(double h) {
  const double h2 = h * h;
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    Surface& s = *surfaces_[si];
    Scratch& sc = scratch_[si];
    auto view = s.solver_view();
    const double ratio = s.material().direction_stiffness_ratio;
    const double tau_h = s.material().internal_damping_s * h;
    const double* w = sc.effective_inverse_mass.data();
    const auto* ev = view.edge_v.data();
    const Vec3* rv = view.rest_vec.data();
    const double* rl = view.rest_len.data();
    const double* k = view.stiffness.data();
    SolverSpring* out = sc.springs.data();
    std::uint32_t n = 0;
    for_each_active_edge(si, [&](std::uint32_t e) {
      const std::uint32_t a = ev[e][0], b = ev[e][1];
      const double wa = w[a], wb = w[b], ws = wa + wb;
      if (ws == 0.0) return;
      SolverSpring& sp = out[n++];
      sp.a = a;
      sp.b = b;
      sp.edge = e;
      sp.wake_block = 0;
      sp.wake_length = 0.0;
      if (wa == 0.0 || wb == 0.0) {
        const std::uint32_t still = wa == 0.0 ? a : b;
        if (!s.vertex_awake(still)) {
          const std::uint32_t block = still / Surface::kSleepBlock;
          sp.wake_block = block + 1;
          const std::uint64_t key = (std::uint64_t{block} << 32) | sc.block_sleep_serial[block];
          if (sc.wake_key[e] != key) {  // first step with this sleep of that block
            sc.wake_key[e] = key;
            sc.wake_length[e] = (view.x[b] - view.x[a]).norm();
          }
          sp.wake_length = sc.wake_length[e];
        }
      }
      sp.wa = wa;
      sp.wb = wb;
      sp.rest_vec = rv[e];
      sp.rest_len = rl[e];
      sp.kh2 = k[e] * h2;
      sp.kth = k[e] * tau_h;
      sp.inverse_denominator = 1.0 / (ws * (sp.kh2 + sp.kth) + 1.0);
      const double kvh2 = ratio * sp.kh2;
      sp.direction_gain = std::min(kvh2 / (ws * kvh2 + 1.0), kMaxDirectionFraction / ws);
    });
    sc.spring_count = n;
  }
}

void TissueWorld::project_springs(std::uint32_t si, bool accumulate) {
  const bool direction = surfaces_[si]->material().direction_stiffness_ratio > 0.0;
  if (accumulate) {
    if (direction) {
      sweep_springs<true, true>(si);
    } else {
      sweep_springs<true, false>(si);
    }
  } else if (direction) {
    sweep_springs<false, true>(si);
  } else {
    sweep_springs<false, false>(si);
  }
}

template <bool kAccumulate, bool kDirection>
void TissueWorld::sweep_springs(std::uint32_t si) {
  Surface& s = *surfaces_[si];
  Scratch& sc = scratch_[si];
  [[maybe_unused]] const double ratio = s.material().direction_stiffness_ratio;
  Vec3* x = s.solver_view().x.data();
  const Vec3* prev = sc.previous.data();
  [[maybe_unused]] double* lam = sc.lambda_distance.data();
  [[maybe_unused]] Vec3* lam_dir = sc.lambda_direction.data();
  std::uint8_t* wake = sc.wake_request.data();
  const double wake_strain = settings_.wake_strain;
  const SolverSpring* springs = sc.springs.data();
  const std::uint32_t n = sc.spring_count;
  for (std::uint32_t i = 0; i < n; ++i) {
    const SolverSpring& sp = springs[i];
    const std::uint32_t a = sp.a, b = sp.b;
    const double wa = sp.wa, wb = sp.wb;
    Vec3 d = x[b] - x[a];

    // The vector spring's rest-direction term (thesis eq. 2.1): C = d − r, a 3-vector constraint.
    if constexpr (kDirection) {
      // It is a gentle shape memory, not a structural constraint: where it would be stiff for the
      // substep (k h² w ≫ 1, stiff membranes on a fine mesh) it is capped to remove at most
      // kMaxDirectionFraction of its violation per substep (direction_gain, see pack_springs).
      // Uncapped, a rigid world-frame direction term fights the length and wall constraints and
      // makes stiff membranes jitter.
      const double ws = wa + wb;
      Vec3 dl = (sp.rest_vec - d);
      if constexpr (kAccumulate) {
        const double kvh2 = ratio * sp.kh2;
        dl = (dl * kvh2 - lam_dir[sp.edge]) / (ws * kvh2 + 1.0);
        lam_dir[sp.edge] += dl;
      } else {
        dl *= sp.direction_gain;
      }
      x[a] -= wa * dl;
      x[b] += wb * dl;
      d += ws * dl;
    }

    // Distance term: C = |d| − L.
    const double len2 = d.squaredNorm();
    const double len = std::sqrt(len2);
    if (!(len > 0.0)) continue;
    const double c = len - sp.rest_len;
    // A spring from an awake vertex whose pull on a sleeping one has changed wakes it for the
    // next step.
    if (sp.wake_block != 0 && std::abs(len - sp.wake_length) > wake_strain * sp.rest_len) wake[sp.wake_block - 1] = 1;
    // Dashpot β = τ k: with γ = β/(k h), XPBD's damped update multiplied through by k h² becomes
    // Δλ = −(k h² C + τ k h · ∇C·Δx) / (Σw (k h² + τ k h) + 1), Δx the motion in this substep.
    // One division per spring (the denominator's inverse is packed), and 1/len as len/len², so
    // the division runs beside the square root instead of after it: the sweep is a chain of
    // dependent projections, and their latency is its cost.
    const double inv_len = len * (1.0 / len2);
    const double rate = sp.kth > 0.0 ? d.dot((x[b] - prev[b]) - (x[a] - prev[a])) * inv_len : 0.0;
    double dl = -c * sp.kh2 - sp.kth * rate;
    if constexpr (kAccumulate) {
      dl = (dl - lam[sp.edge]) * sp.inverse_denominator;
      lam[sp.edge] += dl;
    } else {
      dl *= sp.inverse_denominator;
    }
    const Vec3 corr = d * (dl * inv_len);
    x[a] -= wa * corr;
    x[b] += wb * corr;
  }
}

void TissueWorld::project_attachments(double h, bool accumulate) {
  const double h2 = h * h;
  for (auto& at : attachments_) {
    if (!at.intact) continue;
    Surface& sa = *surfaces_[at.d.surface_a];
    auto va = sa.solver_view();
    Vec3& xa = va.x[at.a.index];
    const double wa = scratch_[at.d.surface_a].effective_inverse_mass[at.a.index];
    Vec3* xb = nullptr;
    double wb = 0.0;
    Vec3 pb = at.d.world_point_mm;
    if (at.d.surface_b != AttachmentDescription::kWorld) {
      auto vb = surfaces_[at.d.surface_b]->solver_view();
      xb = &vb.x[at.b.index];
      wb = scratch_[at.d.surface_b].effective_inverse_mass[at.b.index];
      pb = *xb;
    }
    const double ws = wa + wb;
    if (ws == 0.0) continue;
    if ((wa == 0.0 || wb == 0.0) && (pb - xa).squaredNorm() > kAttachmentWake_mm * kAttachmentWake_mm) {
      if (wa == 0.0 && !sa.vertex_awake(at.a.index)) scratch_[at.d.surface_a].wake_request[at.a.index / Surface::kSleepBlock] = 1;
      if (wb == 0.0 && xb && !surfaces_[at.d.surface_b]->vertex_awake(at.b.index)) {
        scratch_[at.d.surface_b].wake_request[at.b.index / Surface::kSleepBlock] = 1;
      }
    }
    // Zero-length spring: C = pb − pa (vector); its multiplier over h² is the force it carries.
    const double kh2 = at.d.stiffness_un_per_mm * h2;
    Vec3 dl = (pb - xa) * kh2;
    if (accumulate) dl -= at.lambda;
    dl /= ws * kh2 + 1.0;
    at.lambda += dl;
    xa += wa * dl;
    if (xb) *xb -= wb * dl;
    const double force = at.lambda.norm() / h2;
    at.last_force_un = force;
    at.peak_force_un = std::max(at.peak_force_un, force);
  }
}

void TissueWorld::project_wall() {
  const double offset = settings_.wall_offset_mm;
  for (auto& sp : surfaces_) {
    Surface& s = *sp;
    if (!s.contained_by_globe()) continue;
    auto view = s.solver_view();
    auto& touched = scratch_[static_cast<std::size_t>(&sp - surfaces_.data())].wall_touched;
    for_each_awake_vertex(s, [&](std::uint32_t v) {
      if (view.inverse_mass[v] == 0.0) return;  // dead and anchored vertices have w = 0
      if (wall_.project_inside(view.x[v], offset)) touched[v] = 1;
    });
  }
}

}  // namespace vitreo::core
