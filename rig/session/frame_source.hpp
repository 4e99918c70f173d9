#pragma once
// From the physics state to the renderer's FrameScene, without making physics wait or allocate.
//
// Physics copies what the picture needs (vertex positions; triangle lists only when the topology
// changed; instruments with their handles and pedals, the light, burns, the fluid level, the
// microscope, guide progress, the instructor's numbers) into a preallocated slot of a triple buffer
// at display rate; the render service thread turns the newest slot into a FrameScene and hands it
// to the render thread. This is the thesis' double-buffered vertex state (ch. 2.3.2), with a third
// buffer so neither side ever waits.
//
// What a case looks like (CaseVisuals, built on the loader thread when the case is loaded): the eye
// model's static meshes (sclera, choroid with the choroid map, iris, lens, ciliary processes, the
// three port cannulas), the retina's vessel map, which surface is retina, gel or membrane, the
// case's guides and the names of its structures, the gel's stain, the chandelier. The render thread
// adds per frame (FrameBuilder):
//   - the retina with its vessel alpha map over the choroid, coloured by how far each vertex has
//     lifted off the wall (detached = greyer, more opaque, the subretinal fluid under it), cut edges
//     and tears rolled and whiter; membranes white-grey and glistening; the gel a faint haze (or
//     white with triamcinolone) that is gone wherever the vitrector removed it; laser burns greying
//     over a few hundred milliseconds where the instrument system recorded them; the fluid–gas level;
//   - the instruments from their real geometry (instrument_models.hpp), the light pipe's light and
//     the chandelier's;
//   - the guides on the fundus, the done parts in another colour, and the structures' names (the
//     labels toggle shows or hides both);
//   - the microscope: the view through the eye's optics (contact lens, or the wide-angle system with
//     its inversion) from the pupil toward the field centre, zoomed, focused (depth of field);
//   - the instructor's overlay (score, criteria, retina force, the latest events).
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/anatomy/eye_model.hpp"
#include "core/scene/scene_description.hpp"
#include "rig/runtime/triple_buffer.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/session/view_snapshot.hpp"
#include "vitreo/render/frame_scene.hpp"

namespace vitreo::rig {

struct GuideVisual {
  std::string name;
  core::GuideKind kind = core::GuideKind::kCutPath;
  std::vector<render::Vec3> points;  // along the guide on the retina (the measured points when measured)
  bool measured = false;             // a criterion measures it: ViewSnapshot::guides carries its progress
};

struct CaseVisuals {
  int index = 0;
  std::string name, title;
  core::EyeModel eye;                       // wall (detachment distance) and fundus mapping
  std::vector<render::Mesh> statics;        // static meshes, ids 1..99
  render::ImagePtr retina_texture;          // vessel colour + alpha (fundus plane)
  render::ImagePtr gel_stain;               // triamcinolone crystals (alpha), when the case stains the gel
  std::vector<render::MaterialKind> surface_material;  // per world surface
  core::Vec3 focus_mm = core::Vec3::Zero();
  float globe_radius_mm = 12.0f;
  float camera_z_mm = 4.0f;                 // the view through the eye's optics: from just behind the lens
  std::vector<Port> ports;                  // instrument pivots by the eye's port index
  std::vector<GuideVisual> guides;          // the scene's guides, in order
  std::vector<render::Label> labels;        // the case's structures (disc, fovea, tears, membranes, detachments)
  double retina_edge_polar_rad = 0.0;       // a retina boundary beyond this polar angle is the ora, not a cut
  bool chandelier = false;
  render::Vec3 chandelier_tip, chandelier_direction;
};

// Loader thread: the case's look. Needs the scene's textures (load with textures on).
std::unique_ptr<CaseVisuals> build_case_visuals(const PreparedCase& c);
// Loader thread: gives the case its view snapshots, sized for its surfaces: one for each slot of
// the physics → render triple buffer, and one for the picture of a key moment (key_moments.hpp).
inline constexpr std::size_t kViewSnapshotsPerCase = 4;
void prepare_view_snapshots(PreparedCase& c);

// Physics thread: copies the model's current state into `out` (no allocation: when `out` was sized
// for another case it is swapped with one of the case's spares first; without one nothing is
// copied and false is returned). The case's criteria and score are measured again (for the guides'
// progress and the instructor) at most every kProgressEvery_s of case time: they scan the world.
inline constexpr double kProgressEvery_s = 0.25;
bool capture_view(SimulationModel& model, std::uint64_t step, double t_s, ViewSnapshot& out);

// Render service thread: builds the FrameScene of a snapshot. Keeps what it derived from the
// topology (the cut edges' rims) and the instructor's recent events between calls.
class FrameBuilder {
 public:
  render::FrameScene build(const ViewSnapshot& snapshot);

 private:
  struct Rims {
    std::uint64_t topology_version = ~std::uint64_t{0};
    std::vector<float> rim;  // per vertex slot
  };
  void update_rims(std::size_t surface, const SurfaceSnapshot& s, const CaseVisuals& cv);
  void add_overlay(const ViewSnapshot& snap, const CaseVisuals& cv, render::FrameScene& scene);

  std::uint64_t serial_ = 0;
  std::uint64_t frame_ = 0;
  std::vector<Rims> rims_;
  std::array<std::uint32_t, OverlaySnapshot::kMaxEventKinds> events_seen_{};
  std::vector<std::string> recent_events_;
};

}  // namespace vitreo::rig
