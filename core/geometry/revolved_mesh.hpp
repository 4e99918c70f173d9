#pragma once
// Surfaces of revolution about the z axis, triangulated with near-equilateral triangles.
//
// The thesis built its eye by sweeping anatomical cross-sections around the optical axis (ch. 2.2).
// We do the same, but triangulate directly: rings are spaced by a target edge length along the
// profile, and each ring gets as many vertices as its circumference needs, so triangles stay close to
// equilateral from the pole to the equator. That keeps spring stiffness (derived from triangle areas)
// and mass (from vertex areas) uniform, and keeps vertices in ring order, which is also a good memory
// order for the solver.
#include <vector>

#include "core/geometry/triangle_mesh.hpp"

namespace vitreo::core {

// A point of a meridional profile: z along the axis, rho the distance from it (rho >= 0).
struct ProfilePoint {
  double z_mm;
  double rho_mm;
};

struct RevolveOptions {
  double target_edge_mm = 0.5;
  // Sweep angle in radians; 2π for a closed surface of revolution.
  double sweep_rad = 6.283185307179586;
};

// Revolves the polyline `profile` about z. A profile end on the axis (rho == 0) becomes a single
// pole vertex. Triangle normals point to the right of the direction of travel in the (z, rho) plane:
// outward for a profile running from a -z pole toward +z. surface_coords = (arc length mm, azimuth rad).
// Throws InvalidArgument on a profile with fewer than two points, negative or non-finite values, or
// a non-positive edge length.
TriangleMesh revolve_profile(const std::vector<ProfilePoint>& profile, const RevolveOptions& options);

// Profile of a sphere arc of radius r centred at the origin, from polar angle theta0 to theta1
// (measured from -z, so theta 0 is the pole at z = -r), with `segments` straight pieces.
std::vector<ProfilePoint> sphere_arc_profile(double radius_mm, double theta0_rad, double theta1_rad, int segments);

// Target edge length that gives a revolved sphere cap of this radius and polar extent about
// `vertex_count` vertices.
double edge_length_for_vertex_count(double radius_mm, double theta1_rad, int vertex_count);

}  // namespace vitreo::core
