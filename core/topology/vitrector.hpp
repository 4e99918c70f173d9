#pragma once
// The vitrector (suction cutter), one model with one parameter set (VitrectorSettings) in one unit
// per quantity (mm, Pa, cuts per minute). Suction draws tissue to the port; the guillotine removes
// what has entered it (thesis ch. 2.6.2.3, without its clamped tiny masses).
//
// Suction itself is a force of the solver's step: the instruments hand the port's suction field
// (suction_pa · vacuum inside field_radius_mm · vacuum, at least removal_radius_mm) to the
// TissueWorld as a SuctionField (core/instruments). This class does what happens at the step
// boundary, once per step before TissueWorld::step(dt):
//
// Leaving the field: material inside the field hemisphere (radius field_radius_mm in front of the
// port, along the suction direction) that moves away from the port is slowed by an opposing,
// implicit damping (Δv = v_out · k·dt / (1 + k·dt), k = leaving_damping_per_s), and every vertex in
// the field is woken.
//
// Removal: at every cut of the guillotine (cut rate in cuts per minute), the tissue inside the
// removal hemisphere (radius removal_radius_mm, in front of the port) is clipped at its boundary —
// springs crossing it are split where they cross (snapping onto a vertex within snap_fraction of the
// spring's length, so no piece is smaller than that fraction of its parent triangle) — and the
// triangles inside are removed with their mass (Surface::remove_triangle): the reported removed
// mass is exactly what total_mass() loses.
//
// Aspiration (RemovalModel::kAspirate, the vitreous gel): a gel shell is not a sheet but stands for
// the layer of gel around it (its material thickness), and gel is not clipped by the port's rim:
// it flows into the port as a volume. The port aspirates gel_flow_mm3_per_s at full vacuum (in
// proportion to the vacuum; none while the cutter is off: uncut gel plugs the port, Magalhaes et
// al. 2008). Each cut takes its bite: whole triangles, nearest to the port first, within the suction
// field (its hemisphere, reaching removal_radius_mm behind the port's plane), as long as the volume
// aspirated since the last bite (rest area × thickness) pays for them.
// The flow only accrues while gel is in the field (otherwise the port draws fluid).
//
// No allocation: scratch is sized to the surface's capacity when built.
#include <cstdint>
#include <vector>

#include "core/common/status.hpp"
#include "core/common/types.hpp"
#include "core/tissue/external_forces.hpp"
#include "core/tissue/surface.hpp"
#include "core/topology/quality.hpp"
#include "core/topology/vertex_index.hpp"

namespace vitreo::core {

struct VitrectorSettings {
  double suction_pa = 300.0;        // suction pressure at the port at full vacuum (the solver's SuctionField)
  double field_radius_mm = 1.5;     // suction hemisphere at full vacuum; the leaving damping acts in it
  double removal_radius_mm = 0.3;   // what enters this hemisphere is cut away
  // Gel aspirated at full vacuum and 7500 cpm. Porcine vitreous through 23-25 G probes: 0.5-2 ml/min
  // (Magalhaes et al., Retina 2008: 25 G, 500 mmHg: up to 0.015 ml/s; Abulon & Buboltz, TVST 2016:
  // 23 G flows most at 7500 cpm); 1.5 ml/min here.
  double gel_flow_mm3_per_s = 25.0;
  double cut_rate_cpm = 7500.0;     // the console's cut rate, cuts per minute
  double max_cut_rate_cpm = 10000.0;
  double leaving_damping_per_s = 50.0;
  double snap_fraction = 0.05;
  double min_piece_mm = 0.005;  // crossings closer than this to a vertex snap onto it too
  QualitySettings quality;  // cleanup after each removal (quality.hpp)
  void validate() const;  // throws InvalidArgument
};

struct VitrectorStepResult {
  Status status = Status::ok();
  std::uint32_t in_field = 0;   // vertices in the field this step (damped when leaving, woken)
  bool cut = false;             // the guillotine cut this step
  std::uint32_t springs_split = 0;
  std::uint32_t triangles_removed = 0;
  std::uint32_t vertices_removed = 0;
  double removed_area_mm2 = 0.0;
  double removed_mass_g = 0.0;
  std::uint32_t collapsed = 0;   // slivers removed by the cleanup
  std::uint32_t unresolved = 0;  // slivers the cleanup could not remove
};

// How a surface is removed: clipped at the port's hemisphere (sheets: retina, membranes), or
// aspirated as a volume (the gel's shells).
enum class RemovalModel : std::uint8_t { kClip, kAspirate };

class Vitrector {
 public:
  explicit Vitrector(Surface& surface, VitrectorSettings settings = {}, RemovalModel model = RemovalModel::kClip);

  // Port position and suction direction (out of the port, into the eye). Refuses non-finite values
  // and a zero direction, changing nothing.
  Status set_pose(const Vec3& port_mm, const Vec3& suction_direction);
  Status set_cut_rate(double cuts_per_minute);  // 0 (cutter off)..max_cut_rate_cpm
  // The pedal's vacuum, 0..1 of the maximum: scales the aspiration model's flow and field (the
  // clipping model's hemisphere does not depend on it). Default 1.
  Status set_vacuum(double vacuum);

  // The leaving damping for this step, and removal if the guillotine cuts during it.
  VitrectorStepResult apply(double dt_s);
  // One cut of the guillotine now (removal only), regardless of the cut rate.
  VitrectorStepResult cut_now();

  const VitrectorSettings& settings() const { return settings_; }
  const Vec3& port() const { return port_; }
  double total_removed_mass_g() const { return removed_mass_g_; }

 private:
  double region(const Vec3& x) const;  // < 0 inside the removal hemisphere
  void remove(VitrectorStepResult& r);
  void aspirate(VitrectorStepResult& r, double since_last_cut_s);
  void finish_removal(VitrectorStepResult& r);  // bow-ties and slivers around inside_

  Surface& surface_;
  VitrectorSettings settings_;
  VertexIndex index_;  // the field and the removal region visit only the vertices near the port
  MeshQuality quality_;
  Vec3 port_ = Vec3::Zero(), dir_ = Vec3::UnitZ();
  RemovalModel model_ = RemovalModel::kClip;
  double cut_rate_cpm_ = 0.0, cut_phase_ = 0.0, vacuum_ = 1.0;
  double aspirated_mm3_ = 0.0;  // aspirated since the last bite, not yet spent on a triangle
  struct Candidate {
    double distance2;
    std::uint32_t triangle;
  };
  std::vector<Candidate> candidates_;
  bool posed_ = false;
  double removed_mass_g_ = 0.0;
  std::vector<AccelerationSample> samples_;
  std::vector<std::uint32_t> inside_, triangles_, stamp_, tri_stamp_;
  std::vector<double> phi_;
  std::uint32_t round_ = 0;
  struct Crossing {
    EdgeId edge;
    double t;
  };
  std::vector<Crossing> crossings_;
};

}  // namespace vitreo::core
