#pragma once
// The instruments as the surgeon sees them: meshes built from each instrument's real geometry (its
// gauge, the tip the core's collision capsules describe — core/instruments/instrument.hpp) and
// animated by the handle and the pedals: forceps jaws and scissors blades open with the actuation,
// the vitrector's guillotine flickers across its side port at the cut rate, the blade and the
// sideways blade, the soft silicone tip of the flute needle, the endolaser with its aiming beam and
// spot where the ray meets the tissue, the light pipe with its glowing tip and a faint cone of light
// in the vitreous, and the chandelier fibre. Shadows come from the renderer (instruments cast them).
//
// Each model is built in the instrument's own frame (origin at the tip, +z along the shaft into the
// eye, +x its `up` v: jaw opening, port facing, bent tip) and placed by Mesh::model.
#include <cstdint>
#include <vector>

#include "core/instruments/instrument.hpp"
#include "vitreo/render/frame_scene.hpp"

namespace vitreo::rig {

struct InstrumentView {
  core::InstrumentKind kind = core::InstrumentKind::kLightPipe;
  render::Vec3 tip_mm;
  render::Vec3 axis{0, 0, -1};  // u: along the shaft into the eye
  render::Vec3 up{1, 0, 0};     // v ⊥ u
  float shaft_length_mm = 30.0f;  // from the tip back out past the port
  float shaft_radius_mm = 0.32f;
  float actuation = 0.0f;       // handle: 0 open … 1 closed
  core::InstrumentDimensions dims;
  // Vitrector: cutting (vacuum on) at cut_rate_hz; the guillotine's phase in the frame shown.
  bool cutting = false;
  float cut_phase = 0.0f;       // 0..1: fraction of a cut cycle at the frame's time
  // Endolaser: the aiming beam hits the tissue at aim_mm (with the surface facing aim_normal).
  bool aim_hit = false;
  render::Vec3 aim_mm;
  render::Vec3 aim_normal{0, 0, 1};
  float aim_spot_mm = 0.2f;
  bool firing = false;           // treatment pulse: the spot flares
  // Light pipe: its cone (half angle) and how far the light reaches visibly.
  float cone_half_angle_deg = 40.0f;
  float light_intensity = 1.0f;
};

// Appends the instrument's meshes (ids first_id, first_id+1, … up to kMeshesPerInstrument) to `out`.
inline constexpr std::uint32_t kMeshesPerInstrument = 8;
void add_instrument_meshes(const InstrumentView& v, std::uint32_t first_id, std::uint64_t version,
                           std::vector<render::Mesh>& out);

// The chandelier: a fibre standing through the wall at `base_mm`, pointing along `direction`.
void add_chandelier_meshes(render::Vec3 base_mm, render::Vec3 direction, std::uint32_t first_id,
                           std::vector<render::Mesh>& out);

// The rigid placement taking the instrument frame (x = up, y = up × axis… see above) to the eye frame.
render::Mat4 instrument_placement(const render::Vec3& tip, const render::Vec3& axis, const render::Vec3& up);

}  // namespace vitreo::rig
