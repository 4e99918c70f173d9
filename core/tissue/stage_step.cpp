// The step pipeline: validate → save rollback → forces → substeps (predict, project, velocities) →
// step-boundary changes (broken attachments, tears) → events.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "core/tissue/awake_vertices.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

namespace {
constexpr double kMaxDt_s = 0.02;
// Without a topology hook: the smallest spring a tear may split (10 µm, the topology engine's
// floor on piece size).
constexpr double kMinTearRest_mm = 0.01;
}

// Only awake vertices can change during a step (sleeping ones are skipped, and wake-ups are applied
// at its end), so only they need saving.
void TissueWorld::save_rollback() {
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    auto view = surfaces_[si]->solver_view();
    Scratch& sc = scratch_[si];
    for_awake_vertices(si, [&](std::uint32_t v) {
      sc.rollback_x[v] = view.x[v];
      sc.rollback_v[v] = view.v[v];
    });
  }
}

void TissueWorld::restore_rollback() {
  for (std::size_t si = 0; si < surfaces_.size(); ++si) {
    auto view = surfaces_[si]->solver_view();
    const Scratch& sc = scratch_[si];
    for_each_awake_vertex(*surfaces_[si], [&](std::uint32_t v) {
      view.x[v] = sc.rollback_x[v];
      view.v[v] = sc.rollback_v[v];
    });
  }
}

void TissueWorld::integrate_and_predict(double h) {
  const double offset = settings_.wall_offset_mm;
  const double settle_keep = 1.0 / (1.0 + h * settings_.settling_damping_per_s);
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    const Surface& s = *surfaces_[si];
    auto view = surfaces_[si]->solver_view();
    Scratch& sc = scratch_[si];
    const bool walled = s.contained_by_globe();
    for_awake_vertices(si, [&](std::uint32_t v) {
      sc.previous[v] = view.x[v];
      if (view.inverse_mass[v] == 0.0) return;
      if (sc.contact_load[v] > 0.0) {
        // Lying on the wall: no velocity into it (an inelastic contact), and Coulomb friction
        // takes up to μ·load·h of the sliding speed each substep, so attached retina stays put.
        const Vec3& normal = sc.contact_normal[v];
        const double vn = view.v[v].dot(normal);
        if (vn > 0.0) view.v[v] -= vn * normal;
        const double vt = view.v[v].norm();
        const double stop = settings_.wall_friction * sc.contact_load[v] * h;
        view.v[v] *= vt > stop ? 1.0 - stop / vt : 0.0;
      }
      // Implicit Euler with drag: (m + h c) v' = m v + h f, i.e. v' = (v + h a) / (1 + h c/m). It
      // damps any rate without reversing the velocity and gives the right terminal speed; the
      // solve uses the matching effective mass (see Scratch::effective_inverse_mass) and this
      // inertial target x̃, which carries the external forces.
      sc.target[v] = view.x[v] + (h * view.v[v] + (h * h) * sc.acceleration[v]) * sc.velocity_keep[v];
      // The sweeps start from the motion continued: x + h v (see stage_solve.cpp for why not x̃).
      // Where the last substep's sweeps confirmed it (momentum[v], set in update_velocities), not
      // slowed by the fluid's drag, which the target carries: tissue in fluid moves at the speed
      // its forces and the drag balance at, slowly changing, so the last velocity is the best
      // guess of the next, and each substep's sweeps build on the last's instead of starting over
      // (a sweep started from x + h v × the drag's factor lets a 20k retina strip stretch tens of
      // times slower than the material and the fluid allow). The artificial settling damping does
      // act here: a sweep far from converged stays near its start, so damping meant to stop motion
      // must slow the start itself.
      // A vertex whose springs are far stiffer than its inertia (kStartInertial, see
      // sweep_vertices) starts from the target instead: one sweep nearly solves its own block, so
      // the external forces' share does not soften it, and a stiff fragment moved as a whole by
      // an outside force (suction drawing a shred of membrane into the vitrector) moves at its
      // drag-limited speed rather than creeping by the fraction of inertia to stiffness a sweep
      // started without that force would move it.
      if (sc.momentum[v] == Scratch::kStartInertial) {
        view.x[v] += settle_keep * (sc.target[v] - view.x[v]);
      } else {
        const double carried = sc.momentum[v] == Scratch::kStartCarried ? 1.0 : sc.velocity_keep[v];
        view.x[v] += (h * settle_keep * carried) * view.v[v];
      }
      // A target through the wall stops on it (an inelastic contact, like the wall projection in
      // the sweeps): the springs then work from where the tissue can be, and the pressure that
      // pressed it there is taken by the wall (see compute_external_accelerations).
      if (walled) {
        wall_.project_inside(sc.target[v], offset);
        if (wall_.project_inside(view.x[v], offset)) sc.wall_touched[v] = 1;
      }
    });
  }
}

