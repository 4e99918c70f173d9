// vitreo — the rig's main job.
//
// Without options it runs its embedded default: simulated devices (an instrument tracker, the foot
// pedals and the eyeball fixture, as firmware emulators behind ptys) playing the expert surgical
// script of a real case from scenes/ (scenes/scripts/low_membrane_macula.expert.toml), in lockstep,
// through the real drivers, a fixed-step physics thread, stereo frames, telemetry to an LCM log and
// a recording — then replays the recording and checks it ends in the same state.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "rig/app/cli_checks.hpp"
#include "rig/app/stop_signals.hpp"
#include "rig/files/data_dir.hpp"
#include "rig/files/read_text_file.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/report/trainee_history.hpp"
#include "rig/report/write_report.hpp"
#include "rig/session/calibration_in_force.hpp"
#include "rig/session/rig_session.hpp"
#include "rig/session/scripted_session.hpp"

namespace {

using vitreo::core::Vec3;
namespace fs = std::filesystem;

// The case a first-time user sees: a membrane peel shows approach, grasp and pull at a glance.
constexpr const char* kDefaultCase = "low_membrane_macula.toml";

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

// The case's own scripted surgeon, beside the cases: scripts/<case>.<kind>.toml.
std::string case_script(const std::string& cases_dir, const std::string& case_file, const std::string& kind) {
  return (fs::path(cases_dir) / "scripts" / (fs::path(case_file).stem().string() + "." + kind + ".toml")).string();
}

std::string lcm_file_url(const fs::path& p) { return "file://" + p.string() + "?mode=w"; }

// fsync a file:// LCM log after its writer closed it, so a stopped rig leaves its telemetry on disk.
void sync_file(const std::string& lcm_url) {
  if (lcm_url.rfind("file://", 0) != 0) return;
  std::string path = lcm_url.substr(7);
  path = path.substr(0, path.find('?'));
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
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
  std::string rig_path;
  std::string calibration_path;
  double calibration_max_age_days = -1.0;  // unset: the rig file's, else 30
  std::string calibration_in_force = "none (uncalibrated input mapping)";  // for the summary
  std::string script_path;
  bool idle = false;
  std::vector<std::string> serial_devices;
  std::vector<std::string> sim_unplugs;
  bool realtime = false;
  bool lockstep = false, no_lockstep = false, unpaced = false;
  bool verify_replay = true;
  bool render = true;
  bool commands_from_stdin = false;
  int eye_width = 640;

  CLI::App app{"vitreo: vitreoretinal surgery training rig — the real-time simulation process.\n"
               "Default: simulated tracker, pedals and eyeball fixture over ptys peel the membrane of the case\n"
               "scenes/low_membrane_macula.toml; stereo frames, telemetry to an LCM log, the session recorded\n"
               "and then replayed to verify it. Operator commands: vitreo-cmd (LCM) or typed on this terminal."};
  auto* duration_opt = app.add_option("--duration", duration_s, "session length in seconds")
                           ->check(vitreo::app::finite_range(0.01, 36000.0));
  auto* case_opt = app.add_option("--case", case_files, "a case file (repeatable: the case list, in order; the first starts)")
                       ->check(CLI::ExistingFile);
  auto* cases_opt = app.add_option("--cases", cases_dir, "every *.toml case in this folder, sorted (default: ./scenes, else the installed cases, else the source tree's)")
                        ->check(CLI::ExistingDirectory);
  auto* start_opt =
      app.add_option("--start", first_case, "with --cases: the file name to start with (default low_membrane_macula.toml)");
  auto* retina_opt = app.add_option("--retina-vertices", retina_vertices,
                                    "retina resolution override (0 = the case's own; default 5000 keeps up with 1 kHz on 2 cores)")
                         ->check(CLI::Range(0, 2'000'000));
  unsigned physics_threads = 1;
  app.add_option("--physics-threads", physics_threads,
                 "threads the tissue step splits its independent passes over (1-64; the vertex sweep stays on one).\n"
                 "The simulation's state is the same bit for bit at any count; more threads only shorten the step\n"
                 "on a machine with cores to spare (default 1; not with --realtime)")
      ->check(CLI::Range(1u, 64u));
  auto* texture_opt = app.add_option("--texture-size", texture_px, "fundus texture size override in pixels (0 = the case's own)")
                          ->check(CLI::Range(0, 8192));
  app.add_option("--out", out_dir, "folder for frames, the telemetry log, the recording and snapshots");
  app.add_option("--cache", cache_dir, "folder for settled case starts (default: OUT/case-cache)");
  auto* lcm_opt = app.add_option("--lcm-url", lcm_url,
                 "publish telemetry live on this LCM URL (e.g. udpm://239.255.76.67:7667?ttl=0) instead of to a log");
  auto* rig_option = app.add_option("--rig", rig_path,
                                    "the rig's devices from a rig file (rig/config/*.toml): each device's URI (serial:, can:, usb:,\n"
                                    "sim:), identity and role, and the pedal mapping (default: simulated devices over ptys)")
                         ->check(CLI::ExistingFile);
  auto* serial_opt = app.add_option("--serial", serial_devices,
                 "a real serial device instead of the simulators: KIND=PATH with KIND tracker|pedals|eyeball (repeatable)")
      ->excludes(rig_option);
  app.add_option("--sim-unplug", sim_unplugs,
                 "simulated devices: pull NAME's cable AT seconds into the session (physics time) and plug it back FOR\n"
                 "seconds later: NAME:AT:FOR, e.g. tracker-0:1.5:0.5 (repeatable)");
  app.add_option("--calibration", calibration_path,
                 "the sensor calibration to apply (vitreo-calibrate's file; overrides the rig file's [calibration])\n"
                 "refused when made for other devices' serial numbers")
      ->check(CLI::ExistingFile);
  app.add_option("--calibration-max-age-days", calibration_max_age_days, "warn when the calibration is older than this (default 30)")
      ->check(vitreo::app::finite_range(0.001, 36500.0));
  app.add_option("--pedal-config", pedal_config, "TOML pedal mapping (see rig/config/default-rig.toml; overrides the rig file's)")
      ->check(CLI::ExistingFile);
  auto* replay_opt =
      app.add_option("--replay", replay_path,
                     "replay a recording as fast as possible (its cases and settings come from the recording) and print\n"
                     "its verdict and final state hash. Exit status: 0 complete and the recorded final state reached,\n"
                     "3 a different final state, 4 truncated, 5 corrupted (replayed up to there), 1 unreadable")
          ->check(CLI::ExistingFile);
  auto* realtime_opt = app.add_flag("--realtime", realtime, "ask for SCHED_FIFO, locked memory and a dedicated core for physics");
  auto* script_opt = app.add_option("--script", script_path,
                 "play this surgical script (scenes/scripts/*.toml) with the simulated devices (default: the first case's\n"
                 "expert script, scenes/scripts/CASE.expert.toml, when it has one)")
                         ->check(CLI::ExistingFile);
  std::string trainee;
  app.add_option("--trainee", trainee, "who does the session (1-64 characters of A-Z a-z 0-9 . _ -): kept in OUT/trainee.txt and "
                 "named in the report, for `vitreo-report --trainee ID` (a learning curve)")
      ->check([](const std::string& id) { return vitreo::report::valid_trainee_id(id) ? std::string() : "1-64 characters of A-Z a-z 0-9 . _ -"; });
  auto* idle_opt = app.add_flag("--idle", idle, "play no script: the simulated hand stays outside the eye, the pedals at rest")->excludes(script_opt);
  std::uint64_t script_seed = 1;
  auto* script_seed_opt =
      app.add_option("--script-seed", script_seed,
                     "play the script with this seed for its sensor noise and tremor instead of its own `seed` (another\n"
                     "realisation of the same hand: does the script's outcome hold up, or did one noise sample decide it?)")
          ->check(CLI::Range(std::uint64_t{0}, std::uint64_t{1'000'000'000'000'000}))  // the script file's own range
          ->excludes(idle_opt)
          ->excludes(serial_opt);
  auto* lockstep_opt = app.add_flag("--lockstep", lockstep,
               "simulated devices on the simulation's clock: each step waits for its inputs, so a scripted session\n"
               "receives the same samples at the same steps however loaded the machine is (the default when every\n"
               "device is simulated)");
  app.add_flag("--no-lockstep", no_lockstep, "simulated devices on the wall clock, as real ones run")->excludes(lockstep_opt);
  app.add_flag("--unpaced", unpaced, "in lockstep: run as fast as the machine goes instead of at real time");
  app.add_flag("!--no-verify", verify_replay, "do not replay the recording at the end");
  app.add_flag("!--no-render", render, "no stereo frames (EGL) at all");
  auto* stdin_opt = app.add_flag("--commands-from-stdin", commands_from_stdin,
               "read operator commands from stdin even when it is not a terminal (a pipe, a script); when it is a\n"
               "terminal they are read anyway: n(ext) p(rev) pause resume r(eset) s NAME w(ireframe) l(abels) z X,\n"
               "pan X Y, focus F, flat, wide, invert, laser_power MW, laser_duration MS");
  std::vector<std::string> displays;
  auto* display_opt = app.add_option("--display", displays,
                 "show the frames on a rig display through KMS: CARD[:CONNECTOR[:sbs|left|right]], e.g.\n"
                 "/dev/dri/card0:HDMI-A-1:left (repeatable: one per eyepiece display; default: first connected, side by side)");
  app.add_option("--eye-size", eye_width, "width of each eye's image in pixels (height = 4/5 of it)")
      ->check(CLI::Range(64, 4096));
  std::string frame_ring, instructor_ring;
  app.add_option("--frame-ring", frame_ring, "publish the stereo frames in this shared-memory ring (e.g. /vitreo-frames)");
  app.add_option("--instructor-ring", instructor_ring,
                 "publish the instructor's view (left eye, score, retina force, events) in this shared-memory ring\n"
                 "(e.g. /vitreo-instructor); it is also written beside the frames as step_*_instructor.png");
  // A replay takes its cases, resolution and length from the recording: options that would choose
  // them are refused rather than silently ignored.
  for (CLI::Option* o : {case_opt, cases_opt, start_opt, retina_opt, texture_opt, duration_opt, serial_opt, rig_option, lcm_opt, realtime_opt,
                         stdin_opt, display_opt, script_seed_opt})
    replay_opt->excludes(o);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "vitreo: %s\n", e.what());  // one line; --help lists the options
    return 2;
  }
  if (realtime && physics_threads > 1) {
    // The workers would be started by the physics thread and inherit its one pinned core and its
    // FIFO priority: they would take turns with it instead of running beside it.
    std::fprintf(stderr, "vitreo: --physics-threads %u with --realtime: the step's workers are not placed on cores of their own yet, "
                 "so they would share the pinned physics core; use one of the two\n", physics_threads);
    return 2;
  }

  vitreo::rig::ModelConfig model;
  try {
    std::vector<vitreo::rig::DeviceSpec> devices;
    if (!rig_path.empty()) {
      vitreo::rig::RigFile rig = vitreo::rig::read_rig_file(rig_path);
      devices = std::move(rig.devices);
      if (rig.pedals) model.pedals = *rig.pedals;
      if (rig.laser) model.laser = *rig.laser;
      if (calibration_path.empty()) calibration_path = rig.calibration_path;
      if (calibration_max_age_days < 0.0 && rig.calibration_max_age_days) calibration_max_age_days = *rig.calibration_max_age_days;
      spdlog::info("rig {}: {} device(s){}", rig_path, devices.size(), rig.name.empty() ? "" : " — " + rig.name);
    }
    if (!pedal_config.empty()) {
      const auto file = vitreo::files::read_text_file(pedal_config);
      if (!file.text) throw std::runtime_error("--pedal-config: " + file.error);
      model.pedals = vitreo::rig::parse_pedal_mapping(*file.text, pedal_config);
    }
    fs::create_directories(out_dir);
    const auto out = fs::absolute(out_dir);
    model.load.cache_dir = cache_dir.empty() ? (out / "case-cache").string() : cache_dir;
    model.load.physics_threads = physics_threads;

    if (!replay_path.empty()) {
      const auto r = vitreo::rig::replay_session(replay_path, model);
      std::printf("replay of %s (case %s, %zu in its list)\n  recording   %s\n"
                  "  replayed    %llu steps, %llu inputs, %.2f s wall (%.1fx real time)\n",
                  replay_path.c_str(), r.case_id.c_str(), r.cases.size(), r.verdict_text.c_str(),
                  static_cast<unsigned long long>(r.steps), static_cast<unsigned long long>(r.inputs), r.wall_s,
                  static_cast<double>(r.steps) * 1e-3 / std::max(r.wall_s, 1e-9));
      if (r.recorded_state_hash) {
        std::printf("  state hash  %016llx — %s the recorded final state (session ended: %s)\n",
                    static_cast<unsigned long long>(r.state_hash), r.matches_recording() ? "identical to" : "DIFFERENT from",
                    r.stop_reason.c_str());
      } else {
        std::printf("  state hash  %016llx (the recording has no final state to compare with)\n",
                    static_cast<unsigned long long>(r.state_hash));
      }
      for (const auto& line : r.score_lines) std::printf("  score       %s\n", line.c_str());
      switch (r.verdict) {
        case vitreo::telemetry::RecordingVerdict::Truncated: return 4;
        case vitreo::telemetry::RecordingVerdict::Corrupted: return 5;
        case vitreo::telemetry::RecordingVerdict::Complete: return r.matches_recording() ? 0 : 3;
      }
      return 1;
    }

    // Who does this session (a replay above leaves the folder's as it was).
    if (!trainee.empty()) {
      std::ofstream(out / "trainee.txt") << trainee << '\n';
    } else {
      fs::remove(out / "trainee.txt");  // a folder reused for another session names no one from before
    }

    // The case list: --case files in order, or a folder's cases (scenes/ by default).
    std::vector<std::string> files = case_files;
    if (files.empty()) {
      files = cases_in(cases_dir.empty() ? vitreo::files::default_scenes_dir() : cases_dir);
      const std::string start = first_case.empty() ? kDefaultCase : first_case;
      const auto it = std::find_if(files.begin(), files.end(), [&](const std::string& f) { return fs::path(f).filename() == start; });
      if (it == files.end() && !first_case.empty()) throw std::runtime_error("--start " + first_case + ": not in the case folder");
      model.first_case = it == files.end() ? 0 : static_cast<int>(it - files.begin());
    }
    for (const auto& f : files) model.cases.push_back(vitreo::scene_io::read_case_text(f));
    model.load.retina_vertices = retina_vertices;
    model.load.texture_size_px = texture_px;

    // The scripted surgeon the simulated devices play: --script, else the first case's expert
    // script beside the cases, else none (the hand stays out, the pedals at rest).
    vitreo::rig::SurgicalScript script;
    script.kind = "idle";
    script.duration_s = duration_s;
    const std::string first_file = files[static_cast<std::size_t>(model.first_case)];
    if (!script_path.empty()) {
      script = vitreo::rig::read_surgical_script(script_path);
    } else if (!idle) {
      const std::string expert = case_script(fs::path(first_file).parent_path().string(), first_file, "expert");
      std::error_code ec;
      if (fs::exists(expert, ec)) script = vitreo::rig::read_surgical_script(expert);
      else spdlog::warn("{} has no expert script ({}): the simulated hand stays outside the eye", first_file, expert);
    }
    if (script_seed_opt->count() > 0) {
      // Only the simulated devices play a script: a seed with nothing to play it would be ignored.
      if (script.file.empty()) throw std::runtime_error("--script-seed: no script plays (" + first_file + " has no expert script; name one with --script)");
      script.seed = script_seed;
    }
    if (script.case_name.empty()) script.case_name = fs::path(first_file).stem().string();
    if (duration_opt->count() == 0 && !script.file.empty()) duration_s = script.duration_s;

    vitreo::rig::SessionConfig config;
    config.model = model;
    config.lcm_url = lcm_url.empty() ? lcm_file_url(out / "telemetry.lcmlog") : lcm_url;
    config.record_path = (out / "session.lcmlog").string();
    config.snapshot_dir = out.string();
    config.realtime = realtime;
    config.unpaced = unpaced;
    config.render = render;
    if (commands_from_stdin || ::isatty(STDIN_FILENO)) {
      config.command_fd = STDIN_FILENO;
      std::printf("operator commands: n(ext) p(rev) pause resume r(eset) s NAME w(ireframe) l(abels) z X pan X Y focus F flat wide invert laser_power MW laser_duration MS — one per line\n");
      std::fflush(stdout);
    }
    config.eye_width = eye_width;
    config.eye_height = eye_width * 4 / 5;
    config.png_dir = (out / "frames").string();
    config.png_every_frames = 10;
    config.frame_ring_name = frame_ring;
    config.instructor_ring_name = instructor_ring;
    if (render) fs::create_directories(config.png_dir);
    for (const auto& d : displays) config.displays.push_back(vitreo::render::parse_display_spec(d));
    if (!config.displays.empty() && !render) throw std::runtime_error("--display needs rendering (drop --no-render)");
    using vitreo::rig::DeviceRole;
    if (!serial_devices.empty()) {
      int id = 1;
      for (const auto& spec : serial_devices) {
        const auto eq = spec.find('=');
        if (eq == std::string::npos) throw std::runtime_error("--serial expects KIND=PATH, got '" + spec + "'");
        const std::string kind = spec.substr(0, eq), path = spec.substr(eq + 1);
        vitreo::rig::DeviceSpec d;
        d.name = kind;
        if (kind == "tracker") d.role = DeviceRole::tracker;
        else if (kind == "pedals") d.role = DeviceRole::pedals;
        else if (kind == "eyeball") d.role = DeviceRole::eyeball;
        else throw std::runtime_error("--serial " + spec + ": unknown device kind '" + kind + "' (tracker, pedals, eyeball)");
        for (const auto& other : devices) {
          if (other.name == kind) throw std::runtime_error("--serial " + spec + ": a second " + kind + " (one of each)");
          if (other.uri == "serial:" + path) throw std::runtime_error("--serial " + spec + ": " + path + " is already the " + other.name);
        }
        if (const std::string why = vitreo::app::serial_port_problem(path); !why.empty())
          throw std::runtime_error("--serial " + spec + ": " + why);
        d.uri = "serial:" + path;
        d.device_id = id++;
        devices.push_back(d);
      }
    } else if (devices.empty()) {
      // The embedded default: the three devices simulated behind ptys.
      devices = vitreo::rig::simulated_devices(script);  // a second tracker when the script has a second hand
    }
    if (!calibration_path.empty()) {
      const auto now_s = std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
      const auto load = vitreo::rig::load_calibration(
          calibration_path, devices, model,
          calibration_max_age_days > 0.0 ? calibration_max_age_days : vitreo::rig::kDefaultCalibrationMaxAgeDays, now_s);
      for (const auto& n : load.notes) spdlog::info("{}", n);
      for (const auto& w : load.warnings) spdlog::warn("{}", w);
      calibration_in_force = calibration_path + " (" + vitreo::rig::calibration_id(load.file) + ")" +
                             (load.warnings.empty() ? "" : " — " + load.warnings.front());
      config.model = model;
      if (load.file.eyepieces) config.eyepieces = vitreo::rig::eyepiece_settings(*load.file.eyepieces);
    }
    config.devices = devices;
    // Lockstep wherever every device is simulated (a scripted session's outcome must not depend on
    // the machine's load); real devices run on their own clocks.
    const bool all_simulated = std::all_of(devices.begin(), devices.end(), [](const auto& d) { return d.uri.rfind("sim:", 0) == 0; });
    if (lockstep && !all_simulated) throw std::runtime_error("--lockstep needs every device simulated (sim:...)");
    if (all_simulated && !no_lockstep) lockstep = true;
    if (unpaced && !lockstep) throw std::runtime_error("--unpaced needs lockstep");
    config.device_mode = lockstep ? vitreo::rig::HubMode::lockstep : vitreo::rig::HubMode::realtime;
    config.steps = static_cast<std::uint64_t>(std::llround(duration_s / model.dt_s));
    struct Unplug {
      std::string name;
      std::uint64_t at_step, back_step;
    };
    std::vector<Unplug> unplugs;
    for (const auto& u : sim_unplugs) {
      const auto a = u.find(':'), b = u.rfind(':');
      char* end = nullptr;
      const double at = a == std::string::npos || a == b ? -1.0 : std::strtod(u.c_str() + a + 1, &end);
      const double len = at < 0.0 ? -1.0 : std::strtod(u.c_str() + b + 1, &end);
      const std::string name = u.substr(0, a);
      if (!(at >= 0.0) || !(len > 0.0) || *end != '\0') throw std::runtime_error("--sim-unplug " + u + ": expected NAME:AT:FOR (seconds)");
      const auto named = std::find_if(devices.begin(), devices.end(), [&](const auto& d) { return d.name == name; });
      if (named == devices.end()) throw std::runtime_error("--sim-unplug " + u + ": no device named " + name);
      if (named->uri.rfind("sim:", 0) != 0) throw std::runtime_error("--sim-unplug " + u + ": " + name + " is not simulated");
      unplugs.push_back({name, static_cast<std::uint64_t>(std::llround(at / model.dt_s)),
                         static_cast<std::uint64_t>(std::llround((at + len) / model.dt_s))});
    }
    if (!unplugs.empty()) {
      config.on_step = [unplugs](std::uint64_t step, vitreo::rig::DeviceHub& hub) {
        for (const auto& u : unplugs) {
          if (step != u.at_step && step != u.back_step) continue;
          for (std::size_t i = 0; i < hub.device_count(); ++i) {
            if (hub.name(i) != u.name) continue;
            step == u.at_step ? hub.unplug(i) : hub.plug(i);
          }
        }
      };
    }
    // Simulated devices without a script of their own play the surgical script, resolved against the
    // first case as loaded (its landmarks at its resolution).
    config.adapt_devices = vitreo::rig::play_script(script, model.pedals, model.microscope);

    static std::atomic<int> stop_signal{0};
    vitreo::app::install_stop_signals(stop_signal);
    config.stop = &stop_signal;
    spdlog::info("session: {} steps of {} ms on {} ({} cases in the list); telemetry → {}", config.steps, model.dt_s * 1e3,
                 files[static_cast<std::size_t>(model.first_case)], files.size(), config.lcm_url);
    const auto s = vitreo::rig::run_session(config);

    std::printf("vitreo session summary\n");
    std::printf("  case             %s — %s\n", s.case_name.c_str(), s.case_title.c_str());
    std::printf("  case file        %s (%s; %zu cases in the list)\n", s.case_file.c_str(),
                s.case_from_cache ? "settled start from the cache" : "settled now, cached", files.size());
    std::printf("  retina           %s vertices\n", retina_vertices > 0 ? std::to_string(retina_vertices).c_str() : "the case's");
    std::printf("  physics threads  %u\n", physics_threads);
    std::printf("  instruments      %s\n", s.instruments.c_str());
    std::printf("  script           %s%s%s\n", script.file.empty() ? "none (idle)" : script.file.c_str(),
                script.file.empty() ? "" : (" (" + script.kind + ", seed " + std::to_string(script.seed) + ")").c_str(),
                script.summary.empty() ? "" : (": " + script.summary).c_str());
    std::printf("  calibration      %s\n", calibration_in_force.c_str());
    std::printf("  laser            %g mW × %g ms per shot", s.laser_at_start.power_mw, s.laser_at_start.duration_ms);
    if (s.laser_at_end.power_mw != s.laser_at_start.power_mw || s.laser_at_end.duration_ms != s.laser_at_start.duration_ms)
      std::printf(", %g mW × %g ms at the end (operator commands)", s.laser_at_end.power_mw, s.laser_at_end.duration_ms);
    std::printf("\n");
    for (const auto& line : s.cases_loaded) std::printf("  case loaded      %s\n", line.c_str());
    std::printf("  simulated        %.3f s in %llu steps (%s)\n", s.simulated_s, static_cast<unsigned long long>(s.steps),
                s.stop_reason == "duration reached" ? "the whole duration" : ("stopped early by " + s.stop_reason).c_str());
    // Said so that nobody reads "dropped" as steps lost: a paced loop that falls behind gives up
    // deadlines (the session runs longer than real time), never steps; and in lockstep a step's time
    // includes the devices' round, which the outcome does not depend on.
    std::printf("  step time        p50 %.0f us, p99 %.0f us, max %.0f us; %llu steps over the %g ms period, %llu started late, "
                "%llu deadlines given up",
                s.loop.step_p50_ns * 1e-3, s.loop.step_p99_ns * 1e-3, s.loop.step_max_ns * 1e-3,
                static_cast<unsigned long long>(s.loop.overruns), model.dt_s * 1e3, static_cast<unsigned long long>(s.loop.late_steps),
                static_cast<unsigned long long>(s.loop.dropped_steps));
    if (s.loop.dropped_steps > 0)
      std::printf(" (%.1f s behind the wall clock; every step simulated)", static_cast<double>(s.loop.slip_ns) * 1e-9);
    if (config.device_mode == vitreo::rig::HubMode::lockstep)
      std::printf("; lockstep: a step includes the devices' round, and the outcome does not depend on its time");
    std::printf("\n");
    std::printf("  inputs           %llu applied, %llu refused, %llu recorded (%llu dropped)\n",
                static_cast<unsigned long long>(s.inputs_applied), static_cast<unsigned long long>(s.inputs_refused),
                static_cast<unsigned long long>(s.inputs_recorded), static_cast<unsigned long long>(s.recorder_dropped));
    for (const auto& line : s.device_lines) std::printf("  device           %s\n", line.c_str());
    if (!s.lockstep_line.empty()) std::printf("  lockstep         %s\n", s.lockstep_line.c_str());
    for (const auto& line : s.fault_lines) std::printf("  sensor faults    %s\n", line.c_str());
    std::printf("  events           %llu grasps, %llu burns, %llu attachments broken, %llu tears, %llu instrument events, "
                "%llu steps rolled back\n",
                static_cast<unsigned long long>(s.grasps), static_cast<unsigned long long>(s.burns),
                static_cast<unsigned long long>(s.attachments_broken), static_cast<unsigned long long>(s.tears),
                static_cast<unsigned long long>(s.instrument_events), static_cast<unsigned long long>(s.rolled_back));
    std::printf("  telemetry        %llu messages (%llu dropped) → %s\n",
                static_cast<unsigned long long>(s.telemetry_published), static_cast<unsigned long long>(s.telemetry_dropped),
                config.lcm_url.c_str());
    for (const auto& line : s.receive_lines) std::printf("  received         %s\n", line.c_str());
    std::printf("  recording        %s%s%s\n", config.record_path.c_str(), s.recording_problem.empty() ? "" : " — ",
                s.recording_problem.c_str());
    for (const auto& line : s.snapshots) std::printf("  snapshot         %s\n", line.c_str());
    if (render) {
      std::printf("  frames           %llu stereo frames %dx%d per eye (%s); %zu written to %s, the last: %s\n",
                  static_cast<unsigned long long>(s.frames_rendered), config.eye_width, config.eye_height, s.renderer.c_str(),
                  s.pngs.size(), config.png_dir.c_str(), s.pngs.empty() ? "none" : (s.pngs.back() + "_stereo.png").c_str());
      std::printf("  instructor view  %s%s\n", s.pngs.empty() ? "none" : (s.pngs.back() + "_instructor.png").c_str(),
                  instructor_ring.empty() ? "" : (" and the shared-memory ring " + instructor_ring).c_str());
      for (const auto& m : s.key_moment_frames) std::printf("  key moment       %s_instructor.png\n", m.c_str());
    }
    for (const auto& line : s.displays) std::printf("  display          %s\n", line.c_str());
    for (std::size_t i = 0; i < s.score_lines.size(); ++i)
      std::printf("  %s %s\n", i == 0 ? "score           " : "                ", s.score_lines[i].c_str());
    std::printf("  state hash       %016llx\n", static_cast<unsigned long long>(s.state_hash));
    std::fflush(stdout);
    sync_file(config.lcm_url);  // the telemetry log, when it is one (the recording synced itself)
    // The debrief, from the telemetry log just written (rig/report): it never fails the session.
    if (lcm_url.empty()) {
      try {
        const auto r = vitreo::report::write_report(out.string());
        std::printf("  report           %s (numbers: %s)%s\n", r.html_path.c_str(), r.json_path.c_str(),
                    r.notices.empty() ? "" : (" — " + r.notices.front()).c_str());
      } catch (const std::exception& e) {
        std::printf("  report           not written: %s\n", e.what());
      }
      std::fflush(stdout);
    } else {
      std::printf("  report           none: telemetry went to %s, not to a log (vitreo-report reads a log)\n", lcm_url.c_str());
    }
    if (verify_replay) {
      const auto r = vitreo::rig::replay_session(config.record_path, model);
      const bool complete = r.verdict == vitreo::telemetry::RecordingVerdict::Complete;
      const bool same = complete && r.matches_recording() && r.state_hash == s.state_hash && r.score_lines == s.score_lines;
      std::printf("  replay           %llu steps in %.2f s (%.1fx real time), cases from the recording: %s\n",
                  static_cast<unsigned long long>(r.steps), r.wall_s, static_cast<double>(r.steps) * model.dt_s / r.wall_s,
                  same ? "identical final state and score" : complete ? "DIFFERENT final state" : r.verdict_text.c_str());
      if (!same) return 3;
    }
    return s.rolled_back == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
