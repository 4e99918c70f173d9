#pragma once
// Iteration over the vertices of awake blocks only (see Surface::kSleepBlock), in order, on the
// calling thread. Inside a step, passes whose vertices are independent use
// TissueWorld::for_awake_vertices instead: the same vertices, split over the worker pool.
#include <algorithm>
#include <cstdint>

#include "core/tissue/surface.hpp"

namespace vitreo::core {

template <class F>
void for_each_awake_vertex(const Surface& s, F&& f) {
  const std::uint32_t n = s.vertex_slots();
  for (std::uint32_t b = 0; b < s.block_count(); ++b) {
    if (!s.block_awake(b)) continue;
    const std::uint32_t end = std::min(n, (b + 1) * Surface::kSleepBlock);
    for (std::uint32_t v = b * Surface::kSleepBlock; v < end; ++v) f(v);
  }
}

}  // namespace vitreo::core
