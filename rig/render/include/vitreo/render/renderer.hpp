#pragma once
// StereoRenderer: draws a FrameScene for both eyes of the microscope into one side-by-side
// framebuffer and reads it back. Needs a current GL 4.5 core context (EglContext) on the calling
// thread for its whole life; one renderer per context, used from one thread.
//
// Per frame:
//  1. sync: upload vertex data of meshes whose geometry changed (deforming tissue), indices whose
//     topology changed (cuts, removal); static meshes and textures are uploaded once; paint new
//     laser burns into each mesh's burn texture.
//  2. shadow pass: depth of the shadow casters seen from the light-pipe tip (shadow mapping,
//     Williams 1978: a fragment is in shadow when something nearer the light covers it in the map).
//  3. both eyes into one 2W×H framebuffer (left eye on the left half): opaque meshes, then
//     translucent ones (retina over the choroid, membranes, gel, the fluid–gas interface) back to front.
//     The spotlight is a cone from the tip projected like a slide projector (the projective-texture
//     spotlight of Segal et al. 1992 that the thesis used), with angular and distance falloff.
//  4. one glReadPixels for both eyes at the end of the frame (reading after each eye stalls llvmpipe).
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "vitreo/render/frame_scene.hpp"

namespace vitreo::render {

class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RenderSettings {
  int eye_width = 1280;
  int eye_height = 1024;
  int shadow_map_size = 1024;
  int burn_texture_size = 1024;  // per mesh that has burns
};

/// One rendered stereo frame: both eyes side by side (left eye on the left), RGBA8, rows top to bottom.
struct StereoFrame {
  int eye_width = 0;
  int eye_height = 0;
  double sim_time_s = 0;
  std::uint64_t step_index = 0;
  std::uint64_t frame_index = 0;  // counts rendered frames
  std::vector<std::uint8_t> rgba;  // (2*eye_width) * eye_height * 4

  int width() const { return 2 * eye_width; }
  Image side_by_side() const;
  Image eye(int index) const;  // 0 = left, 1 = right
};

struct RenderStats {
  std::uint64_t frames = 0;
  std::uint64_t vertex_uploads = 0;  // meshes whose vertex buffer was re-uploaded
  std::uint64_t index_uploads = 0;
  std::uint64_t texture_uploads = 0;
  std::uint64_t burns_painted = 0;
  std::uint64_t burns_missed = 0;  // hit position farther than 0.5 mm from the mesh surface
  std::uint64_t triangles_last_frame = 0;  // per eye
};

class StereoRenderer {
 public:
  explicit StereoRenderer(RenderSettings settings = {});
  ~StereoRenderer();
  StereoRenderer(const StereoRenderer&) = delete;
  StereoRenderer& operator=(const StereoRenderer&) = delete;

  /// Renders `scene` and reads it back into `out` (resized as needed; reuse it to avoid allocation).
  void render(const FrameScene& scene, StereoFrame& out);
  const RenderSettings& settings() const { return settings_; }
  const RenderStats& stats() const { return stats_; }

 private:
  struct Impl;
  RenderSettings settings_;
  RenderStats stats_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vitreo::render
