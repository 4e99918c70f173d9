// vitreo-calibrate: the technicians' sensor calibration (issue 18; rig/calibration/README.md).
//
//   vitreo-calibrate --rig rig/config/sim-calibration.toml --out rig.calibration.toml --non-interactive
//   vitreo-calibrate --from-recording rig.calibration.recording --out again.calibration.toml
//
// Runs the procedure of rig/calibration/procedure.hpp against the rig file's devices over their
// transports — tip pivot per instrument, tracker-to-fixture registration, ports, pedal travel, the
// eyeball fixture's zero, the devices' clocks — prints each step with its feedback and a summary,
// and writes the calibration file atomically only when every step passed (a failed run keeps the
// previous file). Every run leaves its report (NAME.report.html/.json) and its recording
// (NAME.recording, every sample and each step's window) beside the file, passed or failed.
//
// Who does the procedure:
// - by default a technician at the devices, guided step by step in the terminal with live feedback
//   (rig/session/guided_calibration.hpp), in real time; with simulated devices, --technician-script
//   makes their emulators play a scripted technician's motions meanwhile (a test engineer's rig);
// - --non-interactive: a scripted technician (the surgical-script format, kind = "calibration";
//   rig/session/technician_script.hpp), against simulated devices, in lockstep;
// - --from-recording FILE: nobody — the samples of an earlier run are analysed again.
//
// --eyepieces calibrates the stereo eyepiece displays instead (rig/session/eyepiece_calibration.hpp):
// the technician adjusts each eye's image shift, the stereo base and convergence while looking at
// the test pattern; only the file's [eyepieces] table changes. A sensor calibration written over a
// file keeps its [eyepieces] table, so neither run undoes the other.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "rig/calibration/calibration_file.hpp"
#include "rig/calibration/calibration_recording.hpp"
#include "rig/calibration/procedure.hpp"
#include "rig/report/calibration_report.hpp"
#include "rig/session/calibration_run.hpp"
#include "rig/session/eyepiece_calibration.hpp"
#include "rig/session/guided_calibration.hpp"
#include "rig/session/rig_file.hpp"
#include "rig/session/technician_script.hpp"

namespace cal = vitreo::rig::calibration;
namespace fs = std::filesystem;

