// vitreo-cases: the instructors' case tool — list, validate and inspect scene files.
//
//   vitreo-cases list [--dir scenes]
//   vitreo-cases validate scenes/*.toml
//   vitreo-cases inspect my_case.toml [--no-settle] [--snapshot start.snap]
//   vitreo-cases sites my_case.toml MEMBRANE [--retina-vertices N] [--height-mm H]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "rig/files/data_dir.hpp"
#include "rig/session/surgical_script.hpp"
#include "core/scene/scene_builder.hpp"
#include "core/scene/snapshot.hpp"
#include "rig/scene_io/scene_file.hpp"

namespace {

using namespace vitreo;

std::vector<std::string> scene_files(const std::string& dir) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().extension() == ".toml" && e.path().filename() != "materials.toml") {
      out.push_back(e.path().string());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Parses and builds (without settling or textures): catches everything a case can get wrong.
core::SceneDescription check(const std::string& file) {
  core::SceneDescription d = scene_io::load_scene_file(file);
  try {
    core::BuildOptions o;
    o.settle = false;
    o.textures = false;
    (void)core::build_scene(d, o);
  } catch (const core::InvalidArgument& e) {
    throw scene_io::SceneError(file, 1, "", std::string("cannot build: ") + e.what());
  }
  return d;
}

int cmd_list(const std::string& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    spdlog::error("no such directory: {}", dir);
    return 1;
  }
  int bad = 0;
  for (const auto& f : scene_files(dir)) {
    try {
      const auto d = scene_io::load_scene_file(f);
      std::printf("%-34s %-8s %s\n", d.name.c_str(), d.category.c_str(), d.title.c_str());
      // Its surgical scripts (scenes/scripts/CASE.KIND.toml), each parsed: a malformed one is listed as such.
      const auto scripts = std::filesystem::path(dir) / "scripts";
      std::vector<std::filesystem::path> found;
      for (const auto& e : std::filesystem::directory_iterator(scripts, ec)) {
        const std::string file = e.path().filename().string();
        if (e.path().extension() == ".toml" && file.rfind(std::filesystem::path(f).stem().string() + ".", 0) == 0) found.push_back(e.path());
      }
      std::sort(found.begin(), found.end());
      for (const auto& p : found) {
        try {
          const rig::SurgicalScript s = rig::read_surgical_script(p.string());
          std::printf("    script %-7s %5.1f s  %s — %s\n", s.kind.c_str(), s.duration_s, p.filename().c_str(), s.summary.c_str());
        } catch (const std::exception& e) {
          std::printf("    script INVALID  %s\n", e.what());
          ++bad;
        }
      }
    } catch (const scene_io::SceneError& e) {
      std::printf("%-34s INVALID  %s\n", std::filesystem::path(f).filename().c_str(), e.what());
      ++bad;
    }
  }
  return bad ? 1 : 0;
}

int cmd_validate(const std::vector<std::string>& files) {
  int bad = 0;
  for (const auto& f : files) {
    if (std::filesystem::path(f).filename() == "materials.toml") {
      std::printf("--  %s (materials library, checked through the cases)\n", f.c_str());
      continue;
    }
    try {
      const auto d = check(f);
      std::printf("ok  %s (%s)\n", f.c_str(), d.name.c_str());
    } catch (const scene_io::SceneError& e) {
      spdlog::error("{}", e.what());
      ++bad;
    }
  }
  return bad ? 1 : 0;
}

const char* yes_no(bool b) { return b ? "yes" : "no"; }

