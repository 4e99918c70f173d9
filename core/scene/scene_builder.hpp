#pragma once
// From a SceneDescription to a running case: the eye model, the TissueWorld (retina, gel, membranes,
// attachments, detachment forces, tears), the static render meshes, fundus textures and guides, then
// settled to equilibrium.
//
//   core::SceneDescription d = scene_io::load_scene_file("scenes/rhegmatogenous_u_tear.toml");
//   core::Scene scene = core::build_scene(d);          // builds and settles
//   scene.world.step(0.001);                            // the physics loop
//   scene.eye.static_meshes, scene.textures             // for the renderer
#include <cstdint>
#include <string>
#include <vector>

#include "core/anatomy/eye_model.hpp"
#include "core/anatomy/fundus_texture.hpp"
#include "core/scene/scene_description.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

struct SettleReport {
  int steps = 0;
  double max_speed_mm_s = 0.0;  // fastest free vertex at the end
  bool settled = false;  // false: the step budget ran out first
  bool ok = true;        // false: a step was rolled back while settling
};

struct BuiltMembrane {
  std::string name;
  std::uint32_t surface = kNone;
  std::uint32_t first_attachment = 0;
  std::uint32_t attachment_count = 0;
  std::uint32_t strong_attachments = 0;
  // Per site of the attachment lattice (MembraneSpec::attachment_spacing_mm), in the order the
  // builder numbers them from the description alone: the site's attachment, or kNone where no vertex
  // of this mesh lies near it. Empty for the perpendicular plane (attached at every base vertex).
  std::vector<std::uint32_t> sites;
  std::uint32_t detachment_force = kNone;  // with detach_radius_mm > 0
};

struct BuiltTear {
  std::string name;
  std::vector<std::uint32_t> flap_vertices;  // retina vertices of the flap (after the cut)
  std::uint32_t cut_vertices = 0;            // vertices split along the U
};

struct Guide {
  std::string name;
  GuideKind kind;
  std::vector<Vec3> polyline_mm;  // on the retina, eye frame
};

struct Scene {
  Scene(SceneDescription d, EyeModel e, TissueWorld w);
  SceneDescription description;
  EyeModel eye;
  TissueWorld world;
  FundusTextures textures;
  std::uint32_t retina = kNone;
  std::uint32_t gel = kNone;
  std::uint32_t anchored_retina_vertices = 0;
  std::uint32_t gel_attachments = 0;
  std::vector<std::uint32_t> detachment_forces;  // local force ids, in description order
  std::vector<BuiltMembrane> membranes;
  std::vector<BuiltTear> tears;
  std::vector<Guide> guides;
  SettleReport settle;
};

struct BuildOptions {
  bool settle = true;
  bool textures = true;
};

// Throws InvalidArgument on a description that does not validate or cannot be built.
Scene build_scene(const SceneDescription& description, const BuildOptions& options = {});

// Runs the world with extra damping until no free vertex moves faster than the threshold (after min_steps) or
// max_steps have run; then restores the surgery settings and resets time and step count to zero, so
// the settled state is the case's start.
SettleReport settle_world(TissueWorld& world, const SettleSpec& spec);

// Largest distance of a retina vertex from the wall (mm): how far the retina is detached.
double max_retina_lift_mm(const Scene& scene);

}  // namespace vitreo::core
