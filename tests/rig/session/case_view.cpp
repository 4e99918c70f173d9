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
#include "synthetic_scene.hpp"
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
  double zoom = 0.0, focus = 0.0, actuation = -1.0;
  std::vector<double> pan;
  bool wide = false, invert = false, no_labels = false, flat = false;
  app.add_option("--zoom", zoom, "microscope zoom (operator command)");
  app.add_option("--pan", pan, "microscope pan X Y (mm from the region of interest)")->expected(2);
  app.add_option("--focus", focus, "microscope focus offset (mm, + toward the microscope)");
  app.add_option("--actuation", actuation, "the tool's handle, 0 open .. 1 closed");
  app.add_flag("--wide", wide, "wide-angle viewing system");
  app.add_flag("--invert", invert, "with --wide: re-inverter off");
  app.add_flag("--no-labels", no_labels, "hide guides and labels");
  app.add_flag("--flat", flat, "flat shading");
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
  if (names.empty()) names = rig::testing::shipped_case_names();
  std::filesystem::create_directories(out);
  vr::EglContext context;
  vr::StereoRenderer renderer(vr::RenderSettings{w, h, 1024, 1024});
  for (const std::string& name : names) {
    rig::testing::CaseUnderTest under_test(scenes + "/" + name + ".toml", retina,
                                           (std::filesystem::temp_directory_path() / "vitreo-case-view-cache").string());
    rig::SimulationModel& model = under_test.model;
    auto command = [&](int code, double a, double b) { return model.apply(rig::testing::command_input(code, a, b)); };
    if (zoom > 0.0) command(9, zoom, 0);
    if (pan.size() == 2) command(10, pan[0], pan[1]);
    if (focus != 0.0) command(11, focus, 0);
    if (flat) command(12, 0, 0);
    if (wide) command(13, 0, 0);
    if (invert) command(14, 0, 0);
    if (no_labels) command(8, 0, 0);
    if (!rig::testing::place_at_fixed_poses(model)) {
      std::fprintf(stderr, "case_view: %s: poses refused\n", name.c_str());
      return 1;
    }
    if (actuation >= 0.0) {
      const auto& c = model.current_case();
      const core::Vec3 tp = c.tracker_ports[rig::kToolTracker].position_mm;
      model.apply(rig::testing::tracker_sample(rig::kToolTracker, c.focus_mm - rig::testing::kToolClearance_mm * (c.focus_mm - tp).normalized(), actuation));
      model.step();
    }
    // The microscope's motors reach their targets (the tissue steps along).
    for (int i = 0; i < 4000 && (std::abs(model.microscope().zoom() - (zoom > 0 ? zoom : 1.0)) > 1e-9 ||
                                 std::abs(model.microscope().focus_mm() - focus) > 1e-9 ||
                                 (pan.size() == 2 && (model.microscope().center_mm() - model.microscope().region_of_interest_mm() - core::Vec2(pan[0], pan[1])).norm() > 1e-6));
         ++i) {
      model.step();
    }
    rig::ViewSnapshot view;
    if (!rig::capture_view(model, 3, 0.003, view)) return 1;
    rig::FrameBuilder builder;
    vr::FrameScene scene = builder.build(view);
    if (const char* drop = std::getenv("CASE_VIEW_DROP")) {  // debugging: leave one material out
      std::erase_if(scene.meshes, [&](const vr::Mesh& m) { return static_cast<int>(m.material) == std::atoi(drop); });
    }
    for (const auto& ins : view.instruments) {
      if (!ins.present) continue;
      const vr::Vec2 px = render::testing::project_to_pixel(scene, 0, vr::Vec3{ins.tip[0], ins.tip[1], ins.tip[2]}, w, h);
      std::printf("  instrument kind %d inserted %d tip at pixel (%.0f, %.0f) aim_hit %d\n", ins.kind, ins.inserted, px.x, px.y, ins.aim_hit);
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
