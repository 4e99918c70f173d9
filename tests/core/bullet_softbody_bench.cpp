// Bullet's btSoftBody (Debian libbullet-dev, double precision) on the solver benchmark's own mesh, in
// the same binary as BM_TissueStep so that one run measures both (issue 14: "the ratio to Bullet's
// btSoftBody on the same mesh at equal stiffness error, measured in one run").
//
// The same mesh: the 20k retina cap of build_retina_cap (retina + epiretinal membrane, the same
// vertices, masses and anchored border), every spring a Bullet link, every membrane attachment a
// zero-length link to its retina vertex, the detachment's breathing pressure as per-node forces
// (pressure × vertex area × weight toward its point, ±10 % at 1 Hz, as BM_TissueStep's working load),
// gravity as vitreo's. Units as vitreo's (mm, g, s: forces in µN). The same substeps (2 per 1 ms step:
// predictMotion / solveConstraints / integrateMotion at 0.5 ms). Not modelled for Bullet, and so not
// paid for: the globe wall's contact, the intraocular pressure, tearing, bending, sleeping — Bullet's
// figure is a lower bound of what it would cost to do vitreo's job.
//
// At equal stiffness error: Bullet's links are position constraints with a stiffness share kLST in
// (0, 1], not a modulus. For each number of position iterations the benchmark finds (bisection) the
// kLST at which a strip cut from the same retina (strip_stiffness.hpp: clamped, pulled by the traction
// for 1 % strain, read once settled) stretches as vitreo's solver stretches it at the rig's settings,
// and times the 20k step with it; the counters say which kLST that was and the strip's error Bullet
// then has, beside vitreo's.
#include <BulletSoftBody/btSoftBody.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "core/anatomy/retina_cap.hpp"
#include "strip_stiffness.hpp"

using namespace vitreo::core;

namespace {

constexpr double kDt = 1e-3;
constexpr int kSubsteps = 2;  // the rig's

btVector3 bt(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }

// One Bullet soft body and what it needs to live (its world info is referenced, not copied).
struct BulletBody {
  std::unique_ptr<btSoftBodyWorldInfo> info = std::make_unique<btSoftBodyWorldInfo>();
  std::unique_ptr<btSoftBody> body;
  btSoftBody::Material* material = nullptr;