bool TissueWorld::update_velocities(double h) {
  const double inv_h = 1.0 / h;
  // A NaN or infinity anywhere propagates into its block's sum. Summed per block, not over the
  // surface, so the check does not depend on how the blocks are split over threads.
  std::atomic<bool> finite{true};
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    const Surface& s = *surfaces_[si];
    auto view = surfaces_[si]->solver_view();
    Scratch& sc = scratch_[si];
    std::fill(sc.block_max_speed2.begin(), sc.block_max_speed2.end(), 0.0);
    std::fill(sc.block_max_move2.begin(), sc.block_max_move2.end(), 0.0);
    for_awake_blocks(si, [&](std::uint32_t block, std::uint32_t first, std::uint32_t end) {
      double checksum = 0.0;
      double max_move2 = 0.0;  // kinematic vertices move too
      double max_speed2 = 0.0;
      for (std::uint32_t v = first; v < end; ++v) {
        const Vec3 moved = view.x[v] - sc.previous[v];
        max_move2 = std::max(max_move2, moved.squaredNorm());
        if (view.inverse_mass[v] == 0.0) continue;
        // Keep the momentum in the next start only while it helps (adaptive restart, O'Donoghue &
        // Candès 2015, per vertex): where the sweeps carried the vertex at least as far along its
        // last velocity as the drag alone would, the motion is real; where they pulled it back, the
        // continued motion overshot, and an overshoot left in would feed an oscillation of the
        // unconverged sweeps (stiff slivers after a cut shake themselves apart without this).
        const Vec3& last = view.v[v];
        if (sc.momentum[v] == Scratch::kStartCarried && moved.dot(last) < h * sc.velocity_keep[v] * last.squaredNorm()) {
          sc.momentum[v] = Scratch::kStartDamped;
        }
        view.v[v] = moved * inv_h;
        if (sc.wall_touched[v]) {
          sc.wall_touched[v] = 0;
          const Vec3 radial = view.x[v] - wall_.center();
          const Vec3 normal = radial * (1.0 / radial.norm());  // touched: on the wall, never at the centre
          const double vn = view.v[v].dot(normal);
          if (vn > 0.0) view.v[v] -= vn * normal;
        }
        checksum += view.x[v].x() + view.x[v].y() + view.x[v].z() + view.v[v].x() + view.v[v].y() + view.v[v].z();
        max_speed2 = std::max(max_speed2, view.v[v].squaredNorm());
      }
      sc.block_max_move2[block] = max_move2;
      sc.block_max_speed2[block] = max_speed2;
      if (!std::isfinite(checksum)) finite.store(false, std::memory_order_relaxed);
    });
    for (std::uint32_t b = 0; b < s.block_count(); ++b) {
      if (sc.block_max_move2[b] > 0.0) sc.block_step_drift_mm[b] += std::sqrt(sc.block_max_move2[b]);
    }
  }
  return finite.load(std::memory_order_relaxed);
}

void TissueWorld::prepare_sleep_groups() {
  for (std::size_t si = 0; si < surfaces_.size(); ++si) {
    const Surface& s = *surfaces_[si];
    Scratch& sc = scratch_[si];
    sc.groups.update(s);
    sc.awake_block_count = 0;
    for (std::uint32_t b = 0; b < s.block_count(); ++b) {
      if (s.block_awake(b)) sc.awake_blocks[sc.awake_block_count++] = b;
    }
  }
}

