#include "core/tissue/tissue_world.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "core/common/state_hasher.hpp"
#include "core/common/validate.hpp"

namespace vitreo::core {

void Environment::validate() const {
  require_finite(gravity_mm_s2, "environment: gravity");
  if (gravity_mm_s2.norm() > 10.0 * units::kStandardGravity_mm_s2) {
    throw InvalidArgument("environment: gravity above 10 g");
  }
  require_range(fluid_density_g_per_mm3, 0.0, 1e-2, "environment: fluid density");
  require_range(gas_density_g_per_mm3, 0.0, 1e-2, "environment: gas density");
  if (std::isnan(fluid_level_z_mm)) throw InvalidArgument("environment: fluid level is NaN");
  // Documented range: 0 (open globe) to 80 mmHg (severe glaucoma crisis).
  require_range(intraocular_pressure_pa, 0.0, units::mmhg_to_pa(80.0), "environment: intraocular pressure");
}

void SolverSettings::validate() const {
  if (substeps < 1 || substeps > 64) throw InvalidArgument("solver: substeps must be in [1, 64]");
  if (iterations < 1 || iterations > 64) throw InvalidArgument("solver: iterations must be in [1, 64]");
  if (max_tears_per_step < 0 || max_tears_per_step > 1024) {
    throw InvalidArgument("solver: max_tears_per_step must be in [0, 1024]");
  }
  require_range(wall_offset_mm, 0.0, 5.0, "solver: wall_offset_mm");
  require_range(settling_damping_per_s, 0.0, 1e4, "solver: settling_damping_per_s");
  require_range(wall_friction, 0.0, 10.0, "solver: wall_friction");
  require_range(sleep_speed_mm_s, 0.0, 100.0, "solver: sleep_speed_mm_s");
  if (sleep_after_steps < 1 || sleep_after_steps > 60000) throw InvalidArgument("solver: sleep_after_steps must be in [1, 60000]");
  require_range(wake_strain, 1e-6, 1.0, "solver: wake_strain");
  require_range(contact_stiffness_un_per_mm, 1e2, 1e8, "solver: contact_stiffness_un_per_mm");
}

TissueWorld::TissueWorld(GlobeWall wall, Environment environment, SolverSettings settings)
    : wall_(std::move(wall)), environment_(environment), settings_(settings) {
  environment_.validate();
  settings_.validate();
  events_.reserve(256);
  tear_candidates_.reserve(4096);
  crept_short_.reserve(4096);
  colliders_.resize(kMaxColliders);
  candidates_.reserve(kMaxContactCandidates);
  suction_.reserve(kMaxSuctionFields);
  contact_depth_.assign(kMaxColliders, 0.0);
  grips_.resize(kMaxGrips);
  reserve_point_terms();
}

// Room for every attachment, grip and contact term of a substep (grown while building, by
// doubling; the step never allocates).
void TissueWorld::reserve_point_terms() {
  const std::size_t terms = attachments_.size() + kMaxGrips + kMaxContactTerms;
  if (point_terms_.capacity() >= terms) return;
  point_terms_.reserve(2 * terms);
  point_refs_.reserve(6 * terms);
  point_vertices_.reserve(6 * terms);
}

std::uint32_t TissueWorld::add_surface(const SurfaceDescription& description) {
  auto surface = std::make_unique<Surface>(description);
  const std::size_t cap = surface->vertex_capacity();
  Scratch s;
  s.previous.resize(cap);
  s.acceleration.resize(cap);
  s.rollback_x.resize(cap);
  s.rollback_v.resize(cap);
  s.drag_rate.resize(cap);
  s.velocity_keep.resize(cap);
  s.triangle_area2.resize(surface->triangle_capacity());
  s.triangle_epoch.assign(surface->triangle_capacity(), 0);
  s.effective_inverse_mass.resize(cap);
  s.current_area.resize(cap);
  s.contact_load.resize(cap);
  s.contact_normal.resize(cap);
  s.wall_touched.resize(cap);
  s.momentum.assign(cap, 0);
  const std::size_t blocks = surface->block_count();
  s.block_was_awake.assign(blocks, 0);
  s.awake_blocks.assign(blocks, 0);
  s.wake_request.assign(blocks, 0);
  s.block_max_speed2.assign(blocks, 0.0);
  s.block_sleep_speed2.assign(blocks, 0.0);
  s.block_max_move2.assign(blocks, 0.0);
  s.block_step_drift_mm.assign(blocks, 0.0);
  s.block_sleep_serial.assign(blocks, 0);
  s.wake_key.assign(surface->edge_capacity(), ~std::uint64_t{0});
  s.wake_length.assign(surface->edge_capacity(), 0.0);
  s.groups.reserve(*surface);
  s.active.resize(cap);
  s.slot.assign(cap, kNone);
  s.spring_begin.resize(cap + 1);
  s.stencil_begin.resize(cap + 1);
  s.fill.resize(cap + 1);
  s.spring_terms.resize(2 * std::size_t{surface->edge_capacity()});
  s.spring_edge.resize(s.spring_terms.size());
  s.stencil_edge.resize(surface->edge_capacity());
  s.stencil_refs.resize(4 * std::size_t{surface->edge_capacity()});
  s.stencils.resize(surface->edge_capacity());
  // A stencil's four corners give each of them three other corners: at most 12 row entries a spring.
  s.bend_begin.resize(cap + 1);
  s.bend_other.resize(12 * std::size_t{surface->edge_capacity()});
  s.bend_coef.resize(s.bend_other.size());
  s.bend_diag.resize(cap);
  s.bend_force.resize(cap);
  s.target.resize(cap);
  s.point_head.assign(cap, kNone);
  surfaces_.push_back(std::move(surface));
  hooks_.push_back(nullptr);
  scratch_.push_back(std::move(s));
  contact_force_.assign(std::size_t{kMaxColliders} * surfaces_.size(), Vec3::Zero());
  return static_cast<std::uint32_t>(surfaces_.size() - 1);
}

void TissueWorld::set_worker_threads(unsigned threads) {
  if (threads < 1 || threads > 64) throw InvalidArgument("worker threads: must be 1..64, got " + std::to_string(threads));
  if (threads == worker_threads()) return;
  workers_.reset();
  if (threads > 1) workers_ = std::make_unique<WorkerPool>(threads);
}

void TissueWorld::set_topology_hook(std::uint32_t surface, std::unique_ptr<TopologyHook> hook) {
  if (surface >= surfaces_.size()) throw InvalidArgument("topology hook: surface out of range");
  hooks_[surface] = std::move(hook);
}

std::uint32_t TissueWorld::add_attachment(const AttachmentDescription& d) {
  if (d.surface_a >= surfaces_.size()) throw InvalidArgument("attachment: surface_a out of range");
  const Surface& sa = *surfaces_[d.surface_a];
  if (!sa.vertex_alive(d.vertex_a)) throw InvalidArgument("attachment: vertex_a is not a live vertex");
  Attachment a{d, sa.vertex_id(d.vertex_a), {}, true, false, 0.0, 0.0};
  if (d.surface_b == AttachmentDescription::kWorld) {
    require_finite(d.world_point_mm, "attachment: world point");
  } else {
    if (d.surface_b >= surfaces_.size()) throw InvalidArgument("attachment: surface_b out of range");
    const Surface& sb = *surfaces_[d.surface_b];
    if (!sb.vertex_alive(d.vertex_b)) throw InvalidArgument("attachment: vertex_b is not a live vertex");
    if (d.surface_a == d.surface_b && d.vertex_a == d.vertex_b) throw InvalidArgument("attachment binds a vertex to itself");
    a.b = sb.vertex_id(d.vertex_b);
  }
  require_range(d.stiffness_un_per_mm, 1e-6, 1e12, "attachment: stiffness");
  if (std::isnan(d.break_force_un) || !(d.break_force_un > 0.0)) {
    throw InvalidArgument("attachment: break force must be > 0 (infinity = unbreakable)");
  }
  require_range(d.rest_length_mm, 0.0, 5.0, "attachment: rest length");
  if (d.rest_length_mm > 0.0 && d.surface_b == AttachmentDescription::kWorld) {
    throw InvalidArgument("attachment: a rest length needs two surfaces (a stalk between layers)");
  }
  attachments_.push_back(a);
  reserve_point_terms();
  return static_cast<std::uint32_t>(attachments_.size() - 1);
}

std::uint32_t TissueWorld::add_local_force(const LocalForceDescription& d) {
  if (d.surface >= surfaces_.size()) throw InvalidArgument("local force '" + d.name + "': surface out of range");
  const Surface& s = *surfaces_[d.surface];
  for (auto v : d.vertices) {
    if (!s.vertex_alive(v)) throw InvalidArgument("local force '" + d.name + "': vertex is not live");
  }
  if (!d.weights.empty() && d.weights.size() != d.vertices.size()) {
    throw InvalidArgument("local force '" + d.name + "': weights must match vertices");
  }
  for (double w : d.weights) require_range(w, 0.0, 1.0, "local force '" + d.name + "': weight");
  require_finite(d.toward_point_mm, "local force '" + d.name + "': toward point");
  require_range(d.pressure_pa, -1e5, 1e5, "local force '" + d.name + "': pressure");
  require_range(d.scale, 0.0, 1.0, "local force '" + d.name + "': scale");
  local_forces_.push_back({d});
  return static_cast<std::uint32_t>(local_forces_.size() - 1);
}

Status TissueWorld::set_environment(const Environment& environment) {
  try {
    environment.validate();
  } catch (const InvalidArgument& e) {
    return Status::error(e.what());
  }
  environment_ = environment;
  wake_all();
  return Status::ok();
}

void TissueWorld::wake_all() {
  for (auto& sp : surfaces_) sp->wake_all();
}

void TissueWorld::wake_sphere(const Vec3& center, double radius) {
  if (!is_finite(center) || !std::isfinite(radius)) return;
  const double r2 = radius * radius;
  for (auto& sp : surfaces_) {
    Surface& s = *sp;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (s.vertex_alive(v) && !s.vertex_awake(v) && (s.position(v) - center).squaredNorm() <= r2) s.wake_vertex(v);
    }
  }
}

