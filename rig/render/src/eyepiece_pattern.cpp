#include "vitreo/render/eyepiece_pattern.hpp"

#include <cmath>
#include <memory>

#include "vitreo/render/camera.hpp"

namespace vitreo::render {
namespace {

// A flat strip from a to b, `width` wide, in the plane across `normal` (unlit light: Glow).
void add_line(MeshGeometry& g, Vec3 a, Vec3 b, float width, Vec3 normal) {
  const Vec3 along = normalize(b - a);
  const Vec3 side = normalize(cross(normal, along)) * (0.5f * width);
  const auto base = static_cast<std::uint32_t>(g.vertices.size());
  for (const Vec3& p : {a - side, a + side, b + side, b - side}) {
    Vertex v;
    v.position_mm = p;
    v.normal = normal;
    v.highlight = 1.0f;  // Glow: full radiance
    g.vertices.push_back(v);
  }
  for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) g.indices.push_back(base + i);
}

Mesh glow_mesh(std::uint32_t id, std::shared_ptr<MeshGeometry> g, Vec3 colour, std::uint8_t eyes) {
  Mesh m;
  m.id = id;
  m.material = MaterialKind::Glow;
  m.geometry = std::move(g);
  m.tint = colour;
  m.eyes = eyes;
  m.casts_shadow = false;
  return m;
}

}  // namespace

FrameScene eyepiece_test_pattern(const Microscope& m, float globe_radius_mm, int width, int height, const EyepiecePatternGeometry& geo) {
  const StereoViews views = stereo_views(m, globe_radius_mm, width, height);
  const Vec3 centre_eye = (views.eye[0].position_mm + views.eye[1].position_mm) * 0.5f;
  const float to_target = dot(m.target_mm - centre_eye, views.forward);
  const float convergence = m.convergence_distance_mm > 0 && !m.wide_angle ? m.convergence_distance_mm : to_target;
  const Vec3 centre = centre_eye + views.forward * convergence;
  const Vec3 right = views.right, up = views.up, normal = views.forward * -1.0f;
  // 2 pixels on the plane: P[1][1] = 1 / tan(half the vertical field).
  const float mm_per_px = 2.0f * convergence / (views.eye[0].projection.at(1, 1) * static_cast<float>(std::max(height, 1)));
  const float line = 2.0f * mm_per_px;
  const float half_h = 0.5f * static_cast<float>(height) * mm_per_px;
  const float half_w = half_h * static_cast<float>(width) / static_cast<float>(std::max(height, 1));

  auto grid = std::make_shared<MeshGeometry>();
  const int nx = static_cast<int>(half_w / geo.grid_mm) + 1, ny = static_cast<int>(half_h / geo.grid_mm) + 1;
  for (int i = -nx; i <= nx; ++i) {
    if (i == 0) continue;  // the centre lines are the nonius cross
    const Vec3 x = centre + right * (static_cast<float>(i) * geo.grid_mm);
    add_line(*grid, x - up * half_h, x + up * half_h, 0.5f * line, normal);
  }
  for (int j = -ny; j <= ny; ++j) {
    if (j == 0) continue;
    const Vec3 y = centre + up * (static_cast<float>(j) * geo.grid_mm);
    add_line(*grid, y - right * half_w, y + right * half_w, 0.5f * line, normal);
  }
  auto left_arms = std::make_shared<MeshGeometry>(), right_arms = std::make_shared<MeshGeometry>();
  add_line(*left_arms, centre, centre + up * geo.cross_arm_mm, line, normal);
  add_line(*left_arms, centre, centre + right * geo.cross_arm_mm, line, normal);
  add_line(*right_arms, centre, centre - up * geo.cross_arm_mm, line, normal);
  add_line(*right_arms, centre, centre - right * geo.cross_arm_mm, line, normal);

  auto markers = std::make_shared<MeshGeometry>();
  for (const float side : {-1.0f, 1.0f}) {
    // The nearer square (toward the microscope) left of the cross, the deeper one right of it.
    const Vec3 c = centre + right * (side * geo.marker_offset_mm) + views.forward * (side * geo.marker_depth_mm);
    const float h = 0.5f * geo.marker_size_mm;
    const Vec3 corners[4] = {c - right * h - up * h, c + right * h - up * h, c + right * h + up * h, c - right * h + up * h};
    for (int k = 0; k < 4; ++k) add_line(*markers, corners[k], corners[(k + 1) % 4], line, normal);
  }

  FrameScene scene;
  scene.microscope = m;
  scene.globe_radius_mm = globe_radius_mm;
  scene.ambient = 0.0f;
  scene.haze_density_per_mm = 0.0f;
  scene.meshes.push_back(glow_mesh(1, grid, {0.55f, 0.55f, 0.55f}, 3));
  scene.meshes.push_back(glow_mesh(2, left_arms, {0.2f, 1.0f, 0.3f}, 1));
  scene.meshes.push_back(glow_mesh(3, right_arms, {1.0f, 0.25f, 0.2f}, 2));
  scene.meshes.push_back(glow_mesh(4, markers, {0.9f, 0.9f, 0.3f}, 3));
  return scene;
}

}  // namespace vitreo::render
