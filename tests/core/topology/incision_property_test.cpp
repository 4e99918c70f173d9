// Property test of issue 14 item 3: the same path cut in 1 sweep or in 1000 (down to 1 µm each) —
// straight, curved, closed or self-crossing, through vertices or along springs, on regular and
// jittered sheets — gives, once the path is complete, the same topology and a boundary within 10 %
// of the local mean spring length of the path.
//
// Each random path is checked against references independent of the cutter:
//  - the components and boundary loops of the sheet cut along the path, from a raster of it with
//    the path drawn in as a wall (mesh_topology.hpp), so a path whose loop did not close, or that
//    left separate slits, fails even when every subdivision agrees;
//  - the mesh's own topology computed from its corner lists alone (not from the surface's springs,
//    fans or edge–triangle links), with the Euler characteristic of planar pieces (χ = 2C − B);
//  - the new boundary's Hausdorff distance to the path, in the rest shape.
// Each path is cut three ways: one sweep per polyline segment, a random number of sweeps up to 1000
// at random places, and 1000 sweeps with a burst of 1 µm ones. After every sweep the mesh passes
// check_surface with the quality floor and the mass is exact.
// Default: 8 paths per sheet (fixed seeds); VITREO_LONG_TESTS=1: 80.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "core/tissue/surface_validity.hpp"
#include "core/topology/geometry.hpp"
#include "core/topology/incision.hpp"
#include "mesh_topology.hpp"
#include "topology_test_util.hpp"

using namespace vitreo::core;
using namespace vitreo::core::test;

