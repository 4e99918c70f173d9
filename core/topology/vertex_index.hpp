#pragma once
// Spatial query over a surface's vertices by current position, so a blade stroke or a suction step
// visits only the vertices near it instead of every slot.
//
// The patches are runs of kPatch consecutive vertex slots (in mesh order: short strips of
// surface), each with a bounding box of its live vertices' current positions; each sleep block
// keeps the union of its patch boxes. A query is a pass over the block boxes, then over the patch
// boxes of the blocks it overlaps, and a scan of the vertices of the patches it overlaps. Every box
// is fitted at construction. A patch is at most 16 slots however large a sleep block is: a strip of
// a revolved mesh's ring longer than that is an arc several mm long, and a query for a thin shape
// across it (a blade's stroke) would scan the whole arc. With today's sleep blocks of 16
// (Surface::kSleepBlock) a block is one patch (~1 300 blocks on the 20k-vertex retina).
//
// Positions change every step, and reading them all again before each query would cost as much as
// the query itself, so the index keeps a box until it may be wrong where it matters, using the
// solver's motion bounds (Surface::block_motion and block_drift_mm):
//  - a patch whose block was woken, changed or restored since its fit is fitted again;
//  - otherwise its vertices moved at most the block's drift since the fit: the box grown by that
//    much still holds them. A patch whose grown box misses the query is skipped unread; one it
//    overlaps is fitted again (and the grown slack is gone).
// Tissue settling by micrometres a step is thus re-read only where a query looks: the
// collision engine's "coarse fixed patches with lazily refitted boxes", on the solver's own
// motion tracking.
//
// Exact, not approximate: every box (grown or fitted) contains every live vertex of its patch, so
// the query reports every live vertex inside the query box, and only those; in ascending slot
// order, so the callers' results do not depend on the index (identical to a full scan). No
// allocation after construction (sized to the surface's block count, which is fixed by its capacity).
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
    const Surface& s = surface_;
    const std::uint32_t n = s.vertex_slots();
    last_refits_ = 0;
    auto overlaps = [&](const Vec3& box_lo, const Vec3& box_hi) {
      return (box_hi.x() >= lo.x()) & (box_hi.y() >= lo.y()) & (box_hi.z() >= lo.z()) & (box_lo.x() <= hi.x()) &
             (box_lo.y() <= hi.y()) & (box_lo.z() <= hi.z());
    };
    // A box fitted at drift d0 grown by what the block drifted since (the slack covers the
    // rounding of positions and of the drift's sum).
    auto grown = [](const Vec3& box_lo, const Vec3& box_hi, double drift_since, Vec3& out_lo, Vec3& out_hi) {
      const double g = drift_since * (1.0 + 1e-9) + 1e-9;
      out_lo = box_lo.array() - g;
      out_hi = box_hi.array() + g;
    };
    const std::uint32_t blocks = (n + Surface::kSleepBlock - 1) / Surface::kSleepBlock;
    for (std::uint32_t b = 0; b < blocks; ++b) {
      if (block_motion_[b] != s.block_motion(b)) fit_block(b);  // woken or changed: look again
      const double drift = s.block_drift_mm(b);
      // The whole block first (four patches at once), then its patches.
      Vec3 block_lo = block_lo_[b], block_hi = block_hi_[b];
      if (drift > block_fit_drift_[b]) grown(block_lo_[b], block_hi_[b], drift - block_fit_drift_[b], block_lo, block_hi);
      if (!overlaps(block_lo, block_hi) || !block_may_hold(block_lo, block_hi)) continue;
      for (std::uint32_t p = b * kPatchesPerBlock; p < (b + 1) * kPatchesPerBlock; ++p) {
        if (drift > fit_drift_[p]) {
          Vec3 patch_lo, patch_hi;
          grown(box_lo_[p], box_hi_[p], drift - fit_drift_[p], patch_lo, patch_hi);
          if (!overlaps(patch_lo, patch_hi) || !block_may_hold(patch_lo, patch_hi)) continue;
          fit(p);
        }
        if (!overlaps(box_lo_[p], box_hi_[p]) || !block_may_hold(box_lo_[p], box_hi_[p])) continue;
        const std::uint32_t end = std::min(n, (p + 1) * kPatch);
        for (std::uint32_t v = p * kPatch; v < end; ++v) {
          if (!s.vertex_alive(v)) continue;
          const Vec3& x = s.position(v);
          if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
          f(v);
        }
      }
    }
  }

  // Patches fitted again by the last query (for tests and benchmarks).
  std::uint32_t last_refits() const { return last_refits_; }
  std::uint32_t patches_in_use() const { return (surface_.vertex_slots() + kPatch - 1) / kPatch; }

 private:
  static constexpr std::uint32_t kPatchesPerBlock = Surface::kSleepBlock / kPatch;
  void fit(std::uint32_t patch);        // one patch (its block's motion counter unchanged)
  void fit_block(std::uint32_t block);  // all its patches (its motion counter changed)
  void fit_patch(std::uint32_t patch);  // the box only; the block's union is left to the caller
  void update_block_box(std::uint32_t block);

  const Surface& surface_;
  // Per patch: its box and the block's drift when it was fitted.
  std::vector<Vec3> box_lo_, box_hi_;
  std::vector<double> fit_drift_;
  // Per sleep block: the union of its patches' boxes, the smallest of their fit drifts (so the
  // union grown by drift − that holds every patch's grown box), and its motion counter when its
  // patches were last all fitted.
  std::vector<Vec3> block_lo_, block_hi_;
  std::vector<double> block_fit_drift_;
  std::vector<std::uint32_t> block_motion_;
  std::uint32_t last_refits_ = 0;
};

}  // namespace vitreo::core
