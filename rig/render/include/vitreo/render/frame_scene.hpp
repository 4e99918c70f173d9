#pragma once
// FrameScene: everything the renderer needs to draw one stereo frame, and nothing more.
//
// The simulation (core/) publishes an immutable snapshot per physics step; the rig converts it into a
// FrameScene and puts it into the render mailbox. The renderer never looks at core/ types, so the two
// can evolve apart. Heavy data (vertex arrays, index lists, textures) is held through shared_ptr to
// const, so copying a FrameScene is cheap and the data cannot change under the render thread.
//
// Units and frame: millimetres, seconds; the *eye frame* has its origin at the globe centre and +z
// anterior (toward the microscope). The patient is supine and the surgeon looks down −z through the
// microscope, so "deeper into the eye" is "downward" for the surgeon — the orientation the thesis'
// surgeons asked for after complaining the prototype's axes were reversed.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vitreo/render/math.hpp"

namespace vitreo::render {

/// An RGBA8 image, rows top to bottom (row 0 is v = 0 in texture space).
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  // width*height*4
};
using ImagePtr = std::shared_ptr<const Image>;

/// How a surface looks. The defaults for each kind are in default_appearance().
enum class MaterialKind : std::uint8_t {
  Retina,      // `texture` = vessel map: rgb vessel colour, a = vessel coverage; blended over the choroid
  Choroid,     // `texture` = choroid colour (opaque)
  Static,      // sclera, lens, iris, ports: opaque, `texture` or tint
  Membrane,    // epiretinal / fibrovascular membrane: whitish, translucent
  Gel,         // vitreous gel: a faint haze thickest where seen edge-on; `texture` = stain (white crystals)
  Instrument,  // metallic; `tint` colours it (silicone soft tip, laser fibre, …)
  Guide,       // a task guide on the fundus (cut path, laser ring, target): unlit; Vertex::highlight = done 0..1
  Glow,        // light itself (aiming spot and beam, the light pipe's cone and tip): added, unlit;
               // `tint` × Vertex::highlight is its radiance
};

struct Vertex {
  Vec3 position_mm;
  Vec3 normal;  // need not be unit length; orientation does not matter (two-sided lighting)
  Vec2 uv;
  /// Retina only: 0 = attached, 1 = detached (greyish, more opaque); blends in between. Lets one
  /// mesh carry a local detachment whose border moves as the simulation lifts or reattaches it.
  float detachment = 0.0f;
  /// Retina: 1 on a cut edge or tear (rolled, whiter rim), fading to 0 a step inward.
  /// Guide: 1 where that part of the task is done (cut, lasered). Glow: radiance 0..1.
  float highlight = 0.0f;
};

/// Vertex data and triangle list of one mesh. Removed tissue is simply absent from `indices`.
struct MeshGeometry {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;  // 3 per triangle
};
using MeshGeometryPtr = std::shared_ptr<const MeshGeometry>;

/// A laser burn on one mesh, painted once into that mesh's burn texture (in its uv space, so the
/// burn moves with the tissue and sits exactly where the ray hit, not at the nearest vertex — the
/// thesis' "geometry dependence" complaint). Give the hit as surface coordinates (the triangle, by
/// its three vertex indices into the mesh, and the barycentric point in it: what the simulation
/// knows, so nothing is searched), or as a point on the current surface (the renderer finds the
/// nearest triangle), or directly as uv.
struct LaserBurn {
  struct SurfacePoint {
    std::array<std::uint32_t, 3> corners{};   // vertex indices of the hit triangle
    std::array<float, 3> barycentric{1, 0, 0};
  };
  std::optional<Vec3> hit_position_mm;  // on the mesh's *current* surface; used without hit_point
  std::optional<Vec2> hit_uv;           // used without either
  float radius_mm = 0.25f;              // soft edge from 0.6·radius out to radius
  std::optional<SurfacePoint> hit_point;  // preferred when given
  /// Seconds since the pulse: coagulated retina whitens over FrameScene::burn_whitening_s (grey at
  /// first, whitish after a few hundred milliseconds).
  float age_s = 1e9f;
};

