#pragma once
// Spatial query over a surface's vertices by current position, so a blade stroke or a suction step
// visits only the vertices near it instead of every slot.
//
// The patches are the surface's sleep blocks (Surface::kSleepBlock consecutive slots in mesh order:
// compact strips of surface), each with a bounding box of its live vertices' current positions.
// Positions change every step, but only where a block is awake; Surface::block_motion(b) changes
// whenever block b may have moved (woken, awake during a step, a snapshot restored), so before a
// query the index refits exactly the blocks whose counter changed since it last looked — the
// collision engine's "coarse fixed patches with lazily refitted boxes", on the solver's own
// activity tracking. A query is then a pass over the block boxes (a few hundred) and a scan of the
// vertices of the blocks its box overlaps.
//
// Exact, not approximate: a refitted box contains every live vertex of its block, so the query
// reports every live vertex inside the query box, and only those; in ascending slot order, so the
// callers' results do not depend on the index (identical to a full scan). No allocation after
// construction (sized to the surface's block count, which is fixed by its capacity).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/common/types.hpp"
#include "core/tissue/surface.hpp"

namespace vitreo::core {

class VertexIndex {
 public:
  explicit VertexIndex(const Surface& surface);

  // Calls f(v) for every live vertex v whose current position lies in [lo, hi] (inclusive), in
  // ascending slot order. Refits the blocks that moved first. f must not move vertices (it may
  // change the mesh only when it stops using the index for this query).
  template <class F>
  void for_each_in_box(const Vec3& lo, const Vec3& hi, F&& f) {
    refresh();
    const Surface& s = surface_;
    const std::uint32_t n = s.vertex_slots();
    for (std::uint32_t b = 0; b < blocks_in_use(); ++b) {
      if ((box_hi_[b].array() < lo.array()).any() || (box_lo_[b].array() > hi.array()).any()) continue;
      const std::uint32_t end = std::min(n, (b + 1) * Surface::kSleepBlock);
      for (std::uint32_t v = b * Surface::kSleepBlock; v < end; ++v) {
        if (!s.vertex_alive(v)) continue;
        const Vec3& x = s.position(v);
        if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
        f(v);
      }
    }
  }

  // Blocks refitted by the last query (for tests and benchmarks).
  std::uint32_t last_refits() const { return last_refits_; }

 private:
  std::uint32_t blocks_in_use() const {
    return (surface_.vertex_slots() + Surface::kSleepBlock - 1) / Surface::kSleepBlock;
  }
  void refresh();

  const Surface& surface_;
  std::vector<Vec3> box_lo_, box_hi_;
  std::vector<std::uint32_t> seen_motion_;
  std::vector<std::uint8_t> fitted_;
  std::uint32_t last_refits_ = 0;
};

}  // namespace vitreo::core