int cmd_inspect(const std::string& file, bool settle, const std::string& snapshot) {
  core::SceneDescription d;
  try {
    d = check(file);
  } catch (const scene_io::SceneError& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  const auto t0 = std::chrono::steady_clock::now();
  core::BuildOptions o;
  o.settle = settle;
  core::Scene s = core::build_scene(d, o);
  const double build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto& e = s.eye;
  const auto& p = e.parameters;
  std::printf("case        %s (%s, format %d)\n", d.name.c_str(), d.category.c_str(), d.format_version);
  std::printf("title       %s\n", d.title.c_str());
  if (!d.summary.empty()) std::printf("summary     %s\n", d.summary.c_str());
  std::printf("\n-- anatomy (mm)\n");
  std::printf("axial length %.2f  globe diameter %.2f  wall radius at pole %.2f\n", e.cornea_apex_z_mm - e.posterior_pole_z_mm,
              p.globe_diameter_mm, e.wall.radius_toward(core::Vec3(0, 0, -1)));
  std::printf("limbus radius %.2f at z %.2f  ora serrata %.1f deg from the pole (%.1f mm behind the limbus)\n",
              e.limbus_radius_mm, e.limbus_z_mm, e.ora_polar_rad * 180.0 / 3.141592653589793, p.ora_serrata_mm);
  std::printf("optic disc %.1f deg nasal (r %.2f)  fovea r %.2f  macula r %.2f  fundus extent %.2f\n",
              p.optic_disc_offset_deg, p.optic_disc_radius_mm, p.fovea_radius_mm, p.macula_radius_mm, e.fundus_extent_mm);
  for (const auto& port : e.ports) {
    std::printf("port %-10s outer (%6.2f %6.2f %6.2f)\n", port.name.c_str(), port.outer_mm.x(), port.outer_mm.y(), port.outer_mm.z());
  }
  std::printf("\n-- static meshes\n");
  for (const auto& m : e.static_meshes) {
    std::printf("%-18s %6zu vertices %6zu triangles  texture %s\n", m.name.c_str(), m.mesh.vertex_count(),
                m.mesh.triangle_count(), m.texture.empty() ? "-" : m.texture.c_str());
  }
  std::printf("\n-- physical surfaces\n");
  for (std::uint32_t i = 0; i < s.world.surface_count(); ++i) {
    const auto& sf = s.world.surface(i);
    std::uint32_t fixed = 0;
    for (std::uint32_t v = 0; v < sf.vertex_slots(); ++v) fixed += sf.vertex_alive(v) && sf.is_fixed(v);
    std::printf("%-24s %6u vertices (%u anchored) %6u springs %6u triangles  mass %.4f g\n", sf.material().name.c_str(),
                sf.vertex_count(), fixed, sf.edge_count(), sf.triangle_count(), sf.total_mass());
  }
  std::printf("attachments %u (gel adhesions %u)\n", s.world.attachment_count(), s.gel_attachments);
  for (const auto& m : s.membranes) {
    std::printf("membrane %-16s %u attachments, %u strong, %zu lattice sites\n", m.name.c_str(), m.attachment_count, m.strong_attachments,
                m.sites.size());
  }
  for (const auto& t : s.tears) std::printf("tear %-20s %u vertices cut, flap of %zu vertices\n", t.name.c_str(), t.cut_vertices, t.flap_vertices.size());
  for (std::size_t i = 0; i < s.detachment_forces.size(); ++i) {
    std::printf("detachment %-14s %.0f Pa net\n", d.detachments[i].name.c_str(), d.detachments[i].pressure_pa);
  }
  for (const auto& g : s.guides) std::printf("guide %-19s %s, %zu points\n", g.name.c_str(), core::to_string(g.kind), g.polyline_mm.size());
  std::printf("\n-- materials\n");
  const std::pair<const char*, const core::TissueMaterial*> mats[] = {
      {"retina", &d.materials.retina}, {"gel", &d.materials.gel}, {"membrane", &d.materials.membrane}};
  for (const auto& [name, m] : mats) {
    std::printf("%s: density %.4g g/mm3, thickness %.3g mm, E*t %.4g Pa*mm, tear strain %.3g, drag %.3g Pa*s/mm\n", name,
                m->density_g_per_mm3, m->thickness_mm, m->membrane_modulus_pa_mm, m->tear_strain, m->drag_pa_s_per_mm);
    const auto it = d.materials.sources.find(name);
    if (it != d.materials.sources.end()) {
      for (const auto& [k, src] : it->second) std::printf("    %-26s %s\n", k.c_str(), src.c_str());
    }
  }
  std::printf("\n-- instruments: ");
  for (const auto& i : d.instruments) std::printf("%s ", i.c_str());
  std::printf("\n-- completion criteria\n");
  for (const auto& c : d.criteria) {
    std::printf("%-18s %-16s threshold %g\n", core::to_string(c.kind), c.target.c_str(), c.threshold);
  }
  std::printf("\n-- load\n");
  std::printf("build + settle %.3f s; settled %s after %d steps (max speed %.3f mm/s); max retina lift %.2f mm\n", build_s,
              yes_no(s.settle.settled), s.settle.steps, s.settle.max_speed_mm_s, core::max_retina_lift_mm(s));
  std::printf("state hash %016llx\n", static_cast<unsigned long long>(s.world.state_hash()));
  if (!snapshot.empty()) {
    const auto st = core::save_snapshot(s.world, d.name, snapshot);
    if (!st) {
      spdlog::error("{}", st.message());
      return 1;
    }
    std::printf("snapshot written to %s\n", snapshot.c_str());
  }
  if (!s.settle.ok) {
    spdlog::error("{}: a settling step was rolled back", file);
    return 1;
  }
  return 0;
}

// A membrane's attachment sites in the settled start, for whoever writes a script that cuts its stalks
// (tools/delamination_script.py reads this table).
int cmd_sites(const std::string& file, const std::string& membrane, int retina_vertices, double height_mm) {
  scene_io::CaseLoadOptions o;
  o.textures = false;
  o.retina_vertices = retina_vertices;
  const auto c = rig::prepare_case({scene_io::read_case_text(file)}, 0, o);
  std::printf("# %s at %d retina vertices, the working hand through %s\n", c->scene->description.name.c_str(),
              c->scene->description.anatomy.retina_vertices, c->tracker_port_names[rig::kToolTracker].c_str());
  std::fputs(rig::describe_membrane_sites(*c, membrane, height_mm).c_str(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("vitreo-cases"));
  spdlog::set_pattern("%^%l%$: %v");
  CLI::App app{"vitreo-cases: list, validate and inspect the surgical cases (scene files)"};
  app.require_subcommand(1);

  std::string dir;
  auto* list = app.add_subcommand("list", "list the cases in a directory, each with its surgical scripts (DIR/scripts)");
  list->add_option("--dir", dir, "directory of scene files (default: ./scenes, else the installed cases, else the source tree's)");

  std::vector<std::string> files;
  auto* validate = app.add_subcommand("validate", "parse and build scene files; non-zero exit on the first bad one");
  validate->add_option("files", files, "scene files")->required();

  std::string file, snapshot;
  bool no_settle = false;
  auto* inspect = app.add_subcommand("inspect", "load a case (build + settle) and print counts, dimensions and materials");
  inspect->add_option("file", file, "scene file")->required();
  inspect->add_flag("--no-settle", no_settle, "skip settling");
  inspect->add_option("--snapshot", snapshot, "write the settled state to this snapshot file");

  std::string membrane;
  int retina_vertices = 0;
  double height_mm = 0.55;
  auto* sites = app.add_subcommand("sites", "print a membrane's attachment sites in the settled start (where each strand crosses a height above the wall), for script writers");
  sites->add_option("file", file, "scene file")->required();
  sites->add_option("membrane", membrane, "membrane name")->required();
  sites->add_option("--retina-vertices", retina_vertices, "load at this retina resolution (default: the case's own)");
  sites->add_option("--height-mm", height_mm, "the height above the wall at which to report each strand (default 0.55)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    spdlog::error("{}", e.what());
    return 2;
  }
  try {
    if (*list) return cmd_list(dir.empty() ? vitreo::files::default_scenes_dir() : dir);
    if (*validate) return cmd_validate(files);
    if (*inspect) return cmd_inspect(file, !no_settle, snapshot);
    if (*sites) return cmd_sites(file, membrane, retina_vertices, height_mm);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
  return 0;
}
