#pragma once
// Swept-blade cutting (thesis ch. 2.6.2.1–2.6.2.2), independent of how the blade's motion is sampled.
//
// A blade's cutting edge moving from one pose to the next sweeps a planar polygon (p0, q0, q1, p1)
// — the thesis' intersection parallelogram — with a tolerance band of `band_mm` around it (a pose
// change that twists the edge out of that plane is cut as two planar sweeps, pivoting about p0 and
// then about q1). The cut is where that polygon meets the tissue: in each triangle a straight piece
// whose ends lie on the triangle's boundary (a crossing of a spring, or a vertex) or inside it
// where the polygon's rim passes (the blade at either pose, or the path of one of its ends).
//
// The cut is made by an Incision (incision.hpp), which follows each crack the blade extends from
// sweep to sweep: a crack tip is the vertex where the cut made so far ends, plus the point where
// the blade now is (anchored on the tissue by triangle and barycentric coordinates, so it moves
// with the tissue between sweeps). Each sweep walks the cut from that point through the mesh,
// triangle by triangle, and inserts only what the crack has left behind:
//   - a point on the cut is inserted (split_edge, split_triangle, or an existing vertex) when the
//     cut goes on beyond the triangles around the crack tip — so the new spring from the tip to
//     it lies inside one triangle and exists after the one split — or when the cut ends there
//     (the blade's end left the tissue, the cut reached the tissue's boundary, the incision
//     ended: an interior point, thesis 2.6.2.1.1), or where the path bends: samples are dropped
//     while the chord from the tip passes within kink_fraction of the local spring length of
//     every one (the thesis dropped samples collinear with the previous two; this is the same
//     rule with a bound on the deviation, O(1) per sample);
//   - the spring from the tip to each inserted point is opened (disconnect_edge) and the vertices
//     on opened springs are separated into one copy per fan (separate_vertex_fans), at the end of
//     the sweep.
// So a sweep shorter than a triangle changes nothing until the cut leaves the triangle, and the same
// path cut in one sweep or in a thousand inserts the same crossings and opens the same springs
// (sampling only moves the interior points at bends, within the kink tolerance). Where the blade's
// plane runs along a row of springs, through their vertices, the point where a walk stops lies a
// hair from a vertex: the next walk looks round that vertex, and the blade's point there is that
// crack's, not a new one's (so a slow blade's slit keeps one spring behind it). A cut meeting
// the tissue's boundary — its outer edge, or a cut made before, the same incision's included —
// ends there and a new crack starts where the polygon enters the tissue again, so closed and
// self-crossing paths part the tissue.
//
// Cutter::sweep(from, to) is one incision: the blade at `from`, moved to `to`, and ended there.
//
// Snapping (documented tolerance): an inserted point whose barycentric coordinate to an edge is
// below snap_fraction, or whose rest distance to it is below min_piece_mm, goes onto that edge (or
// vertex); nothing moves farther than max(min_piece_mm, snap_fraction × the local spring), and no
// split makes a piece smaller than snap_fraction of its parent or min_piece_mm. Slivers existing
// geometry still forces are removed by the cleanup after each sweep (quality.hpp).
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

class Incision;
struct CrackTip;
struct TissuePoint;

// The cutting edge of a blade, as a segment in the eye frame (mm).
struct BladeEdge {
  Vec3 a_mm = Vec3::Zero();
  Vec3 b_mm = Vec3::Zero();
};

struct CutSettings {
  double band_mm = 1e-3;         // tolerance band around the swept surface
  double snap_fraction = 0.05;   // see above; in [0, 0.25]
  // Inserted points closer than this (rest length) to a vertex or edge snap onto it, so repeated
  // cuts at one spot never make springs shorter than this (the absolute floor under snap_fraction).
  double min_piece_mm = 0.005;
  // A bend in the blade's path is inserted where the chord from the crack tip would pass farther
  // than this fraction of the local spring length from a point the blade went through.
  double kink_fraction = 0.03;
  double min_blade_length_mm = 1e-4;
  double min_swept_area_mm2 = 1e-10;
  // Cleanup after each sweep (quality.hpp): slivers the existing geometry forces are collapsed.
  QualitySettings quality;
  void validate() const;  // throws InvalidArgument
};

struct CutResult {
  Status status = Status::ok();
  std::uint32_t end_points = 0;       // crack ends inserted inside the surface (where a cut starts or stops)
  std::uint32_t springs_split = 0;    // points inserted on springs
  std::uint32_t springs_opened = 0;   // springs along the cut that were disconnected
  std::uint32_t vertices_added = 0;   // all new vertices (ends, crossings, bends, copies)
  std::uint32_t snapped = 0;          // points moved onto an existing vertex (within the tolerance)
  std::uint32_t bends = 0;            // interior points inserted where the path bends
  std::uint32_t collapsed = 0;        // slivers removed by the cleanup (quality.hpp)
  std::uint32_t dissolved = 0;        // slivers the cleanup merged into a neighbour (the surface opens there)
  std::uint32_t unresolved = 0;       // slivers the cleanup could not remove
  // Pieces of cut that could not be joined to their crack tip (the mesh around a tip changed in
  // a way the incision could not follow, or more cracks at once than an incision holds): 0 in
  // every case the tests know.
  std::uint32_t gaps = 0;
  double removed_mass_g = 0.0;        // lone sliver fragments the cleanup removed (exact)
  void add(const CutResult& o);       // sums the counts; the first error wins
};

