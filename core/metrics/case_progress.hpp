#pragma once
// How far a case has got: each completion criterion of the case (scene_description.hpp,
// CriterionSpec) measured on the current world, as a progress fraction 0..1 and met/unmet, and the
// tissue removed or released so far. Everything is measured against the state at construction (the
// case's start), from public state of the world and the instruments; nothing here is stepped.
//
// The measures (why each is what it is is in core/metrics/README.md):
//   gel_removed        1 − gel rest area now / at the start; target "core": only the central gel,
//                      more than kCoreGelDepth_mm inside the wall and behind the globe's equator at
//                      rest (the cortical shell on the retina and the peripheral gel toward the
//                      vitreous base stay, as in a core vitrectomy)
//   membrane_removed   1 − rest area now / rest area at the start
//   membrane_released  fraction of the membrane's attachments broken or with an end cut away
//   membrane_freed     fraction of the membrane's start area removed or in pieces that no holding
//                      attachment ties to the retina (peeled off and cut loose)
//   path_cut           fraction of the guide's arc length within path_tolerance_mm (along the
//                      wall) of a retina boundary edge that was not a boundary at the start
//   laser_coverage     fraction of the ring's arc length within one spot radius of an adhered burn
//   drained            the detachment force's scale (≤ threshold)
//   retina_flat        largest distance of a retina vertex from the wall, mm (≤ threshold)
//   time_limit         elapsed simulated time, s (≤ threshold)
//   targets_reached    fraction of a target guide's points reached in order: a working (not light
//                      pipe) tip within target_reach_mm of the next target, tangentially, and at most
//                      target_hover_mm above the wall there (observe_tip, every step)
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "core/scene/scene_builder.hpp"
#include "core/scene/scene_description.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

class InstrumentSystem;

// What the metrics need to know about a case, by surface and item index. from_scene() fills it
// from a built Scene; a world built another way (core/anatomy/retina_cap) can fill it by hand.
struct MetricsCase {
  struct Membrane {
    std::string name;
    std::uint32_t surface = kNone;
    std::uint32_t first_attachment = 0;
    std::uint32_t attachment_count = 0;
  };
  struct Detachment {
    std::string name;
    std::uint32_t local_force = kNone;
  };
  std::uint32_t retina = kNone;
  std::uint32_t gel = kNone;
  std::vector<Membrane> membranes;
  std::vector<Detachment> detachments;
  std::vector<Guide> guides;
  std::vector<CriterionSpec> criteria;

  static MetricsCase from_scene(const Scene& scene);
};

// gel_removed's "core": gel lying more than this inside the wall at rest, and behind the equator (the
// plane through the globe's centre at right angles to the optical axis, eye frame z: anterior is +z).
// The outer shell lies on the retina (the cortical vitreous); the next one in stands 2.5 mm inside it
// (anatomy.gel_shell_spacing_mm). In front of the equator the shells run along the wall to the
// vitreous base: peripheral gel, shaved in a later step, not part of a core vitrectomy.
inline constexpr double kCoreGelDepth_mm = 1.0;

struct ProgressOptions {
  double path_tolerance_mm = 0.25;  // a guide point counts as cut when a new edge passes this close
  double sample_spacing_mm = 0.05;  // guides are measured at points this far apart along their arc
  double target_reach_mm = 0.47;    // a target is reached by a tip this close along the wall (its drawn ring)…
  double target_hover_mm = 1.0;     // …and at most this far above the wall
  void validate() const;            // throws InvalidArgument
};

struct CriterionProgress {
  CriterionKind kind = CriterionKind::kGelRemoved;
  std::string target;       // membrane / guide / detachment name, empty when the kind needs none
  double threshold = 0.0;
  double value = 0.0;       // the measure above, in the criterion's unit
  double progress = 0.0;    // 0..1; time_limit: the share of the time still left
  bool met = false;
};

