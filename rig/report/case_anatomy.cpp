#include "rig/report/case_anatomy.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

#include "core/anatomy/eye_model.hpp"
#include "core/common/units.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/telemetry/recording.hpp"

namespace vitreo::report {

namespace {

using core::units::kDeg;
using core::units::kPi;

// Draws on the fundus plane (EyeModel::fundus_coords) and maps each point back onto the wall.
class FundusPen {
 public:
  explicit FundusPen(const core::EyeModel& eye) : eye_(eye) {}

  core::Vec2 plane(const core::Vec3& wall_point) const { return eye_.fundus_coords(wall_point); }
  core::Vec2 plane(const core::FundusLocation& at) const { return plane(core::wall_point_at(eye_, at)); }

  void point(FundusOutline& o, const core::Vec2& q) const {
    const double s = std::min(q.norm(), eye_.fundus_extent_mm);
    const double phi = std::atan2(q.y(), q.x());
    const core::Vec3 p = eye_.wall_point(eye_.polar_at_arc(s), phi);
    o.x_mm.push_back(p.x());
    o.y_mm.push_back(p.y());
  }
  FundusOutline circle(std::string name, std::string kind, const core::Vec2& centre, double radius_mm) const {
    FundusOutline o{std::move(name), std::move(kind), {}, {}};
    for (int k = 0; k <= 48; ++k) {
      const double a = 2.0 * kPi * k / 48;
      point(o, centre + radius_mm * core::Vec2(std::cos(a), std::sin(a)));
    }
    return o;
  }
  // The region between arc lengths s0..s1 from the pole and azimuths phi0..phi1, as its boundary.
  FundusOutline patch(std::string name, std::string kind, double s0, double s1, double phi0, double phi1) const {
    FundusOutline o{std::move(name), std::move(kind), {}, {}};
    const int n = 16;
    auto at = [&](double s, double phi) { point(o, s * core::Vec2(std::cos(phi), std::sin(phi))); };
    for (int k = 0; k <= n; ++k) at(s0, phi0 + (phi1 - phi0) * k / n);
    for (int k = 0; k <= n; ++k) at(s1, phi1 - (phi1 - phi0) * k / n);
    at(s0, phi0);
    return o;
  }
  // The radius of the circle the ring of arc length s lies on (for lengths along a circumference).
  double ring_radius(double s) const {
    const double r = eye_.fundus_extent_mm / eye_.ora_polar_rad;
    return r * std::sin(std::max(1e-3, s / r));
  }

 private:
  const core::EyeModel& eye_;
};

std::string named(const std::string& name, const char* what) { return name + " (" + what + ")"; }

}  // namespace

CaseAnatomy case_anatomy(const core::SceneDescription& d) {
  const core::EyeModel eye = core::build_eye_model(d.anatomy);
  const FundusPen pen(eye);
  CaseAnatomy a;
  a.case_id = d.name;
  auto& out = a.outlines;
  out.push_back(pen.circle("ora serrata", "ora", core::Vec2::Zero(), eye.fundus_extent_mm));
  out.push_back(pen.circle("optic disc", "disc", pen.plane(eye.optic_disc_mm), eye.parameters.optic_disc_radius_mm));
  const core::Vec2 fovea = pen.plane(eye.fovea_mm);
  out.push_back(pen.circle("macula", "macula", fovea, kMaculaRadiusMm));
  out.push_back(pen.circle("fovea", "fovea", fovea, kFoveaRadiusMm));
  for (const auto& t : d.detachments) {
    // Its radius is an angle on the globe; as an arc on the wall from its centre.
    const double r = t.radius_deg * kDeg * core::wall_point_at(eye, t.center).norm();
    out.push_back(pen.circle(named(t.name, "detachment"), "detachment", pen.plane(t.center), r));
  }
  for (const auto& t : d.tears)
    out.push_back(pen.circle(named(t.name, "tear"), "tear", pen.plane(t.center), 0.5 * std::max(t.width_mm, t.length_mm)));
  for (const auto& m : d.membranes) {
    const core::Vec2 c = pen.plane(m.center);
    const double sc = c.norm(), phc = std::atan2(c.y(), c.x());
    // The regions the scene builder gives each kind (core/scene/scene_builder.cpp, build_membrane).
    switch (m.kind) {
      case core::MembraneKind::kEpiretinal: out.push_back(pen.circle(named(m.name, "membrane"), "membrane", c, m.size_mm)); break;
      case core::MembraneKind::kCircumferential: {
        const double half = 0.5 * m.size_mm / pen.ring_radius(sc);
        out.push_back(pen.patch(named(m.name, "membrane"), "membrane", sc - 0.5 * m.width_mm, sc + 0.5 * m.width_mm, phc - half, phc + half));
        break;
      }
      case core::MembraneKind::kAnteroposterior: {
        const double half = 0.5 * m.width_mm / pen.ring_radius(sc);
        out.push_back(pen.patch(named(m.name, "membrane"), "membrane", sc, std::min(sc + m.size_mm, eye.fundus_extent_mm - 0.3), phc - half, phc + half));
        break;
      }
      case core::MembraneKind::kPerpendicular: {
        // A sheet standing on the retina along the circumference: its foot.
        const double half = 0.5 * m.size_mm / pen.ring_radius(sc);
        out.push_back(pen.patch(named(m.name, "membrane"), "membrane", sc, sc, phc - half, phc + half));
        break;
      }
    }
  }
  for (const auto& g : d.guides) {
    if (g.kind == core::GuideKind::kLaserRing) {
      core::FundusLocation c = g.center;
      for (const auto& t : d.tears)
        if (!g.around.empty() && t.name == g.around) c = t.center;
      out.push_back(pen.circle(named(g.name, "laser ring"), "guide", pen.plane(c), g.radius_mm));
    } else if (!g.points.empty()) {
      FundusOutline o{named(g.name, g.kind == core::GuideKind::kCutPath ? "cut path" : "target"), "guide", {}, {}};
      for (std::size_t i = 0; i + 1 < g.points.size(); ++i) {
        const core::Vec2 p = pen.plane(g.points[i]), q = pen.plane(g.points[i + 1]);
        for (int k = 0; k < 16; ++k) pen.point(o, p + (q - p) * (k / 16.0));
      }
      pen.point(o, pen.plane(g.points.back()));
      out.push_back(std::move(o));
    }
  }
  return a;
}

std::optional<CaseAnatomy> anatomy_from_recording(const std::string& path, const std::string& case_id, std::string& problem) {
  try {
    const telemetry::Recording rec = telemetry::read_recording(path);
    rig::ModelConfig cases;
    rig::decode_case_list(rec.header.config_text, cases);
    if (cases.cases.empty()) {
      problem = "the recording lists no case";
      return std::nullopt;
    }
    std::optional<core::SceneDescription> chosen;
    for (const auto& c : cases.cases) {
      core::SceneDescription d = scene_io::case_description(c);
      if (d.name == case_id || !chosen) {
        const bool exact = d.name == case_id;
        chosen = std::move(d);
        if (exact) break;
      }
    }
    return case_anatomy(*chosen);
  } catch (const std::exception& e) {
    problem = e.what();
    return std::nullopt;
  }
}

}  // namespace vitreo::report
