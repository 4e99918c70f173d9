#pragma once
// The other cutting instruments, on the same swept-surface mechanism as the straight blade (Cutter).
//
// SidewaysBlade: a small fixed cutting parallelogram at the tip — the cutting edge runs from the tip
// back along `edge_direction` for `edge_length_mm`. The surgeon cuts in strokes: while the blade is
// down, every `stroke_length_mm` of tip travel cuts one stroke (the edge's sweep since the last one);
// end_stroke() cuts what is left; lift() forgets the last pose without cutting.
//
// Scissors: two blades hinged at a pivot, in the plane normal to `plane_normal`, opening
// symmetrically about `bisector` by `opening_rad`. As they close, each blade sweeps the wedge between
// its old and new angle (a triangle with the pivot as apex), and the tissue in those wedges is cut —
// the cut between the blades grows as they close and spans the whole initial wedge when they meet.
// Opening cuts nothing.
#include "core/topology/cut.hpp"

namespace vitreo::core {

class SidewaysBlade {
 public:
  SidewaysBlade(Cutter& cutter, double edge_length_mm, double stroke_length_mm);
  // Moves the tip; returns the stroke cut (if one completed) or an empty ok result.
  CutResult move_to(const Vec3& tip_mm, const Vec3& edge_direction);
  CutResult end_stroke();
  void lift() { has_last_ = false; }

 private:
  BladeEdge edge_at(const Vec3& tip, const Vec3& direction) const;
  Cutter& cutter_;
  double edge_length_mm_, stroke_length_mm_;
  bool has_last_ = false;
  Vec3 last_tip_ = Vec3::Zero(), last_dir_ = Vec3::UnitX();
  Vec3 cur_tip_ = Vec3::Zero(), cur_dir_ = Vec3::UnitX();
};

class Scissors {
 public:
  Scissors(Cutter& cutter, double blade_length_mm);
  // Sets the pose; closing from the previous opening cuts both swept wedges.
  CutResult set_pose(const Vec3& pivot_mm, const Vec3& bisector, const Vec3& plane_normal, double opening_rad);
  void release() { has_last_ = false; }

 private:
  Cutter& cutter_;
  double blade_length_mm_;
  bool has_last_ = false;
  double last_opening_ = 0.0;
};

}  // namespace vitreo::core