struct TissueProgress {
  double gel_area_initial_mm2 = 0.0;  // rest area, all the gel
  double gel_area_removed_mm2 = 0.0;
  double membrane_area_initial_mm2 = 0.0;  // rest area, all membranes
  double membrane_area_removed_mm2 = 0.0;
  std::uint32_t membrane_attachments = 0;
  std::uint32_t membrane_attachments_released = 0;
};

class CaseProgress {
 public:
  // Records the start state. Throws InvalidArgument when a criterion names a membrane, guide or
  // detachment the case does not have, a needed surface is missing, or the guide kind is wrong.
  CaseProgress(const TissueWorld& world, MetricsCase c, ProgressOptions options = {});

  // Re-measures every criterion into criteria() (no allocation). instruments may be null (no
  // burns); elapsed_s is the case's simulated time.
  void evaluate(const TissueWorld& world, const InstrumentSystem* instruments, double elapsed_s);
  // A working instrument's tip this step (targets_reached: the next target in order is reached when
  // the tip is at it). Cheap; the session calls it every step for every working tip inside the eye.
  void observe_tip(const TissueWorld& world, const Vec3& tip_mm);
  const std::vector<CriterionProgress>& criteria() const { return criteria_; }

  TissueProgress tissue(const TissueWorld& world) const;
  const MetricsCase& description() const { return case_; }
  // Tangential distance (along the wall, mm) from p to the nearest laser-ring guide; +inf if none.
  double distance_to_laser_ring(const Vec3& p) const;

  // The points along each measured guide (path_cut, laser_coverage) and which of them the last
  // evaluate() found done — what the renderer colours as progress along the guide.
  struct GuideSamples {
    std::uint32_t guide = 0;      // index into description().guides
    std::vector<Vec3> points;
    std::vector<double> weights;  // arc length each point stands for
    std::vector<std::uint8_t> covered;
  };
  const std::vector<GuideSamples>& guide_samples() const { return samples_; }

 private:
  double path_cut_fraction(const TissueWorld& world, GuideSamples& g) const;
  double laser_fraction(const TissueWorld& world, const InstrumentSystem* instruments, GuideSamples& g) const;
  static double reached_fraction(const GuideSamples& g);
  double retina_lift_mm(const TissueWorld& world) const;
  double membrane_released(const TissueWorld& world, std::uint32_t m) const;
  double membrane_freed(const TissueWorld& world, std::uint32_t m) const;

  MetricsCase case_;
  ProgressOptions options_;
  std::vector<CriterionProgress> criteria_;
  std::vector<std::uint32_t> item_;          // per criterion: membrane / detachment / samples index
  std::vector<GuideSamples> samples_;
  std::vector<std::uint32_t> target_samples_;  // samples_ of the targets_reached criteria (covered = reached)
  // Gel rest area (all, core) at the start, and now with the gel's topology version it was taken at.
  struct GelArea {
    double all_mm2 = 0.0, core_mm2 = 0.0;
  };
  GelArea gel_area(const TissueWorld& world) const;
  GelArea gel_start_;
  mutable GelArea gel_now_;
  mutable std::uint64_t gel_now_version_ = ~std::uint64_t{0};
  std::vector<double> membrane_area_start_;  // rest area per membrane at the start
  std::vector<double> scale_start_;          // per criterion (drained): the force scale at the start
  double lift_start_mm_ = 0.0;
  // Retina springs that were boundary edges at the start: generation per slot (kNone: not one).
  std::vector<std::uint32_t> boundary_start_;
  // membrane_freed's work space (sized to the membrane's vertex slots once, grown by cuts only).
  std::vector<double> membrane_free_start_;  // membrane_freed's own value at the start, per membrane
  mutable std::vector<std::uint32_t> piece_parent_;
  mutable std::vector<std::uint8_t> piece_held_;
};

// Distance from p to segment [a, b] measured along the wall: the radial part of the offset (tissue
// thickness, a guide lifted by half a retina) is taken out. Used by the criteria and the scores.
double tangential_distance(const Vec3& p, const Vec3& a, const Vec3& b);

}  // namespace vitreo::core
