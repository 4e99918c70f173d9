// Surface's mutable state for snapshots: the one list of its fields (surface.hpp, state I/O).
// A field added to Surface that a restored surface needs to step on in the same bits is one line here.
#include "core/tissue/surface.hpp"

namespace vitreo::core {

namespace {
constexpr std::uint32_t kSectionSurface = 0x53524631;  // "SRF1"
}  // namespace

template <class IO>
void Surface::state_io(IO& io) {
  io.section(kSectionSurface, "surface");
  io.record(material_, [&](TissueMaterial& m) { material_io(io, m); }, [](const TissueMaterial& m) { m.validate(); });
  io.flag(contained_by_globe_);
  io.flag(pressurised_);
  io.pod(surface_traction_);

  io.vec(x_);
  io.vec(v_);
  io.vec(rest_);
  io.vec(mass_);
  io.vec(inverse_mass_);
  io.vec(extra_mass_);
  io.vec(vertex_area_);
  io.vec(vertex_alive_);
  io.vec(fixed_);
  io.vec(vertex_generation_);
  io.vec(first_corner_);
  io.vec(free_vertices_);
  io.pod(live_vertices_);

  io.vec(edge_v_);
  io.vec(edge_t_);
  io.vec(base_rest_vec_);
  io.vec(rest_vec_);
  io.vec(rest_len_);
  io.vec(stiffness_);
  io.vec(edge_traction_);
  io.vec(bend_);
  io.vec(bend_rest_);
  io.vec(edge_alive_);
  io.vec(edge_is_line_);
  io.vec(edge_generation_);
  io.vec(free_edges_);
  io.pod(live_edges_);

  io.vec(tri_v_);
  io.vec(tri_e_);
  io.vec(next_corner_);
  io.vec(tri_rest_area_);
  io.vec(tri_alive_);
  io.vec(tri_generation_);
  io.vec(free_triangles_);
  io.pod(live_triangles_);

  io.fixed_vec(block_awake_);
  io.fixed_vec(block_quiet_steps_);
  io.pod(topology_version_);
}

void Surface::write_state(StateWriter& out) const {
  // the writer only reads the fields; state_io is one list for both directions
  const_cast<Surface*>(this)->state_io(out);
}

void Surface::read_state(StateReader& in) {
  state_io(in);
  if (in.applying() && in.ok()) {
    note_all_blocks_moved();  // positions replaced: spatial indexes refit everything
    ++awake_version_;         // awake blocks replaced: the solver lays them out again
    forget_spring_log();      // springs replaced: derived groups rebuild from every spring
    ++spring_values_version_;  // and their rest lengths and stiffnesses
  }
}

}  // namespace vitreo::core
