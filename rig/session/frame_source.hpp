#pragma once
// From the physics state to the renderer's FrameScene, without making physics wait or allocate.
//
// Physics copies what the picture needs (vertex positions; triangle lists only when the topology
// changed; instruments, light, burns, fluid level) into a preallocated slot of a triple buffer at
// display rate; the render service thread turns the newest slot into a FrameScene and hands it to
// the render thread. This is the thesis' double-buffered vertex state (ch. 2.3.2), with a third
// buffer so neither side ever waits.
//
// What a case looks like (CaseVisuals, built on the loader thread when the case is loaded): the eye
// model's static meshes (sclera, choroid with the choroid map, iris, lens, ciliary processes, the
// three port cannulas), the retina's vessel map, and which surface is retina, gel or membrane. The
// render thread adds per frame: the retina with its vessel alpha map over the choroid, coloured by
// how far each vertex has lifted off the wall (detached = greyish), membranes whitish, gel hazy,
// laser burns where the instrument system recorded them, the fluid–gas level, the instruments.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/anatomy/eye_model.hpp"
#include "rig/runtime/triple_buffer.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/session/view_snapshot.hpp"
#include "vitreo/render/frame_scene.hpp"

namespace vitreo::rig {

struct CaseVisuals {
  int index = 0;
  std::string name, title;
  core::EyeModel eye;                       // wall (detachment distance) and fundus mapping
  std::vector<render::Mesh> statics;        // static meshes, ids 1..99
  render::ImagePtr retina_texture;          // vessel colour + alpha (fundus plane)
  std::vector<render::MaterialKind> surface_material;  // per world surface
  core::Vec3 focus_mm = core::Vec3::Zero();
  float globe_radius_mm = 12.0f;
  float camera_z_mm = 4.0f;                 // wide-angle view: just behind the lens
  std::vector<Port> ports;                  // instrument pivots by the eye's port index
};

// Loader thread: the case's look. Needs the scene's textures (load with textures on).
std::unique_ptr<CaseVisuals> build_case_visuals(const PreparedCase& c);
// Loader thread: gives the case its three view snapshots, sized for its surfaces.
void prepare_view_snapshots(PreparedCase& c);

// Physics thread: copies the model's current state into `out` (no allocation: when `out` was sized
// for another case it is swapped with one of the case's spares first; without one nothing is
// copied and false is returned).
bool capture_view(SimulationModel& model, std::uint64_t step, double t_s, ViewSnapshot& out);

// Render service thread: builds the FrameScene of a snapshot. Keeps the last case's static meshes
// and the geometry versions between calls.
class FrameBuilder {
 public:
  render::FrameScene build(const ViewSnapshot& snapshot);

 private:
  std::uint64_t serial_ = 0;
  std::uint64_t frame_ = 0;
};

}  // namespace vitreo::rig