  BulletBody(const std::vector<Vec3>& x, const std::vector<double>& mass, const Vec3& gravity) {
    info->air_density = 0;
    info->water_density = 0;
    info->m_gravity = bt(gravity);
    info->m_sparsesdf.Initialize();
    std::vector<btVector3> bx;
    std::vector<btScalar> bm;
    for (std::size_t i = 0; i < x.size(); ++i) bx.push_back(bt(x[i])), bm.push_back(mass[i]);
    body = std::make_unique<btSoftBody>(info.get(), static_cast<int>(x.size()), bx.data(), bm.data());
    material = body->appendMaterial();
    material->m_kLST = 1.0;
    material->m_kAST = 0.0;
    material->m_kVST = 0.0;
  }
  void link(int a, int b) { body->appendLink(a, b, material); }
  void configure(double klst, int piterations, double damping) {
    material->m_kLST = klst;
    body->m_cfg.piterations = piterations;
    body->m_cfg.viterations = 0;
    body->m_cfg.diterations = 0;
    body->m_cfg.kDP = damping;
    body->updateConstants();
  }
  // One 1 ms step in kSubsteps substeps; `force` adds each substep's external forces.
  template <class Forces>
  void step(Forces&& force) {
    for (int k = 0; k < kSubsteps; ++k) {
      force();
      body->predictMotion(kDt / kSubsteps);
      body->solveConstraints();
      body->integrateMotion();
    }
  }
};

// The strip of strip_stiffness.hpp (the same load case: strip_load, strip_strain) in Bullet, its
// masses lumped from the retina's density and thickness as vitreo's; read once settled (every node
// slower than 1 µm/s, or 10 s). Returns the modulus's error (−0.1: 10 % too soft).
double bullet_strip_error(int retina_vertices, double klst, int piterations) {
  const TissueMaterial retina;
  const TriangleMesh m = vitreo::test::retina_strip(retina_vertices, 2.0, 8.0);
  const double rho_area = retina.density_g_per_mm3 * retina.thickness_mm;
  std::vector<double> mass(m.positions.size(), 0.0);
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (const auto& t : m.triangles) {
    const double area = 0.5 * (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).norm();
    for (std::size_t k = 0; k < 3; ++k) {
      mass[t[k]] += rho_area * area / 3.0;
      edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
    }
  }
  const double sigma = 0.01 * retina.membrane_modulus_pa_mm;
  const vitreo::test::StripLoad load = vitreo::test::strip_load(m, sigma);
  for (const auto v : load.clamped) mass[v] = 0.0;  // clamped: Bullet's static node
  BulletBody b(m.positions, mass, Vec3::Zero());
  for (const auto& [a, c] : edges) b.link(static_cast<int>(a), static_cast<int>(c));
  b.configure(klst, piterations, 0.05);  // a little damping, so that the strip comes to rest (vitreo's settles under its drag)
  for (int i = 0; i < 10000; ++i) {
    b.step([&] {
      for (std::size_t k = 0; k < load.pulled.size(); ++k) b.body->addForce(btVector3(load.force_un[k], 0, 0), static_cast<int>(load.pulled[k]));
    });
    double vmax = 0.0;
    for (int n = 0; n < b.body->m_nodes.size(); ++n) vmax = std::max(vmax, static_cast<double>(b.body->m_nodes[n].m_v.length()));
    if (i > 100 && vmax < 1e-3) break;
  }
  const double strain = vitreo::test::strip_strain(m, load, [&](std::uint32_t v) {
    const btVector3& p = b.body->m_nodes[static_cast<int>(v)].m_x;
    return Vec3(p.x(), p.y(), p.z());
  });
  return (sigma / strain) / retina.membrane_modulus_pa_mm - 1.0;
}

// The kLST whose strip error is closest to `target` (the error grows with kLST: stiffer links).
std::pair<double, double> klst_for_error(int retina_vertices, double target, int piterations) {
  double lo = 1e-5, hi = 1.0;
  double e_hi = bullet_strip_error(retina_vertices, hi, piterations);
  if (e_hi < target) return {hi, e_hi};  // even rigid-as-it-gets links are softer than vitreo's
  double best = hi, best_e = e_hi;
  for (int i = 0; i < 14; ++i) {
    const double mid = std::sqrt(lo * hi);
    const double e = bullet_strip_error(retina_vertices, mid, piterations);
    if (std::abs(e - target) < std::abs(best_e - target)) best = mid, best_e = e;
    if (e > target) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return {best, best_e};
}

void BM_BulletSoftBodyStep(benchmark::State& state) {
  const int vertices_wanted = static_cast<int>(state.range(0));
  const int piterations = static_cast<int>(state.range(1));
  SolverSettings rig;  // vitreo's error at the rig's settings, the target
  const double vitreo_error = vitreo::test::strip_stiffness_error(vertices_wanted, rig);
  const auto [klst, bullet_error] = klst_for_error(vertices_wanted, vitreo_error, piterations);

  RetinaCapOptions o;
  o.retina_vertices = vertices_wanted;
  o.membrane = true;
  const RetinaCapScene scene = build_retina_cap(o);
  const TissueWorld& world = scene.world;
  // Nodes: every vertex of every surface, in order; anchored vertices massless (static).
  std::vector<Vec3> x;
  std::vector<double> mass;
  std::vector<std::uint32_t> base(world.surface_count());
  for (std::uint32_t s = 0; s < world.surface_count(); ++s) {
    const Surface& surface = world.surface(s);
    base[s] = static_cast<std::uint32_t>(x.size());
    for (std::uint32_t v = 0; v < surface.vertex_slots(); ++v) {
      x.push_back(surface.rest_position(v));
      mass.push_back(surface.is_fixed(v) ? 0.0 : surface.mass(v));
    }
  }
  BulletBody b(x, mass, world.environment().gravity_mm_s2);
  std::size_t links = 0;
  for (std::uint32_t s = 0; s < world.surface_count(); ++s) {
    const Surface& surface = world.surface(s);
    for (std::uint32_t e = 0; e < surface.edge_slots(); ++e) {
      if (!surface.edge_alive(e)) continue;
      const auto [a, c] = surface.edge_vertices(e);
      b.link(static_cast<int>(base[s] + a), static_cast<int>(base[s] + c)), ++links;
    }
  }
  // The membrane's attachments as build_retina_cap makes them: every stride-th membrane vertex to
  // the retina vertex it was copied from (the same rest position).
  if (scene.membrane != kNone) {
    const Surface& r = world.surface(scene.retina);
    const Surface& mem = world.surface(scene.membrane);
    std::map<std::tuple<double, double, double>, std::uint32_t> at;
    for (std::uint32_t v = 0; v < r.vertex_slots(); ++v) {
      const Vec3& p = r.rest_position(v);
      at[{p.x(), p.y(), p.z()}] = v;
    }
    for (std::uint32_t v = 0; v < mem.vertex_slots(); v += static_cast<std::uint32_t>(o.membrane_attachment_stride)) {
      const Vec3& p = mem.rest_position(v);
      if (const auto it = at.find({p.x(), p.y(), p.z()}); it != at.end())
        b.link(static_cast<int>(base[scene.membrane] + v), static_cast<int>(base[scene.retina] + it->second)), ++links;
    }
  }
  b.configure(klst, piterations, 0.0);
  // The detachment: pressure × area × weight toward its point, breathing ±10 % at 1 Hz.
  const LocalForceDescription& f = world.local_force(scene.detachment_force);
  const Surface& fs = world.surface(f.surface);
  std::vector<std::pair<int, double>> push;  // node, force at scale 1 (µN; toward the point from where the node is)
  for (std::size_t i = 0; i < f.vertices.size(); ++i) {
    const std::uint32_t v = f.vertices[i];
    const double w = f.weights.empty() ? 1.0 : f.weights[i];
    push.push_back({static_cast<int>(base[f.surface] + v), f.pressure_pa * fs.vertex_rest_area(v) * w});
  }
  std::uint64_t step = 0;
  auto forces = [&] {
    const double scale = 0.9 + 0.1 * std::sin(2.0 * std::numbers::pi * kDt * static_cast<double>(step));
    for (const auto& [node, force_un] : push) {
      const btVector3& p = b.body->m_nodes[node].m_x;
      const Vec3 dir = (f.toward_point_mm - Vec3(p.x(), p.y(), p.z())).normalized();
      b.body->addForce(bt(scale * force_un * dir), node);
    }
  };
  for (int i = 0; i < 200; ++i, ++step) b.step(forces);  // warm-up (BM_TissueStep's is 1000 steps: Bullet's are slower)

  std::vector<double> samples;
  samples.reserve(1 << 16);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    b.step(forces);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(b.body->m_nodes[0].m_x);
    samples.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    ++step;
  }
  std::sort(samples.begin(), samples.end());
  auto q = [&](double p) { return samples[static_cast<std::size_t>(p * static_cast<double>(samples.size() - 1))]; };
  state.counters["nodes"] = static_cast<double>(x.size());
  state.counters["links"] = static_cast<double>(links);
  state.counters["substeps"] = kSubsteps;
  state.counters["piterations"] = piterations;
  state.counters["kLST"] = klst;
  state.counters["p50_us"] = q(0.50);
  state.counters["p99_us"] = q(0.99);
  state.counters["stiffness_error_pct"] = 100.0 * bullet_error;
  state.counters["vitreo_stiffness_error_pct"] = 100.0 * vitreo_error;
}

}  // namespace

BENCHMARK(BM_BulletSoftBodyStep)
    ->ArgNames({"vertices", "piterations"})
    ->ArgsProduct({{20000}, {1, 8, 32, 64}})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(2.0);
