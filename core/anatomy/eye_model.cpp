#include "core/anatomy/eye_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/common/validate.hpp"
#include "core/common/units.hpp"

namespace vitreo::core {

namespace {

using units::kDeg;
using units::kPi;
constexpr int kProfileSamples = 1441;  // polar angle samples pole → pole (1/8°)

// Cross-section of a surface that is star-shaped about the origin: radius as a function of the polar
// angle theta from the posterior pole (−z).
struct CrossSection {
  double transverse = 0.0;      // equatorial semi-axis
  double posterior = 0.0;       // semi-axis toward −z
  double anterior = 0.0;        // semi-axis toward +z
  double cornea_center_z = 0.0;
  double cornea_radius = 0.0;
  double limbus_theta = kPi;    // beyond this polar angle the cornea bulges out of the ellipsoid

  double ellipse(double theta) const {
    const double s = std::sin(theta), c = std::cos(theta);
    const double az = c > 0.0 ? posterior : anterior;
    return 1.0 / std::sqrt((s / transverse) * (s / transverse) + (c / az) * (c / az));
  }
  double cornea(double theta) const {
    // Ray from the origin along (rho, z) = (sin θ, −cos θ) against the sphere centred on the axis.
    const double dc = -std::cos(theta) * cornea_center_z;
    const double disc = dc * dc - cornea_center_z * cornea_center_z + cornea_radius * cornea_radius;
    return disc > 0.0 ? dc + std::sqrt(disc) : 0.0;
  }
  double radius(double theta) const {
    const double r = ellipse(theta);
    return theta > limbus_theta ? std::max(r, cornea(theta)) : r;
  }
  ProfilePoint point(double theta) const {
    const double r = radius(theta);
    return {-r * std::cos(theta), std::max(0.0, r * std::sin(theta))};
  }
};

std::vector<double> arc_table(const CrossSection& cs) {
  std::vector<double> arc(kProfileSamples, 0.0);
  ProfilePoint prev = cs.point(0.0);
  for (int i = 1; i < kProfileSamples; ++i) {
    const ProfilePoint q = cs.point(kPi * i / (kProfileSamples - 1));
    arc[static_cast<std::size_t>(i)] =
        arc[static_cast<std::size_t>(i - 1)] + std::hypot(q.z_mm - prev.z_mm, q.rho_mm - prev.rho_mm);
    prev = q;
  }
  return arc;
}

double interpolate_arc(const std::vector<double>& arc, double theta) {
  const double f = std::clamp(theta / kPi, 0.0, 1.0) * (kProfileSamples - 1);
  const auto i = std::min<std::size_t>(static_cast<std::size_t>(f), kProfileSamples - 2);
  const double t = f - static_cast<double>(i);
  return arc[i] + t * (arc[i + 1] - arc[i]);
}

double invert_arc(const std::vector<double>& arc, double s) {
  s = std::clamp(s, 0.0, arc.back());
  const auto it = std::upper_bound(arc.begin(), arc.end(), s);
  std::size_t i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(1, it - arc.begin())) - 1;
  i = std::min<std::size_t>(i, kProfileSamples - 2);
  const double len = arc[i + 1] - arc[i];
  const double t = len > 0.0 ? (s - arc[i]) / len : 0.0;
  return kPi * (static_cast<double>(i) + t) / (kProfileSamples - 1);
}

std::vector<ProfilePoint> section_profile(const CrossSection& cs, double theta0, double theta1) {
  std::vector<ProfilePoint> out;
  const int n = std::max(8, static_cast<int>(std::ceil((theta1 - theta0) / (0.25 * kDeg))));
  for (int i = 0; i <= n; ++i) out.push_back(cs.point(theta0 + (theta1 - theta0) * i / n));
  return out;
}

Vec3 at_azimuth(const ProfilePoint& q, double phi) {
  return {q.rho_mm * std::cos(phi), q.rho_mm * std::sin(phi), q.z_mm};
}

// uv from surface_coords (arc, azimuth): u around, v along.
std::vector<Vec2> cylindrical_uv(const TriangleMesh& m) {
  double smax = 1e-9;
  for (const auto& c : m.surface_coords) smax = std::max(smax, c.x());
  std::vector<Vec2> uv;
  uv.reserve(m.surface_coords.size());
  for (const auto& c : m.surface_coords) uv.emplace_back(c.y() / (2.0 * kPi), c.x() / smax);
  return uv;
}

}  // namespace

