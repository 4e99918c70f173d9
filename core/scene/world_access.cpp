// Complete serialisation of TissueWorld and Surface state (friend access, see world_access.hpp).
#include "core/scene/world_access.hpp"

#include <cstring>
#include <string>
#include <type_traits>

namespace vitreo::core {

namespace {

class Writer {
 public:
  explicit Writer(std::vector<std::uint8_t>& out) : out_(out) {}
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t at = out_.size();
    out_.resize(at + sizeof(T));
    std::memcpy(out_.data() + at, &v, sizeof(T));
  }
  void vec3(const Vec3& v) {
    pod(v.x());
    pod(v.y());
    pod(v.z());
  }
  void str(const std::string& s) {
    pod(static_cast<std::uint64_t>(s.size()));
    const std::size_t at = out_.size();
    out_.resize(at + s.size());
    if (!s.empty()) std::memcpy(out_.data() + at, s.data(), s.size());
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(static_cast<std::uint64_t>(v.size()));
    for (const auto& x : v) item(x);
  }

 private:
  template <class T>
  void item(const T& x) {
    if constexpr (std::is_same_v<T, Vec3>) {
      vec3(x);
    } else {
      pod(x);
    }
  }
  std::vector<std::uint8_t>& out_;
};

// Reads in two passes: with apply = false it only checks that everything is present and fits; with
// apply = true it writes. A failed check sets ok = false and every later read is a no-op.
class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size, bool apply) : p_(data), end_(data + size), apply_(apply) {}
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  bool at_end() const { return p_ == end_; }
  void fail(const std::string& e) {
    if (error_.empty()) error_ = e;
  }

  template <class T>
  T pod_value() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v{};
    if (!ok()) return v;
    if (static_cast<std::size_t>(end_ - p_) < sizeof(T)) {
      fail("snapshot truncated");
      return v;
    }
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    return v;
  }
  template <class T>
  void pod(T& target) {
    const T v = pod_value<T>();
    if (apply_ && ok()) target = v;
  }
  void vec3(Vec3& target) {
    Vec3 v;
    v.x() = pod_value<double>();
    v.y() = pod_value<double>();
    v.z() = pod_value<double>();
    if (apply_ && ok()) target = v;
  }
  void str(std::string& target) {
    const auto n = pod_value<std::uint64_t>();
    if (!ok()) return;
    if (n > static_cast<std::uint64_t>(end_ - p_) || n > 4096) {
      fail("snapshot: bad string length");
      return;
    }
    if (apply_) target.assign(reinterpret_cast<const char*>(p_), static_cast<std::size_t>(n));
    p_ += n;
  }
  // A pool vector: must fit in the capacity reserved when the surface was built (no reallocation),
  // or, with `growable`, any size up to a sanity bound.
  template <class T>
  void vec(std::vector<T>& target, bool growable = false) {
    const auto n = pod_value<std::uint64_t>();
    if (!ok()) return;
    const std::size_t item = std::is_same_v<T, Vec3> ? 24 : sizeof(T);
    if (n > static_cast<std::uint64_t>(end_ - p_) / item) {
      fail("snapshot truncated (vector)");
      return;
    }
    if (!growable && n > target.capacity()) {
      fail("snapshot does not fit this scene (pool larger than its capacity)");
      return;
    }
    if (apply_) target.resize(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (std::is_same_v<T, Vec3>) {
        Vec3 dummy;
        vec3(apply_ ? target[i] : dummy);
      } else {
        T dummy{};
        pod(apply_ ? target[i] : dummy);
      }
    }
  }
  // A vector whose size is fixed by the scene (scratch arrays): must match exactly.
  template <class T>
  void fixed_vec(std::vector<T>& target) {
    const auto before = p_;
    const auto n = pod_value<std::uint64_t>();
    if (ok() && n != target.size()) {
      fail("snapshot does not fit this scene (array size)");
      return;
    }
    p_ = before;
    vec(target, true);
  }

 private:
  const std::uint8_t* p_;
  const std::uint8_t* end_;
  bool apply_;
  std::string error_;
};

constexpr std::uint32_t kSectionSurface = 0x53524631;  // "SRF1"
constexpr std::uint32_t kSectionWorld = 0x574c4431;    // "WLD1"

