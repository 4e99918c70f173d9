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

#include "core/anatomy/fundus_texture.hpp"
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
  std::vector<std::uint64_t> fundus_seeds;
  app.add_option("--fundus", fundus_seeds, "instead: write the fundus (retina map over choroid map) of these texture seeds");
  CLI11_PARSE(app, argc, argv);
  if (!fundus_seeds.empty()) {
    std::filesystem::create_directories(out);
    core::EyeParameters p;
    p.retina_vertices = 1000;
    const core::EyeModel eye = core::build_eye_model(p);
    for (const std::uint64_t seed : fundus_seeds) {
      const core::FundusTextures t = core::generate_fundus(eye, {seed, 512});
      vr::Image img{t.retina.width, t.retina.height, t.choroid.rgba};
      for (std::size_t i = 0; i < img.rgba.size(); i += 4) {
        const double a = t.retina.rgba[i + 3] / 255.0;
        for (int k = 0; k < 3; ++k) img.rgba[i + k] = static_cast<std::uint8_t>(std::lround(t.retina.rgba[i + k] * a + img.rgba[i + k] * (1 - a)));
      }
      // Row 0 is v = 0 (inferior): flip so superior is up, as the surgeon's picture has it.
      vr::Image flipped = img;
      const std::size_t row = static_cast<std::size_t>(img.width) * 4;
      for (int y = 0; y < img.height; ++y) std::copy_n(&img.rgba[y * row], row, &flipped.rgba[(img.height - 1 - y) * row]);
      const std::string path = out + "/fundus_seed_" + std::to_string(seed) + ".png";
      vr::write_png(path, flipped);
      std::printf("%s\n", path.c_str());
    }
    return 0;
  }
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
