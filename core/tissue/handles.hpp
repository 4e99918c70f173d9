#pragma once
// Stable handles into the tissue pools. A handle is a slot index plus the slot's generation: when a
// slot is freed (a vertex removed by the vitrector, an edge split by a cut) its generation advances,
// so every old handle to it is recognisably stale instead of silently pointing at new data.
#include <cstdint>
#include <limits>

namespace vitreo::core {

template <class Tag>
struct Handle {
  static constexpr std::uint32_t kInvalidIndex = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t index = kInvalidIndex;
  std::uint32_t generation = 0;

  bool valid() const { return index != kInvalidIndex; }
  friend bool operator==(const Handle&, const Handle&) = default;
};

struct VertexTag;
struct EdgeTag;
struct TriangleTag;
using VertexId = Handle<VertexTag>;
using EdgeId = Handle<EdgeTag>;
using TriangleId = Handle<TriangleTag>;

inline constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

}  // namespace vitreo::core
