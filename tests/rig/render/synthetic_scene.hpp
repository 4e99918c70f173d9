#pragma once
// Synthetic scenes for the renderer's tests and benchmark, until the real anatomy (core/anatomy)
// feeds the renderer: a posterior hemisphere "retina" with a procedural vessel map over a choroid
// shell, a straight instrument shaft and a light pipe through pars-plana ports.
#include <cstdint>

#include "vitreo/render/camera.hpp"
#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render::testing {

inline constexpr float kRetinaRadius = 11.8f;
inline constexpr float kChoroidRadius = 11.95f;

struct SyntheticOptions {
  int retina_triangles = 4000;  // approximate; the choroid gets the same count
  bool light_pipe = true;
  bool instrument = true;
  bool detached = false;         // a bullous detachment in the superior (+y) retina
  bool gas = false;              // fluid–gas exchange, gas above z = gas_level_mm
  float gas_level_mm = -4.0f;
  bool wide_angle = false;
  Vec3 instrument_tip_mm{1.0f, -1.5f, -6.0f};
};

/// Ids of the meshes in the scene.
enum MeshId : std::uint32_t { kChoroid = 1, kRetina = 2, kInstrument = 3, kLightPipe = 4 };

FrameScene make_scene(const SyntheticOptions& options = {});

/// A point on the (undetached) retina at polar angle theta from the posterior pole (−z) and azimuth phi.
Vec3 retina_point(float theta_deg, float phi_deg, float radius = kRetinaRadius);

/// Pixel (x to the right, y down, per-eye image) where `p` projects for `eye` (0 left, 1 right).
Vec2 project_to_pixel(const FrameScene& scene, int eye, Vec3 p, int width, int height);

/// Where the ray from `from` through `through` meets the sphere of `radius` (beyond `through`).
Vec3 ray_sphere_exit(Vec3 from, Vec3 through, float radius);

/// Rigid transform taking local +z to `axis` and the origin to `origin`.
Mat4 frame_along(Vec3 origin, Vec3 axis);

}  // namespace vitreo::render::testing