class Cutter {
 public:
  // Keeps a reference to the surface; scratch is sized to its capacity. Throws InvalidArgument on
  // invalid settings.
  explicit Cutter(Surface& surface, CutSettings settings = {});

  // One incision: cuts what the blade edge sweeps between the two poses and ends the cut there.
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
  friend class Incision;
  // A point on the cut, in the mesh as it is now: inside triangle `tri` (barycentric `bary`), on
  // one of its springs, or at one of its vertices; with which rims of the swept polygon it lies on.
  struct Spot {
    enum Kind : std::uint8_t { kInside, kEdge, kVertex };
    Kind kind = kInside;
    std::uint32_t tri = kNone;
    std::uint32_t generation = 0;  // tri's, when the spot was found (a changed triangle: a walk passed)
    std::array<double, 3> bary{};
    std::uint32_t vertex = kNone;  // kVertex
    std::uint32_t edge = kNone;    // kEdge
    Vec3 x = Vec3::Zero();         // current position
    std::uint8_t rim = 0;          // kRim* bits
  };
  static constexpr std::uint8_t kRimLeading = 1, kRimTrailing = 2, kRimPath = 4;
  // A vertex this close to the polygon's plane is on it (rounding; the band is for the rims).
  static constexpr double kOnPlane = 1e-10;
  // Where a new crack starts in this sweep (found before any edit).
  struct Start {
    Spot at;
    std::uint8_t priority = 0;  // leading rim, then the blade's ends, then the boundary
  };

  // ---- Incision steps (incision.cpp) ----
  CutResult advance(Incision& inc, const BladeEdge& to);
  CutResult finish(Incision& inc);
  // One planar sweep of the incision's edge from `from` to `to` (set up by advance).
  void sweep_once(Incision& inc, const BladeEdge& from, const BladeEdge& to, CutResult& r);
  // Follows the cut from c through the mesh for one crack tip: kGoesOn while the crack goes on
  // (its blade point set where the sweep ends), kEnded when it ended (inserted where the cut
  // stops), kStuck when nothing went on from c. A fresh crack (a start) that goes nowhere ends.
  enum class Walk : std::uint8_t { kGoesOn, kEnded, kStuck };  // kStuck: nothing went on from c
  Walk walk(CrackTip& tip, Spot c, bool fresh, CutResult& r);
  bool next_piece(const CrackTip& tip, const Spot& c, const Spot* back, std::uint32_t& tri, Spot& e);
  // Inserts y (which lies in the closed star of the tip's origin) and opens the spring from the
  // origin to it; y becomes the origin.
  void commit(CrackTip& tip, const Spot& y, CutResult& r, bool crack_end);
  void insert_origin(CrackTip& tip, CutResult& r);
  // crack_end: y ends a crack (snaps onto a nearby corner other than `from`, the crack's tip).
  std::uint32_t insert_spot(const Spot& y, CutResult& r, bool crack_end, std::uint32_t from);
  bool splits_into_sliver(std::uint32_t e, double t) const;
  bool in_star(const CrackTip& tip, std::uint32_t tri) const;
  Spot in_origin_star(const CrackTip& tip, const Spot& c) const;
  bool on_boundary(const Spot& c) const;
  // origin: the crack's tip (the cut it just made, ending there, does not count).
  bool along_boundary(std::uint32_t tri, const Spot& c, const Spot& e, std::uint32_t origin);
  void set_pending(CrackTip& tip, const Spot& c);
  Spot blade_point(std::uint32_t tri, const Spot& c, const Spot& e) const;
  // Whether the chord from the tip's origin to p keeps every sample since within tolerance;
  // note_sample adds p's constraint.
  bool chord_accepts(CrackTip& tip, const Spot& p);
  void note_sample(CrackTip& tip, const Spot& p);
  bool turned_back(const CrackTip& tip, const Spot& p) const;
  void reset_chord(CrackTip& tip);
  CrackTip new_tip(const Spot& at) const;
  Spot tip_spot(const CrackTip& tip) const;
  Vec3 tip_position(const CrackTip& tip) const;
  void hold(const CrackTip& tip);
  bool taken(const Spot& at) const;
  bool at_crack_point(const Incision& inc, const Spot& p) const;
  // Brings a tip's anchors up to date after edits (false: the tip could not be found again).
  bool reanchor(CrackTip& tip);
  void reanchor_tips(Incision& inc, CutResult& r);
  bool locate(const TissuePoint& p, std::span<const std::uint32_t> around, TissuePoint& out,
              const CrackTip* prefer = nullptr) const;
  bool locate_near(const TissuePoint& p, TissuePoint& out);
  Vec3 position_of(const TissuePoint& p) const;
  Vec3 rest_of(const Spot& s) const;
  Spot make_spot(std::uint32_t tri, std::array<double, 3> bary) const;
  Spot spot_of(const TissuePoint& p) const;
  TissuePoint anchor_of(const Spot& s) const;
  // Barycentric coordinates with (near) zeros made exact: inside (kind 0), on the spring opposite
  // the zero (1), at the corner of the one (2).
  static void classify(std::array<double, 3>& w, const std::array<std::uint32_t, 3>& tv,
                       const std::array<std::uint32_t, 3>& te, std::uint8_t& kind, std::uint32_t& vertex, std::uint32_t& edge);