void TissueWorld::finish_sleep() {
  const double sleep2 = settings_.sleep_speed_mm_s * settings_.sleep_speed_mm_s;
  for (std::size_t si = 0; si < surfaces_.size(); ++si) {
    Surface& s = *surfaces_[si];
    Scratch& sc = scratch_[si];
    s.note_awake_blocks_moved(sc.block_step_drift_mm);
    if (settings_.sleeping) {
      // A block counts as slow only while every block it shares a spring with is slow too (a halo
      // of one block). Without it a small block by a clamp or an attachment falls asleep while the
      // tissue beyond it still creeps below the sleep speed, anchors that tissue, and the next
      // block slows and sleeps in turn: a clamped flap froze 11 % short of its cantilever sag
      // (core/tissue/MEASUREMENTS.md, 2026-11-29).
      std::copy(sc.block_max_speed2.begin(), sc.block_max_speed2.end(), sc.block_sleep_speed2.begin());
      const auto* ev = s.solver_view().edge_v.data();
      for_each_active_edge(static_cast<std::uint32_t>(si), [&](std::uint32_t e) {
        const std::uint32_t a = ev[e][0] / Surface::kSleepBlock, b = ev[e][1] / Surface::kSleepBlock;
        if (a == b) return;
        sc.block_sleep_speed2[a] = std::max(sc.block_sleep_speed2[a], sc.block_max_speed2[b]);
        sc.block_sleep_speed2[b] = std::max(sc.block_sleep_speed2[b], sc.block_max_speed2[a]);
      });
      s.update_sleep(sc.block_sleep_speed2, sleep2, static_cast<std::uint32_t>(settings_.sleep_after_steps));
    }
    for (std::uint32_t b = 0; b < s.block_count(); ++b) {
      if (!sc.wake_request[b]) continue;
      sc.wake_request[b] = 0;
      if (b * Surface::kSleepBlock < s.vertex_slots()) s.wake_vertex(b * Surface::kSleepBlock);
    }
  }
}

void TissueWorld::break_attachments() {
  if (!breaking_) return;
  for (std::uint32_t i = 0; i < attachments_.size(); ++i) {
    Attachment& at = attachments_[i];
    if (!at.intact) continue;
    const bool stale = !surfaces_[at.d.surface_a]->is_current(at.a) ||
                       (at.d.surface_b != AttachmentDescription::kWorld && !surfaces_[at.d.surface_b]->is_current(at.b));
    if (stale || at.cut || at.peak_force_un > at.d.break_force_un) {
      at.intact = false;
      at.cut = false;
      // Where it was: its tissue end; when an instrument took that away (a stale attachment), the
      // end that is left — the base under it, or the world point it held to.
      const Surface& sa = *surfaces_[at.d.surface_a];
      const Surface* sb = at.d.surface_b == AttachmentDescription::kWorld ? nullptr : surfaces_[at.d.surface_b].get();
      Vec3 p = at.d.world_point_mm;
      if (sa.is_current(at.a)) {
        p = sa.position(at.a.index);
      } else if (sb && sb->is_current(at.b)) {
        p = sb->position(at.b.index);
      }
      if (events_.size() < events_.capacity()) {
        events_.push_back({TissueEventKind::kAttachmentBroken, at.d.surface_a, i, p, at.peak_force_un});
      }
    }
  }
}

void TissueWorld::find_overstrained() {
  if (!breaking_) return;
  // Measured on the final positions of the step: inside the sweep a spring's length is still
  // changing as its neighbours are projected after it. Springs among sleeping vertices do not
  // change, so only the active groups are scanned.
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    Surface& s = *surfaces_[si];
    const double tear = s.material().tear_strain;
    if (!std::isfinite(tear)) continue;
    auto view = s.solver_view();
    const double f2 = (1.0 + tear) * (1.0 + tear);
    // Springs too short to split are not torn again: repeated tears at one spot would otherwise
    // halve them towards zero length (and zero-area triangles).
    const double min_rest = hooks_[si] ? hooks_[si]->min_tear_rest_mm() : kMinTearRest_mm;
    for_each_active_edge(si, [&](std::uint32_t e) {
      const auto [a, b] = view.edge_v[e];
      const double len2 = (view.x[b] - view.x[a]).squaredNorm();
      const double limit2 = f2 * view.rest_len[e] * view.rest_len[e];
      if (view.rest_len[e] < min_rest) return;
      if (len2 > limit2 && tear_candidates_.size() < tear_candidates_.capacity()) {
        tear_candidates_.push_back({si, s.edge_id(e), std::sqrt(len2) / view.rest_len[e] - 1.0});
      }
    });
  }
}