namespace {

// NAME.toml → NAME (the report's and the recording's base).
std::string base_of(const std::string& out_path) {
  return out_path.size() > 5 && out_path.ends_with(".toml") ? out_path.substr(0, out_path.size() - 5) : out_path;
}

// The analysis of what was taken, the steps' feedback and summary printed, the file written when
// every step passed, the report and the recording beside it. Returns the exit status.
int finish(const cal::CalibrationSession& session, const std::string& out_path, const std::string& recording_path) {
  cal::Analysis a = cal::analyse(session.procedure, cal::default_fixture(), session.recording);
  std::printf("\nsteps\n");
  for (const cal::StepOutcome& o : a.steps)
    std::printf("  %s %-10s %s: %s\n", o.ok ? "ok  " : "FAIL", o.step->device.c_str(), o.step->instruction.c_str(), o.feedback.c_str());
  for (const std::string& e : session.events) a.errors.push_back(e), a.ok = false;
  std::printf("\n%s", cal::summary_text(a).c_str());
  a.file.created_unix_s = std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  a.file.tool = std::string("vitreo-calibrate ") + VITREO_VERSION;
  a.file.rig = session.rig;
  // The eyepieces calibrated before (vitreo-calibrate --eyepieces) stay as they were.
  if (fs::exists(out_path)) {
    try {
      a.file.eyepieces = cal::read_calibration_file(out_path).eyepieces;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vitreo-calibrate: the file there now is not kept whole (%s)\n", e.what());
    }
  }
  bool written = false;
  if (a.ok) {
    try {
      cal::write_calibration_file(out_path, a.file);
      written = true;
      std::printf("wrote %s\n", out_path.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    }
  } else {
    std::fprintf(stderr, "vitreo-calibrate: calibration failed; %s was not written (a previous calibration there is kept)\n", out_path.c_str());
  }
  // The report a technician files, passed or failed: beside the calibration file.
  try {
    vitreo::report::CalibrationReportInputs in;
    in.analysis = &a;
    if (written) in.calibration_file = out_path;
    in.generated = cal::utc_timestamp(a.file.created_unix_s);
    const auto r = vitreo::report::write_calibration_report(base_of(out_path), in);
    std::printf("report %s (numbers: %s)\n", r.html_path.c_str(), r.json_path.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: the report was not written: %s\n", e.what());
  }
  if (!recording_path.empty()) {
    try {
      cal::write_calibration_recording(recording_path, session);
      std::printf("recording %s\n", recording_path.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vitreo-calibrate: the recording was not written: %s\n", e.what());
    }
  }
  return written ? 0 : 1;
}

// The eyepiece displays: the test pattern on the rig's outputs, adjusted on standard input; only the
// file's [eyepieces] table changes (a file that cannot be read is not overwritten).
int eyepieces(const std::string& out_path, const std::string& rig_name, vitreo::rig::EyepieceRunOptions options) {
  cal::CalibrationFile file;
  if (fs::exists(out_path)) {
    try {
      file = cal::read_calibration_file(out_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vitreo-calibrate: %s; it is not overwritten\n", e.what());
      return 2;
    }
    if (file.eyepieces) options.start = *file.eyepieces;
  } else {
    file.rig = rig_name;
  }
  std::optional<cal::EyepieceRecord> kept;
  try {
    kept = vitreo::rig::run_eyepiece_calibration(options, STDIN_FILENO, stdout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 1;
  }
  if (!kept) {
    std::fprintf(stderr, "vitreo-calibrate: given up; %s was not changed\n", out_path.c_str());
    return 3;
  }
  file.eyepieces = *kept;
  file.created_unix_s = std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  file.tool = std::string("vitreo-calibrate ") + VITREO_VERSION;
  try {
    cal::write_calibration_file(out_path, file);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 1;
  }
  std::printf("wrote %s ([eyepieces]; the rest of the file as it was)\n", out_path.c_str());
  return 0;
}

// The guided procedure at the rig's devices, answered on standard input.
int guided(const vitreo::rig::RigFile& rig, const std::vector<cal::ProcedureStep>& planned, const std::string& out_path,
           const std::string& recording_path) {
  vitreo::rig::GuidedOutcome g;
  try {
    g = vitreo::rig::run_guided_calibration(rig, planned, STDIN_FILENO, stdout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 1;
  }
  if (!g.completed) {
    std::fprintf(stderr, "vitreo-calibrate: given up; %s was not written (a previous calibration there is kept)\n", out_path.c_str());
    return 3;
  }
  return finish(g.session, out_path, recording_path);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vitreo-calibrate: calibrate the rig's sensors (tip pivot, registration, ports, pedals, eyeball zero, clocks)\n"
               "  vitreo-calibrate --rig rig/config/sim-calibration.toml --out rig.calibration.toml --non-interactive\n"
               "  vitreo-calibrate --from-recording rig.calibration.recording --out again.calibration.toml"};
  std::string rig_path, out_path, motion_dir, technician_path, from_recording, record_path;
  bool non_interactive = false;
  app.add_option("--rig", rig_path, "the rig file whose devices are calibrated")->check(CLI::ExistingFile);
  app.add_option("--out", out_path, "the calibration file to write (atomically; kept as it was when a step fails)")->required();
  auto* scripted = app.add_flag("--non-interactive", non_interactive,
                                "a scripted technician performs the procedure against the rig's simulated devices (lockstep)");
  app.add_option("--technician-script", technician_path,
                 "the scripted technician (kind = \"calibration\"; default with --non-interactive: RIG.technician.toml beside "
                 "the rig file RIG.toml; guided: the simulated devices play it while the prompts are answered)")
      ->check(CLI::ExistingFile);
  auto* replay = app.add_option("--from-recording", from_recording, "analyse the samples of an earlier run (its NAME.recording) again")
                     ->check(CLI::ExistingFile)
                     ->excludes(scripted);
  app.add_option("--record", record_path, "where to write this run's recording (default: NAME.recording beside --out)");
  app.add_option("--save-motion", motion_dir, "write the scripted technician's emulator scripts to this folder")->needs(scripted);
  bool eyepiece_mode = false;
  std::vector<std::string> displays;
  vitreo::rig::EyepieceRunOptions eyepiece_options;
  std::string pattern_dir;
  auto* eyepiece_flag = app.add_flag("--eyepieces", eyepiece_mode,
                                     "calibrate the stereo eyepiece displays at the test pattern (commands on standard input)")
                            ->excludes(scripted)
                            ->excludes(replay);
  app.add_option("--display", displays, "with --eyepieces: show the pattern on a rig display, CARD[:CONNECTOR[:sbs|left|right]] (repeatable)")
      ->needs(eyepiece_flag);
  app.add_option("--frame-ring", eyepiece_options.frame_ring_name, "with --eyepieces: publish the pattern in this shared-memory ring")
      ->needs(eyepiece_flag);
  app.add_option("--pattern-png", pattern_dir, "with --eyepieces: write the pattern as last set to DIR/eyepieces_{left,right,stereo}.png")
      ->needs(eyepiece_flag);
  app.add_option("--eye-size", eyepiece_options.eye_width, "with --eyepieces: each eye's width in pixels (height 4/5 of it)")
      ->check(CLI::Range(64, 4096))
      ->needs(eyepiece_flag);
  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("%^%l%$: %v");
  if (eyepiece_mode) {
    std::string rig_name;
    try {
      for (const std::string& d : displays) eyepiece_options.displays.push_back(vitreo::render::parse_display_spec(d));
      if (!rig_path.empty()) {
        const vitreo::rig::RigFile rig = vitreo::rig::read_rig_file(rig_path);
        rig_name = rig.name;
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
      return 2;
    }
    eyepiece_options.eye_height = eyepiece_options.eye_width * 4 / 5;
    if (!pattern_dir.empty()) {
      std::error_code ec;
      fs::create_directories(pattern_dir, ec);
      eyepiece_options.png_prefix = (fs::path(pattern_dir) / "eyepieces").string();
    }
    return eyepieces(out_path, rig_name, eyepiece_options);
  }
  if (record_path.empty() && from_recording.empty()) record_path = base_of(out_path) + ".recording";

  if (!from_recording.empty()) {
    cal::CalibrationSession session;
    try {
      session = cal::read_calibration_recording(from_recording);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
      return 2;
    }
    std::printf("vitreo-calibrate: %s, the recorded run %s (%zu steps, %.1f s)\n", session.rig.c_str(), from_recording.c_str(),
                session.procedure.steps.size(), session.procedure.duration_s);
    return finish(session, out_path, record_path);
  }

  if (rig_path.empty()) {
    std::fprintf(stderr, "vitreo-calibrate: --rig FILE: the rig whose devices are calibrated (or --from-recording FILE)\n");
    return 2;
  }
  vitreo::rig::RigFile rig;
  try {
    rig = vitreo::rig::read_rig_file(rig_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 2;
  }
  const vitreo::rig::CalibrationRoles roles = vitreo::rig::calibration_roles(rig);
  const cal::Fixture fixture = cal::default_fixture();
  const std::vector<cal::ProcedureStep> planned = cal::plan_steps(fixture, roles.trackers, roles.pedals, roles.eyeball);

  if (technician_path.empty() && non_interactive) {
    const fs::path rig_file(rig_path);
    technician_path = (rig_file.parent_path() / (rig_file.stem().string() + ".technician.toml")).string();
  }
  cal::Procedure proc;
  if (!non_interactive && technician_path.empty()) return guided(rig, planned, out_path, record_path);
  try {
    const vitreo::rig::SurgicalScript script = vitreo::rig::read_surgical_script(technician_path);
    proc = vitreo::rig::resolve_technician_script(script, fixture, {roles.trackers, roles.pedals, roles.eyeball}, planned);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 2;
  }
  if (const auto missing = cal::missing_steps(planned, proc.steps); !missing.empty()) {
    std::fprintf(stderr, "vitreo-calibrate: %s does not do every step this rig needs:\n", technician_path.c_str());
    for (const std::string& m : missing) std::fprintf(stderr, "  %s\n", m.c_str());
    return 2;
  }
  if (!non_interactive) {
    // Guided, with simulated devices playing the scripted technician's motion in real time.
    for (vitreo::rig::DeviceSpec& d : rig.devices) {
      if (d.uri.rfind("sim:", 0) != 0) {
        std::fprintf(stderr, "vitreo-calibrate: --technician-script moves simulated devices; %s (%s) is a real one\n", d.name.c_str(), d.uri.c_str());
        return 2;
      }
      const auto m = proc.motion.find(d.name);
      d.sim_script = vitreo::rig::with_technician_motion(d, m == proc.motion.end() ? std::string() : m->second);
    }
    return guided(rig, planned, out_path, record_path);
  }
  if (!motion_dir.empty()) {
    for (const vitreo::rig::DeviceSpec& d : rig.devices) {
      const auto m = proc.motion.find(d.name);
      std::error_code ec;
      fs::create_directories(motion_dir, ec);
      std::ofstream f(fs::path(motion_dir) / (d.name + ".sim"));
      if (!(f << vitreo::rig::with_technician_motion(d, m == proc.motion.end() ? std::string() : m->second)) || !f.flush()) {
        std::fprintf(stderr, "vitreo-calibrate: --save-motion: cannot write %s/%s.sim\n", motion_dir.c_str(), d.name.c_str());
        return 2;
      }
    }
  }

  std::printf("vitreo-calibrate: %s, %zu devices, scripted technician %s (%.1f s of procedure)\n", rig.name.c_str(), rig.devices.size(),
              technician_path.c_str(), proc.duration_s);
  cal::CalibrationSession session;
  try {
    session = vitreo::rig::run_scripted_calibration(rig, proc, stdout);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 1;
  }
  return finish(session, out_path, record_path);
}
