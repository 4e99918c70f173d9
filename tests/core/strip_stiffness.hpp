#pragma once
// The retina's effective stretch stiffness as the solver delivers it (issue 14's definition):
// a strip cut from the retina's own mesh, one end clamped, the other pulled by a known traction
// for a 1 % strain, read once settled, against plane-stress linear elasticity (traction / strain
// = the material's membrane modulus E·t). Shared by the accuracy test, which holds it within 5 %
// at the rig's settings, and the solver benchmark, which reports it as a counter beside the step
// time so speed can never be bought with softness.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/geometry/triangle_mesh.hpp"
#include "core/tissue/material.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::test {

// A wall too far to touch, and an environment without gravity or pressure: tissue alone.
core::GlobeWall far_wall();
core::Environment weightless();

// The retina of the solver benchmark (core/anatomy/retina_cap: a revolved sphere cap, R 12 mm) at
// the given resolution; the triangles within a band around its equator, W wide across the rings
// and L long around the axis, laid flat (x along the azimuth, y across the rings). Near the
// equator the rings barely change radius, so the triangles keep their shape.
core::TriangleMesh retina_strip(int retina_vertices, double width_mm, double length_mm);

// The strip's load case, whatever solver carries it: the vertices clamped (within 0.3 of the longest
// edge of the left end), those pulled (the same at the right end, sorted across the strip) with the
// force each takes (σ × its share of the width, µN, along +x), and where the strain is read.
struct StripLoad {
  std::vector<std::uint32_t> clamped, pulled;
  std::vector<double> force_un;
  double x0 = 0.0, x1 = 0.0, width = 0.0, y_mid = 0.0, longest_edge = 0.0;
};
StripLoad strip_load(const core::TriangleMesh& mesh, double sigma);
// The strain between the material lines at a third and two thirds of the strip's length (mean x of
// the vertices within 0.6 edge of each), from the solver's positions of the mesh's vertices.
double strip_strain(const core::TriangleMesh& mesh, const StripLoad& load, const std::function<core::Vec3(std::uint32_t)>& position);

struct StripResult {
  double modulus = 0.0;        // traction / strain, µN/mm
  double settle_s = 0.0;       // simulated time until every vertex slept (the cap when it never did)
  std::size_t vertices = 0;
  bool steps_ok = true;        // every step succeeded
  bool clamped = true;         // every clamped vertex could be fixed
  double applied_force_un = 0.0;  // the traction's total, σ × width (checked by the caller)
  double expected_force_un = 0.0;
};

// Clamps the strip's left end, pulls its right end with a traction σ = strain_target × E·t spread
// along the end by each vertex's share of the width (a local force toward a far point), and
// measures the strain between material lines at a third and two thirds of the length once the
// tissue has come to rest (at most max_settle_s), with the given solver settings at dt = 1 ms.
StripResult stretch_strip(const core::TriangleMesh& mesh, const core::TissueMaterial& material, double strain_target,
                          const core::SolverSettings& settings = {}, double max_settle_s = 10.0);

// stretch_strip's modulus over the nominal one, minus 1 (−0.1: 10 % too soft).
double strip_stiffness_error(int retina_vertices, const core::SolverSettings& settings = {});

}  // namespace vitreo::test