namespace {

constexpr double kW = kSheetW, kH = kSheetH, kCell = kSheetCell;
constexpr double kPi = std::numbers::pi;

struct Path {
  std::string kind;
  std::vector<Vec3> points;   // the polyline the blade's point follows (z = 0)
  Vec3 tilt = Vec3::UnitZ();  // the blade's direction (through the sheet)
};

std::vector<Vec3> sample(const std::function<Vec3(double)>& f, double t0, double t1, int n) {
  std::vector<Vec3> p;
  for (int i = 0; i <= n; ++i) p.push_back(f(t0 + (t1 - t0) * i / n));
  return p;
}

// Random paths of each kind. `regular`: the sheet is the unjittered grid, so paths along its
// springs and through its vertices are possible.
Path random_path(std::mt19937& rng, int kind, bool regular) {
  auto u = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  Path p;
  p.tilt = Vec3(u(-0.4, 0.4), u(-0.4, 0.4), 1.0);
  switch (kind) {
    case 0: {  // an arc, in or across the sheet
      p.kind = "arc";
      const Vec3 c(u(-0.5, kW + 0.5), u(-0.5, kH + 0.5), 0.0);
      const double r = u(0.6, 2.5), a0 = u(0.0, 2 * kPi), span = u(0.6, 2.6) * (u(0, 1) < 0.5 ? -1 : 1);
      p.points = sample([&](double a) { return Vec3(c + r * Vec3(std::cos(a), std::sin(a), 0.0)); }, a0, a0 + span,
                        static_cast<int>(std::abs(span) * r / 0.04) + 2);
      break;
    }
    case 1: {  // a closed circle: the disc comes out
      p.kind = "circle";
      const double r = u(0.45, 1.0);
      const Vec3 c(u(r + 0.35, kW - r - 0.35), u(r + 0.35, kH - r - 0.35), 0.0);
      const double a0 = u(0.0, 2 * kPi);
      p.points = sample([&](double a) { return Vec3(c + r * Vec3(std::cos(a), std::sin(a), 0.0)); }, a0, a0 + 2 * kPi,
                        static_cast<int>(2 * kPi * r / 0.04));
      p.points.back() = p.points.front();
      break;
    }
    case 2: {  // a wave across the sheet or inside it
      p.kind = "wave";
      const double amp = u(0.08, 0.4), wl = u(1.0, 3.0), phase = u(0, 2 * kPi), y0 = u(0.7, kH - 0.7);
      const bool across = u(0, 1) < 0.5;
      const double x0 = across ? -0.4 : u(0.4, 1.4), x1 = across ? kW + 0.4 : u(kW - 1.4, kW - 0.4);
      p.points = sample([&](double x) { return Vec3(x, y0 + amp * std::sin(2 * kPi * x / wl + phase), 0.0); }, x0, x1,
                        static_cast<int>((x1 - x0) / 0.04));
      break;
    }
    case 3: {  // a figure of eight: crosses itself, two pieces come out
      p.kind = "figure-eight";
      const double a = u(0.7, 1.3), b = a * u(0.8, 1.6);
      const Vec3 c(u(a + 0.4, kW - a - 0.4), u(0.25 * b + 0.5, kH - 0.25 * b - 0.5), 0.0);
      p.points = sample([&](double t) { return Vec3(c + Vec3(a * std::sin(t), 0.5 * b * std::sin(t) * std::cos(t), 0.0)); }, 0.0,
                        2 * kPi, 160);
      p.points.back() = p.points.front();
      break;
    }
    case 4: {  // a curl: a loop that crosses itself at right angles, its two branches running on
      // The nodal cubic (t² − 1, t (t² − 1)): the loop is t ∈ [−1, 1], the crossing at the origin.
      p.kind = "curl";
      const double scale = u(0.5, 0.9), t1 = u(1.35, 1.9), turn = u(0, 2 * kPi);
      const Vec3 c(u(1.0, kW - 1.0), u(1.0, kH - 1.0), 0.0);
      const Vec3 ex(std::cos(turn), std::sin(turn), 0.0), ey(-std::sin(turn), std::cos(turn), 0.0);
      p.points = sample([&](double t) { return Vec3(c + scale * ((t * t - 1.0) * ex + t * (t * t - 1.0) * ey)); }, -t1, t1, 160);
      break;
    }
    default: {  // straight: along springs or through vertices on the regular grid, anywhere otherwise
      if (regular && u(0, 1) < 0.7) {
        const bool along = u(0, 1) < 0.5;
        p.kind = along ? "along springs" : "through vertices";
        p.tilt = Vec3::UnitZ();
        if (along) {  // a grid row, from outside or from a vertex inside
          const double y = kCell * std::uniform_int_distribution<int>(2, kSheetRows - 2)(rng);
          const double x0 = u(0, 1) < 0.5 ? -0.3 : kCell * std::uniform_int_distribution<int>(2, 5)(rng);
          const double x1 = u(0, 1) < 0.5 ? kW + 0.3 : kCell * std::uniform_int_distribution<int>(kSheetCols - 5, kSheetCols - 2)(rng);
          p.points = {Vec3(x0, y, 0.0), Vec3(x1, y, 0.0)};
        } else {  // a diagonal through grid vertices (i, i + k)
          const int k = std::uniform_int_distribution<int>(-4, 6)(rng);
          p.points = {Vec3(-0.3, kCell * k - 0.3, 0.0), Vec3(kW + 0.3, kCell * k + kW + 0.3, 0.0)};
        }
      } else {
        p.kind = "straight";
        const double a = u(0, kPi);
        const Vec3 c(u(1.0, kW - 1.0), u(0.8, kH - 0.8), 0.0), d(std::cos(a), std::sin(a), 0.0);
        const double l0 = u(0.5, 3.0), l1 = u(0.5, 3.0);
        p.points = {c - l0 * d, c + l1 * d};
      }
      break;
    }
  }
  return p;
}

double arc_length(const std::vector<Vec3>& pts) {
  double l = 0.0;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) l += (pts[i + 1] - pts[i]).norm();
  return l;
}

bool inside_sheet(const Vec3& x, double margin = 0.0) {
  return x.x() > margin && x.y() > margin && x.x() < kW - margin && x.y() < kH - margin;
}
double distance_to_border(const Vec3& x) { return std::min({x.x(), x.y(), kW - x.x(), kH - x.y()}); }