std::uint32_t TissueWorld::awake_blocks() const {
  std::uint32_t n = 0;
  for (const auto& sp : surfaces_) n += sp->awake_block_count();
  return n;
}

std::uint32_t TissueWorld::total_blocks() const {
  std::uint32_t n = 0;
  for (const auto& sp : surfaces_) n += sp->block_count();
  return n;
}

Status TissueWorld::set_local_force_scale(std::uint32_t force, double scale) {
  if (force >= local_forces_.size()) return Status::error("set_local_force_scale: no such force");
  if (!std::isfinite(scale) || scale < 0.0 || scale > 1.0) {
    return Status::error("set_local_force_scale: scale must be finite and in [0, 1]");
  }
  auto& f = local_forces_[force].d;
  if (f.scale != scale) {
    Surface& s = *surfaces_[f.surface];
    for (auto v : f.vertices) {
      if (s.vertex_alive(v)) s.wake_vertex(v);
    }
  }
  f.scale = scale;
  return Status::ok();
}

std::uint32_t TissueWorld::cut_attachments_in(const Vec3& center_mm, const Vec3& normal, double radius_mm) {
  const double n2 = normal.squaredNorm();
  if (!(n2 > 0.0) || !std::isfinite(n2) || !center_mm.allFinite() || !(radius_mm > 0.0)) return 0;
  const Vec3 n = normal / std::sqrt(n2);
  return cut_attachments_if([&](const Vec3& top, const Vec3& base) {
    const Vec3 mid = 0.5 * (top + base) - center_mm;
    return mid.dot(n) >= 0.0 && mid.squaredNorm() <= radius_mm * radius_mm;
  });
}

