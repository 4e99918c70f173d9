#pragma once
// An incision: the cut one blade edge makes while it moves through the tissue, pose after pose.
//
// The rig hands the blade's pose to advance() every step (a tracked blade at 5 mm/s moves 5 µm a
// step: a cut is thousands of sweeps, and scissors close in small increments). Cut sweep by sweep
// on its own, each of those would end its piece of cut inside a triangle and the next would start
// a new one: whether the pieces joined depended on snapping, and a path cut in 48 sweeps left
// separate slits where 8 sweeps parted the tissue. An Incision instead carries each crack it is
// extending from sweep to sweep (CrackTip: the vertex the cut has reached and the point where the
// blade now is, held by the tissue), and the Cutter walks on from there (cut.hpp has the rules).
// The result no longer depends on how the path was sampled: the same path cut in 1 sweep or in
// 1000 makes the same crossings, opens the same springs, and parts the tissue the same way.
//
// end() finishes the cut where the blade is (an interior point inside a triangle: thesis
// 2.6.2.1.1) — call it when the blade leaves the tissue or stops cutting. A later advance() starts
// a new incision from that pose. Between sweeps the anchors follow the tissue: the blade's previous
// pose is carried along with the tissue under the crack tip, so tissue that moved between two
// steps is cut from where the blade really was in it.
//
// No allocation: crack tips live in a fixed array; the Cutter's scratch does the rest.
#include <array>
#include <cstdint>

#include "core/tissue/handles.hpp"
#include "core/topology/cut.hpp"

namespace vitreo::core {

// A point held by the tissue: a triangle and barycentric coordinates in it, with its rest position
// and the triangle's corners (to find it again after the triangle has been split).
struct TissuePoint {
  TriangleId triangle;
  std::array<double, 3> bary{};
  std::array<VertexId, 3> corners{};
  Vec3 rest = Vec3::Zero();
};

// One crack an incision is extending.
struct CrackTip {
  // Where the cut made so far ends: a vertex of the mesh, or — for a crack that has not left the
  // triangle (or spring) where it started — a point not inserted yet.
  bool origin_inserted = false;
  VertexId origin;
  TissuePoint origin_point;  // while !origin_inserted
  Vec3 origin_rest = Vec3::Zero();
  // Where the blade is now: the crack runs on from the origin to here, not inserted yet. Lies in
  // the closed star of the origin (a triangle of the origin's, its springs or corners).
  bool has_pending = false;
  TissuePoint pending;
  // The bend test (chord_accepts): the directions from the origin, in the rest shape's tangent
  // plane, that keep every sample since the origin within tol_mm of the chord.
  bool chord_constrained = false, chord_frame = false;
  double tol_mm = 0.0, ref = 0.0, lo = 0.0, hi = 0.0, r_max = 0.0;
  Vec3 e1 = Vec3::UnitX(), e2 = Vec3::UnitY();
  // The crack's last spring when it has not been opened yet: alone it would have opened as a slit
  // of one spring, which needs a middle vertex (Cutter::open_cut); it opens with the next one.
  bool deferred_inserted = false;
  std::array<VertexId, 2> deferred{};
};

class Incision {
 public:
  static constexpr std::uint32_t kMaxCrackTips = 8;
  // Cuts cutter's surface; several incisions may share one Cutter (its scratch is per call).
  explicit Incision(Cutter& cutter) : cutter_(cutter) {}

  // The blade's cutting edge at its next pose: cuts what it swept since the previous pose (the
  // first call only records the pose). Refuses non-finite poses and degenerate edges, changing
  // nothing; a pose that sweeps no area (the blade at rest, or moved along its own edge) cuts
  // nothing and is not an error.
  CutResult advance(const BladeEdge& edge);
  // Pivoting edge (a scissor blade): the edge from apex to tip.
  CutResult advance_pivot(const Vec3& apex_mm, const Vec3& tip_mm) { return advance({apex_mm, tip_mm}); }
  // Ends the cut where the blade is and forgets the pose.
  CutResult end();

  bool has_pose() const { return has_pose_; }
  std::uint32_t crack_tips() const { return ntips_; }
  Cutter& cutter() { return cutter_; }

 private:
  friend class Cutter;
  Cutter& cutter_;
  bool has_pose_ = false;
  BladeEdge pose_;
  // Where the first crack tip's blade point was when pose_ was recorded: the next sweep starts from
  // pose_ moved as the tissue there has moved since.
  Vec3 pose_anchor_ = Vec3::Zero();
  bool pose_anchored_ = false;
  std::array<CrackTip, kMaxCrackTips> tips_{};
  std::uint32_t ntips_ = 0;
};

}  // namespace vitreo::core