void TissueWorld::tear_overstrained() {
  if (settings_.max_tears_per_step == 0) return;
  find_overstrained();
  if (tear_candidates_.empty()) return;
  // Most strained first: a tear starts where the pull is, and the crack it opens relieves the
  // springs around it before they are considered.
  std::sort(tear_candidates_.begin(), tear_candidates_.end(), [](const TearCandidate& l, const TearCandidate& r) {
    if (l.strain != r.strain) return l.strain > r.strain;
    if (l.surface != r.surface) return l.surface < r.surface;
    return l.edge.index < r.edge.index;
  });
  int torn = 0;
  for (const auto& c : tear_candidates_) {
    if (torn >= settings_.max_tears_per_step) break;
    Surface& s = *surfaces_[c.surface];
    // An earlier tear this step may have split it (its handle is then stale) or relieved it.
    if (!s.is_current(c.edge)) continue;
    const double strain = s.edge_strain(c.edge.index);
    if (!(strain > s.material().tear_strain)) continue;
    const auto ev = s.edge_vertices(c.edge.index);
    const Vec3 where = 0.5 * (s.position(ev[0]) + s.position(ev[1]));
    TopologyHook* hook = hooks_[c.surface].get();
    Status status = Status::ok();
    if (hook) {
      const TopologyHookResult r = hook->tear(c.edge);
      status = r.status;
      cleanup_removed_mass_g_ += r.removed_mass_g;
    } else {
      status = s.tear_edge(c.edge).status;
    }
    if (!status) continue;  // pool full: the spring stays, the next step tries again
    ++torn;
    if (events_.size() < events_.capacity()) {
      events_.push_back({TissueEventKind::kTear, c.surface, c.edge.index, where, strain});
    }
  }
}

// Plastic creep, and the topology hook's cleanup where it shrank springs below the quality floor
// (creep is the one change of rest shape that happens inside the step, not through an operation
// that cleans up after itself).
void TissueWorld::creep_and_tidy(double dt_s) {
  for (std::uint32_t si = 0; si < surfaces_.size(); ++si) {
    TopologyHook* hook = hooks_[si].get();
    crept_short_.clear();
    surfaces_[si]->apply_plasticity(dt_s, hook ? hook->min_rest_mm() : 0.0, hook ? &crept_short_ : nullptr);
    if (hook && !crept_short_.empty()) cleanup_removed_mass_g_ += hook->clean_around(crept_short_).removed_mass_g;
  }
}

StepReport TissueWorld::step(double dt_s) {
  StepReport report;
  events_.clear();
  tear_candidates_.clear();
  if (!std::isfinite(dt_s) || !(dt_s > 0.0) || dt_s > kMaxDt_s) {
    report.ok = false;
    report.error = "step: dt must be finite and in (0, " + std::to_string(kMaxDt_s) + "] s, got " + std::to_string(dt_s);
    return report;
  }
  for (auto& at : attachments_) at.peak_force_un = 0.0;
  for (std::uint32_t i = 0; i < grip_high_water_; ++i) grips_[i].peak_force_un = 0.0;
  std::fill(contact_force_.begin(), contact_force_.end(), Vec3::Zero());
  std::fill(contact_depth_.begin(), contact_depth_.end(), 0.0);

  prepare_sleep_groups();
  save_rollback();
  for (auto& sc : scratch_) std::fill(sc.block_step_drift_mm.begin(), sc.block_step_drift_mm.end(), 0.0);
  const int substeps = settings_.substeps;
  const double h = dt_s / substeps;
  compute_external_accelerations(h);
  pack_terms(h);
  bool finite = true;
  for (int sub = 0; sub < substeps && finite; ++sub) {
    const double fraction = static_cast<double>(sub + 1) / substeps;
    integrate_and_predict(h);
    add_point_terms(fraction);
    for (int it = 0; it < settings_.iterations; ++it) {
      sweep_vertices(h);
      project_contacts(h, fraction);
    }
    measure_point_forces(1.0 / substeps);
    finite = update_velocities(h);
  }

  // The instruments' poses of this step become the start of the next.
  for (std::uint32_t c = 0; c < collider_count_; ++c) {
    colliders_[c].a0 = colliders_[c].a1;
    colliders_[c].b0 = colliders_[c].b1;
  }
  for (std::uint32_t i = 0; i < grip_high_water_; ++i) grips_[i].previous_target = grips_[i].d.target_mm;

  if (!finite) {
    restore_rollback();
    tear_candidates_.clear();
    report.ok = false;
    report.error = "step: the state became non-finite; the step was rolled back";
    events_.push_back({TissueEventKind::kRolledBack, 0, 0, Vec3::Zero(), 0.0});
    return report;
  }

  creep_and_tidy(dt_s);
  break_attachments();
  break_grips();
  tear_overstrained();
  rebind_grips();
  finish_sleep();
  for (const auto& e : events_) {
    if (e.kind == TissueEventKind::kTear) ++report.tears;
    if (e.kind == TissueEventKind::kAttachmentBroken) ++report.attachments_broken;
  }
  ++step_count_;
  time_s_ += dt_s;
  return report;
}

}  // namespace vitreo::core
