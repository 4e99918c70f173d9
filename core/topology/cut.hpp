#pragma once
// Swept-blade cutting (thesis ch. 2.6.2.1–2.6.2.2, without its lag and vertex snapping).
//
// A blade's cutting edge moving from one pose to the next sweeps a quad (p0, q0, q1, p1) — the
// thesis' intersection parallelogram — taken as the two triangles (p0, q0, q1) and (p0, q1, p1),
// with a tolerance band of `band_mm` around them. The cut is the intersection of that swept surface
// with the tissue, inserted into the mesh at once, at the step boundary:
//   1. Ends: where the quad's boundary (the blade at either pose, the paths of its two ends) passes
//      through a triangle, a vertex is inserted there (split_triangle; on an edge: split_edge) — the
//      partial-edge cases and a stroke wholly inside one triangle.
//   2. Crossings: every spring the swept surface crosses is split at the crossing (split_edge).
//      Vertices within the band of the swept surface are on the cut as they are (the vertex and
//      grazing cases).
//   3. The springs whose two ends lie on the cut and whose midpoint lies on the swept surface are
//      opened (disconnect_edge), and every vertex on them is separated into one copy per fan
//      (separate_vertex_fans), so the two sides part. A cut that would open a single spring with
//      both ends inside the surface first gets a vertex at its middle, so the slit can open.
//
// Snapping (documented tolerance): a crossing closer than snap_fraction × the spring's length (or
// the band) to one of its vertices is moved onto that vertex; an end point whose barycentric
// coordinate to an edge is below snap_fraction goes onto that edge. Nothing is ever moved farther
// than max(band, min_piece_mm, snap_fraction × local edge length). The same rule is the sliver rule: no split
// makes a triangle smaller than snap_fraction of the triangle it came from, so there is no need to
// merge or collapse slivers afterwards (and nothing is ever switched off).
//
// Rest configuration: new springs get rest vectors by vector addition of the rest vectors of the
// springs they subdivide (Surface::split_edge / split_triangle), rest areas split exactly by the
// split parameters, so total mass is unchanged by cutting.
//
// No allocation: the Cutter sizes its scratch to the surface's capacity when built. Refusals
// (non-finite pose, degenerate blade or sweep, full pools) return an error and change nothing.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/common/status.hpp"
#include "core/common/types.hpp"
#include "core/tissue/surface.hpp"
#include "core/topology/quality.hpp"
#include "core/topology/vertex_index.hpp"

namespace vitreo::core {

// The cutting edge of a blade, as a segment in the eye frame (mm).
struct BladeEdge {
  Vec3 a_mm = Vec3::Zero();
  Vec3 b_mm = Vec3::Zero();
};

struct CutSettings {
  double band_mm = 1e-3;         // tolerance band around the swept surface
  double snap_fraction = 0.05;   // see above; in [0, 0.25]
  // Crossings closer than this to a vertex snap onto it too, so repeated cuts at one spot never
  // make springs shorter than this (the absolute floor under snap_fraction).
  double min_piece_mm = 0.005;
  double min_blade_length_mm = 1e-4;
  double min_swept_area_mm2 = 1e-10;
  // Cleanup after each sweep (quality.hpp): slivers the existing geometry forces are collapsed.
  QualitySettings quality;
  void validate() const;  // throws InvalidArgument
};

struct CutResult {
  Status status = Status::ok();
  std::uint32_t end_points = 0;       // vertices inserted where the cut ends inside the surface
  std::uint32_t springs_split = 0;    // crossings inserted on springs
  std::uint32_t springs_opened = 0;   // springs along the cut that were disconnected
  std::uint32_t vertices_added = 0;   // all new vertices (ends, crossings, copies)
  std::uint32_t snapped = 0;          // crossings moved onto a vertex (within the tolerance)
  std::uint32_t collapsed = 0;        // slivers removed by the cleanup (quality.hpp)
  std::uint32_t unresolved = 0;       // slivers the cleanup could not remove
  double removed_mass_g = 0.0;        // lone sliver fragments the cleanup removed (exact)
};

class Cutter {
 public:
  // Keeps a reference to the surface; scratch is sized to its capacity. Throws InvalidArgument on
  // invalid settings.
  explicit Cutter(Surface& surface, CutSettings settings = {});

