#pragma once
// The other cutting instruments, on the same incisions as the straight blade (incision.hpp): what
// they cut does not depend on how finely their motion is sampled.
//
// SidewaysBlade: a small fixed cutting parallelogram at the tip — the cutting edge runs from the tip
// back along `edge_direction` for `edge_length_mm`. While the blade is down, every
// `stroke_length_mm` of tip travel advances its incision to the current pose; end_stroke() cuts to
// the current pose and ends the cut there (the blade comes out of the tissue); lift() ends the cut
// where it last advanced and forgets the pose.
//
// Scissors: two blades hinged at a pivot, in the plane normal to `plane_normal`, opening
// symmetrically about `bisector` by `opening_rad`. As they close, each blade sweeps the wedge between
// its old and new angle (its edge pivoting about the hinge: Incision::advance_pivot), and the tissue
// in those wedges is cut — the cut between the blades grows as they close and spans the whole
// initial wedge when they meet (which ends the cut), whether they close in one step or in a
// thousand. Opening (or moving without closing) ends the cut; opening cuts nothing.
#include "core/topology/incision.hpp"

namespace vitreo::core {

class SidewaysBlade {
 public:
  SidewaysBlade(Cutter& cutter, double edge_length_mm, double stroke_length_mm);
  // Moves the tip; returns what the incision cut (if a stroke length was reached) or an empty ok result.
  CutResult move_to(const Vec3& tip_mm, const Vec3& edge_direction);
  CutResult end_stroke();
  CutResult lift();

 private:
  BladeEdge edge_at(const Vec3& tip, const Vec3& direction) const;
  Incision incision_;
  double edge_length_mm_, stroke_length_mm_;
  bool has_last_ = false;
  Vec3 last_tip_ = Vec3::Zero();
  Vec3 cur_tip_ = Vec3::Zero(), cur_dir_ = Vec3::UnitX();
};

class Scissors {
 public:
  Scissors(Cutter& cutter, double blade_length_mm);
  // Sets the pose; closing from the previous opening cuts both swept wedges.
  CutResult set_pose(const Vec3& pivot_mm, const Vec3& bisector, const Vec3& plane_normal, double opening_rad);
  // Ends the cut (the blades let go of the tissue) and forgets the pose.
  CutResult release();
  // The jaws' length (the instrument's, when it is set per step); refuses a length out of range.
  Status set_blade_length(double blade_length_mm);

 private:
  Incision upper_, lower_;
  double blade_length_mm_;
  bool has_last_ = false;
  double last_opening_ = 0.0;
};

}  // namespace vitreo::core