template <class IO, class M>
void material_io(IO& io, M& m) {
  io.str(m.name);
  io.pod(m.density_g_per_mm3);
  io.pod(m.thickness_mm);
  io.pod(m.membrane_modulus_pa_mm);
  io.pod(m.bending_modulus_un_mm);
  io.pod(m.tear_strain);
  io.pod(m.drag_pa_s_per_mm);
  io.pod(m.internal_damping_s);
  io.pod(m.entrained_fluid_mm);
  io.pod(m.plastic_yield_strain);
  io.pod(m.plastic_rate_per_s);
}

}  // namespace

void WorldAccess::set_settings(TissueWorld& world, const SolverSettings& settings) {
  settings.validate();
  world.settings_ = settings;
}

void WorldAccess::set_clock(TissueWorld& world, std::uint64_t steps, double time_s) {
  world.step_count_ = steps;
  world.time_s_ = time_s;
}

void WorldAccess::write_state(const TissueWorld& w, std::vector<std::uint8_t>& out) {
  Writer o(out);
  o.pod(kSectionWorld);
  o.pod(w.step_count_);
  o.pod(w.time_s_);
  const Environment& e = w.environment_;
  o.vec3(e.gravity_mm_s2);
  o.pod(e.fluid_density_g_per_mm3);
  o.pod(e.gas_density_g_per_mm3);
  o.pod(e.fluid_level_z_mm);
  o.pod(e.intraocular_pressure_pa);
  o.pod(static_cast<std::uint8_t>(e.apply_pressure));
  const SolverSettings& s = w.settings_;
  o.pod(s.substeps);
  o.pod(s.iterations);
  o.pod(s.max_tears_per_step);
  o.pod(s.wall_offset_mm);
  o.pod(s.settling_damping_per_s);
  o.pod(static_cast<std::uint8_t>(s.sleeping));
  o.pod(s.sleep_speed_mm_s);
  o.pod(s.sleep_after_steps);
  o.pod(s.wake_strain);
  o.pod(s.wall_friction);

  o.pod(static_cast<std::uint64_t>(w.surfaces_.size()));
  for (std::size_t i = 0; i < w.surfaces_.size(); ++i) {
    const Surface& f = *w.surfaces_[i];
    o.pod(kSectionSurface);
    TissueMaterial m = f.material_;
    material_io(o, m);
    o.pod(static_cast<std::uint8_t>(f.contained_by_globe_));
    o.pod(static_cast<std::uint8_t>(f.pressurised_));
    o.pod(f.surface_traction_);
    o.vec(f.x_);
    o.vec(f.v_);
    o.vec(f.rest_);
    o.vec(f.mass_);
    o.vec(f.inverse_mass_);
    o.vec(f.extra_mass_);
    o.vec(f.vertex_area_);
    o.vec(f.vertex_alive_);
    o.vec(f.fixed_);
    o.vec(f.vertex_generation_);
    o.vec(f.first_corner_);
    o.vec(f.free_vertices_);
    o.pod(f.live_vertices_);
    o.vec(f.edge_v_);
    o.vec(f.edge_t_);
    o.vec(f.base_rest_vec_);
    o.vec(f.rest_vec_);
    o.vec(f.rest_len_);
    o.vec(f.stiffness_);
    o.vec(f.edge_traction_);
    o.vec(f.bend_);
    o.vec(f.bend_rest_);
    o.vec(f.edge_alive_);
    o.vec(f.edge_is_line_);
    o.vec(f.edge_generation_);
    o.vec(f.free_edges_);
    o.pod(f.live_edges_);
    o.vec(f.tri_v_);
    o.vec(f.tri_e_);
    o.vec(f.next_corner_);
    o.vec(f.tri_rest_area_);
    o.vec(f.tri_alive_);
    o.vec(f.tri_generation_);
    o.vec(f.free_triangles_);
    o.pod(f.live_triangles_);
    o.vec(f.block_awake_);
    o.vec(f.block_quiet_steps_);
    o.pod(f.topology_version_);

    const auto& sc = w.scratch_[i];
    o.vec(sc.previous);
    o.vec(sc.acceleration);
    o.vec(sc.rollback_x);
    o.vec(sc.rollback_v);
    o.vec(sc.drag_rate);
    o.vec(sc.effective_inverse_mass);
    o.vec(sc.current_area);
    o.vec(sc.contact_load);
    o.vec(sc.wall_touched);
    o.vec(sc.momentum);
    o.vec(sc.block_was_awake);
    o.vec(sc.wake_request);
    o.vec(sc.block_max_speed2);
    o.vec(sc.block_sleep_serial);
    o.vec(sc.wake_key);
    o.vec(sc.wake_length);
  }

  o.pod(static_cast<std::uint64_t>(w.attachments_.size()));
  for (const auto& a : w.attachments_) {
    o.pod(a.d.surface_a);
    o.pod(a.d.vertex_a);
    o.pod(a.d.surface_b);
    o.pod(a.d.vertex_b);
    o.vec3(a.d.world_point_mm);
    o.pod(a.d.stiffness_un_per_mm);
    o.pod(a.d.break_force_un);
    o.pod(a.a.index);
    o.pod(a.a.generation);
    o.pod(a.b.index);
    o.pod(a.b.generation);
    o.pod(static_cast<std::uint8_t>(a.intact));
    o.pod(a.last_force_un);
    o.pod(a.peak_force_un);
  }
  o.pod(static_cast<std::uint64_t>(w.local_forces_.size()));
  for (const auto& lf : w.local_forces_) {
    o.str(lf.d.name);
    o.pod(lf.d.surface);
    o.vec(lf.d.vertices);
    o.vec(lf.d.weights);
    o.vec3(lf.d.toward_point_mm);
    o.pod(lf.d.pressure_pa);
    o.pod(lf.d.scale);
  }
  o.pod(static_cast<std::uint64_t>(w.events_.size()));
  for (const auto& ev : w.events_) {
    o.pod(static_cast<std::uint8_t>(ev.kind));
    o.pod(ev.surface);
    o.pod(ev.item);
    o.vec3(ev.position_mm);
    o.pod(ev.magnitude);
  }
}