bool TissueWorld::attachment_holds(std::uint32_t i) const {
  const Attachment& at = attachments_.at(i);
  if (!at.intact || !surfaces_[at.d.surface_a]->is_current(at.a)) return false;
  return at.d.surface_b == AttachmentDescription::kWorld || surfaces_[at.d.surface_b]->is_current(at.b);
}

double TissueWorld::total_mass() const {
  double m = 0.0;
  for (const auto& s : surfaces_) m += s->total_mass();
  return m;
}

Energy TissueWorld::energy() const {
  Energy en;
  for (const auto& sp : surfaces_) {
    const Surface& s = *sp;
    const double buoyant = 1.0 - environment_.fluid_density_g_per_mm3 / s.material().density_g_per_mm3;
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (!s.vertex_alive(v)) continue;
      en.kinetic += 0.5 * s.mass(v) * s.velocity(v).squaredNorm();
      en.gravity -= s.mass(v) * buoyant * environment_.gravity_mm_s2.dot(s.position(v));
    }
    for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
      if (!s.edge_alive(e)) continue;
      const auto [a, b] = s.edge_vertices(e);
      const double stretch = (s.position(b) - s.position(a)).norm() - s.edge_rest_length(e);
      en.elastic += 0.5 * s.edge_stiffness(e) * stretch * stretch;
      const Surface::BendStencil& st = s.edge_bend(e);
      if (st.stiffness == 0.0) continue;
      const auto [c, d] = s.edge_opposite_vertices(e);
      const Vec3 &xa = s.position(a), &xb = s.position(b), &xc = s.position(c), &xd = s.position(d);
      const Vec3 off = st.curvature(xa, xb, xc, xd) - s.edge_rest_curvature(e) * st.normal(xa, xb, xc, xd);
      en.elastic += 0.5 * st.stiffness * off.squaredNorm();
    }
  }
  for (const auto& at : attachments_) {
    if (!at.intact) continue;
    const Vec3 pa = surfaces_[at.d.surface_a]->position(at.a.index);
    const Vec3 pb = at.d.surface_b == AttachmentDescription::kWorld ? at.d.world_point_mm
                                                                     : surfaces_[at.d.surface_b]->position(at.b.index);
    en.elastic += 0.5 * at.d.stiffness_un_per_mm * (pb - pa).squaredNorm();
  }
  return en;
}

