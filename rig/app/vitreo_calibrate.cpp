// vitreo-calibrate: the technicians' sensor calibration (issue 18; rig/calibration/README.md).
//
//   vitreo-calibrate --rig rig/config/sim-calibration.toml --out rig.calibration.toml --non-interactive
//
// Runs the procedure of rig/calibration/procedure.hpp against the rig file's devices over their
// transports — tip pivot per instrument, tracker-to-fixture registration, ports, pedal travel, the
// devices' clocks — prints each step with its feedback and a summary, and writes the calibration
// file atomically only when every step passed (a failed run keeps the previous file).
//
// --non-interactive plays a scripted technician: the procedure's motions become the simulated
// devices' emulator keyframes (their own script's imperfections, noise and faults kept), and the
// run goes in lockstep on the simulation's clock, so it is reproducible and as fast as the machine.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "rig/calibration/calibration_file.hpp"
#include "rig/calibration/procedure.hpp"
#include "rig/report/calibration_report.hpp"
#include "rig/session/device_hub.hpp"
#include "rig/session/device_inputs.hpp"
#include "rig/session/rig_file.hpp"
#include "rig/session/simulation_model.hpp"

namespace cal = vitreo::rig::calibration;
using vitreo::rig::DeviceRole;
using vitreo::rig::DeviceSpec;

namespace {

constexpr std::uint64_t kStepUs = 1000;  // the lockstep grant: 1 ms, the trackers' sample period

// The device's own script with its motion replaced by the technician's: every directive but `key`
// and `loop` (imperfections, noise, serial, rate, faults) is kept.
std::string technician_script(const DeviceSpec& d, const std::string& motion) {
  std::istringstream in(d.sim_script);
  std::string out, line;
  bool have_device = false;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string first;
    words >> first;
    if (first == "key" || first == "loop") continue;
    if (first == "device") have_device = true;
    out += line + "\n";
  }
  if (!have_device) out = "device " + std::string(vitreo::rig::to_string(d.role)) + "\n" + out;
  if (d.role == DeviceRole::eyeball && motion.empty()) return out + "loop 0\nkey 0 0 0 0 0 0\n";
  return out + "loop 0\n" + motion;
}

