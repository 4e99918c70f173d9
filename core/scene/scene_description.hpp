#pragma once
// A surgical case as data: anatomy, pathology, materials (with the source of every value),
// instruments, guides and completion criteria. Parsed from TOML by rig/scene_io; built into a
// TissueWorld by build_scene (scene_builder.hpp). The core never reads TOML.
//
// Locations on the fundus are (polar_deg, azimuth_deg): polar angle from the posterior pole
// (0 = fovea, the ora serrata lies near 80–90°), azimuth 0 = nasal (+x), 90 = superior (+y),
// 180 = temporal, 270 = inferior.
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/anatomy/eye_model.hpp"
#include "core/common/units.hpp"
#include "core/tissue/material.hpp"

namespace vitreo::core {

inline constexpr int kSceneFormatVersion = 1;
// A case's pass score when its file names none ([proficiency] pass_score).
inline constexpr double kDefaultPassScore = 70.0;

struct FundusLocation {
  double polar_deg = 0.0;
  double azimuth_deg = 0.0;
};

// The point of the eye's wall at a fundus location.
inline Vec3 wall_point_at(const EyeModel& eye, const FundusLocation& at) {
  return eye.wall_point(at.polar_deg * units::kDeg, at.azimuth_deg * units::kDeg);
}

// Subretinal fluid: the thesis' local radial force pulling the retina toward the centre (ch. 2.4).
struct DetachmentSpec {
  std::string name = "detachment";
  FundusLocation center;
  double radius_deg = 20.0;
  double pressure_pa = 150.0;  // net inward, on top of intraocular pressure
};

// A horseshoe (U) tear: the U's apex points posterior, its open end (the hinge, where the flap stays
// attached) anterior, the flap curls inward by up to lift_mm at the apex (a 3-D flap).
struct TearSpec {
  std::string name = "tear";
  FundusLocation center;
  double width_mm = 2.0;
  double length_mm = 3.0;
  double lift_mm = 0.8;
};

enum class MembraneKind : std::uint8_t { kPerpendicular, kCircumferential, kAnteroposterior, kEpiretinal };
enum class AttachmentStrength : std::uint8_t { kWeak, kStrong, kMixed };

// Fibrovascular tissue attached to the retina through instance vertices (thesis ch. 2.3.1, 2.4),
// contracting by rest-length scaling.
struct MembraneSpec {
  std::string name = "membrane";
  MembraneKind kind = MembraneKind::kEpiretinal;
  FundusLocation center;
  double size_mm = 4.0;     // radius (epiretinal), band length (circumferential, anteroposterior, perpendicular)
  double width_mm = 1.5;    // band width
  double height_mm = 2.0;   // perpendicular sheet: height toward the centre
  double rest_length_scale = 0.9;  // < 1 contracts: epiretinal in its plane, bands along them, the
                                   // perpendicular plane along its height
  AttachmentStrength strength = AttachmentStrength::kMixed;
  double strong_fraction = 0.25;   // kMixed: share of strong attachments (epiretinal: those at the disc are strong)
  // Attachments stand at the sites of a square lattice of this pitch in fundus coordinates (mm),
  // each on the membrane vertex nearest it: the same number and places at every mesh resolution
  // (the perpendicular plane: every base vertex; an epiretinal membrane: also every vertex over the
  // disc rim).
  double attachment_spacing_mm = 0.7;
  double weak_break_force_un = 40.0;
  double strong_break_force_un = std::numeric_limits<double>::infinity();
  // Tractional detachment: within this distance (mm) of the membrane, subretinal fluid carries most
  // of the intraocular pressure that otherwise holds the retina on the wall (90 %, a local force
  // toward the centre), so the traction can lift it and, cut, lets it settle. 0 = the retina stays
  // pressed on.
  double detach_radius_mm = 0.0;
  // Bands only (circumferential, anteroposterior): the band stands this far off the retina on
  // stalks — its attachments are pegs of this length (AttachmentDescription::rest_length_mm), the
  // "table-top" elevation of fibrovascular tissue between its epicentres, which leaves the room a
  // vitrector or horizontal scissors enter to cut the pegs (delamination). 0: the band lies on the
  // retina, its attachments coincident instance vertices.
  double elevation_mm = 0.0;
};

enum class GuideKind : std::uint8_t { kCutPath, kLaserRing, kTarget };
struct GuideSpec {
  std::string name;
  GuideKind kind = GuideKind::kCutPath;
  std::vector<FundusLocation> points;  // cut path / target: the polyline
  FundusLocation center;               // laser ring
  double radius_mm = 1.5;
  std::string around;                  // laser ring around this tear (its centre), optional
};

enum class CriterionKind : std::uint8_t {
  kGelRemoved,        // fraction of gel vertices removed ≥ threshold
  kMembraneRemoved,   // fraction of a membrane's area removed ≥ threshold
  kMembraneReleased,  // fraction of a membrane's attachments broken or cut ≥ threshold
  kPathCut,           // fraction of a cut path guide followed within tolerance ≥ threshold
  kLaserCoverage,     // fraction of a laser ring covered by spots ≥ threshold
  kDrained,           // detachment force scale ≤ threshold
  kRetinaFlat,        // largest retina lift from the wall (mm) ≤ threshold
  kTimeLimit,         // elapsed s ≤ threshold
  kMembraneFreed,     // fraction of a membrane's area removed or in pieces no attachment holds ≥ threshold
  kTargetsReached,    // (keep last: rig/report walks the kinds up to it) fraction of a target guide's points reached in order by a working tip ≥ threshold
};
struct CriterionSpec {
  CriterionKind kind = CriterionKind::kGelRemoved;
  std::string target;  // membrane / guide / detachment name where the kind needs one
  double threshold = 0.9;
};

// How the case is seen (not physics): where the microscope starts, what the gel looks like, the
// lighting. Read by the rig's microscope and renderer only; a change here never moves tissue.
enum class GelStain : std::uint8_t { kClear, kTriamcinolone };
struct ViewSpec {
  // Where the microscope's field starts; unset: the pathology the case is about (its first tear,
  // membrane, detachment or guide), else the fovea.
  std::optional<FundusLocation> region_of_interest;
  // The vitreous as the surgeon sees it: clear (a faint haze) or stained white with triamcinolone
  // crystals, as surgeons do to see the gel they are removing. Needs gel (anatomy.gel_shells > 0).
  GelStain gel_stain = GelStain::kClear;
  bool wide_angle = false;  // the case starts with the wide-angle viewing system swung in
  bool chandelier = false;  // a chandelier fibre in the superior pars plana lights the cavity
};

struct SettleSpec {
  int max_steps = 800;
  int min_steps = 100;
  double dt_s = 0.001;
  double damping_per_s = 20.0;
  double max_speed_mm_s = 1.0;  // settled when no free vertex is faster (mm/s)
};

struct SceneMaterials {
  TissueMaterial retina;
  TissueMaterial gel;
  TissueMaterial membrane;
  // sources["retina"]["membrane_modulus_pa_mm"] = "Wollensak & Spoerl 2004; ..."
  std::map<std::string, std::map<std::string, std::string>> sources;
};

struct SceneDescription {
  int format_version = kSceneFormatVersion;
  std::string name;
  std::string title;
  std::string summary;
  std::string category = "case";  // "case" or "exercise"
  EyeParameters anatomy;
  std::uint64_t texture_seed = 1;
  int texture_size_px = 1024;
  double intraocular_pressure_mmhg = 15.0;
  int substeps = 2;
  double gel_adhesion_break_force_un = 30.0;  // cortex ↔ retina, per attachment
  int gel_adhesion_stride = 2;
  SceneMaterials materials;
  std::vector<DetachmentSpec> detachments;
  std::vector<TearSpec> tears;
  std::vector<MembraneSpec> membranes;
  std::vector<std::string> instruments;
  // The sclerotomy the working hand's instruments go through ("working_1" or "working_2"); the light
  // pipe takes the other. A break on the same side as working_1 is reached across the eye from
  // working_2, as a surgeon switches hands for it (the near port meets it at a grazing angle).
  std::string working_port = "working_1";
  // What the other hand holds through the other working port: the light pipe, or — with a
  // chandelier lighting the cavity instead (view.chandelier) — a second instrument for bimanual
  // membrane work ("forceps", "pick" or "scissors": tools its own handle works; the pedals work the
  // working hand's). A second-hand instrument is its own, besides the working hand's `available`.
  std::string second_hand = "light_pipe";
  std::vector<GuideSpec> guides;
  std::vector<CriterionSpec> criteria;
  // [proficiency] pass_score: the final score (0..100) an attempt must reach to pass this case. The
  // instructor's standard for the case, published with every score card, so the debrief and a
  // trainee's history say which attempts passed.
  double pass_score = kDefaultPassScore;
  SettleSpec settle;
  ViewSpec view;
  std::string source_file;  // where it was read from (diagnostics)

  // Checks cross-references and ranges; throws InvalidArgument naming the item.
  void validate() const;
};

const char* to_string(MembraneKind k);
const char* to_string(AttachmentStrength s);
const char* to_string(GuideKind k);
const char* to_string(CriterionKind k);
const char* to_string(GelStain s);
// Names accepted for instruments.
const std::vector<std::string>& known_instruments();
// What the other hand may hold (SceneDescription::second_hand): the light pipe, or a tool its own
// handle works.
const std::vector<std::string>& second_hand_instruments();

// Default materials with their sources (the values the scene files start from).
SceneMaterials default_materials();

}  // namespace vitreo::core