void EyeParameters::validate() const {
  require_range(axial_length_mm, 16.0, 35.0, "eye: axial_length_mm");
  require_range(globe_diameter_mm, 16.0, 35.0, "eye: globe_diameter_mm");
  require_range(sclera_thickness_mm, 0.2, 2.0, "eye: sclera_thickness_mm");
  require_range(choroid_thickness_mm, 0.05, 1.0, "eye: choroid_thickness_mm");
  require_range(retina_thickness_mm, 0.05, 1.0, "eye: retina_thickness_mm");
  require_range(cornea_radius_mm, 5.0, 11.0, "eye: cornea_radius_mm");
  require_range(cornea_diameter_mm, 8.0, 14.0, "eye: cornea_diameter_mm");
  if (cornea_diameter_mm / 2.0 >= cornea_radius_mm) throw InvalidArgument("eye: cornea_diameter_mm must be < 2 × cornea_radius_mm");
  if (cornea_diameter_mm >= 0.8 * globe_diameter_mm) throw InvalidArgument("eye: cornea_diameter_mm too large for the globe");
  require_range(cornea_thickness_mm, 0.3, 1.2, "eye: cornea_thickness_mm");
  require_range(pars_plicata_end_mm, 0.8, 4.0, "eye: pars_plicata_end_mm");
  require_range(ora_serrata_mm, 4.0, 10.0, "eye: ora_serrata_mm");
  require_range(ports_mm, 2.5, 6.0, "eye: ports_mm");
  if (ports_mm >= ora_serrata_mm) throw InvalidArgument("eye: ports_mm must lie in front of the ora serrata (pars plana)");
  if (pars_plicata_end_mm >= ports_mm) throw InvalidArgument("eye: pars_plicata_end_mm must lie in front of the ports");
  for (double a : {infusion_port_deg, working_port_1_deg, working_port_2_deg}) require_range(a, -360.0, 360.0, "eye: port azimuth");
  require_range(optic_disc_offset_deg, 5.0, 30.0, "eye: optic_disc_offset_deg");
  require_range(optic_disc_radius_mm, 0.3, 1.5, "eye: optic_disc_radius_mm");
  require_range(fovea_radius_mm, 0.1, 1.5, "eye: fovea_radius_mm");
  require_range(macula_radius_mm, 1.0, 4.0, "eye: macula_radius_mm");
  if (macula_radius_mm <= fovea_radius_mm) throw InvalidArgument("eye: macula_radius_mm must exceed fovea_radius_mm");
  require_range(anterior_chamber_depth_mm, 1.5, 5.0, "eye: anterior_chamber_depth_mm");
  require_range(lens_diameter_mm, 6.0, 11.0, "eye: lens_diameter_mm");
  require_range(lens_thickness_mm, 2.5, 6.0, "eye: lens_thickness_mm");
  require_range(pupil_diameter_mm, 1.0, 9.0, "eye: pupil_diameter_mm");
  require_range(iris_depth_mm, 0.0, 2.0, "eye: iris_depth_mm");
  if (ciliary_processes < 0 || ciliary_processes > 120) throw InvalidArgument("eye: ciliary_processes must be in [0, 120]");
  require_range(ciliary_process_height_mm, 0.1, 2.0, "eye: ciliary_process_height_mm");
  if (retina_vertices < 500 || retina_vertices > 200000) throw InvalidArgument("eye: retina_vertices must be in [500, 200000]");
  if (gel_shells < 0 || gel_shells > 4) throw InvalidArgument("eye: gel_shells must be in [0, 4]");
  require_range(gel_vertex_ratio, 0.02, 1.0, "eye: gel_vertex_ratio");
  require_range(gel_shell_spacing_mm, 0.5, 4.0, "eye: gel_shell_spacing_mm");
  require_range(vitreous_base_mm, 0.5, 5.0, "eye: vitreous_base_mm");
}

