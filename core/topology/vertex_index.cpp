#include "core/topology/vertex_index.hpp"

#include <algorithm>
#include <limits>

namespace vitreo::core {

VertexIndex::VertexIndex(const Surface& surface) : surface_(surface) {
  const std::size_t blocks = surface.block_count();
  box_lo_.assign(blocks, Vec3::Zero());
  box_hi_.assign(blocks, Vec3::Zero());
  seen_motion_.assign(blocks, 0);
  fitted_.assign(blocks, 0);
}

void VertexIndex::refresh() {
  const Surface& s = surface_;
  const std::uint32_t n = s.vertex_slots();
  last_refits_ = 0;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (std::uint32_t b = 0; b < blocks_in_use(); ++b) {
    if (fitted_[b] && seen_motion_[b] == s.block_motion(b)) continue;
    // An empty block gets an inverted box, which no query overlaps.
    Vec3 lo = Vec3::Constant(kInf), hi = Vec3::Constant(-kInf);
    const std::uint32_t end = std::min(n, (b + 1) * Surface::kSleepBlock);
    for (std::uint32_t v = b * Surface::kSleepBlock; v < end; ++v) {
      if (!s.vertex_alive(v)) continue;
      lo = lo.cwiseMin(s.position(v));
      hi = hi.cwiseMax(s.position(v));
    }
    box_lo_[b] = lo;
    box_hi_[b] = hi;
    seen_motion_[b] = s.block_motion(b);
    fitted_[b] = 1;
    ++last_refits_;
  }
}

}  // namespace vitreo::core