struct Mesh {
  /// Stable identity across frames: GPU buffers and burn textures are cached by id.
  std::uint32_t id = 0;
  MaterialKind material = MaterialKind::Static;
  MeshGeometryPtr geometry;
  /// Bump when the vertex data changed (deforming tissue: every step). Positions/normals/uv are
  /// re-uploaded only when this differs from the last frame; static meshes keep 0 forever.
  std::uint64_t geometry_version = 0;
  /// Bump when `indices` changed (cuts, removal). Indices are re-uploaded only then.
  std::uint64_t topology_version = 0;
  /// Rigid placement (instruments move without re-uploading their vertices).
  Mat4 model = Mat4::identity();
  ImagePtr texture;                  // optional; meaning depends on `material`
  Vec3 tint{1, 1, 1};                // multiplies the base colour
  float opacity = -1.0f;             // < 0: the material's default
  bool detached = false;             // retina only: the whole mesh is detached (overrides Vertex::detachment)
  std::optional<bool> casts_shadow;  // empty: the material's default (instruments, membranes, detached retina)
  std::vector<LaserBurn> burns;      // all burns so far (append-only within a case; shrinking = reset)
  /// Which eyes see it: bit 0 the left, bit 1 the right (the eyepiece test pattern's nonius marks
  /// are each seen by one eye only); everything in a surgery is seen by both.
  std::uint8_t eyes = 3;
};

/// The light pipe (endoilluminator): a spotlight from its tip. Absent → the interior is dark but for
/// the dim ambient term.
struct LightPipe {
  Vec3 tip_mm;
  Vec3 direction{0, 0, -1};      // need not be unit length
  float cone_half_angle_deg = 40.0f;
  float intensity = 1.0f;        // 1 = nominal; scales the spot's radiance
  float range_mm = 18.0f;        // distance at which the light has fallen to half (1/(1+(d/range)²))
};

/// A structure's name drawn beside it (the labels toggle): a marker at `anchor_mm` and the text to
/// its right, placed per eye so the label sits at the structure's depth.
struct Label {
  Vec3 anchor_mm;
  std::string text;
  Vec3 colour{0.95f, 0.95f, 0.85f};
};

/// What the instructor's view adds over the surgeon's picture (RenderThreadOptions::instructor_ring):
/// text lines (score, criteria, elapsed time), the retina contact force as a bar against its
/// damage limit, and the latest events.
struct InstructorOverlay {
  std::vector<std::string> lines;
  float retina_force_un = 0.0f;
  float force_limit_un = 3000.0f;
  std::vector<std::string> events;  // newest last
};

/// Fluid–gas exchange: everything on the `up` side of the plane dot(p, up) = level_mm is gas.
struct FluidGas {
  Vec3 up{0, 0, 1};              // opposite gravity, in the eye frame (supine patient: +z)
  float level_mm = 0.0f;
};