Vec3 EyeModel::wall_point(double theta, double phi) const {
  const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), -std::cos(theta));
  return d * wall.radius_toward(d) + wall.center();
}

double EyeModel::arc_at_polar(double theta) const { return interpolate_arc(arc_table_, theta); }
double EyeModel::polar_at_arc(double s) const { return invert_arc(arc_table_, s); }

Vec2 EyeModel::fundus_coords(const Vec3& p) const {
  const double rho = std::hypot(p.x(), p.y());
  const double theta = std::atan2(rho, -p.z());
  const double s = arc_at_polar(theta);
  if (rho < 1e-12) return Vec2::Zero();
  return {s * p.x() / rho, s * p.y() / rho};
}

Vec2 EyeModel::fundus_uv(const Vec2& f) const {
  return {0.5 + f.x() / (2.0 * fundus_extent_mm), 0.5 + f.y() / (2.0 * fundus_extent_mm)};
}

const RenderMesh* EyeModel::find_static(const std::string& name) const {
  for (const auto& m : static_meshes) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

EyeModel build_eye_model(const EyeParameters& p) {
  p.validate();
  EyeModel eye;
  eye.parameters = p;

  // ---- Outer sclera and cornea ---------------------------------------------------------------
  const double half_axial = 0.5 * p.axial_length_mm;
  const double limbus_r = 0.5 * p.cornea_diameter_mm;
  const double sagitta = p.cornea_radius_mm - std::sqrt(p.cornea_radius_mm * p.cornea_radius_mm - limbus_r * limbus_r);
  const double rt = 0.5 * p.globe_diameter_mm;
  const double limbus_z = half_axial - sagitta;
  CrossSection outer;
  outer.transverse = rt;
  outer.posterior = half_axial;
  outer.anterior = limbus_z / std::sqrt(1.0 - (limbus_r / rt) * (limbus_r / rt));
  outer.cornea_center_z = half_axial - p.cornea_radius_mm;
  outer.cornea_radius = p.cornea_radius_mm;
  outer.limbus_theta = std::atan2(limbus_r, -limbus_z);

  const double tw = p.sclera_thickness_mm + p.choroid_thickness_mm;
  CrossSection inner = outer;
  inner.transverse -= tw;
  inner.posterior -= tw;
  inner.anterior -= tw;
  inner.cornea_radius -= p.cornea_thickness_mm;

  eye.posterior_pole_z_mm = -half_axial;
  eye.cornea_apex_z_mm = half_axial;
  eye.limbus_z_mm = limbus_z;
  eye.limbus_radius_mm = limbus_r;

  eye.outer_profile = section_profile(outer, 0.0, kPi);
  eye.wall_profile = section_profile(inner, 0.0, kPi);
  eye.outer_profile.back().rho_mm = 0.0;
  eye.wall_profile.back().rho_mm = 0.0;
  eye.wall = GlobeWall::from_profile(Vec3::Zero(), eye.wall_profile);
  eye.arc_table_ = arc_table(inner);

  // Positions behind the limbus are measured along the outer sclera and carried radially inward.
  const std::vector<double> outer_arc = arc_table(outer);
  const double limbus_arc = interpolate_arc(outer_arc, outer.limbus_theta);
  const auto behind_limbus = [&](double mm) { return invert_arc(outer_arc, limbus_arc - mm); };

  eye.ora_polar_rad = behind_limbus(p.ora_serrata_mm);
  eye.fundus_extent_mm = eye.arc_at_polar(eye.ora_polar_rad);
  eye.fovea_mm = eye.wall_point(0.0, 0.0);
  const double disc_theta = p.optic_disc_offset_deg * kDeg;
  eye.optic_disc_mm = eye.wall_point(disc_theta, 0.0);
  eye.optic_disc_fundus_mm = {eye.arc_at_polar(disc_theta), 0.0};

  // ---- Ports ------------------------------------------------------------------------------------
  const double port_theta = behind_limbus(p.ports_mm);
  const std::pair<const char*, double> port_list[] = {
      {"infusion", p.infusion_port_deg}, {"working_1", p.working_port_1_deg}, {"working_2", p.working_port_2_deg}};
  for (const auto& [name, deg] : port_list) {
    SclerotomyPort port;
    port.name = name;
    port.outer_mm = at_azimuth(outer.point(port_theta), deg * kDeg);
    port.inner_mm = eye.wall_point(port_theta, deg * kDeg);
    port.axis = -port.outer_mm.normalized();
    eye.ports.push_back(port);
  }

  // ---- Static meshes --------------------------------------------------------------------------
  const double static_edge = 0.6;
  {
    RenderMesh m;
    m.name = "sclera";
    m.mesh = revolve_profile(section_profile(outer, 0.0, outer.limbus_theta), {static_edge, 2.0 * kPi});
    m.uv = cylindrical_uv(m.mesh);
    m.base_rgba = {0.93f, 0.91f, 0.87f, 1.0f};
    eye.static_meshes.push_back(std::move(m));
  }
  {
    RenderMesh m;
    m.name = "choroid";  // inner surface, fundus-mapped (uv beyond [0,1] anterior to the ora)
    m.mesh = revolve_profile(section_profile(inner, 0.0, inner.limbus_theta), {static_edge, 2.0 * kPi});
    for (const auto& q : m.mesh.positions) m.uv.push_back(eye.fundus_uv(eye.fundus_coords(q)));
    m.base_rgba = {0.75f, 0.3f, 0.15f, 1.0f};
    m.texture = "choroid";
    eye.static_meshes.push_back(std::move(m));
  }
  {
    RenderMesh m;
    m.name = "cornea";
    m.mesh = revolve_profile(section_profile(outer, outer.limbus_theta, kPi), {0.4, 2.0 * kPi});
    m.uv = cylindrical_uv(m.mesh);
    m.base_rgba = {0.95f, 0.97f, 1.0f, 0.15f};
    eye.static_meshes.push_back(std::move(m));
  }
  const double cornea_inner_apex = half_axial - p.cornea_thickness_mm;
  // Iris: a flat annulus just behind the inner limbus, from its root at the wall to the pupil.
  eye.iris_z_mm = limbus_z - tw - p.iris_depth_mm;
  {
    const double theta_iris = std::atan2(std::sqrt(std::max(0.0, 1.0 - std::pow(eye.iris_z_mm / inner.anterior, 2))) *
                                             inner.transverse,
                                         -eye.iris_z_mm);
    const double root = inner.point(theta_iris).rho_mm - 0.05;
    if (root <= 0.5 * p.pupil_diameter_mm + 0.5) throw InvalidArgument("eye: pupil_diameter_mm too large for the iris");
    RenderMesh m;
    m.name = "iris";
    m.mesh = revolve_profile({{eye.iris_z_mm, root}, {eye.iris_z_mm, 0.5 * p.pupil_diameter_mm}}, {0.3, 2.0 * kPi});
    m.uv = cylindrical_uv(m.mesh);
    m.base_rgba = {0.35f, 0.22f, 0.12f, 1.0f};
    eye.static_meshes.push_back(std::move(m));
  }
  {
    const double front = cornea_inner_apex - p.anterior_chamber_depth_mm;
    eye.lens_center_z_mm = front - 0.5 * p.lens_thickness_mm;
    std::vector<ProfilePoint> prof;
    for (int i = 0; i <= 96; ++i) {
      const double a = kPi * i / 96;
      prof.push_back({eye.lens_center_z_mm - 0.5 * p.lens_thickness_mm * std::cos(a),
                      i == 0 || i == 96 ? 0.0 : 0.5 * p.lens_diameter_mm * std::sin(a)});
    }
    RenderMesh m;
    m.name = "lens";
    m.mesh = revolve_profile(prof, {0.3, 2.0 * kPi});
    m.uv = cylindrical_uv(m.mesh);
    m.base_rgba = {0.97f, 0.96f, 0.9f, 0.25f};
    eye.static_meshes.push_back(std::move(m));
  }
  if (p.ciliary_processes > 0) {
    // Forty radial ridges on the pars plicata (thesis ch. 2.2): triangular prisms on the wall,
    // from 0.5 mm behind the limbus to the end of the pars plicata, standing inward.
    RenderMesh m;
    m.name = "ciliary_processes";
    m.base_rgba = {0.3f, 0.15f, 0.1f, 1.0f};
    const double t0 = behind_limbus(0.5), t1 = behind_limbus(p.pars_plicata_end_mm);
    const double half_width = 0.3 * kPi / p.ciliary_processes;
    for (int k = 0; k < p.ciliary_processes; ++k) {
      const double phi = 2.0 * kPi * k / p.ciliary_processes;
      const auto base = static_cast<std::uint32_t>(m.mesh.positions.size());
      for (double t : {t0, t1}) {
        const Vec3 l = eye.wall_point(t, phi - half_width), r = eye.wall_point(t, phi + half_width);
        const Vec3 c = eye.wall_point(t, phi);
        m.mesh.positions.push_back(l);
        m.mesh.positions.push_back(r);
        m.mesh.positions.push_back(c - c.normalized() * p.ciliary_process_height_mm);
      }
      // Vertices: 0 L0, 1 R0, 2 T0, 3 L1, 4 R1, 5 T1.
      const std::array<std::array<std::uint32_t, 3>, 6> tris{{{0, 3, 5}, {0, 5, 2}, {1, 2, 5}, {1, 5, 4}, {0, 2, 1}, {3, 4, 5}}};
      for (const auto& t : tris) m.mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
      for (int i = 0; i < 6; ++i) m.uv.emplace_back(static_cast<double>(k) / p.ciliary_processes, i < 3 ? 0.0 : 1.0);
    }
    eye.static_meshes.push_back(std::move(m));
  }

  // ---- Physical surfaces -------------------------------------------------------------------
  const double mean_r = eye.fundus_extent_mm / eye.ora_polar_rad;
  const double retina_edge = edge_length_for_vertex_count(mean_r, eye.ora_polar_rad, p.retina_vertices);
  eye.retina_mesh = revolve_profile(section_profile(inner, 0.0, eye.ora_polar_rad), {retina_edge, 2.0 * kPi});

  const double gel_edge = retina_edge / std::sqrt(p.gel_vertex_ratio);
  for (int k = 0; k < p.gel_shells; ++k) {
    const double inset = k * p.gel_shell_spacing_mm;
    std::vector<ProfilePoint> prof;
    for (const auto& q : section_profile(inner, 0.0, eye.ora_polar_rad)) {
      const double r = std::hypot(q.z_mm, q.rho_mm);
      const double f = (r - inset) / r;
      prof.push_back({q.z_mm * f, q.rho_mm * f});
    }
    const TriangleMesh shell = revolve_profile(prof, {gel_edge, 2.0 * kPi});
    const auto base = static_cast<std::uint32_t>(eye.gel_mesh.positions.size());
    for (std::size_t i = 0; i < shell.positions.size(); ++i) {
      eye.gel_mesh.positions.push_back(shell.positions[i]);
      eye.gel_mesh.surface_coords.push_back(shell.surface_coords[i]);
      eye.gel_shell_of_vertex.push_back(static_cast<std::uint32_t>(k));
    }
    for (const auto& t : shell.triangles) eye.gel_mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
  return eye;
}

}  // namespace vitreo::core
