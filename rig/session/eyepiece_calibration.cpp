#include "rig/session/eyepiece_calibration.hpp"

#include <unistd.h>

#include <cmath>
#include <sstream>

#include "rig/session/calibration_in_force.hpp"
#include "vitreo/render/eyepiece_pattern.hpp"
#include "vitreo/render/render_thread.hpp"

namespace vitreo::rig {
namespace {

std::string describe(const calibration::EyepieceRecord& e) {
  char b[240];
  std::snprintf(b, sizeof b, "left (%.1f, %.1f) px, right (%.1f, %.1f) px, stereo base %.1f mm, convergence %s", e.offset_px[0][0],
                e.offset_px[0][1], e.offset_px[1][0], e.offset_px[1][1], e.stereo_base_mm,
                e.convergence_mm > 0 ? (std::to_string(static_cast<int>(std::lround(e.convergence_mm))) + " mm").c_str() : "at the working plane");
  return b;
}

// Reads one line from fd (blocking); nothing at the end of the input.
std::optional<std::string> read_line(int fd) {
  std::string line;
  char c;
  for (;;) {
    const ssize_t n = ::read(fd, &c, 1);
    if (n <= 0) return line.empty() ? std::nullopt : std::optional<std::string>(line);
    if (c == '\n') return line;
    line += c;
  }
}

}  // namespace

std::optional<calibration::EyepieceRecord> run_eyepiece_calibration(const EyepieceRunOptions& o, int input_fd, std::FILE* out) {
  render::RenderThreadOptions ro;
  ro.render.eye_width = o.eye_width;
  ro.render.eye_height = o.eye_height;
  ro.displays = o.displays;
  ro.shm_ring_name = o.frame_ring_name;
  render::RenderThread renderer(ro);
  calibration::EyepieceRecord set = o.start;
  const render::Microscope microscope;  // the surgical microscope's view: the pattern at its working plane
  // Draws the pattern as the rig will: the settings applied to the microscope, then the pattern
  // built for that microscope (its grid on the zero-disparity plane). The PNGs are of a frame
  // rendered after this change: the render thread renders the newest scene, then the next request.
  auto draw = [&] {
    render::Microscope m = microscope;
    eyepiece_settings(set).apply(m);
    const render::FrameScene scene = render::eyepiece_test_pattern(m, 12.0f, o.eye_width, o.eye_height);
    const std::uint64_t before = renderer.frames_rendered();
    renderer.publish(scene);
    if (o.png_prefix.empty()) return;
    while (renderer.frames_rendered() == before) ::usleep(1000);
    renderer.request_png(o.png_prefix);
    renderer.publish(scene);
    while (renderer.frames_rendered() < before + 2) ::usleep(1000);
  };
  std::fprintf(out,
               "vitreo-calibrate: the eyepiece displays. Look into the eyepieces at the test pattern: the green arms of the centre "
               "cross are the left eye's, the red arms the right eye's.\n"
               "  1. Shift one eye's picture until the arms meet as one straight cross:   right DX DY   (or left DX DY; pixels, x "
               "right, y up)\n"
               "  2. Set the stereo base until the yellow squares stand comfortably before (left) and behind (right) the grid:   base MM\n"
               "  3. If the grid itself does not fuse at rest, move the zero-disparity plane:   convergence MM   (0: the working plane)\n"
               "  show: what is set; done: keep it; q: give up\n  %s\n",
               describe(set).c_str());
  std::fflush(out);
  draw();
  for (;;) {
    std::fprintf(out, "> ");
    std::fflush(out);
    const auto line = read_line(input_fd);
    if (!line) return std::nullopt;
    std::istringstream in(*line);
    std::string word;
    in >> word;
    if (word.empty()) continue;
    if (word == "q") return std::nullopt;
    if (word == "done") return set;
    if (word == "show") {
      std::fprintf(out, "  %s\n", describe(set).c_str());
      continue;
    }
    double a = 0.0, b = 0.0;
    std::string extra;
    const bool two = static_cast<bool>(in >> a) && (word == "base" || word == "convergence" || static_cast<bool>(in >> b));
    if (!two || (in >> extra) || !std::isfinite(a) || !std::isfinite(b)) {
      std::fprintf(out, "  '%s': left DX DY, right DX DY, base MM, convergence MM, show, done or q\n", line->c_str());
      continue;
    }
    if ((word == "left" || word == "right") && std::abs(a) <= 2000 && std::abs(b) <= 2000) {
      const int eye = word == "left" ? 0 : 1;
      set.offset_px[eye][0] = a;
      set.offset_px[eye][1] = b;
    } else if (word == "base" && a >= 1.0 && a <= 100.0) {
      set.stereo_base_mm = a;
    } else if (word == "convergence" && (a == 0.0 || (a >= 50.0 && a <= 2000.0))) {
      set.convergence_mm = a;
    } else {
      std::fprintf(out, "  '%s': out of range (offsets ±2000 px, base 1..100 mm, convergence 0 or 50..2000 mm)\n", line->c_str());
      continue;
    }
    draw();
    std::fprintf(out, "  %s\n", describe(set).c_str());
  }
}

}  // namespace vitreo::rig
