// vitreo — the rig's main job.
//
// Without options it runs its embedded default: simulated devices (an instrument tracker, the foot
// pedals and the eyeball fixture, as firmware emulators behind ptys) playing a scripted peel on a
// real case from scenes/ (the epiretinal membrane over the macula: the forceps come in through
// their port, grasp the membrane, pull it up and let go), through the real drivers, a fixed-step
// physics thread, stereo frames, telemetry to an LCM log and a recording — then replays the
// recording and checks it ends in the same state.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "rig/scene_io/case_loader.hpp"
#include "rig/session/rig_session.hpp"

#ifndef VITREO_SCENES_DIR
#define VITREO_SCENES_DIR "scenes"
#endif

namespace {

using vitreo::core::Vec3;
namespace fs = std::filesystem;

// The case a first-time user sees: a membrane peel shows approach, grasp and pull at a glance.
constexpr const char* kDefaultCase = "low_membrane_macula.toml";

std::string default_scenes_dir() {
  std::error_code ec;
  if (fs::is_directory("scenes", ec)) return "scenes";
  return VITREO_SCENES_DIR;
}

// Every *.toml in `dir` except the materials library, sorted by name (the case list order).
std::vector<std::string> cases_in(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".toml" && e.path().filename() != "materials.toml") out.push_back(e.path().string());
  }
  if (ec) throw std::runtime_error("cannot list cases in " + dir + ": " + ec.message());
  std::sort(out.begin(), out.end());
  if (out.empty()) throw std::runtime_error("no cases (*.toml) in " + dir);
  return out;
}

std::string key(double t_ms, const Vec3& p, double actuation) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "key %.0f %.3f %.3f %.3f 0 0 0 %.2f\n", t_ms, p.x(), p.y(), p.z(), actuation);
  return buf;
}

// The scripted hand for the first case: the tool tracker's keyframes, from where this case's tissue
// really lies. Target: on a case with a membrane, a membrane vertex half-way out from its middle on
// the side of the tool's port (where a surgeon starts a peel); else the case's region of interest.
std::string tool_script(const vitreo::rig::PreparedCase& c) {
  const vitreo::core::Scene& s = *c.scene;
  const Vec3 port = c.tracker_ports[vitreo::rig::kToolTracker].position_mm;
  Vec3 target = c.focus_mm;
  bool membrane = false;
  if (!s.membranes.empty()) {
    const auto& surf = s.world.surface(s.membranes.front().surface);
    Vec3 centroid = Vec3::Zero();
    int n = 0;
    for (std::uint32_t v = 0; v < surf.vertex_slots(); ++v) {
      if (surf.vertex_alive(v)) centroid += surf.position(v), ++n;
    }
    if (n > 0) {
      centroid /= n;
      double radius = 0.0;
      for (std::uint32_t v = 0; v < surf.vertex_slots(); ++v) {
        if (surf.vertex_alive(v)) radius = std::max(radius, (surf.position(v) - centroid).norm());
      }
      double best = std::numeric_limits<double>::infinity();
      for (std::uint32_t v = 0; v < surf.vertex_slots(); ++v) {
        if (!surf.vertex_alive(v)) continue;
        const double r = (surf.position(v) - centroid).norm();
        if (r < 0.4 * radius || r > 0.6 * radius) continue;
        const double d = (surf.position(v) - port).norm();
        if (d < best) best = d, target = surf.position(v);
      }
      membrane = true;
    }
  }
  const Vec3 inward = -target.normalized();                  // toward the globe centre
  const Vec3 along = (target - port).normalized();           // the shaft's direction at the target
  const Vec3 outside = port - 1.5 * along;                   // tip just out of the cannula
  const Vec3 inside = port + 3.0 * along;
  const Vec3 hover = target + 1.0 * inward;
  const Vec3 touch = target + (membrane ? 0.02 : 0.3) * inward;
  const Vec3 sideways = (port - target) - (port - target).dot(inward) * inward;
  const Vec3 pulled = touch + 2.5 * inward + 1.0 * sideways.normalized();
  std::string script = "device tracker\nrate_hz 1000\nserial 1001\ntool 3\ninstrument 0\nloop 0\n";
  script += key(0, outside, 0);
  script += key(600, inside, 0);
  script += key(1600, hover, 0);
  script += key(2200, touch, 0);
  script += key(2500, touch, 1);     // close the jaws on the membrane
  script += key(3700, pulled, 1);    // peel: up and toward the port
  script += key(4100, pulled, 0);    // let go
  script += key(4800, outside, 0);   // withdraw
  return script;
}

const char* kPedalScript = "device pedals\nrate_hz 500\nserial 2001\nloop 0\nkey 0 0 0 0\nkey 5000 0 0 0\n";
const char* kEyeballScript =
    "device eyeball\nrate_hz 250\nserial 3001\nloop 0\n"
    "key 0 0 0 0 0 0\nkey 4200 0 0 0 0 0\nkey 4800 2 -1 0 0 0\n";

