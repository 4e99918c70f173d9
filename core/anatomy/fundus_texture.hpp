#pragma once
// Fundus textures, generated deterministically from a seed: a choroid map (orange-red, pigmented)
// and a separate retina map with alpha carrying the vessel tree, the optic disc and the macula, so a
// detached retina carries its vessels away from the choroid (the thesis' surgeons only believed the
// detachment once the vessels lay on their own layer, ch. 3.2).
//
// Both are drawn in the fundus plane of the EyeModel (azimuthal equidistant about the posterior
// pole, mm) and sampled with EyeModel::fundus_uv. Row 0 is v = 0 (−y side); pixels are RGBA8,
// straight (not premultiplied) alpha.
#include <cstdint>
#include <vector>

#include "core/anatomy/eye_model.hpp"

namespace vitreo::core {

struct RgbaImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  // width × height × 4, row-major

  std::uint8_t* pixel(int x, int y) { return &rgba[4 * (static_cast<std::size_t>(y) * width + x)]; }
  const std::uint8_t* pixel(int x, int y) const { return &rgba[4 * (static_cast<std::size_t>(y) * width + x)]; }
};

struct VesselSegment {
  Vec2 a_mm;
  Vec2 b_mm;
  double width_mm;
  bool artery;
  int depth;  // 0 = trunk from the disc
};

struct FundusOptions {
  std::uint64_t seed = 1;
  int size_px = 1024;  // square textures, 64..8192
};

struct FundusTextures {
  RgbaImage choroid;
  RgbaImage retina;
  std::vector<VesselSegment> vessels;  // in the fundus plane (mm)
  double vessel_free_radius_mm = 0.0;  // around the fovea (fundus-plane origin)
};

// Throws InvalidArgument on a bad size.
FundusTextures generate_fundus(const EyeModel& eye, const FundusOptions& options);

// Distance from point p to segment ab.
double distance_to_segment(const Vec2& p, const Vec2& a, const Vec2& b);

}  // namespace vitreo::core