Status WorldAccess::read_state(TissueWorld& w, const std::uint8_t* data, std::size_t size) {
  for (const bool apply : {false, true}) {
    Reader in(data, size, apply);
    if (in.pod_value<std::uint32_t>() != kSectionWorld) return Status::error("snapshot: world section missing");
    in.pod(w.step_count_);
    in.pod(w.time_s_);
    Environment env = w.environment_;
    in.vec3(env.gravity_mm_s2);
    in.pod(env.fluid_density_g_per_mm3);
    in.pod(env.gas_density_g_per_mm3);
    in.pod(env.fluid_level_z_mm);
    in.pod(env.intraocular_pressure_pa);
    env.apply_pressure = in.pod_value<std::uint8_t>() != 0;
    SolverSettings s = w.settings_;
    in.pod(s.substeps);
    in.pod(s.iterations);
    in.pod(s.max_tears_per_step);
    in.pod(s.wall_offset_mm);
    in.pod(s.settling_damping_per_s);
    s.sleeping = in.pod_value<std::uint8_t>() != 0;
    in.pod(s.sleep_speed_mm_s);
    in.pod(s.sleep_after_steps);
    in.pod(s.wake_strain);
    in.pod(s.wall_friction);
    if (!apply && in.ok()) {
      try {
        env.validate();
        s.validate();
      } catch (const InvalidArgument& e) {
        return Status::error(std::string("snapshot: ") + e.what());
      }
    }
    if (apply) {
      w.environment_ = env;
      w.settings_ = s;
    }

    if (in.pod_value<std::uint64_t>() != w.surfaces_.size()) return Status::error("snapshot: surface count differs from the scene");
    for (std::size_t i = 0; i < w.surfaces_.size() && in.ok(); ++i) {
      Surface& f = *w.surfaces_[i];
      if (in.pod_value<std::uint32_t>() != kSectionSurface) return Status::error("snapshot: surface section missing");
      TissueMaterial m = f.material_;
      material_io(in, m);
      if (!apply && in.ok()) {
        try {
          m.validate();
        } catch (const InvalidArgument& e) {
          return Status::error(std::string("snapshot: ") + e.what());
        }
      }
      if (apply) f.material_ = m;
      std::uint8_t flag = 0;
      in.pod(flag);
      if (apply) f.contained_by_globe_ = flag != 0;
      in.pod(flag);
      if (apply) f.pressurised_ = flag != 0;
      in.pod(f.surface_traction_);
      in.vec(f.x_);
      in.vec(f.v_);
      in.vec(f.rest_);
      in.vec(f.mass_);
      in.vec(f.inverse_mass_);
      in.vec(f.extra_mass_);
      in.vec(f.vertex_area_);
      in.vec(f.vertex_alive_);
      in.vec(f.fixed_);
      in.vec(f.vertex_generation_);
      in.vec(f.first_corner_);
      in.vec(f.free_vertices_);
      in.pod(f.live_vertices_);
      in.vec(f.edge_v_);
      in.vec(f.edge_t_);
      in.vec(f.base_rest_vec_);
      in.vec(f.rest_vec_);
      in.vec(f.rest_len_);
      in.vec(f.stiffness_);
      in.vec(f.edge_traction_);
      in.vec(f.bend_);
      in.vec(f.bend_rest_);
      in.vec(f.edge_alive_);
      in.vec(f.edge_is_line_);
      in.vec(f.edge_generation_);
      in.vec(f.free_edges_);
      in.pod(f.live_edges_);
      in.vec(f.tri_v_);
      in.vec(f.tri_e_);
      in.vec(f.next_corner_);
      in.vec(f.tri_rest_area_);
      in.vec(f.tri_alive_);
      in.vec(f.tri_generation_);
      in.vec(f.free_triangles_);
      in.pod(f.live_triangles_);
      in.fixed_vec(f.block_awake_);
      in.fixed_vec(f.block_quiet_steps_);
      in.pod(f.topology_version_);
      if (apply) {
        f.note_all_blocks_moved();  // positions replaced: spatial indexes refit everything
        f.forget_spring_log();      // springs replaced: derived groups rebuild from every spring
      }

      auto& sc = w.scratch_[i];
      in.fixed_vec(sc.previous);
      in.fixed_vec(sc.acceleration);
      in.fixed_vec(sc.rollback_x);
      in.fixed_vec(sc.rollback_v);
      in.fixed_vec(sc.drag_rate);
      in.fixed_vec(sc.effective_inverse_mass);
      in.fixed_vec(sc.current_area);
      in.fixed_vec(sc.contact_load);
      in.fixed_vec(sc.wall_touched);
      in.fixed_vec(sc.momentum);
      in.fixed_vec(sc.block_was_awake);
      in.fixed_vec(sc.wake_request);
      in.fixed_vec(sc.block_max_speed2);
      in.fixed_vec(sc.block_sleep_serial);
      in.fixed_vec(sc.wake_key);
      in.fixed_vec(sc.wake_length);
    }

    if (in.pod_value<std::uint64_t>() != w.attachments_.size()) {
      if (in.ok()) return Status::error("snapshot: attachment count differs from the scene");
    }
    for (auto& a : w.attachments_) {
      in.pod(a.d.surface_a);
      in.pod(a.d.vertex_a);
      in.pod(a.d.surface_b);
      in.pod(a.d.vertex_b);
      in.vec3(a.d.world_point_mm);
      in.pod(a.d.stiffness_un_per_mm);
      in.pod(a.d.break_force_un);
      in.pod(a.a.index);
      in.pod(a.a.generation);
      in.pod(a.b.index);
      in.pod(a.b.generation);
      const bool intact = in.pod_value<std::uint8_t>() != 0;
      if (apply) a.intact = intact;
      in.pod(a.last_force_un);
      in.pod(a.peak_force_un);
      if (!apply && in.ok() && (a.d.surface_a >= w.surfaces_.size() ||
                                (a.d.surface_b != AttachmentDescription::kWorld && a.d.surface_b >= w.surfaces_.size()))) {
        return Status::error("snapshot: attachment refers to a missing surface");
      }
    }
    if (in.pod_value<std::uint64_t>() != w.local_forces_.size()) {
      if (in.ok()) return Status::error("snapshot: local force count differs from the scene");
    }
    for (auto& lf : w.local_forces_) {
      in.str(lf.d.name);
      in.pod(lf.d.surface);
      in.vec(lf.d.vertices, true);
      in.vec(lf.d.weights, true);
      in.vec3(lf.d.toward_point_mm);
      in.pod(lf.d.pressure_pa);
      in.pod(lf.d.scale);
      if (!apply && in.ok() && lf.d.surface >= w.surfaces_.size()) return Status::error("snapshot: force on a missing surface");
    }
    const auto nev = in.pod_value<std::uint64_t>();
    if (in.ok() && nev > 1'000'000) return Status::error("snapshot: too many events");
    if (apply) w.events_.clear();
    for (std::uint64_t k = 0; k < nev && in.ok(); ++k) {
      TissueEvent ev{};
      ev.kind = static_cast<TissueEventKind>(in.pod_value<std::uint8_t>());
      in.pod(ev.surface);
      in.pod(ev.item);
      in.vec3(ev.position_mm);
      in.pod(ev.magnitude);
      if (apply) w.events_.push_back(ev);
    }
    if (!in.ok()) return Status::error(in.error());
    if (!in.at_end()) return Status::error("snapshot: trailing bytes");
  }
  return Status::ok();
}

}  // namespace vitreo::core
