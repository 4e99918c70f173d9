// render_snapshot: renders one synthetic case to PNGs (left, right, side by side).
// Used to look at the renderer's output, to regenerate goldens by eye, and by the EGL-failure test
// to check that a broken EGL set-up ends the process with a one-line reason and a non-zero exit.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "synthetic_scene.hpp"
#include "vitreo/render/egl_context.hpp"
#include "vitreo/render/png_io.hpp"
#include "vitreo/render/renderer.hpp"

int main(int argc, char** argv) {
  using namespace vitreo::render;
  CLI::App app{"Render a synthetic vitreo scene through headless EGL and write PNGs"};
  std::string out = "snapshot";
  std::string platform = "auto";
  int width = 640, height = 512, tris = 20000;
  float defocus_mm = 0.0f;
  bool dark = false, detached = false, gas = false, wide = false, burn = false;
  app.add_option("--out", out, "output prefix: <out>_left.png, _right.png, _stereo.png");
  app.add_option("--platform", platform, "EGL platform: auto, surfaceless, device, gbm");
  app.add_option("--width", width, "width of one eye in pixels")->check(CLI::Range(16, 4096));
  app.add_option("--height", height, "height in pixels")->check(CLI::Range(16, 4096));
  app.add_option("--triangles", tris, "approximate retina triangle count")->check(CLI::Range(100, 2000000));
  app.add_flag("--dark", dark, "no light pipe");
  app.add_flag("--detached", detached, "bullous retinal detachment");
  app.add_flag("--gas", gas, "fluid-gas exchange");
  app.add_flag("--wide", wide, "wide-angle view");
  app.add_flag("--burn", burn, "a laser burn at the posterior pole");
  app.add_option("--defocus", defocus_mm, "depth of field on, focus this many mm above the fundus");
  CLI11_PARSE(app, argc, argv);
  try {
    EglOptions egl;
    egl.platform = parse_egl_platform(platform);
    EglContext context(egl);
    std::printf("%s\n", context.description().c_str());
    StereoRenderer renderer({width, height, 1024, 1024});
    testing::SyntheticOptions o;
    o.retina_triangles = tris;
    o.light_pipe = !dark;
    o.detached = detached;
    o.gas = gas;
    o.wide_angle = wide;
    FrameScene scene = testing::make_scene(o);
    if (burn) {
      for (auto& m : scene.meshes)
        if (m.id == testing::kRetina) m.burns.push_back({testing::retina_point(14, 250), {}, 0.4f, {}});
    }
    if (defocus_mm != 0.0f) {
      scene.microscope.depth_of_field = true;
      scene.microscope.focus_distance_mm =
          scene.microscope.working_distance_mm + scene.microscope.target_mm.z + testing::kRetinaRadius - defocus_mm;
    }
    StereoFrame frame;
    renderer.render(scene, frame);
    write_png(out + "_left.png", frame.eye(0));
    write_png(out + "_right.png", frame.eye(1));
    write_png(out + "_stereo.png", frame.side_by_side());
    std::printf("wrote %s_{left,right,stereo}.png (t=%.3f s, step %llu; %llu tris/eye, burns painted %llu, missed %llu)\n",
                out.c_str(), frame.sim_time_s, static_cast<unsigned long long>(frame.step_index),
                static_cast<unsigned long long>(renderer.stats().triangles_last_frame),
                static_cast<unsigned long long>(renderer.stats().burns_painted),
                static_cast<unsigned long long>(renderer.stats().burns_missed));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_snapshot: %s\n", e.what());
    return 2;
  }
}