bool is_sim(const DeviceSpec& d) { return d.uri.rfind("sim:", 0) == 0; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vitreo-calibrate: calibrate the rig's sensors (tip pivot, registration, ports, pedals, clocks)\n"
               "  vitreo-calibrate --rig rig/config/sim-calibration.toml --out rig.calibration.toml --non-interactive"};
  std::string rig_path, out_path, motion_dir;
  bool non_interactive = false;
  app.add_option("--rig", rig_path, "the rig file whose devices are calibrated")->required()->check(CLI::ExistingFile);
  app.add_option("--out", out_path, "the calibration file to write (atomically; kept as it was when a step fails)")->required();
  app.add_flag("--non-interactive", non_interactive,
               "a scripted technician performs the procedure against the rig's simulated devices (lockstep)");
  app.add_option("--save-motion", motion_dir, "write the scripted technician's emulator scripts to this folder");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_pattern("%^%l%$: %v");

  vitreo::rig::RigFile rig;
  try {
    rig = vitreo::rig::read_rig_file(rig_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 2;
  }
  if (!non_interactive) {
    std::fprintf(stderr,
                 "vitreo-calibrate: the interactive procedure (a technician at real devices, confirming each step) is not "
                 "implemented yet; run --non-interactive against simulated devices\n");
    return 2;
  }
  for (const DeviceSpec& d : rig.devices) {
    if (!is_sim(d)) {
      std::fprintf(stderr, "vitreo-calibrate: %s (%s) is a real device; --non-interactive needs simulated devices (sim: URIs)\n",
                   d.name.c_str(), d.uri.c_str());
      return 2;
    }
  }

  std::vector<cal::TrackerRole> trackers;
  std::string pedals, eyeball;
  for (const DeviceSpec& d : rig.devices) {
    if (d.role == DeviceRole::tracker) trackers.push_back({d.name, d.channel});
    if (d.role == DeviceRole::pedals && pedals.empty()) pedals = d.name;
    if (d.role == DeviceRole::eyeball && eyeball.empty()) eyeball = d.name;
  }
  // Instrument 0 (the tool hand) registers and measures the ports when present.
  std::stable_sort(trackers.begin(), trackers.end(), [](const auto& a, const auto& b) { return a.instrument < b.instrument; });
  const cal::Fixture fixture = cal::default_fixture();
  const cal::Procedure proc = cal::plan_procedure(fixture, trackers, pedals, eyeball);

  std::vector<DeviceSpec> specs = rig.devices;
  std::map<std::int32_t, std::string> name_of;
  for (DeviceSpec& d : specs) {
    const auto m = proc.motion.find(d.name);
    d.sim_script = technician_script(d, m == proc.motion.end() ? std::string() : m->second);
    name_of[d.device_id] = d.name;
    if (!motion_dir.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(motion_dir, ec);
      std::ofstream f(std::filesystem::path(motion_dir) / (d.name + ".sim"));
      if (!(f << d.sim_script) || !f.flush()) {
        std::fprintf(stderr, "vitreo-calibrate: --save-motion: cannot write %s/%s.sim\n", motion_dir.c_str(), d.name.c_str());
        return 2;
      }
    }
  }

  std::printf("vitreo-calibrate: %s, %zu devices, scripted technician (%.1f s of procedure)\n", rig.name.c_str(), specs.size(),
              proc.duration_s);
  cal::Recording rec;
  std::mutex clocks_mutex;  // time syncs arrive on the hub's driver thread
  std::vector<std::string> link_events;
  try {
    vitreo::rig::DeviceHub hub(specs, nullptr, vitreo::rig::HubMode::lockstep);
    for (std::size_t i = 0; i < hub.device_count(); ++i) {
      const std::string name = hub.name(i);
      hub.on_time_sync(i, [&rec, &clocks_mutex, name](std::uint64_t t1, std::uint64_t t2, std::uint64_t t3, std::uint64_t t4) {
        std::lock_guard lock(clocks_mutex);
        rec.clocks[name].push_back({t1, t2, t3, t4});
      });
    }
    hub.start();
    hub.lockstep_connect();
    // The file names the units it calibrated.
    for (std::size_t i = 0; i < hub.device_count(); ++i)
      if (proc.motion.count(hub.name(i))) rec.serials[hub.name(i)] = hub.announced_serial(i);
    const std::uint64_t steps = static_cast<std::uint64_t>(proc.duration_s * 1e6 / kStepUs);
    std::size_t next_step = 0;
    std::vector<const cal::ProcedureStep*> ordered;
    for (const cal::ProcedureStep& s : proc.steps)
      if (s.kind != cal::StepKind::clock) ordered.push_back(&s);
    std::stable_sort(ordered.begin(), ordered.end(), [](auto* a, auto* b) { return a->start_s < b->start_s; });
    for (std::uint64_t k = 0; k < steps; ++k) {
      const double t_s = static_cast<double>(k * kStepUs) * 1e-6;
      while (next_step < ordered.size() && ordered[next_step]->start_s <= t_s) {
        std::printf("[%5.1f s] %s: %s…\n", t_s, ordered[next_step]->device.c_str(), ordered[next_step]->instruction.c_str());
        ++next_step;
      }
      hub.lockstep_deliver(k, kStepUs);
      hub.take_new([&](const vitreo::telemetry::RecordedInput& in) {
        namespace tm = vitreo::telemetry;
        const std::string& name = name_of[in.device_id];
        if (const auto* t = std::get_if<tm::TrackerSample>(&in.what)) {
          const vitreo::rig::TrackedPose pose = vitreo::rig::tracked_pose(*t);
          rec.poses[name].push_back({t_s, pose.tip_mm, pose.orientation});
        } else if (const auto* e = std::get_if<tm::EyeFixtureSample>(&in.what)) {
          rec.eyeball[name].push_back({t_s, vitreo::rig::fixture_orientation(*e)});
        } else if (const auto* p = std::get_if<tm::PedalSample>(&in.what)) {
          rec.pedals[name].push_back({t_s, p->pedal_id, {p->axes[0], p->axes[1]}});
        } else if (const auto* l = std::get_if<tm::LinkChange>(&in.what); l && l->event != tm::LinkEvent::Up) {
          char b[160];
          std::snprintf(b, sizeof b, "%s: link %s at %.3f s", name.c_str(), l->event == tm::LinkEvent::Lost ? "lost" : "stuck", t_s);
          link_events.emplace_back(b);
          std::printf("[%5.1f s] %s\n", t_s, b);
        }
      });
    }
    hub.stop();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: %s\n", e.what());
    return 1;
  }

  cal::Analysis a;
  {
    std::lock_guard lock(clocks_mutex);
    a = cal::analyse(proc, fixture, rec);
  }
  std::printf("\nsteps\n");
  for (const cal::StepOutcome& o : a.steps)
    std::printf("  %s %-10s %s: %s\n", o.ok ? "ok  " : "FAIL", o.step->device.c_str(), o.step->instruction.c_str(), o.feedback.c_str());
  for (const std::string& e : link_events) a.errors.push_back(e), a.ok = false;
  std::printf("\n%s", cal::summary_text(a).c_str());
  a.file.created_unix_s =
      std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  a.file.tool = std::string("vitreo-calibrate ") + VITREO_VERSION;
  a.file.rig = rig.name;
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
    std::fprintf(stderr, "vitreo-calibrate: calibration failed; %s was not written (a previous calibration there is kept)\n",
                 out_path.c_str());
  }
  // The report a technician files, passed or failed: beside the calibration file.
  const std::string base = out_path.size() > 5 && out_path.ends_with(".toml") ? out_path.substr(0, out_path.size() - 5) : out_path;
  try {
    vitreo::report::CalibrationReportInputs in;
    in.analysis = &a;
    if (written) in.calibration_file = out_path;
    in.generated = cal::utc_timestamp(a.file.created_unix_s);
    const auto r = vitreo::report::write_calibration_report(base, in);
    std::printf("report %s (numbers: %s)\n", r.html_path.c_str(), r.json_path.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-calibrate: the report was not written: %s\n", e.what());
  }
  return written ? 0 : 1;
}
