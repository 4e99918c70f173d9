// vitreo — the rig's main job.
//
// With no arguments it runs its embedded default: a headless simulation of a retina lining the
// globe, under gravity, intraocular pressure and a local detachment force, and prints a summary.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <cstdio>
#include <vector>

#include "core/anatomy/retina_cap.hpp"

namespace {

struct Options {
  int steps = 3000;
  double dt_s = 1e-3;
  int retina_vertices = 20000;
  bool membrane = true;
  int substeps = 2;
};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App app{"vitreo: vitreoretinal surgery training rig — simulation process.\n"
               "Without options: a headless retina simulation (gravity, intraocular pressure, a local\n"
               "detachment) with a summary of step timing, energy and mass."};
  app.add_option("--steps", opt.steps, "number of physics steps to run")->check(CLI::Range(1, 100'000'000));
  app.add_option("--dt", opt.dt_s, "physics step in seconds")->check(CLI::Range(1e-5, 0.02));
  app.add_option("--retina-vertices", opt.retina_vertices, "retina mesh resolution")->check(CLI::Range(100, 2'000'000));
  app.add_flag("!--no-membrane", opt.membrane, "leave out the epiretinal membrane");
  app.add_option("--substeps", opt.substeps, "solver substeps per step")->check(CLI::Range(1, 64));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  vitreo::core::RetinaCapOptions scene_options;
  scene_options.retina_vertices = opt.retina_vertices;
  scene_options.membrane = opt.membrane;
  scene_options.solver.substeps = opt.substeps;
  auto build_start = std::chrono::steady_clock::now();
  std::optional<vitreo::core::RetinaCapScene> scene;
  try {
    scene.emplace(vitreo::core::build_retina_cap(scene_options));
  } catch (const std::exception& e) {
    spdlog::error("cannot build the scene: {}", e.what());
    return 1;
  }
  auto& world = scene->world;
  const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - build_start).count();
  const auto& retina = world.surface(scene->retina);
  spdlog::info("scene: retina {} vertices, {} springs, {} anchored; {} attachments; built in {:.0f} ms",
               retina.vertex_count(), retina.edge_count(), scene->anchored_vertices, world.attachment_count(), build_ms);

  const double mass0 = world.total_mass();
  const double energy0 = world.energy().total();
  std::vector<double> step_us;
  step_us.reserve(static_cast<std::size_t>(opt.steps));
  std::uint64_t tears = 0, broken = 0, failed = 0;
  for (int i = 0; i < opt.steps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto report = world.step(opt.dt_s);
    step_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    tears += report.tears;
    broken += report.attachments_broken;
    if (!report.ok) {
      ++failed;
      spdlog::warn("step {}: {}", i, report.error);
    }
  }

  const auto energy = world.energy();
  double max_lift = 0.0;
  for (std::uint32_t v = 0; v < retina.vertex_slots(); ++v) {
    if (retina.vertex_alive(v)) max_lift = std::max(max_lift, world.wall().clearance(retina.position(v)));
  }
  std::printf("vitreo summary\n");
  std::printf("  simulated        %.3f s in %d steps of %.3g ms (%d substeps)\n", world.time_s(), opt.steps, opt.dt_s * 1e3,
              opt.substeps);
  std::printf("  step time        median %.0f us, p99 %.0f us, max %.0f us\n", quantile(step_us, 0.5),
              quantile(step_us, 0.99), quantile(step_us, 1.0));
  std::printf("  energy           start %.4g, end %.4g (kinetic %.3g, gravity %.4g, elastic %.4g) nJ\n", energy0,
              energy.total(), energy.kinetic, energy.gravity, energy.elastic);
  std::printf("  mass             start %.6f g, end %.6f g\n", mass0, world.total_mass());
  std::printf("  detachment       retina lifted up to %.2f mm off the choroid\n", max_lift);
  std::printf("  events           %llu tears, %llu attachments broken, %llu steps rolled back\n",
              static_cast<unsigned long long>(tears), static_cast<unsigned long long>(broken),
              static_cast<unsigned long long>(failed));
  std::printf("  state hash       %016llx\n", static_cast<unsigned long long>(world.state_hash()));
  return failed == 0 ? 0 : 2;
}