// Whether a path is one the mesh can follow at this resolution: its ends well inside the sheet or
// well outside it, crossing the sheet's border steeply, away from itself except where it crosses
// itself (steeply), and leaving no piece of sheet smaller than two cells.
bool acceptable(const Path& p, RasterCut& reference, std::string& why) {
  const auto& pts = p.points;
  if (std::none_of(pts.begin(), pts.end(), [](const Vec3& x) { return inside_sheet(x, 0.3); })) {
    why = "misses the sheet";
    return false;
  }
  for (const Vec3& e : {pts.front(), pts.back()}) {
    if (inside_sheet(e) ? distance_to_border(e) < 0.3 : inside_sheet(e, -0.15)) {
      why = "an end near the border";
      return false;
    }
  }
  // Fine samples with their arc length.
  std::vector<Vec3> s;
  std::vector<double> at;
  double len = 0.0;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const double l = (pts[i + 1] - pts[i]).norm();
    const int n = std::max(1, static_cast<int>(l / 0.02));
    for (int k = 0; k < n; ++k) {
      s.push_back(pts[i] + (k / static_cast<double>(n)) * (pts[i + 1] - pts[i]));
      at.push_back(len + l * k / n);
    }
    len += l;
  }
  s.push_back(pts.back());
  at.push_back(len);
  const bool closed = (pts.front() - pts.back()).norm() < 1e-12;
  // Self-crossings: steep, and elsewhere the path keeps away from itself.
  std::vector<double> crossings;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    for (std::size_t j = i + 2; j + 1 < pts.size(); ++j) {
      if (closed && i == 0 && j + 2 == pts.size()) continue;
      const Vec3 a = pts[i], b = pts[i + 1], c = pts[j], d = pts[j + 1];
      const Vec3 r = b - a, q = d - c;
      const double den = r.x() * q.y() - r.y() * q.x();
      if (std::abs(den) < 1e-15) continue;
      const double t = ((c - a).x() * q.y() - (c - a).y() * q.x()) / den, v = ((c - a).x() * r.y() - (c - a).y() * r.x()) / den;
      if (t < 0 || t > 1 || v < 0 || v > 1) continue;
      const double sin_angle = std::abs(den) / (r.norm() * q.norm());
      if (sin_angle < std::sin(35.0 * kPi / 180.0)) {
        why = "a shallow self-crossing";
        return false;
      }
      const Vec3 x = a + t * r;
      if (inside_sheet(x) && distance_to_border(x) < 0.3) {
        why = "a self-crossing near the border";
        return false;
      }
      // Arc positions of both branches.
      double li = 0.0, lj = 0.0;
      for (std::size_t k = 0; k < i; ++k) li += (pts[k + 1] - pts[k]).norm();
      for (std::size_t k = 0; k < j; ++k) lj += (pts[k + 1] - pts[k]).norm();
      crossings.push_back(li + t * r.norm());
      crossings.push_back(lj + v * q.norm());
    }
  }
  auto near_crossing = [&](double l) {
    for (double c : crossings) {
      if (std::abs(l - c) < 0.2) return true;
    }
    return false;
  };
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!inside_sheet(s[i], -0.05)) continue;
    for (std::size_t j = i + 1; j < s.size(); ++j) {
      double along = at[j] - at[i];
      if (closed) along = std::min(along, len - along);
      if (along < 0.35 || near_crossing(at[i]) || near_crossing(at[j])) continue;
      if ((s[i] - s[j]).norm() < 0.15) {
        why = "the path comes close to itself";
        return false;
      }
    }
  }
  // Crossing the border steeply, and running along it nowhere.
  for (std::size_t i = 0; i + 1 < s.size(); ++i) {
    const bool in0 = inside_sheet(s[i]), in1 = inside_sheet(s[i + 1]);
    const Vec3 d = (s[i + 1] - s[i]).normalized();
    if (in0 != in1) {
      const Vec3 x = in0 ? s[i] : s[i + 1];
      const bool vertical_border = std::min(x.x(), kW - x.x()) < std::min(x.y(), kH - x.y());
      const double steep = vertical_border ? std::abs(d.x()) : std::abs(d.y());
      if (steep < std::sin(30.0 * kPi / 180.0)) {
        why = "a shallow crossing of the border";
        return false;
      }
      if (std::min(x.x(), kW - x.x()) < 0.3 && std::min(x.y(), kH - x.y()) < 0.3) {
        why = "crosses the border near a corner";
        return false;
      }
    } else if (in0 && distance_to_border(s[i]) < 0.12) {
      // Inside and near the border: only right where it crosses it.
      bool crossing_near = false;
      for (std::size_t k = (i > 10 ? i - 10 : 0); k < std::min(s.size() - 1, i + 10); ++k) {
        crossing_near = crossing_near || inside_sheet(s[k]) != inside_sheet(s[k + 1]);
      }
      if (!crossing_near) {
        why = "runs along the border";
        return false;
      }
    }
  }
  reference = raster_cut(kW, kH, {pts}, kCell / 16.0, 1.6 * kCell / 16.0, 2.0 * kCell * kCell);
  if (reference.tiny_regions > 0) {
    why = "leaves a piece smaller than two cells";
    return false;
  }
  return true;
}