Status TissueWorld::check_spring_groups() const {
  for (std::size_t si = 0; si < surfaces_.size(); ++si) {
    const Status st = scratch_[si].groups.check(*surfaces_[si]);
    if (!st) return Status::error("surface " + std::to_string(si) + ": " + st.message());
  }
  return Status::ok();
}

std::uint64_t TissueWorld::spring_group_rebuilds() const {
  std::uint64_t n = 0;
  for (const auto& sc : scratch_) n += sc.groups.rebuilds();
  return n;
}

std::uint64_t TissueWorld::state_hash() const {
  StateHasher h;
  h.add_u64(step_count_);
  h.add_double(time_s_);
  for (const auto& sp : surfaces_) {
    const Surface& s = *sp;
    h.add_u64(s.vertex_slots());
    for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) {
      if (!s.vertex_alive(v)) {
        h.add_u64(0xdead);
        continue;
      }
      h.add_vec3(s.position(v));
      h.add_vec3(s.velocity(v));
    }
    h.add_u64(s.edge_slots());
    for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
      if (!s.edge_alive(e)) continue;
      const auto ev = s.edge_vertices(e);
      h.add_u64((std::uint64_t{ev[0]} << 32) | ev[1]);
      h.add_vec3(s.edge_rest_vector(e));
      h.add_double(s.edge_rest_curvature(e));
    }
    h.add_u64(s.triangle_slots());
  }
  for (const auto& at : attachments_) h.add_u64(at.intact ? 1 : 0);
  for (const auto& f : local_forces_) h.add_double(f.d.scale);
  return h.value();
}

}  // namespace vitreo::core
