#include "core/topology/vertex_index.hpp"

#include <algorithm>
#include <limits>

namespace vitreo::core {

VertexIndex::VertexIndex(const Surface& surface) : surface_(surface) {
  const std::size_t patches = static_cast<std::size_t>(surface.block_count()) * (Surface::kSleepBlock / kPatch);
  box_lo_.assign(patches, Vec3::Zero());
  box_hi_.assign(patches, Vec3::Zero());
  seen_motion_.assign(patches, 0);
  fitted_.assign(patches, 0);
}

void VertexIndex::refresh() {
  const Surface& s = surface_;
  const std::uint32_t n = s.vertex_slots();
  last_refits_ = 0;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (std::uint32_t p = 0; p < patches_in_use(); ++p) {
    const std::uint32_t motion = s.block_motion(p * kPatch / Surface::kSleepBlock);
    if (fitted_[p] && seen_motion_[p] == motion) continue;
    // An empty patch gets an inverted box, which no query overlaps.
    Vec3 lo = Vec3::Constant(kInf), hi = Vec3::Constant(-kInf);
    const std::uint32_t end = std::min(n, (p + 1) * kPatch);
    for (std::uint32_t v = p * kPatch; v < end; ++v) {
      if (!s.vertex_alive(v)) continue;
      lo = lo.cwiseMin(s.position(v));
      hi = hi.cwiseMax(s.position(v));
    }
    box_lo_[p] = lo;
    box_hi_[p] = hi;
    seen_motion_[p] = motion;
    fitted_[p] = 1;
    ++last_refits_;
  }
}

}  // namespace vitreo::core