/// The stereo operating microscope (or the wide-angle contact-lens view).
struct Microscope {
  Vec3 target_mm{0, 0, -8};      // look-at point; the working plane passes through it, normal to the view
  Vec3 image_up{0, 1, 0};        // eye-frame direction that appears upward in the image
  float working_distance_mm = 180.0f;  // objective to working plane (surgical microscopes: 175–225)
  float stereo_base_mm = 22.0f;  // interpupillary offset at the objective (left eye at −base/2)
  float zoom = 1.0f;             // magnification factor; field of view ∝ 1/zoom
  float field_mm = 30.0f;        // field diameter (vertical) on the working plane at zoom 1
  /// Convergence (zero disparity) distance; ≤ 0: at the working plane.
  float convergence_distance_mm = -1.0f;
  /// Focus: distance of the sharp plane; ≤ 0: at the working plane. Out-of-focus depths are
  /// blurred when depth_of_field is on.
  float focus_distance_mm = -1.0f;
  bool depth_of_field = false;
  float aperture_mm = 3.0f;      // depth-of-field strength (thin lens), unless depth_of_field_mm is set
  /// > 0: the blur follows this total depth of field (mm, along the view axis) instead of aperture_mm:
  /// everything within half of it of the focal plane is sharp (circle of confusion ≤ 1 pixel), what
  /// lies farther blurs — so the picture agrees with a depth of field computed elsewhere (the
  /// simulation's microscope, core/scene/microscope.hpp, which also scores the focus).
  float depth_of_field_mm = 0.0f;
  /// Seen through the eye's optics (a contact lens or a wide-angle viewing system) instead of from
  /// outside: a virtual camera at `view_point_mm` (default: on the axis at wide_distance_mm) looks at
  /// the target with a field angle of wide_field_deg / zoom.
  bool wide_angle = false;
  float wide_field_deg = 80.0f;    // vertical field angle at zoom 1 (80°: reaches the equator)
  float wide_distance_mm = 16.0f;  // default viewpoint height above the globe centre (just above the cornea)
  std::optional<Vec3> view_point_mm;
  /// A wide-angle system's image without its re-inverter: what reaches the eyepieces is rotated 180°
  /// and the two eyes' images are swapped (pseudoscopic depth), as on a real rig.
  bool image_inverted = false;
  /// Each eye's picture shifted on its display (pixels, x right, y up): the eyepiece displays'
  /// alignment (EyepieceSettings), so a misaligned display still shows fusable images.
  std::array<Vec2, 2> display_offset_px{};
};

/// The rig's stereo eyepiece displays as calibrated (vitreo-calibrate --eyepieces): each eye's image
/// shift, and the stereo base and convergence the renderer uses for them. Applied to every frame the
/// render thread draws; the wide-angle view keeps its own convergence (at its target).
struct EyepieceSettings {
  std::array<Vec2, 2> offset_px{};
  float stereo_base_mm = 22.0f;
  float convergence_mm = 0.0f;  // zero-disparity distance; ≤ 0: at the working plane
  void apply(Microscope& m) const {
    m.display_offset_px = offset_px;
    m.stereo_base_mm = stereo_base_mm;
    if (!m.wide_angle) m.convergence_distance_mm = convergence_mm;
  }
};

struct FrameScene {
  double sim_time_s = 0.0;
  std::uint64_t step_index = 0;
  std::vector<Mesh> meshes;
  std::optional<LightPipe> light_pipe;
  std::optional<LightPipe> chandelier;  // a fixed wide-angle fibre (no shadows of its own when a light pipe is in)
  std::optional<FluidGas> fluid_gas;
  Microscope microscope;
  float globe_radius_mm = 12.0f;  // inner radius of the globe: bounds the haze and the gas bubble
  float ambient = 0.025f;         // dim ambient (stray light through the sclera and pupil)
  float haze_density_per_mm = 0.02f;  // infusion/vitreous scattering
  bool wireframe = false;         // deformable tissue (retina, membranes, gel) drawn as triangle edges
  bool flat_shading = false;      // one normal per triangle (the thesis' F2) instead of smooth normals
  float burn_whitening_s = 0.3f;  // time constant of a laser burn's whitening (LaserBurn::age_s)
  std::vector<Label> labels;      // drawn on top of both eyes, at each anchor's depth
  std::optional<InstructorOverlay> instructor;  // for the instructor's view only; the eyes never show it
};

/// Per-kind defaults used when a Mesh leaves opacity / casts_shadow unset.
struct Appearance {
  Vec3 base_colour;
  float opacity;
  float specular;
  float shininess;
  bool casts_shadow;
};
Appearance default_appearance(MaterialKind kind, bool detached);

}  // namespace vitreo::render