// Where the sweeps end, as points along the path: every polyline vertex, and `extra` more.
enum class Split { kPerSegment, kRandom, kBurst };
std::vector<Vec3> subdivide(const std::vector<Vec3>& pts, Split how, std::mt19937& rng) {
  std::vector<double> cum{0.0};
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) cum.push_back(cum.back() + (pts[i + 1] - pts[i]).norm());
  const double len = cum.back();
  std::vector<double> at(cum.begin(), cum.end());
  auto u = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const auto segments = static_cast<int>(pts.size()) - 1;
  if (how == Split::kRandom) {
    const int n = std::uniform_int_distribution<int>(segments, 1000)(rng) - segments;
    for (int k = 0; k < n; ++k) at.push_back(u(0.0, len));
  } else if (how == Split::kBurst) {
    // 1000 sweeps: 300 of 1 µm somewhere along the path, the rest at random.
    const double start = u(0.0, std::max(0.0, len - 0.3));
    for (int k = 0; k < 300; ++k) at.push_back(start + 1e-3 * k);
    for (int k = 0; k < 700 - segments; ++k) at.push_back(u(0.0, len));
  }
  std::sort(at.begin(), at.end());
  // Sweeps of at least 1 µm (closer points merge into one); the polyline's vertices stay.
  std::vector<double> kept;
  for (double a : at) {
    if (a < 0.0 || a > len) continue;
    const bool vertex = std::binary_search(cum.begin(), cum.end(), a);
    if (!kept.empty() && a - kept.back() < 1e-3 - 1e-12) {
      if (!vertex) continue;
      kept.back() = a;
      continue;
    }
    kept.push_back(a);
  }
  std::vector<Vec3> out;
  std::size_t seg = 0;
  for (double a : kept) {
    while (seg + 2 < cum.size() && cum[seg + 1] < a) ++seg;
    const double l = cum[seg + 1] - cum[seg];
    const double f = l > 0.0 ? std::clamp((a - cum[seg]) / l, 0.0, 1.0) : 0.0;
    out.push_back(pts[seg] + f * (pts[seg + 1] - pts[seg]));
  }
  return out;
}

// Mean rest length of the original springs near the path (both ends within 1.5 cells of it).
double local_mean_spring(const Surface& s, const std::vector<Vec3>& path) {
  double sum = 0.0;
  int n = 0;
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    if (!s.edge_alive(e)) continue;
    const auto [a, b] = s.edge_vertices(e);
    if (distance_point_polyline(s.rest_position(a), path) > 1.5 * kCell ||
        distance_point_polyline(s.rest_position(b), path) > 1.5 * kCell) {
      continue;
    }
    sum += s.edge_rest_length(e);
    ++n;
  }
  return n > 0 ? sum / n : kCell;
}

// Hausdorff distance between the new boundary and the part of the path on the sheet (rest shape).
double boundary_distance(const Surface& s, const std::vector<Vec3>& path) {
  const auto boundary = new_boundary(s, kW, kH);
  if (boundary.empty()) return INFINITY;
  double d = 0.0;
  for (const auto& seg : boundary) {
    for (double f : {0.0, 0.25, 0.5, 0.75, 1.0}) d = std::max(d, distance_point_polyline(seg.a + f * (seg.b - seg.a), path));
  }
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    for (int k = 0; k <= 10; ++k) {
      const Vec3 p = path[i] + (k / 10.0) * (path[i + 1] - path[i]);
      if (!inside_sheet(p, 1e-9)) continue;
      d = std::max(d, distance_point_segments(p, boundary));
    }
  }
  return d;
}