  // Cuts what the blade edge sweeps between the two poses.
  CutResult sweep(const BladeEdge& from, const BladeEdge& to);
  // Cuts along the triangle (apex, from, to): an edge pivoting about a fixed end (scissors).
  CutResult sweep_pivot(const Vec3& apex_mm, const Vec3& from_mm, const Vec3& to_mm) {
    return sweep({apex_mm, from_mm}, {apex_mm, to_mm});
  }

  const CutSettings& settings() const { return settings_; }
  // Mass of the lone sliver fragments the cleanup removed over all sweeps (g).
  double cleanup_removed_mass_g() const { return quality_.total_removed_mass_g(); }
  Surface& surface() { return surface_; }

 private:
  // Where the quad's boundary passes through the surface (step 1), and the triangle it was found in.
  struct Ends {
    std::array<Vec3, 32> at{};
    std::array<TriangleId, 32> triangle{};
    std::uint32_t count = 0;
  };
  bool near_swept(const Vec3& p, double tolerance) const;
  // Signed distances of x to the planes of the two swept triangles (0 for a degenerate one).
  std::array<double, 2> plane_distances(const Vec3& x) const;
  // Vertex v's plane_distances, computed once per stroke (the springs and triangles around a
  // vertex share it).
  const std::array<double, 2>& side(std::uint32_t v) {
    VertexScratch& vs = vertex_[v];
    if (vs.side_stamp != stamp_) {
      vs.side_stamp = stamp_;
      vs.side = plane_distances(surface_.position(v));
    }
    return vs.side;
  }
  // Appends to crossings_ each of these springs that crosses the swept surface (within the band),
  // with where (t from its first end).
  void find_crossings(std::span<const std::uint32_t> springs);
  void insert_cut(CutResult& r, const Ends& ends);
  void gather_candidates();
  void gather_edges();
  void mark(std::uint32_t v);

  Surface& surface_;
  CutSettings settings_;
  VertexIndex index_;  // finds the vertices near the swept quad without visiting every slot
  MeshQuality quality_;
  double margin_mm_ = 0.0;  // how far beyond the swept box a crossing spring's ends may lie
  // Swept surface.
  std::array<std::array<Vec3, 3>, 2> swept_{};
  std::array<Vec3, 2> swept_normal_{};
  std::array<bool, 2> swept_valid_{};
  std::array<std::array<Vec3, 2>, 4> rim_{};  // the quad's boundary: blade at both poses, end paths
  std::array<Vec3, 4> corners_{};             // the quad's corners p0, q0, p1, q1
  Vec3 box_lo_ = Vec3::Zero(), box_hi_ = Vec3::Zero();
  // Scratch, sized once.
  std::uint32_t stamp_ = 0, edge_round_ = 0;
  std::vector<std::uint32_t> edge_stamp_, triangle_stamp_;
  std::vector<std::uint32_t> candidates_, triangles_, edges_, on_cut_;
  struct Crossing {
    EdgeId edge;
    double t;
  };
  std::vector<Crossing> crossings_;
  std::vector<EdgeId> to_open_;
  // What a stroke keeps per vertex, in one record (a vertex costs one cache line, not six: the
  // stroke visits a few hundred vertices scattered over the surface). A field is this stroke's
  // where its stamp equals stamp_.
  struct VertexScratch {
    std::array<double, 2> side{};     // plane_distances (side_stamp)
    std::uint32_t side_stamp = 0;
    std::uint32_t cut = 0;            // on the cut (stamp)
    std::uint32_t rim = 0;            // within the margin of the quad's boundary (stamp) ...
    std::uint32_t separated = 0;      // its fans were separated (stamp)
    std::uint8_t rim_mask = 0;        // ... bit k: within the margin of rim_[k]; bit 4 + k: of corners_[k]
    std::uint8_t cut_degree = 0;      // opened springs along the cut at it (set in step 3)
  };
  std::vector<VertexScratch> vertex_;
};

}  // namespace vitreo::core
