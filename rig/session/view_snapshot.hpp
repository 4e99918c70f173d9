#pragma once
// What physics copies for the picture at display rate (rig/session/frame_source.hpp): plain,
// preallocated arrays, so a copy never allocates. A case's PreparedCase brings four of these sized
// for its surfaces (made on the loader thread); physics swaps one into the triple buffer's write
// slot, or into the key moment's snapshot, whenever that one was sized for an earlier case.
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
  float age_s = 0.0f;         // since the pulse (the coagulation whitens over a few hundred ms)
  std::uint32_t surface = 0;
};

// The case's measured guides (core::CaseProgress::guide_samples): which points are done.
struct GuideProgressSnapshot {
  static constexpr std::size_t kMaxSamples = 2048;
  std::uint32_t guide = 0;      // index into the scene's guides
  std::uint32_t n = 0;
  std::uint8_t covered[kMaxSamples] = {};
};

// What the instructor's overlay shows: the score and criteria as last measured, the retina force
// and the instrument events counted so far (the render side shows the new ones as they appear).
struct OverlaySnapshot {
  static constexpr std::size_t kMaxEntries = 8;
  static constexpr std::size_t kMaxEventKinds = 16;
  double elapsed_s = 0.0;
  double score_total = 0.0;
  std::uint32_t n_scores = 0;
  const char* score_name[kMaxEntries] = {};  // static strings (core::ScoreEntry::name)
  double score_value[kMaxEntries] = {};
  std::uint32_t n_criteria = 0;
  const char* criterion_kind[kMaxEntries] = {};  // static strings (core::to_string)
  char criterion_target[kMaxEntries][32] = {};
  double criterion_progress[kMaxEntries] = {};
  bool criterion_met[kMaxEntries] = {};
  double retina_force_un = 0.0;   // the largest of the instruments', now
  double force_limit_un = 0.0;
  std::uint32_t retina_contacts = 0;
  std::uint32_t iatrogenic_events = 0;
  std::uint32_t event_counts[kMaxEventKinds] = {};  // by core::InstrumentEventKind
  std::uint32_t retina_tears = 0;
  // Microscope handling's inputs: the last step's view of the work (core::MicroscopeGlance) and
  // the shares of the working time so far out of the field and out of focus.
  bool scope_judged = false;
  double scope_field_radius = 0.0, scope_defocus_mm = 0.0, scope_depth_of_field_mm = 0.0;
  double out_of_field_share = 0.0, out_of_focus_share = 0.0;
};

struct ViewSnapshot {
  static constexpr std::size_t kMaxBurns = 512;
  static constexpr std::size_t kMaxGuides = 4;
  std::uint64_t case_serial = 0;        // which loaded case these arrays are sized for / show
  const CaseVisuals* visuals = nullptr; // owned by the session for its whole life
  std::uint64_t step = 0;
  double t_s = 0.0;
  double case_time_s = 0.0;             // the case's own simulated time (the world's clock)
  std::vector<SurfaceSnapshot> surfaces;
  struct Instrument {
    bool present = false;
    bool inserted = false;
    float tip[3] = {};
    float axis[3] = {};   // u: along the shaft into the eye
    float up[3] = {};     // v: jaw opening, port facing, bent tip
    int kind = 0;         // core::InstrumentKind
    int port = 0;
    float shaft_radius_mm = 0.32f;
    float actuation = 0.0f;
    float dims[8] = {};   // core::InstrumentDimensions in declaration order
    bool cutting = false;  // vitrector: vacuum on, the guillotine running
    float cut_rate_hz = 0.0f;
    bool aim_hit = false;  // endolaser: the aiming beam meets tissue at aim_point
    float aim_point[3] = {};
    bool firing = false;
  };
  Instrument instruments[8];
  bool light_active = false;
  float light_apex[3] = {};
  float light_axis[3] = {};
  float light_half_angle_deg = 40.0f;
  double light_level = 0.7;
  // The microscope (core::Microscope) and the view toggles.
  double view_center_mm[2] = {};  // field centre, fundus plane
  double zoom = 1.0;
  double focus_mm = 0.0;
  double depth_of_field_mm = 0.0;  // the microscope's now (core::Microscope): the picture blurs beyond it
  double field_deg = 40.0;
  bool wide_angle = false;
  bool image_inverted = false;
  bool wireframe = false;
  bool labels = false;
  bool flat_shading = false;
  double fluid_level_z_mm = 1e300;  // gas above this (eye frame z); huge: all fluid
  std::uint32_t n_burns = 0;
  BurnSnapshot burns[kMaxBurns];
  std::uint32_t n_guides = 0;
  GuideProgressSnapshot guides[kMaxGuides];
  OverlaySnapshot overlay;
};

}  // namespace vitreo::rig
