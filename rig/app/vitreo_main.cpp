// vitreo — the rig's main job.
//
// Without options it runs its embedded default: simulated devices (an instrument tracker, the foot
// pedals and the eyeball fixture, as firmware emulators behind ptys) playing a scripted approach on
// the retina scene, through the real drivers, a fixed-step physics thread, telemetry to an LCM log
// and a recording — then replays the recording and checks it ends in the same state.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "rig/session/rig_session.hpp"

namespace {

using vitreo::core::Vec3;

// Three sclerotomies on the pars plana, 30° anterior of the equator: two working ports (temporal,
// nasal) and the infusion (inferior). +x is nasal, +z anterior.
std::vector<vitreo::rig::Port> default_ports(double globe_radius_mm) {
  std::vector<vitreo::rig::Port> ports;
  const double el = 30.0 * std::numbers::pi / 180.0;
  for (double az_deg : {160.0, 20.0, -100.0}) {
    const double az = az_deg * std::numbers::pi / 180.0;
    vitreo::rig::Port p;
    p.outward = Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    p.position_mm = (globe_radius_mm - 0.5) * p.outward;
    ports.push_back(p);
  }
  return ports;
}

// The embedded demonstration: forceps through the temporal port reach over the detachment, close,
// lift and sweep, then withdraw; the surgeon works the vitrectomy pedal and rolls the eye a little.
const char* kTrackerScript =
    "device tracker\nrate_hz 1000\nserial 1001\ntool 3\ninstrument 0\n"
    "key 0 -12.5 3.7 6.2 0 0 0 0\n"
    "key 800 -9 2 1 0 0 0 0\n"
    "key 1800 -8 0.5 -4.5 0 0 0 0\n"
    "key 2300 -8.5 0 -5.2 0 0 0 1\n"
    "key 3300 -7 -1.5 -3.5 0 0 20 1\n"
    "key 3800 -7 -1.5 -3.5 0 0 20 0\n"
    "key 4600 -12.5 3.7 6.2 0 0 0 0\n";
const char* kPedalScript =
    "device pedals\nrate_hz 500\nserial 2001\n"
    "key 0 0 0 0\nkey 1000 0.6 0.3 0\nkey 2500 0.9 0.5 0\nkey 3500 0 0 4\nkey 4000 0 0 0\n";
const char* kEyeballScript =
    "device eyeball\nrate_hz 250\nserial 3001\n"
    "key 0 0 0 0 0 0\nkey 1500 4 -2 10 0 0\nkey 3000 -3 2 10 0 0\nkey 4500 0 0 0 0 0\n";

std::string lcm_file_url(const std::filesystem::path& p) { return "file://" + p.string() + "?mode=w"; }

}  // namespace