std::string lcm_file_url(const fs::path& p) { return "file://" + p.string() + "?mode=w"; }

// --display CARD[:CONNECTOR[:sbs|left|right]]
vitreo::render::KmsOptions parse_display(const std::string& spec) {
  vitreo::render::KmsOptions o;
  const auto a = spec.find(':');
  o.card = spec.substr(0, a);
  if (a != std::string::npos) {
    const auto b = spec.find(':', a + 1);
    o.connector = spec.substr(a + 1, b == std::string::npos ? std::string::npos : b - a - 1);
    if (b != std::string::npos) {
      const std::string layout = spec.substr(b + 1);
      if (layout == "left") o.layout = vitreo::render::DisplayLayout::LeftEye;
      else if (layout == "right") o.layout = vitreo::render::DisplayLayout::RightEye;
      else if (layout != "sbs") throw std::runtime_error("--display " + spec + ": layout must be sbs, left or right");
    }
  }
  if (o.card.empty()) throw std::runtime_error("--display " + spec + ": no card (e.g. /dev/dri/card0)");
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  double duration_s = 5.0;
  int retina_vertices = 5000;  // keeps up with 1 kHz on this 2-core machine; a rig PC runs the case's own
  int texture_px = 0;
  std::vector<std::string> case_files;
  std::string cases_dir;
  std::string first_case;
  std::string out_dir = "vitreo-out";
  std::string cache_dir;
  std::string lcm_url;
  std::string replay_path;
  std::string pedal_config;
  std::vector<std::string> serial_devices;
  bool realtime = false;
  bool verify_replay = true;
  bool render = true;
  bool commands_from_stdin = false;
  int eye_width = 640;

  CLI::App app{"vitreo: vitreoretinal surgery training rig — the real-time simulation process.\n"
               "Default: simulated tracker, pedals and eyeball fixture over ptys peel the membrane of the case\n"
               "scenes/low_membrane_macula.toml; stereo frames, telemetry to an LCM log, the session recorded\n"
               "and then replayed to verify it. Operator commands: vitreo-cmd (LCM) or typed on this terminal."};
  app.add_option("--duration", duration_s, "session length in seconds")->check(CLI::Range(0.01, 36000.0));
  app.add_option("--case", case_files, "a case file (repeatable: the case list, in order; the first starts)")
      ->check(CLI::ExistingFile);
  app.add_option("--cases", cases_dir, "every *.toml case in this folder, sorted (default: scenes/)")
      ->check(CLI::ExistingDirectory);
  app.add_option("--start", first_case, "with --cases: the file name to start with (default low_membrane_macula.toml)");
  app.add_option("--retina-vertices", retina_vertices,
                 "retina resolution override (0 = the case's own; default 5000 keeps up with 1 kHz on 2 cores)")
      ->check(CLI::Range(0, 2'000'000));
  app.add_option("--texture-size", texture_px, "fundus texture size override in pixels (0 = the case's own)")
      ->check(CLI::Range(0, 8192));
  app.add_option("--out", out_dir, "folder for frames, the telemetry log, the recording and snapshots");
  app.add_option("--cache", cache_dir, "folder for settled case starts (default: OUT/case-cache)");
  app.add_option("--lcm-url", lcm_url,
                 "publish telemetry live on this LCM URL (e.g. udpm://239.255.76.67:7667?ttl=0) instead of to a log");
  app.add_option("--serial", serial_devices,
                 "a real device instead of the simulators: KIND=PATH with KIND tracker|pedals|eyeball (repeatable)");
  app.add_option("--pedal-config", pedal_config, "TOML pedal mapping (see rig/config/default-rig.toml)")
      ->check(CLI::ExistingFile);
  app.add_option("--replay", replay_path,
                 "replay a recording as fast as possible (its cases come from the recording) and print its final state hash")
      ->check(CLI::ExistingFile);
  app.add_flag("--realtime", realtime, "ask for SCHED_FIFO, locked memory and a dedicated core for physics");
  app.add_flag("!--no-verify", verify_replay, "do not replay the recording at the end");
  app.add_flag("!--no-render", render, "no stereo frames (EGL) at all");
  app.add_flag("--commands-from-stdin", commands_from_stdin,
               "read operator commands from stdin even when it is not a terminal (a pipe, a script); when it is a\n"
               "terminal they are read anyway: n(ext) p(rev) pause resume r(eset) s NAME w(ireframe) l(abels) z X,\n"
               "pan X Y, focus F, flat, wide, invert");
  std::vector<std::string> displays;
  app.add_option("--display", displays,
                 "show the frames on a rig display through KMS: CARD[:CONNECTOR[:sbs|left|right]], e.g.\n"
                 "/dev/dri/card0:HDMI-A-1:left (repeatable: one per eyepiece display; default: first connected, side by side)");
  app.add_option("--eye-size", eye_width, "width of each eye's image in pixels (height = 4/5 of it)")
      ->check(CLI::Range(64, 4096));
  std::string frame_ring, instructor_ring;
  app.add_option("--frame-ring", frame_ring, "publish the stereo frames in this shared-memory ring (e.g. /vitreo-frames)");
  app.add_option("--instructor-ring", instructor_ring,
                 "publish the instructor's view (left eye, score, retina force, events) in this shared-memory ring\n"
                 "(e.g. /vitreo-instructor); it is also written beside the frames as step_*_instructor.png");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  vitreo::rig::ModelConfig model;
  try {
    if (!pedal_config.empty()) {
      std::FILE* f = std::fopen(pedal_config.c_str(), "rb");
      std::string text;
      char buf[4096];
      for (std::size_t n; f && (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
      if (f) std::fclose(f);
      model.pedals = vitreo::rig::parse_pedal_mapping(text, pedal_config);
    }
    fs::create_directories(out_dir);
    const auto out = fs::absolute(out_dir);
    model.load.cache_dir = cache_dir.empty() ? (out / "case-cache").string() : cache_dir;

    if (!replay_path.empty()) {
      const auto r = vitreo::rig::replay_session(replay_path, model);
      std::printf("replay of %s (case %s, %zu in its list)\n  %llu steps, %llu inputs, %.2f s wall (%.1fx real time)\n"
                  "  state hash %016llx\n",
                  replay_path.c_str(), r.case_id.c_str(), r.cases.size(), static_cast<unsigned long long>(r.steps),
                  static_cast<unsigned long long>(r.inputs), r.wall_s, static_cast<double>(r.steps) * 1e-3 / r.wall_s,
                  static_cast<unsigned long long>(r.state_hash));
      for (const auto& line : r.score_lines) std::printf("  score  %s\n", line.c_str());
      return 0;
    }

    // The case list: --case files in order, or a folder's cases (scenes/ by default).
    std::vector<std::string> files = case_files;
    if (files.empty()) {
      files = cases_in(cases_dir.empty() ? default_scenes_dir() : cases_dir);
      const std::string start = first_case.empty() ? kDefaultCase : first_case;
      const auto it = std::find_if(files.begin(), files.end(), [&](const std::string& f) { return fs::path(f).filename() == start; });
      if (it == files.end() && !first_case.empty()) throw std::runtime_error("--start " + first_case + ": not in the case folder");
      model.first_case = it == files.end() ? 0 : static_cast<int>(it - files.begin());
    }
    for (const auto& f : files) model.cases.push_back(vitreo::scene_io::read_case_text(f));
    model.load.retina_vertices = retina_vertices;
    model.load.texture_size_px = texture_px;

    vitreo::rig::SessionConfig config;
    config.model = model;
    config.steps = static_cast<std::uint64_t>(std::llround(duration_s / model.dt_s));
    config.lcm_url = lcm_url.empty() ? lcm_file_url(out / "telemetry.lcmlog") : lcm_url;
    config.record_path = (out / "session.lcmlog").string();
    config.snapshot_dir = out.string();
    config.realtime = realtime;
    config.render = render;
    if (commands_from_stdin || ::isatty(STDIN_FILENO)) {
      config.command_fd = STDIN_FILENO;
      std::printf("operator commands: n(ext) p(rev) pause resume r(eset) s NAME w(ireframe) l(abels) z X pan X Y focus F flat wide invert — one per line\n");
      std::fflush(stdout);
    }
    config.eye_width = eye_width;
    config.eye_height = eye_width * 4 / 5;
    config.png_dir = (out / "frames").string();
    config.png_every_frames = 10;
    config.frame_ring_name = frame_ring;
    config.instructor_ring_name = instructor_ring;
    if (render) fs::create_directories(config.png_dir);
    for (const auto& d : displays) config.displays.push_back(parse_display(d));
    if (!config.displays.empty() && !render) throw std::runtime_error("--display needs rendering (drop --no-render)");
    if (serial_devices.empty()) {
      const std::string base = "/tmp/vitreo-" + std::to_string(::getpid());
      config.devices = {{"tracker-0", base + "-tracker", 1, 0, ""},
                        {"pedals", base + "-pedals", 2, 0, kPedalScript},
                        {"eyeball", base + "-eyeball", 3, 0, kEyeballScript}};
      // The tracker's script follows the first case's anatomy (known once it is loaded).
      config.adapt_devices = [](const vitreo::rig::PreparedCase& c, std::vector<vitreo::rig::DeviceSpec>& devices) {
        devices[0].sim_script = tool_script(c);
      };
    } else {
      int id = 1;
      for (const auto& spec : serial_devices) {
        const auto eq = spec.find('=');
        if (eq == std::string::npos) throw std::runtime_error("--serial expects KIND=PATH, got '" + spec + "'");
        config.devices.push_back({spec.substr(0, eq), spec.substr(eq + 1), id++, 0, ""});
      }
    }

    spdlog::info("session: {} steps of {} ms on {} ({} cases in the list); telemetry → {}", config.steps, model.dt_s * 1e3,
                 files[static_cast<std::size_t>(model.first_case)], files.size(), config.lcm_url);
    const auto s = vitreo::rig::run_session(config);

    std::printf("vitreo session summary\n");
    std::printf("  case             %s — %s\n", s.case_name.c_str(), s.case_title.c_str());
    std::printf("  case file        %s (%s; %zu cases in the list)\n", s.case_file.c_str(),
                s.case_from_cache ? "settled start from the cache" : "settled now, cached", files.size());
    std::printf("  retina           %s vertices\n", retina_vertices > 0 ? std::to_string(retina_vertices).c_str() : "the case's");
    std::printf("  instruments      %s\n", s.instruments.c_str());
    for (const auto& line : s.cases_loaded) std::printf("  case loaded      %s\n", line.c_str());
    std::printf("  simulated        %.3f s in %llu steps\n", s.simulated_s, static_cast<unsigned long long>(s.steps));
    std::printf("  step time        p50 %.0f us, p99 %.0f us, max %.0f us; %llu overruns, %llu late, %llu dropped\n",
                s.loop.step_p50_ns * 1e-3, s.loop.step_p99_ns * 1e-3, s.loop.step_max_ns * 1e-3,
                static_cast<unsigned long long>(s.loop.overruns), static_cast<unsigned long long>(s.loop.late_steps),
                static_cast<unsigned long long>(s.loop.dropped_steps));
    std::printf("  inputs           %llu applied, %llu refused, %llu recorded (%llu dropped)\n",
                static_cast<unsigned long long>(s.inputs_applied), static_cast<unsigned long long>(s.inputs_refused),
                static_cast<unsigned long long>(s.inputs_recorded), static_cast<unsigned long long>(s.recorder_dropped));
    for (const auto& line : s.device_lines) std::printf("  device           %s\n", line.c_str());
    std::printf("  events           %llu grasps, %llu burns, %llu attachments broken, %llu tears, %llu instrument events, "
                "%llu steps rolled back\n",
                static_cast<unsigned long long>(s.grasps), static_cast<unsigned long long>(s.burns),
                static_cast<unsigned long long>(s.attachments_broken), static_cast<unsigned long long>(s.tears),
                static_cast<unsigned long long>(s.instrument_events), static_cast<unsigned long long>(s.rolled_back));
    std::printf("  telemetry        %llu messages (%llu dropped) → %s\n",
                static_cast<unsigned long long>(s.telemetry_published), static_cast<unsigned long long>(s.telemetry_dropped),
                config.lcm_url.c_str());
    std::printf("  recording        %s\n", config.record_path.c_str());
    for (const auto& line : s.snapshots) std::printf("  snapshot         %s\n", line.c_str());
    if (render) {
      std::printf("  frames           %llu stereo frames %dx%d per eye (%s); %zu written to %s, the last: %s\n",
                  static_cast<unsigned long long>(s.frames_rendered), config.eye_width, config.eye_height, s.renderer.c_str(),
                  s.pngs.size(), config.png_dir.c_str(), s.pngs.empty() ? "none" : (s.pngs.back() + "_stereo.png").c_str());
      std::printf("  instructor view  %s%s\n", s.pngs.empty() ? "none" : (s.pngs.back() + "_instructor.png").c_str(),
                  instructor_ring.empty() ? "" : (" and the shared-memory ring " + instructor_ring).c_str());
    }
    for (const auto& line : s.displays) std::printf("  display          %s\n", line.c_str());
    for (std::size_t i = 0; i < s.score_lines.size(); ++i)
      std::printf("  %s %s\n", i == 0 ? "score           " : "                ", s.score_lines[i].c_str());
    std::printf("  state hash       %016llx\n", static_cast<unsigned long long>(s.state_hash));
    if (verify_replay) {
      const auto r = vitreo::rig::replay_session(config.record_path, model);
      const bool same = r.state_hash == s.state_hash && r.score_lines == s.score_lines;
      std::printf("  replay           %llu steps in %.2f s (%.1fx real time), cases from the recording: %s\n",
                  static_cast<unsigned long long>(r.steps), r.wall_s, static_cast<double>(r.steps) * model.dt_s / r.wall_s,
                  same ? "identical final state and score" : "DIFFERENT final state");
      if (!same) return 3;
    }
    return s.rolled_back == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
