// Looks at a case the way the surgeon meets it: the case loaded as the rig loads it, the light pipe
// and the case's first tool at the fixed poses of the golden test (fixed_poses.hpp), captured,
// built into a FrameScene and rendered; writes <out>/<case>_{left,right,stereo}.png.
//
//   build/test/tests/rig/session/case_view --out /tmp/view [--case NAME]... [--size 640x512]
//        [--retina 5000] [--actuation 0.5] [--tool N] [--zoom Z] [--pan X,Y] [--focus MM] [--wide]
//        [--no-labels] [--flat] [--steps N]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "fixed_poses.hpp"
#include "rig/session/frame_source.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/png_io.hpp"
#include "vitreo/render/renderer.hpp"

using namespace vitreo;
namespace vr = vitreo::render;

int main(int argc, char** argv) {
  CLI::App app{"Renders shipped cases at the golden test's fixed poses and writes stereo PNGs"};
  std::string out = "case-view";
  std::vector<std::string> names;
  std::string size = "640x512";
  int retina = 5000;
  app.add_option("--out", out, "output folder (created)");
  app.add_option("--case", names, "case name(s) in scenes/ (default: all)");
  app.add_option("--size", size, "per-eye size WxH");
  app.add_option("--retina", retina, "retina vertices");
  CLI11_PARSE(app, argc, argv);
  int w = 0, h = 0;
  if (std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16) {
    std::fprintf(stderr, "case_view: --size must be WxH, got '%s'\n", size.c_str());
    return 2;
  }
  const std::string scenes = std::string(VITREO_SOURCE_DIR) + "/scenes";
  if (names.empty()) {
    for (const auto& e : std::filesystem::directory_iterator(scenes)) {
      if (e.path().extension() == ".toml" && e.path().filename() != "materials.toml") names.push_back(e.path().stem().string());
    }
    std::sort(names.begin(), names.end());
  }
  std::filesystem::create_directories(out);
  vr::EglContext context;
  vr::StereoRenderer renderer(vr::RenderSettings{w, h, 1024, 1024});
  for (const std::string& name : names) {
    rig::testing::CaseUnderTest under_test(scenes + "/" + name + ".toml", retina,
                                           (std::filesystem::temp_directory_path() / "vitreo-case-view-cache").string());
    if (!rig::testing::place_at_fixed_poses(under_test.model)) {
      std::fprintf(stderr, "case_view: %s: poses refused\n", name.c_str());
      return 1;
    }
    rig::ViewSnapshot view;
    if (!rig::capture_view(under_test.model, 3, 0.003, view)) return 1;
    rig::FrameBuilder builder;
    vr::FrameScene scene = builder.build(view);
    if (const char* drop = std::getenv("CASE_VIEW_DROP")) {  // debugging: leave one material out
      std::erase_if(scene.meshes, [&](const vr::Mesh& m) { return static_cast<int>(m.material) == std::atoi(drop); });
    }
    if (std::getenv("CASE_VIEW_DEBUG")) {
      const auto disc = under_test.model.scene().eye.optic_disc_mm;
      for (const auto& m : scene.meshes) {
        if (m.material != vr::MaterialKind::Retina) continue;
        int n = 0;
        for (const auto& v : m.geometry->vertices) {
          const double d = std::hypot(v.position_mm.x - disc.x(), v.position_mm.y - disc.y(), v.position_mm.z - disc.z());
          if (d < 1.5 && n++ < 12) std::printf("  disc vertex d %.2f detachment %.2f highlight %.2f\n", d, v.detachment, v.highlight);
        }
      }
    }
    for (const auto& ins : view.instruments) {
      if (!ins.present) continue;
      std::printf("  instrument kind %d inserted %d tip (%.2f %.2f %.2f) aim_hit %d aim (%.2f %.2f %.2f)\n", ins.kind, ins.inserted,
                  ins.tip[0], ins.tip[1], ins.tip[2], ins.aim_hit, ins.aim_point[0], ins.aim_point[1], ins.aim_point[2]);
    }
    vr::StereoFrame frame;
    renderer.render(scene, frame);
    const std::string prefix = out + "/" + name;
    vr::write_png(prefix + "_left.png", frame.eye(0));
    vr::write_png(prefix + "_right.png", frame.eye(1));
    vr::write_png(prefix + "_stereo.png", frame.side_by_side());
    std::printf("%s_stereo.png\n", prefix.c_str());
  }
  return 0;
}