int main(int argc, char** argv) {
  double duration_s = 5.0;
  int retina_vertices = 5000;  // keeps up with 1 kHz on this 2-core machine; a rig PC runs 20k
  bool membrane = true;
  int substeps = 2;
  std::string out_dir = "vitreo-out";
  std::string lcm_url;
  std::string replay_path;
  std::string pedal_config;
  std::vector<std::string> serial_devices;
  bool realtime = false;
  bool verify_replay = true;
  bool render = true;
  int eye_width = 640, eye_height = 512;

  CLI::App app{"vitreo: vitreoretinal surgery training rig — the real-time simulation process.\n"
               "Default: simulated tracker, pedals and eyeball fixture over ptys drive the retina scene;\n"
               "telemetry goes to an LCM log, the session is recorded and then replayed to verify it."};
  app.add_option("--duration", duration_s, "session length in seconds")->check(CLI::Range(0.01, 36000.0));
  app.add_option("--retina-vertices", retina_vertices, "retina mesh resolution")->check(CLI::Range(100, 2'000'000));
  app.add_flag("!--no-membrane", membrane, "leave out the epiretinal membrane");
  app.add_option("--substeps", substeps, "solver substeps per 1 ms step")->check(CLI::Range(1, 64));
  app.add_option("--out", out_dir, "folder for the telemetry log and the recording");
  app.add_option("--lcm-url", lcm_url,
                 "publish telemetry live on this LCM URL (e.g. udpm://239.255.76.67:7667?ttl=0) instead of to a log");
  app.add_option("--serial", serial_devices,
                 "a real device instead of the simulators: KIND=PATH with KIND tracker|pedals|eyeball (repeatable)");
  app.add_option("--pedal-config", pedal_config, "TOML pedal mapping (see rig/config/default-rig.toml)")
      ->check(CLI::ExistingFile);
  app.add_option("--replay", replay_path, "replay a recording as fast as possible and print its final state hash")
      ->check(CLI::ExistingFile);
  app.add_flag("--realtime", realtime, "ask for SCHED_FIFO, locked memory and a dedicated core for physics");
  app.add_flag("!--no-verify", verify_replay, "do not replay the recording at the end");
  app.add_flag("!--no-render", render, "no stereo frames (EGL) at all");
  app.add_option("--eye-size", eye_width, "width of each eye's image in pixels (height = 4/5 of it)")
      ->check(CLI::Range(64, 4096));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  vitreo::rig::ModelConfig model;
  model.scene.retina_vertices = retina_vertices;
  model.scene.membrane = membrane;
  model.scene.solver.substeps = substeps;
  model.ports = default_ports(model.scene.globe_radius_mm);
  try {
    if (!pedal_config.empty()) {
      std::FILE* f = std::fopen(pedal_config.c_str(), "rb");
      std::string text;
      char buf[4096];
      for (std::size_t n; f && (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
      if (f) std::fclose(f);
      model.pedals = vitreo::rig::parse_pedal_mapping(text, pedal_config);
    }

    if (!replay_path.empty()) {
      const auto r = vitreo::rig::replay_session(replay_path, model);
      std::printf("replay of %s (case %s)\n  %llu steps, %llu inputs, %.2f s wall (%.1fx real time)\n  state hash %016llx\n",
                  replay_path.c_str(), r.case_id.c_str(), static_cast<unsigned long long>(r.steps),
                  static_cast<unsigned long long>(r.inputs), r.wall_s, static_cast<double>(r.steps) * 1e-3 / r.wall_s,
                  static_cast<unsigned long long>(r.state_hash));
      return 0;
    }

    std::filesystem::create_directories(out_dir);
    const auto out = std::filesystem::absolute(out_dir);
    vitreo::rig::SessionConfig config;
    config.model = model;
    config.steps = static_cast<std::uint64_t>(std::llround(duration_s / model.dt_s));
    config.lcm_url = lcm_url.empty() ? lcm_file_url(out / "telemetry.lcmlog") : lcm_url;
    config.record_path = (out / "session.lcmlog").string();
    config.realtime = realtime;
    config.render = render;
    eye_height = eye_width * 4 / 5;
    config.eye_width = eye_width;
    config.eye_height = eye_height;
    config.png_dir = (out / "frames").string();
    config.png_every_frames = 10;
    if (render) std::filesystem::create_directories(config.png_dir);
    config.config_text = "retina-cap vertices=" + std::to_string(retina_vertices) + " substeps=" + std::to_string(substeps);
    if (serial_devices.empty()) {
      const std::string base = "/tmp/vitreo-" + std::to_string(::getpid());
      config.devices = {{"tracker-0", base + "-tracker", 1, 0, kTrackerScript},
                        {"pedals", base + "-pedals", 2, 0, kPedalScript},
                        {"eyeball", base + "-eyeball", 3, 0, kEyeballScript}};
    } else {
      int id = 1;
      for (const auto& spec : serial_devices) {
        const auto eq = spec.find('=');
        if (eq == std::string::npos) throw std::runtime_error("--serial expects KIND=PATH, got '" + spec + "'");
        config.devices.push_back({spec.substr(0, eq), spec.substr(eq + 1), id++, 0, ""});
      }
    }

    spdlog::info("session: {} steps of {} ms on a {}-vertex retina; telemetry → {}", config.steps, model.dt_s * 1e3,
                 retina_vertices, config.lcm_url);
    const auto s = vitreo::rig::run_session(config);

    std::printf("vitreo session summary\n");
    std::printf("  case             retina with a bullous detachment%s (%d vertices)\n", membrane ? " and an epiretinal membrane" : "",
                retina_vertices);
    std::printf("  simulated        %.3f s in %llu steps\n", s.simulated_s, static_cast<unsigned long long>(s.steps));
    std::printf("  step time        p50 %.0f us, p99 %.0f us, max %.0f us; %llu overruns, %llu late, %llu dropped\n",
                s.loop.step_p50_ns * 1e-3, s.loop.step_p99_ns * 1e-3, s.loop.step_max_ns * 1e-3,
                static_cast<unsigned long long>(s.loop.overruns), static_cast<unsigned long long>(s.loop.late_steps),
                static_cast<unsigned long long>(s.loop.dropped_steps));
    std::printf("  inputs           %llu applied, %llu refused, %llu recorded (%llu dropped)\n",
                static_cast<unsigned long long>(s.inputs_applied), static_cast<unsigned long long>(s.inputs_refused),
                static_cast<unsigned long long>(s.inputs_recorded), static_cast<unsigned long long>(s.recorder_dropped));
    for (const auto& line : s.device_lines) std::printf("  device           %s\n", line.c_str());
    std::printf("  events           %llu tears, %llu attachments broken, %llu instrument events, %llu steps rolled back\n",
                static_cast<unsigned long long>(s.tears), static_cast<unsigned long long>(s.attachments_broken),
                static_cast<unsigned long long>(s.instrument_events), static_cast<unsigned long long>(s.rolled_back));
    std::printf("  telemetry        %llu messages (%llu dropped) → %s\n",
                static_cast<unsigned long long>(s.telemetry_published), static_cast<unsigned long long>(s.telemetry_dropped),
                config.lcm_url.c_str());
    std::printf("  recording        %s\n", config.record_path.c_str());
    if (render) {
      std::printf("  frames           %llu stereo frames %dx%d per eye (%s); %zu written to %s, the last: %s\n",
                  static_cast<unsigned long long>(s.frames_rendered), eye_width, eye_height, s.renderer.c_str(), s.pngs.size(),
                  config.png_dir.c_str(), s.pngs.empty() ? "none" : (s.pngs.back() + "_stereo.png").c_str());
    }
    std::printf("  state hash       %016llx\n", static_cast<unsigned long long>(s.state_hash));
    if (verify_replay) {
      const auto r = vitreo::rig::replay_session(config.record_path, model);
      const bool same = r.state_hash == s.state_hash;
      std::printf("  replay           %llu steps in %.2f s (%.1fx real time): %s\n", static_cast<unsigned long long>(r.steps),
                  r.wall_s, static_cast<double>(r.steps) * model.dt_s / r.wall_s,
                  same ? "identical final state" : "DIFFERENT final state");
      if (!same) return 3;
    }
    return s.rolled_back == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
