#include "core/topology/vertex_index.hpp"

#include <algorithm>
#include <limits>

namespace vitreo::core {

VertexIndex::VertexIndex(const Surface& surface) : surface_(surface) {
  const std::size_t blocks = surface.block_count(), patches = blocks * kPatchesPerBlock;
  box_lo_.assign(patches, Vec3::Zero());
  box_hi_.assign(patches, Vec3::Zero());
  fit_drift_.assign(patches, 0.0);
  block_lo_.assign(blocks, Vec3::Zero());
  block_hi_.assign(blocks, Vec3::Zero());
  block_fit_drift_.assign(blocks, 0.0);
  block_motion_.assign(blocks, 0);
  // Fit every box now (at scene load) rather than in the first query: that reads every position,
  // which would otherwise make the first blade stroke twice as slow as the rest. Blocks beyond
  // the slots in use get inverted boxes; a vertex added there later wakes its block.
  for (std::uint32_t b = 0; b < blocks; ++b) fit_block(b);
  last_refits_ = 0;
}

void VertexIndex::fit(std::uint32_t p) {
  fit_patch(p);
  update_block_box(p / kPatchesPerBlock);
}

void VertexIndex::fit_block(std::uint32_t b) {
  for (std::uint32_t p = b * kPatchesPerBlock; p < (b + 1) * kPatchesPerBlock; ++p) fit_patch(p);
  update_block_box(b);
  block_motion_[b] = surface_.block_motion(b);
}

void VertexIndex::fit_patch(std::uint32_t p) {
  const Surface& s = surface_;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // An empty patch gets an inverted box, which no query overlaps (grown or not).
  Vec3 lo = Vec3::Constant(kInf), hi = Vec3::Constant(-kInf);
  const std::uint32_t end = std::min(s.vertex_slots(), (p + 1) * kPatch);
  for (std::uint32_t v = p * kPatch; v < end; ++v) {
    if (!s.vertex_alive(v)) continue;
    lo = lo.cwiseMin(s.position(v));
    hi = hi.cwiseMax(s.position(v));
  }
  box_lo_[p] = lo;
  box_hi_[p] = hi;
  fit_drift_[p] = s.block_drift_mm(p / kPatchesPerBlock);
  ++last_refits_;
}

void VertexIndex::update_block_box(std::uint32_t b) {
  const std::uint32_t first = b * kPatchesPerBlock;
  Vec3 lo = box_lo_[first], hi = box_hi_[first];
  double drift = fit_drift_[first];
  for (std::uint32_t p = first + 1; p < first + kPatchesPerBlock; ++p) {
    lo = lo.cwiseMin(box_lo_[p]);
    hi = hi.cwiseMax(box_hi_[p]);
    drift = std::min(drift, fit_drift_[p]);
  }
  block_lo_[b] = lo;
  block_hi_[b] = hi;
  block_fit_drift_[b] = drift;
}

}  // namespace vitreo::core
