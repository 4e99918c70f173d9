#include "mesh_topology.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "core/topology/geometry.hpp"

namespace vitreo::core::test {

std::string CornerTopology::describe() const {
  std::ostringstream ss;
  ss << "V " << vertices << " E " << edges << " F " << triangles << " χ " << euler << ", " << components << " components, "
     << boundary_loops << " boundary loops";
  for (const auto& p : problems) ss << "; " << p;
  return ss.str();
}

CornerTopology corner_topology(const Surface& s) {
  CornerTopology r;
  std::vector<std::array<std::uint32_t, 3>> tris;
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (s.triangle_alive(t)) tris.push_back(s.triangle_vertices(t));
  }
  r.triangles = static_cast<std::uint32_t>(tris.size());
  std::unordered_set<std::uint32_t> verts;
  struct EdgeUse {
    std::uint32_t uses = 0;
    std::uint32_t forward = 0;  // uses as low → high
    std::uint32_t first_triangle = 0;
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  std::vector<std::uint32_t> parent(tris.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b); };
  for (std::uint32_t i = 0; i < tris.size(); ++i) {
    const auto& c = tris[i];
    if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0]) r.problems.push_back("degenerate triangle (repeated corner)");
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = c[static_cast<std::size_t>(k)], b = c[static_cast<std::size_t>((k + 1) % 3)];
      verts.insert(a);
      EdgeUse& u = edges[key(a, b)];
      if (u.uses == 0) {
        u.first_triangle = i;
      } else {
        parent[find(i)] = find(u.first_triangle);
      }
      ++u.uses;
      if (a < b) ++u.forward;
    }
  }
  r.vertices = static_cast<std::uint32_t>(verts.size());
  r.edges = static_cast<std::uint32_t>(edges.size());
  r.euler = static_cast<std::int64_t>(r.vertices) - static_cast<std::int64_t>(r.edges) + static_cast<std::int64_t>(r.triangles);
  for (std::uint32_t i = 0; i < tris.size(); ++i) r.components += find(i) == i ? 1u : 0u;
  // Boundary edges in the direction their triangle runs them; a manifold boundary gives every
  // boundary vertex exactly one outgoing and one incoming boundary edge.
  std::unordered_map<std::uint32_t, std::uint32_t> next;
  for (const auto& c : tris) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = c[static_cast<std::size_t>(k)], b = c[static_cast<std::size_t>((k + 1) % 3)];
      const EdgeUse& u = edges[key(a, b)];
      if (u.uses > 2) {
        r.problems.push_back("edge used by more than two triangles");
        continue;
      }
      if (u.uses == 2 && (u.forward == 2 || u.forward == 0)) {
        r.problems.push_back("two triangles run an edge in the same direction");
        continue;
      }
      if (u.uses != 1) continue;
      if (!next.emplace(a, b).second) r.problems.push_back("boundary vertex with two outgoing boundary edges (bow-tie)");
    }
  }
  std::unordered_set<std::uint32_t> seen;
  for (const auto& [start, unused] : next) {
    if (seen.count(start)) continue;
    ++r.boundary_loops;
    std::uint32_t v = start;
    for (std::size_t guard = 0; guard <= next.size() && !seen.count(v); ++guard) {
      seen.insert(v);
      const auto it = next.find(v);
      if (it == next.end()) {
        r.problems.push_back("boundary does not close into a loop");
        break;
      }
      v = it->second;
    }
  }
  std::sort(r.problems.begin(), r.problems.end());
  r.problems.erase(std::unique(r.problems.begin(), r.problems.end()), r.problems.end());
  return r;
}

RasterCut raster_cut(double w, double h, const std::vector<std::vector<Vec3>>& paths, double px, double wall_mm,
                     double min_region_mm2) {
  constexpr int kPad = 2;
  const int nx = static_cast<int>(std::ceil(w / px)), ny = static_cast<int>(std::ceil(h / px));
  const int gx = nx + 2 * kPad, gy = ny + 2 * kPad;
  enum : std::uint8_t { kOutside = 0, kSheet = 1, kWall = 2 };
  std::vector<std::uint8_t> cell(static_cast<std::size_t>(gx) * gy, kOutside);
  auto at = [&](int i, int j) { return static_cast<std::size_t>(j) * gx + i; };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Vec3 c((i + 0.5) * px, (j + 0.5) * px, 0.0);
      bool wall = false;
      for (const auto& path : paths) {
        for (std::size_t k = 0; k + 1 < path.size() && !wall; ++k) {
          const Vec3 a(path[k].x(), path[k].y(), 0.0), b(path[k + 1].x(), path[k + 1].y(), 0.0);
          wall = topology::distance_to_segment(c, a, b) <= 0.5 * wall_mm;
        }
      }
      cell[at(i + kPad, j + kPad)] = wall ? kWall : kSheet;
    }
  }
  // Regions: 4-connected sheet pixels.
  std::vector<int> region(cell.size(), -1);
  std::vector<std::size_t> stack;
  std::vector<std::size_t> region_size;
  for (int j = 0; j < gy; ++j) {
    for (int i = 0; i < gx; ++i) {
      if (cell[at(i, j)] != kSheet || region[at(i, j)] >= 0) continue;
      const int id = static_cast<int>(region_size.size());
      region_size.push_back(0);
      stack.assign(1, at(i, j));
      region[at(i, j)] = id;
      while (!stack.empty()) {
        const std::size_t p = stack.back();
        stack.pop_back();
        ++region_size.back();
        const int pi = static_cast<int>(p % gx), pj = static_cast<int>(p / gx);
        const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
        for (int k = 0; k < 4; ++k) {
          const int qi = pi + di[k], qj = pj + dj[k];
          if (qi < 0 || qj < 0 || qi >= gx || qj >= gy) continue;
          const std::size_t q = at(qi, qj);
          if (cell[q] == kSheet && region[q] < 0) {
            region[q] = id;
            stack.push_back(q);
          }
        }
      }
    }
  }
  RasterCut r;
  r.smallest_region_mm2 = INFINITY;
  std::vector<std::uint8_t> mark(cell.size());
  for (std::size_t id = 0; id < region_size.size(); ++id) {
    const double area = static_cast<double>(region_size[id]) * px * px;
    if (area < min_region_mm2) {
      ++r.tiny_regions;
      continue;
    }
    ++r.components;
    r.smallest_region_mm2 = std::min(r.smallest_region_mm2, area);
    // Boundary loops: 8-connected pieces of everything that is not this region.
    std::fill(mark.begin(), mark.end(), 0);
    for (std::size_t p0 = 0; p0 < cell.size(); ++p0) {
      if (region[p0] == static_cast<int>(id) || mark[p0]) continue;
      ++r.boundary_loops;
      stack.assign(1, p0);
      mark[p0] = 1;
      while (!stack.empty()) {
        const std::size_t p = stack.back();
        stack.pop_back();
        const int pi = static_cast<int>(p % gx), pj = static_cast<int>(p / gx);
        for (int dj = -1; dj <= 1; ++dj) {
          for (int di = -1; di <= 1; ++di) {
            const int qi = pi + di, qj = pj + dj;
            if ((di == 0 && dj == 0) || qi < 0 || qj < 0 || qi >= gx || qj >= gy) continue;
            const std::size_t q = at(qi, qj);
            if (region[q] == static_cast<int>(id) || mark[q]) continue;
            mark[q] = 1;
            stack.push_back(q);
          }
        }
      }
    }
  }
  return r;
}

}  // namespace vitreo::core::test
