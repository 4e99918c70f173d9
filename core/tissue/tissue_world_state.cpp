// TissueWorld's mutable state for snapshots: the one list of its fields (tissue_world.hpp, state
// I/O); each surface lists its own (surface_state.cpp). A field added to the world, its
// environment, its settings or its per-surface scratch is one line here.
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

namespace {
constexpr std::uint32_t kSectionWorld = 0x574c4431;  // "WLD1"
}  // namespace

template <class IO>
void TissueWorld::state_io(IO& io) {
  io.section(kSectionWorld, "world");
  io.pod(step_count_);
  io.pod(time_s_);
  io.record(
      environment_,
      [&](Environment& e) {
        io.vec3(e.gravity_mm_s2);
        io.pod(e.fluid_density_g_per_mm3);
        io.pod(e.gas_density_g_per_mm3);
        io.pod(e.fluid_level_z_mm);
        io.pod(e.intraocular_pressure_pa);
        io.flag(e.apply_pressure);
      },
      [](const Environment& e) { e.validate(); });
  io.record(
      settings_,
      [&](SolverSettings& s) {
        io.pod(s.substeps);
        io.pod(s.iterations);
        io.pod(s.max_tears_per_step);
        io.pod(s.wall_offset_mm);
        io.pod(s.settling_damping_per_s);
        io.flag(s.sleeping);
        io.pod(s.sleep_speed_mm_s);
        io.pod(s.sleep_after_steps);
        io.pod(s.wake_strain);
        io.pod(s.wall_friction);
      },
      [](const SolverSettings& s) { s.validate(); });

  io.count(surfaces_.size(), "surface");
  for (std::size_t i = 0; i < surfaces_.size(); ++i) {
    if constexpr (IO::kReading) {
      surfaces_[i]->read_state(io);
    } else {
      surfaces_[i]->write_state(io);
    }
    Scratch& sc = scratch_[i];
    io.fixed_vec(sc.previous);
    io.fixed_vec(sc.acceleration);
    io.fixed_vec(sc.rollback_x);
    io.fixed_vec(sc.rollback_v);
    io.fixed_vec(sc.drag_rate);
    io.fixed_vec(sc.effective_inverse_mass);
    io.fixed_vec(sc.current_area);
    io.fixed_vec(sc.contact_load);
    io.fixed_vec(sc.wall_touched);
    io.fixed_vec(sc.momentum);
    io.fixed_vec(sc.block_was_awake);
    io.fixed_vec(sc.wake_request);
    io.fixed_vec(sc.block_max_speed2);
    io.fixed_vec(sc.block_sleep_serial);
    io.fixed_vec(sc.wake_key);
    io.fixed_vec(sc.wake_length);
    sc.layout_valid = false;  // (reading or writing: a layout is rebuilt at the next step either way)
  }

  const std::size_t surfaces = surfaces_.size();
  io.count(attachments_.size(), "attachment");
  for (Attachment& attachment : attachments_) {
    io.record(
        attachment,
        [&](Attachment& a) {
          io.pod(a.d.surface_a);
          io.pod(a.d.vertex_a);
          io.pod(a.d.surface_b);
          io.pod(a.d.vertex_b);
          io.vec3(a.d.world_point_mm);
          io.pod(a.d.stiffness_un_per_mm);
          io.pod(a.d.break_force_un);
          io.pod(a.a.index);
          io.pod(a.a.generation);
          io.pod(a.b.index);
          io.pod(a.b.generation);
          io.flag(a.intact);
          io.pod(a.last_force_un);
          io.pod(a.peak_force_un);
        },
        [&](const Attachment& a) {
          if (a.d.surface_a >= surfaces || (a.d.surface_b != AttachmentDescription::kWorld && a.d.surface_b >= surfaces)) {
            throw InvalidArgument("attachment refers to a missing surface");
          }
        });
  }
  io.count(local_forces_.size(), "local force");
  for (LocalForce& force : local_forces_) {
    io.record(
        force.d,
        [&](LocalForceDescription& f) {
          io.str(f.name);
          io.pod(f.surface);
          io.vec(f.vertices, true);
          io.vec(f.weights, true);
          io.vec3(f.toward_point_mm);
          io.pod(f.pressure_pa);
          io.pod(f.scale);
        },
        [&](const LocalForceDescription& f) {
          if (f.surface >= surfaces) throw InvalidArgument("force on a missing surface");
        });
  }
  io.list(events_, 1'000'000, "events", [&](TissueEvent& e) {
    auto kind = static_cast<std::uint8_t>(e.kind);
    io.pod(kind);
    e.kind = static_cast<TissueEventKind>(kind);
    io.pod(e.surface);
    io.pod(e.item);
    io.vec3(e.position_mm);
    io.pod(e.magnitude);
  });
}

void TissueWorld::write_state(std::vector<std::uint8_t>& out) const {
  StateWriter writer(out);
  // the writer only reads the fields; state_io is one list for both directions
  const_cast<TissueWorld*>(this)->state_io(writer);
}

Status TissueWorld::read_state(const std::uint8_t* data, std::size_t size) {
  return read_state_twice(data, size, [&](StateReader& in) { state_io(in); });
}

void TissueWorld::replace_settings(const SolverSettings& settings) {
  settings.validate();
  settings_ = settings;
}

void TissueWorld::reset_clock() {
  step_count_ = 0;
  time_s_ = 0.0;
}

}  // namespace vitreo::core
