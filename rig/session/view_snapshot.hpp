#pragma once
// What physics copies for the picture at display rate (rig/session/frame_source.hpp): plain,
// preallocated arrays, so a copy never allocates. A case's PreparedCase brings three of these sized
// for its surfaces (made on the loader thread); physics swaps one into the triple buffer's write
// slot whenever that slot was sized for an earlier case.
#include <cstdint>
#include <vector>

namespace vitreo::rig {

struct CaseVisuals;  // frame_source.hpp: static meshes and textures of one case (render thread)

struct SurfaceSnapshot {
  std::vector<float> xyz;            // 3 per vertex slot (dead slots included; not indexed)
  std::vector<float> rest_xyz;       // for texture coordinates; copied with the indices
  std::vector<std::uint32_t> indices;
  std::uint64_t topology_version = ~std::uint64_t{0};
  std::uint32_t vertex_capacity = 0;
  std::uint32_t index_capacity = 0;
};

struct BurnSnapshot {
  // Surface coordinates of the spot: the triangle it was burnt on (its corner vertices) and the
  // barycentric point in it — it moves with the tissue. on_triangle false: the triangle was cut
  // since, and only the position is known.
  bool on_triangle = false;
  std::uint32_t corners[3] = {};
  float barycentric[3] = {1, 0, 0};
  float position_mm[3] = {};  // where the spot is now
  float diameter_mm = 0.0f;
  std::uint32_t surface = 0;
};

struct ViewSnapshot {
  static constexpr std::size_t kMaxBurns = 512;
  std::uint64_t case_serial = 0;        // which loaded case these arrays are sized for / show
  const CaseVisuals* visuals = nullptr; // owned by the session for its whole life
  std::uint64_t step = 0;
  double t_s = 0.0;
  std::vector<SurfaceSnapshot> surfaces;
  struct Instrument {
    bool present = false;
    bool inserted = false;
    float tip[3] = {};
    float axis[3] = {};
    int tool_type = 0;
    int port = 0;
  };
  Instrument instruments[8];
  bool light_active = false;
  float light_apex[3] = {};
  float light_axis[3] = {};
  float light_half_angle_deg = 40.0f;
  double zoom = 1.0;
  double light_level = 0.7;
  bool wireframe = false;
  bool labels = false;
  double fluid_level_z_mm = 1e300;  // gas above this (eye frame z); huge: all fluid
  std::uint32_t n_burns = 0;
  BurnSnapshot burns[kMaxBurns];
};

}  // namespace vitreo::rig