struct Outcome {
  CornerTopology topology;
  double boundary_mm = 0.0;
  std::uint32_t gaps = 0, sweeps = 0;
  std::string problem;  // the first invalid mesh or inexact mass met, if any
};

Outcome cut(const SurfaceDescription& d, const Path& path, const std::vector<Vec3>& stops) {
  Surface s(d);
  Cutter cutter(s);
  Incision incision(cutter);
  const double mass0 = s.total_mass();
  const ValidityLimits limits = quality_limits();
  Outcome o;
  const Vec3 half = 0.5 * path.tilt;
  auto check = [&](const CutResult& r, std::size_t i) {
    if (!o.problem.empty()) return;
    std::ostringstream ss;
    if (!r.status) ss << "sweep " << i << " refused: " << r.status.message();
    const auto report = check_surface(s, limits);
    if (!report.ok()) ss << "after sweep " << i << ": " << report.summary();
    const double removed = cutter.cleanup_removed_mass_g();
    if (std::abs(s.total_mass() - (mass0 - removed)) > 1e-9 * mass0) ss << "mass not exact after sweep " << i;
    o.problem = ss.str();
  };
  for (std::size_t i = 0; i < stops.size(); ++i) {
    const CutResult r = incision.advance({stops[i] - half, stops[i] + half});
    o.gaps += r.gaps;
    check(r, i);
  }
  const CutResult r = incision.end();
  o.gaps += r.gaps;
  check(r, stops.size());
  o.sweeps = static_cast<std::uint32_t>(stops.size() - 1);
  o.topology = corner_topology(s);
  o.boundary_mm = boundary_distance(s, path.points);
  return o;
}

void run_paths(bool jittered, int paths, unsigned seed) {
  const SurfaceDescription d = sheet(kW, kH, kSheetCols, kSheetRows, jittered ? 0.3 : 0.0, seed);
  const Surface original(d);
  std::mt19937 rng(seed);
  int done = 0, tries = 0;
  while (done < paths && tries < 50 * paths) {
    ++tries;
    const int kind = done % 6;
    const Path path = random_path(rng, kind, !jittered);
    RasterCut reference;
    std::string why;
    if (!acceptable(path, reference, why)) continue;
    ++done;
    const double tolerance = 0.1 * local_mean_spring(original, path.points);
    std::ostringstream what;
    what << (jittered ? "jittered" : "regular") << " sheet, path " << done << " (" << path.kind << ", "
         << path.points.size() << " points, length " << arc_length(path.points) << " mm; raster: " << reference.components
         << " components, " << reference.boundary_loops << " loops)";
    std::mt19937 split_rng(seed * 7919u + static_cast<unsigned>(done));
    for (const Split how : {Split::kPerSegment, Split::kRandom, Split::kBurst}) {
      const Outcome o = cut(d, path, subdivide(path.points, how, split_rng));
      SCOPED_TRACE(what.str() + ", " + std::to_string(o.sweeps) + " sweeps");
      EXPECT_TRUE(o.problem.empty()) << o.problem;
      EXPECT_TRUE(o.topology.ok()) << o.topology.describe();
      EXPECT_EQ(o.gaps, 0u);
      EXPECT_EQ(o.topology.components, reference.components) << o.topology.describe();
      EXPECT_EQ(o.topology.boundary_loops, reference.boundary_loops) << o.topology.describe();
      EXPECT_EQ(o.topology.euler, 2 * static_cast<std::int64_t>(o.topology.components) - o.topology.boundary_loops)
          << "every piece of a cut plane sheet is a disc with holes: " << o.topology.describe();
      EXPECT_LE(o.boundary_mm, tolerance) << "new boundary farther from the path than 10 % of the local spring length";
    }
  }
  EXPECT_EQ(done, paths) << "could not draw enough acceptable paths";
}

}  // namespace

TEST(IncisionProperty, RandomPathsOnARegularSheetPartItTheSameWayInAnyNumberOfSweeps) {
  run_paths(false, long_tests() ? 80 : 8, 2024);
}

TEST(IncisionProperty, RandomPathsOnAJitteredSheetPartItTheSameWayInAnyNumberOfSweeps) {
  run_paths(true, long_tests() ? 80 : 8, 7);
}
