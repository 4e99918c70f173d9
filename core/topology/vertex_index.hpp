#pragma once
// Spatial query over a surface's vertices by current position, so a blade stroke or a suction step
// visits only the vertices near it instead of every slot.
//
// The patches are runs of kPatch consecutive vertex slots (in mesh order: short strips of
// surface), each with a bounding box of its live vertices' current positions. Positions change
// every step, but only where a sleep block is awake; Surface::block_motion(b) changes whenever
// block b may have moved (woken, awake during a step, a snapshot restored), so before a query the
// index refits exactly the patches whose sleep block's counter changed since it last looked — the
// collision engine's "coarse fixed patches with lazily refitted boxes", on the solver's own
// activity tracking. A query is then a pass over the patch boxes (about a thousand on the
// 20k-vertex retina) and a scan of the vertices of the patches its box overlaps. Patches are a
// quarter of a sleep block: a sleep block of a revolved mesh is an arc of a ring 10 mm long, so a
// query for a thin shape across it (a blade's stroke) would scan the whole arc.
//
// Exact, not approximate: a refitted box contains every live vertex of its patch, so the query
// reports every live vertex inside the query box, and only those; in ascending slot order, so the
// callers' results do not depend on the index (identical to a full scan). No allocation after
// construction (sized to the surface's block count, which is fixed by its capacity).
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/common/types.hpp"
#include "core/tissue/surface.hpp"

namespace vitreo::core {

class VertexIndex {
 public:
  static constexpr std::uint32_t kPatch = 16;  // vertex slots per box; divides Surface::kSleepBlock
  static_assert(Surface::kSleepBlock % kPatch == 0);

  explicit VertexIndex(const Surface& surface);

  // Calls f(v) for every live vertex v whose current position lies in [lo, hi] (inclusive), in
  // ascending slot order. Refits the patches that moved first. f must not move vertices (it may
  // change the mesh only when it stops using the index for this query).
  template <class F>
  void for_each_in_box(const Vec3& lo, const Vec3& hi, F&& f) {
    for_each_in_box(lo, hi, std::forward<F>(f), [](const Vec3&, const Vec3&) { return true; });
  }
  // The same, skipping the patches whose box `block_may_hold(box_lo, box_hi)` rules out: a caller
  // looking for vertices near a thin shape (a blade's swept quad, diagonal to the axes) rejects
  // most of the patches its axis-aligned box overlaps without visiting their vertices. The filter
  // must be conservative: it may reject a patch only if no vertex inside that box could be wanted.
  template <class F, class BlockFilter>
  void for_each_in_box(const Vec3& lo, const Vec3& hi, F&& f, BlockFilter&& block_may_hold) {
    refresh();
    const Surface& s = surface_;
    const std::uint32_t n = s.vertex_slots();
    for (std::uint32_t p = 0; p < patches_in_use(); ++p) {
      if ((box_hi_[p].array() < lo.array()).any() || (box_lo_[p].array() > hi.array()).any()) continue;
      if (!block_may_hold(box_lo_[p], box_hi_[p])) continue;
      const std::uint32_t end = std::min(n, (p + 1) * kPatch);
      for (std::uint32_t v = p * kPatch; v < end; ++v) {
        if (!s.vertex_alive(v)) continue;
        const Vec3& x = s.position(v);
        if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
        f(v);
      }
    }
  }

  // Patches refitted by the last query (for tests and benchmarks).
  std::uint32_t last_refits() const { return last_refits_; }
  std::uint32_t patches_in_use() const { return (surface_.vertex_slots() + kPatch - 1) / kPatch; }

 private:
  void refresh();

  const Surface& surface_;
  std::vector<Vec3> box_lo_, box_hi_;
  std::vector<std::uint32_t> seen_motion_;
  std::vector<std::uint8_t> fitted_;
  std::uint32_t last_refits_ = 0;
};

}  // namespace vitreo::core
