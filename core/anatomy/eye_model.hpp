#pragma once
// The procedural eye: sclera, choroid, retina, cornea, iris, lens, 40 ciliary processes, vitreous
// gel and the three sclerotomy ports, in millimetres, from anatomical parameters.
//
// The thesis swept NURBS cross-sections of published anatomical averages around the optical axis
// (ch. 2.2). We sweep analytic cross-sections instead: the outer sclera is two half-ellipsoids
// (posterior and anterior) meeting at the equator, the cornea a sphere cap meeting the sclera at the
// limbus; the choroid's inner surface (the wall the retina lies on) is the sclera moved inward by
// sclera + choroid thickness. Everything is star-shaped about the globe centre, so the same profile
// also gives the exact GlobeWall.
//
// Eye frame: origin at the globe centre (centre of the posterior half-ellipsoid), +z anterior, +x
// nasal, +y superior (a right eye). The fovea lies at the posterior pole; the optic disc is nasal.
//
// Fundus plane: retina and choroid are mapped to a plane by azimuthal equidistant projection about
// the posterior pole: a point at profile arc length s (mm from the pole along the wall) and azimuth φ
// maps to (s cos φ, s sin φ). The fundus textures are drawn in that plane and uv = 0.5 + X / (2·S),
// where S = fundus_extent_mm, covers it.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/types.hpp"
#include "core/geometry/revolved_mesh.hpp"
#include "core/geometry/triangle_mesh.hpp"
#include "core/tissue/globe_wall.hpp"

namespace vitreo::core {

struct EyeParameters {
  // Outer dimensions (Bekerman et al. 2014: emmetropic axial length 23.5–24 mm, globe 24–25 mm).
  double axial_length_mm = 24.0;     // corneal apex to the posterior outer sclera
  double globe_diameter_mm = 24.5;   // transverse, outer sclera
  double sclera_thickness_mm = 0.7;  // (Olsen et al. 1998: 0.5–1.0 mm)
  double choroid_thickness_mm = 0.25;
  double retina_thickness_mm = 0.25;
  // Cornea (Gullstrand: anterior radius 7.7–7.8 mm; horizontal diameter 11.7 mm; 0.55 mm thick).
  double cornea_radius_mm = 7.8;
  double cornea_diameter_mm = 11.7;
  double cornea_thickness_mm = 0.55;
  // Positions along the outer sclera, measured as arc length behind the limbus.
  double pars_plicata_end_mm = 2.0;    // ciliary processes from 0.5 mm to here
  double ora_serrata_mm = 6.0;         // ~6 mm nasal, 7 mm temporal: one value, swept
  double ports_mm = 3.75;              // sclerotomies through the pars plana (3.5–4 mm, phakic)
  // Azimuths (deg, 0 = nasal +x, 90 = superior +y) of the ports: infusion inferotemporal, working
  // ports superotemporal and superonasal — the usual three-port layout of a right eye.
  double infusion_port_deg = 210.0;
  double working_port_1_deg = 150.0;
  double working_port_2_deg = 30.0;
  // Posterior pole landmarks.
  double optic_disc_offset_deg = 15.0;  // polar angle of the disc centre from the posterior pole, nasal
  double optic_disc_radius_mm = 0.9;    // disc ~1.8 mm across
  double fovea_radius_mm = 0.75;        // foveal pit ~1.5 mm across; vessel-free
  double macula_radius_mm = 2.75;       // macula ~5.5 mm across
  // Anterior segment.
  double anterior_chamber_depth_mm = 3.0;  // inner cornea apex to the lens front
  double lens_diameter_mm = 9.5;
  double lens_thickness_mm = 4.0;
  double pupil_diameter_mm = 7.0;  // dilated for surgery
  double iris_depth_mm = 0.5;      // iris plane behind the inner limbus
  int ciliary_processes = 40;      // as in the thesis (ch. 2.2)
  double ciliary_process_height_mm = 0.8;
  // Resolution of the physical surfaces.
  int retina_vertices = 20000;
  int gel_shells = 2;                 // nested vitreous shells (0 = no gel)
  double gel_vertex_ratio = 0.1;      // gel vertices per shell, relative to the retina
  double gel_shell_spacing_mm = 2.5;  // inset of each deeper shell
  double vitreous_base_mm = 2.0;      // band posterior to the ora where the gel is anchored

  // Throws InvalidArgument naming the first value out of range.
  void validate() const;
};

// A static mesh for the renderer. uv (one per vertex) index the named texture (empty: base colour).
struct RenderMesh {
  std::string name;
  TriangleMesh mesh;
  std::vector<Vec2> uv;
  std::array<float, 4> base_rgba{1.0f, 1.0f, 1.0f, 1.0f};
  std::string texture;  // "choroid", "retina" or empty
};

struct SclerotomyPort {
  std::string name;        // "infusion", "working_1", "working_2"
  Vec3 outer_mm;           // entry on the outer sclera
  Vec3 inner_mm;           // exit on the inner wall
  Vec3 axis;               // unit, from outer to the globe centre (the cannula's natural axis)
};

// The eye built from parameters: profiles, landmarks, static meshes and the meshes of the physical
// surfaces (before they become tissue).
struct EyeModel {
  EyeParameters parameters;
  std::vector<ProfilePoint> outer_profile;  // outer sclera + cornea, posterior pole → corneal apex
  std::vector<ProfilePoint> wall_profile;   // choroid inner surface + inner cornea, pole → pole
  GlobeWall wall;

  // Derived dimensions (mm).
  double posterior_pole_z_mm = 0.0;  // outer sclera
  double cornea_apex_z_mm = 0.0;
  double limbus_z_mm = 0.0;
  double limbus_radius_mm = 0.0;
  double ora_polar_rad = 0.0;        // polar angle of the ora serrata from the posterior pole (−z)
  double fundus_extent_mm = 0.0;     // arc length along the wall from the posterior pole to the ora
  double lens_center_z_mm = 0.0;
  double iris_z_mm = 0.0;
  Vec3 fovea_mm = Vec3::Zero();
  Vec3 optic_disc_mm = Vec3::Zero();
  Vec2 optic_disc_fundus_mm = Vec2::Zero();  // in the fundus plane

  std::vector<SclerotomyPort> ports;
  std::vector<RenderMesh> static_meshes;  // sclera, choroid, cornea, iris, lens, ciliary_processes

  // Physical surfaces, not yet tissue: the retina from the pole to the ora serrata and the vitreous
  // shells (one mesh, shell after shell, outermost first). surface_coords = (arc length, azimuth).
  TriangleMesh retina_mesh;
  TriangleMesh gel_mesh;
  std::vector<std::uint32_t> gel_shell_of_vertex;

  // Wall point at polar angle theta from the posterior pole (−z), azimuth phi.
  Vec3 wall_point(double theta_rad, double phi_rad) const;
  // Fundus plane coordinates (mm) of a direction from the globe centre.
  Vec2 fundus_coords(const Vec3& p) const;
  // Texture coordinates in the fundus textures.
  Vec2 fundus_uv(const Vec2& fundus_mm) const;
  // Polar angle from the posterior pole at which the wall's arc length from the pole is s.
  double polar_at_arc(double s_mm) const;
  double arc_at_polar(double theta_rad) const;
  const RenderMesh* find_static(const std::string& name) const;

 private:
  friend EyeModel build_eye_model(const EyeParameters&);
  std::vector<double> arc_table_;  // arc length at polar angle i·π/(n−1) from the posterior pole
};

// Builds the eye. Throws InvalidArgument on out-of-range parameters.
EyeModel build_eye_model(const EyeParameters& parameters);

}  // namespace vitreo::core