  // ---- The swept polygon (cut.cpp) ----
  bool set_swept(const BladeEdge& from, const BladeEdge& to);
  double plane_distance(const Vec3& x) const { return swept_n_.dot(x - swept_o_); }
  // Vertex v's plane distance, computed once per sweep (the triangles around a vertex share it).
  double side(std::uint32_t v) {
    VertexScratch& vs = vertex_[v];
    if (vs.side_stamp != stamp_) {
      vs.side_stamp = stamp_;
      vs.side = plane_distance(surface_.position(v));
    }
    return vs.side;
  }
  std::uint8_t rim_bits(const Vec3& x) const;
  std::uint8_t nearest_rim(const Vec3& x) const;  // rim_bits, or the nearest rim's when none is near
  double progress(const Vec3& x) const;  // 0 at the blade's first pose, 1 at its last
  // Triangle tri's piece of cut (its segment on the plane, clipped to the polygon); false if none.
  bool piece(std::uint32_t tri, Spot& a, Spot& b);
  // The end of tri's piece that goes on from c (not back toward `back`); false if none.
  bool forward_from(std::uint32_t tri, const Spot& c, const Spot* back, Spot& e);
  // The triangle around vertex u (other than `from_tri`) where the cut goes on from u.
  bool forward_at_vertex(std::uint32_t u, std::uint32_t from_tri, const Spot& back, std::uint32_t& tri, Spot& e);
  Spot vertex_spot(std::uint32_t v, std::uint32_t tri) const;
  void gather_candidates();
  void gather_edges();
  void find_starts();
  std::uint32_t count_crossings();
  // Opens the springs the walks recorded; `live`: the crack tips that go on (a tip's last spring
  // that could only open with a middle vertex waits for the next one).
  void open_cut(CutResult& r, std::span<CrackTip> live);
  void clean(CutResult& r);

  Surface& surface_;
  CutSettings settings_;
  VertexIndex index_;  // finds the vertices near the swept polygon without visiting every slot
  MeshQuality quality_;
  double margin_mm_ = 0.0;  // how far beyond the swept box a vertex of a crossed triangle may lie
  // The swept polygon: corners p0, q0, q1, p1, its plane (origin, unit normal, in-plane axes) and
  // its rims (blade at the first pose, at the last, and the paths of the blade's two ends).
  std::array<Vec3, 4> poly_{};
  Vec3 swept_o_ = Vec3::Zero(), swept_n_ = Vec3::UnitZ();
  std::array<std::array<Vec3, 3>, 2> swept_tri_{};
  std::array<bool, 2> swept_tri_valid_{};
  std::array<std::array<Vec3, 2>, 4> rim_{};  // leading, trailing, path of a, path of b
  bool pivot_a_ = false, pivot_b_ = false;     // an end that did not move (a pivot: a fixed crack end)
  Vec3 box_lo_ = Vec3::Zero(), box_hi_ = Vec3::Zero();
  // Scratch, sized once.
  std::uint32_t stamp_ = 0, edge_round_ = 0;
  std::vector<std::uint32_t> edge_stamp_, triangle_stamp_, walked_, held_;
  std::vector<std::uint32_t> candidates_, triangles_, edges_, on_cut_, star_;
  std::vector<Start> starts_;
  std::vector<Spot> trailing_;
  std::vector<std::array<VertexId, 2>> to_open_;
  std::vector<EdgeId> opening_;
  // What a sweep keeps per vertex, in one record (a vertex costs one cache line, not several:
  // a sweep visits a few hundred vertices scattered over the surface). A field is this sweep's
  // where its stamp equals stamp_.
  struct VertexScratch {
    double side = 0.0;                // plane_distance (side_stamp)
    std::uint32_t side_stamp = 0;
    std::uint32_t cut = 0;            // on the cut (stamp)
    std::uint32_t walked = 0;         // a walk passed it, or a crack tip ends at it (stamp)
    std::uint32_t separated = 0;      // its fans were separated (stamp)
    std::uint8_t rim = 0;             // within the margin of the rims (stamp): bit k for rim_[k]
    std::uint8_t on_surface = 0;      // within the band of the polygon (stamp)
    std::uint8_t cut_degree = 0;      // opened springs along the cut at it
  };
  std::vector<VertexScratch> vertex_;
  void mark(std::uint32_t v);
};

}  // namespace vitreo::core
