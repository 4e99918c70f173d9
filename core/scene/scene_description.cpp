#include "core/scene/scene_description.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/common/validate.hpp"

namespace vitreo::core {

const char* to_string(MembraneKind k) {
  switch (k) {
    case MembraneKind::kPerpendicular: return "perpendicular";
    case MembraneKind::kCircumferential: return "circumferential";
    case MembraneKind::kAnteroposterior: return "anteroposterior";
    case MembraneKind::kEpiretinal: return "epiretinal";
  }
  return "?";
}

const char* to_string(AttachmentStrength s) {
  switch (s) {
    case AttachmentStrength::kWeak: return "weak";
    case AttachmentStrength::kStrong: return "strong";
    case AttachmentStrength::kMixed: return "mixed";
  }
  return "?";
}

const char* to_string(GuideKind k) {
  switch (k) {
    case GuideKind::kCutPath: return "cut_path";
    case GuideKind::kLaserRing: return "laser_ring";
    case GuideKind::kTarget: return "target";
  }
  return "?";
}

const char* to_string(CriterionKind k) {
  switch (k) {
    case CriterionKind::kGelRemoved: return "gel_removed";
    case CriterionKind::kMembraneRemoved: return "membrane_removed";
    case CriterionKind::kMembraneReleased: return "membrane_released";
    case CriterionKind::kMembraneFreed: return "membrane_freed";
    case CriterionKind::kTargetsReached: return "targets_reached";
    case CriterionKind::kPathCut: return "path_cut";
    case CriterionKind::kLaserCoverage: return "laser_coverage";
    case CriterionKind::kDrained: return "drained";
    case CriterionKind::kRetinaFlat: return "retina_flat";
    case CriterionKind::kTimeLimit: return "time_limit";
  }
  return "?";
}

const char* to_string(GelStain s) {
  switch (s) {
    case GelStain::kClear: return "none";
    case GelStain::kTriamcinolone: return "triamcinolone";
  }
  return "?";
}

const std::vector<std::string>& known_instruments() {
  static const std::vector<std::string> names{"vitrector", "forceps",   "scissors",  "pick",  "laser",
                                              "light_pipe", "backflush", "infusion", "blade", "sideways_blade"};
  return names;
}

const std::vector<std::string>& second_hand_instruments() {
  static const std::vector<std::string> names{"light_pipe", "forceps", "pick", "scissors"};
  return names;
}

SceneMaterials default_materials() {
  SceneMaterials m;
  m.retina = TissueMaterial{};
  m.sources["retina"] = {
      {"density_g_per_mm3", "Michels, Wilkinson & Rice 1990 (thesis ch. 2.3.3): 1.0174 g/ml"},
      {"thickness_mm", "Michels et al. 1990: 0.1-0.3 mm, 0.25 mm mid-periphery"},
      {"membrane_modulus_pa_mm", "E ~ 20 kPa (Jones et al. 1992; Chen et al. 2010) x 0.25 mm"},
      {"bending_modulus_un_mm", "Kirchhoff plate D = E t^3 / (12 (1 - nu^2)), nu = 1/3: 5000 x 0.25^2 x 3/32"},
      {"tear_strain", "Michels et al. 1990: retina tears at 35-55 % stretch"},
  };
  m.gel.name = "vitreous gel";
  m.gel.density_g_per_mm3 = 1.0053e-3;
  m.gel.thickness_mm = 2.5;
  m.gel.membrane_modulus_pa_mm = 50.0;
  m.gel.bending_modulus_un_mm = 29.3;
  m.gel.tear_strain = 0.8;
  m.gel.drag_pa_s_per_mm = 20.0;
  m.gel.entrained_fluid_mm = 1.0;
  m.sources["gel"] = {
      {"density_g_per_mm3", "Michels et al. 1990: vitreous 1.0053-1.0089 g/ml"},
      {"thickness_mm", "layer represented by one shell = shell spacing"},
      {"membrane_modulus_pa_mm", "vitreous shear modulus 6-120 Pa (Nickerson et al. 2008; Sharif-Kashani 2011) x 2.5 mm, ~20 Pa"},
      {"bending_modulus_un_mm", "Kirchhoff plate D = E t^3 / (12 (1 - nu^2)), nu = 1/3: 50 x 2.5^2 x 3/32"},
      {"tear_strain", "gel is cut, not torn: high so the vitrector decides"},
  };
  m.membrane.name = "fibrovascular membrane";
  m.membrane.density_g_per_mm3 = 1.05e-3;
  m.membrane.thickness_mm = 0.05;
  m.membrane.membrane_modulus_pa_mm = 10000.0;
  m.membrane.bending_modulus_un_mm = 2.34;
  m.membrane.tear_strain = 0.6;
  m.sources["membrane"] = {
      {"density_g_per_mm3", "collagenous tissue ~1.05 g/ml"},
      {"thickness_mm", "epiretinal membranes 20-80 um (OCT, Wilkins et al. 1996)"},
      {"membrane_modulus_pa_mm", "ERM E ~ 0.2 MPa (Chen et al. 2010 range) x 0.05 mm"},
      {"bending_modulus_un_mm", "Kirchhoff plate D = E t^3 / (12 (1 - nu^2)), nu = 1/3: 10000 x 0.05^2 x 3/32"},
      {"tear_strain", "stiffer and tougher than retina; estimate"},
  };
  return m;
}

void SceneDescription::validate() const {
  if (format_version != kSceneFormatVersion) {
    throw InvalidArgument("format_version " + std::to_string(format_version) + " is not supported (expected " +
                          std::to_string(kSceneFormatVersion) + ")");
  }
  if (name.empty()) throw InvalidArgument("name must not be empty");
  if (category != "case" && category != "exercise") throw InvalidArgument("category must be \"case\" or \"exercise\"");
  anatomy.validate();
  if (texture_size_px < 64 || texture_size_px > 8192) throw InvalidArgument("texture_size_px must be in [64, 8192]");
  require_range(intraocular_pressure_mmhg, 0.0, 80.0, "intraocular_pressure_mmhg");
  require_range(pass_score, 0.0, 100.0, "proficiency.pass_score");
  if (substeps < 1 || substeps > 64) throw InvalidArgument("substeps must be in [1, 64]");
  if (!(gel_adhesion_break_force_un > 0.0)) throw InvalidArgument("gel_adhesion_break_force_un must be > 0");
  if (gel_adhesion_stride < 1 || gel_adhesion_stride > 100) throw InvalidArgument("gel_adhesion_stride must be in [1, 100]");
  materials.retina.validate();
  materials.gel.validate();
  materials.membrane.validate();

  std::set<std::string> names;
  const auto unique = [&](const std::string& kind, const std::string& n) {
    if (n.empty()) throw InvalidArgument(kind + ": name must not be empty");
    if (!names.insert(n).second) throw InvalidArgument(kind + " '" + n + "': name used twice");
  };
  const auto location = [](const std::string& what, const FundusLocation& l) {
    require_range(l.polar_deg, 0.0, 100.0, what + ": polar_deg");
    require_range(l.azimuth_deg, -360.0, 360.0, what + ": azimuth_deg");
  };
  for (const auto& d : detachments) {
    unique("detachment", d.name);
    location("detachment '" + d.name + "'", d.center);
    require_range(d.radius_deg, 2.0, 90.0, "detachment '" + d.name + "': radius_deg");
    require_range(d.pressure_pa, 0.0, 2000.0, "detachment '" + d.name + "': pressure_pa");
  }
  for (const auto& t : tears) {
    unique("tear", t.name);
    location("tear '" + t.name + "'", t.center);
    require_range(t.width_mm, 0.5, 6.0, "tear '" + t.name + "': width_mm");
    require_range(t.length_mm, 0.5, 8.0, "tear '" + t.name + "': length_mm");
    if (t.length_mm < 0.5 * t.width_mm) throw InvalidArgument("tear '" + t.name + "': length_mm must be at least width_mm / 2 (a U)");
    require_range(t.lift_mm, 0.0, 3.0, "tear '" + t.name + "': lift_mm");
  }
  for (const auto& m : membranes) {
    unique("membrane", m.name);
    location("membrane '" + m.name + "'", m.center);
    const std::string w = "membrane '" + m.name + "': ";
    require_range(m.size_mm, 0.5, 15.0, w + "size_mm");
    require_range(m.width_mm, 0.3, 6.0, w + "width_mm");
    require_range(m.height_mm, 0.3, 8.0, w + "height_mm");
    require_range(m.rest_length_scale, 0.2, 2.0, w + "rest_length_scale");
    require_range(m.strong_fraction, 0.0, 1.0, w + "strong_fraction");
    require_range(m.attachment_spacing_mm, 0.2, 5.0, w + "attachment_spacing_mm");
    if (std::isnan(m.weak_break_force_un) || !(m.weak_break_force_un > 0.0)) throw InvalidArgument(w + "weak_break_force_un must be > 0");
    if (std::isnan(m.strong_break_force_un) || !(m.strong_break_force_un > 0.0)) throw InvalidArgument(w + "strong_break_force_un must be > 0");
    require_range(m.detach_radius_mm, 0.0, 15.0, w + "detach_radius_mm");
    require_range(m.elevation_mm, 0.0, 1.5, w + "elevation_mm");
    if (m.elevation_mm > 0.0 && m.kind != MembraneKind::kCircumferential && m.kind != MembraneKind::kAnteroposterior) {
      throw InvalidArgument(w + "elevation_mm is for bands (circumferential, anteroposterior)");
    }
    if (m.strong_break_force_un < m.weak_break_force_un) throw InvalidArgument(w + "strong_break_force_un must be >= weak_break_force_un");
  }
  for (const auto& i : instruments) {
    const auto& k = known_instruments();
    if (std::find(k.begin(), k.end(), i) == k.end()) throw InvalidArgument("instrument '" + i + "' is not known");
  }
  if (working_port != "working_1" && working_port != "working_2") {
    throw InvalidArgument("instruments.working_port '" + working_port + "' is not a working port (working_1, working_2)");
  }
  const auto& holdable = second_hand_instruments();
  if (std::find(holdable.begin(), holdable.end(), second_hand) == holdable.end()) {
    throw InvalidArgument("instruments.second_hand '" + second_hand + "' is not one the other hand holds (light_pipe, forceps, pick, scissors)");
  }
  if (second_hand != "light_pipe") {
    if (!view.chandelier) throw InvalidArgument("instruments.second_hand '" + second_hand + "' leaves no hand for the light pipe: set view.chandelier = true");
    if (std::find(instruments.begin(), instruments.end(), "light_pipe") != instruments.end()) {
      throw InvalidArgument("instruments: 'light_pipe' is available but the other hand holds the " + second_hand);
    }
  }
  std::set<std::string> tear_names;
  for (const auto& t : tears) tear_names.insert(t.name);
  for (const auto& g : guides) {
    unique("guide", g.name);
    if (g.kind == GuideKind::kLaserRing) {
      require_range(g.radius_mm, 0.3, 8.0, "guide '" + g.name + "': radius_mm");
      if (!g.around.empty() && !tear_names.count(g.around)) throw InvalidArgument("guide '" + g.name + "': no tear named '" + g.around + "'");
      if (g.around.empty()) location("guide '" + g.name + "'", g.center);
    } else {
      const std::size_t least = g.kind == GuideKind::kTarget ? 1 : 2;
      if (g.points.size() < least) throw InvalidArgument("guide '" + g.name + "': needs at least " + (least == 1 ? "one point" : "two points"));
      for (const auto& p : g.points) location("guide '" + g.name + "'", p);
    }
  }
  for (const auto& c : criteria) {
    const std::string w = std::string("criterion ") + to_string(c.kind) + ": ";
    switch (c.kind) {
      case CriterionKind::kGelRemoved:
        if (anatomy.gel_shells == 0) throw InvalidArgument(w + "the scene has no gel");
        if (!c.target.empty() && c.target != "core") throw InvalidArgument(w + "target must be \"core\" (the gel away from the retina) or absent");
        require_range(c.threshold, 0.0, 1.0, w + "threshold");
        break;
      case CriterionKind::kMembraneRemoved:
      case CriterionKind::kMembraneReleased:
      case CriterionKind::kMembraneFreed:
        if (std::none_of(membranes.begin(), membranes.end(), [&](const auto& m) { return m.name == c.target; })) {
          throw InvalidArgument(w + "no membrane named '" + c.target + "'");
        }
        require_range(c.threshold, 0.0, 1.0, w + "threshold");
        break;
      case CriterionKind::kPathCut:
      case CriterionKind::kLaserCoverage:
      case CriterionKind::kTargetsReached:
        if (std::none_of(guides.begin(), guides.end(), [&](const auto& g) { return g.name == c.target; })) {
          throw InvalidArgument(w + "no guide named '" + c.target + "'");
        }
        if (c.kind == CriterionKind::kTargetsReached &&
            std::none_of(guides.begin(), guides.end(), [&](const auto& g) { return g.name == c.target && g.kind == GuideKind::kTarget; })) {
          throw InvalidArgument(w + "guide '" + c.target + "' is not a target guide");
        }
        require_range(c.threshold, 0.0, 1.0, w + "threshold");
        break;
      case CriterionKind::kDrained:
        if (std::none_of(detachments.begin(), detachments.end(), [&](const auto& d) { return d.name == c.target; })) {
          throw InvalidArgument(w + "no detachment named '" + c.target + "'");
        }
        require_range(c.threshold, 0.0, 1.0, w + "threshold");
        break;
      case CriterionKind::kRetinaFlat: require_range(c.threshold, 0.0, 10.0, w + "threshold"); break;
      case CriterionKind::kTimeLimit: require_range(c.threshold, 1.0, 7200.0, w + "threshold"); break;
    }
  }
  if (view.region_of_interest) {
    location("view: region_of_interest", *view.region_of_interest);
    require_range(view.region_of_interest->polar_deg, 0.0, 90.0, "view: region_of_interest: polar_deg");
  }
  if (view.gel_stain != GelStain::kClear && anatomy.gel_shells == 0) {
    throw InvalidArgument("view: gel_stain needs gel (anatomy.gel_shells > 0)");
  }
  if (settle.max_steps < 0 || settle.max_steps > 20000) throw InvalidArgument("settle: max_steps must be in [0, 20000]");
  if (settle.min_steps < 0 || settle.min_steps > settle.max_steps) throw InvalidArgument("settle: min_steps must be in [0, max_steps]");
  require_range(settle.dt_s, 1e-4, 0.02, "settle: dt_s");
  require_range(settle.damping_per_s, 0.0, 1000.0, "settle: damping_per_s");
  require_range(settle.max_speed_mm_s, 1e-4, 100.0, "settle: max_speed_mm_s");
}

}  // namespace vitreo::core
