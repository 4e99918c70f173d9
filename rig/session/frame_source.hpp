#pragma once
// From the physics state to the renderer's FrameScene, without making physics wait or allocate.
//
// Physics copies what the picture needs (vertex positions; triangle lists only when the topology
// changed) into a preallocated slot of a triple buffer at display rate; the render service thread
// turns the newest slot into a FrameScene (normals, uv, meshes for instruments and the choroid) and
// hands it to the render thread. This is the thesis' double-buffered vertex state (ch. 2.3.2),
// with a third buffer so neither side ever waits.
#include <cstdint>
#include <memory>
#include <vector>

#include "rig/runtime/triple_buffer.hpp"
#include "rig/session/simulation_model.hpp"
#include "vitreo/render/frame_scene.hpp"

namespace vitreo::rig {

struct SurfaceSnapshot {
  std::vector<float> xyz;            // 3 per vertex slot (dead slots included; not indexed)
  std::vector<float> rest_xyz;       // for texture coordinates; copied with the indices
  std::vector<std::uint32_t> indices;
  std::uint64_t topology_version = ~std::uint64_t{0};
  bool is_retina = false;
};

struct ViewSnapshot {
  std::uint64_t step = 0;
  double t_s = 0.0;
  std::vector<SurfaceSnapshot> surfaces;
  struct Instrument {
    bool present = false;
    bool inserted = false;
    float tip[3] = {};
    float axis[3] = {};
    int tool_type = 0;
  };
  Instrument instruments[4];
  bool light_active = false;
  float light_apex[3] = {};
  float light_axis[3] = {};
  float light_half_angle_deg = 40.0f;
  double zoom = 1.0;
  double light_level = 0.7;
};

// Sizes every slot for the model's capacities, so later copies never allocate.
void reserve_view_snapshots(const SimulationModel& model, runtime::TripleBuffer<ViewSnapshot>& buffer);
// Physics thread: copies the model's current state into `out` (no allocation after reserve).
void capture_view(const SimulationModel& model, std::uint64_t step, double t_s, ViewSnapshot& out);

// Render service thread: builds the FrameScene of a snapshot. Keeps the static meshes and the
// geometry versions between calls.
class FrameBuilder {
 public:
  FrameBuilder(double globe_radius_mm, std::vector<Port> ports);
  render::FrameScene build(const ViewSnapshot& snapshot);

 private:
  double globe_radius_mm_;
  std::vector<Port> ports_;
  render::MeshGeometryPtr choroid_;
  std::vector<std::uint64_t> versions_;
  std::uint64_t frame_ = 0;
};

}  // namespace vitreo::rig
