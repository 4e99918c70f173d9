#include "rig/session/calibration_run.hpp"

#include <algorithm>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include "rig/session/device_hub.hpp"
#include "rig/session/device_inputs.hpp"

namespace vitreo::rig {
namespace {

constexpr std::uint64_t kStepUs = 1000;  // the lockstep grant: 1 ms, the trackers' sample period

bool is_sim(const DeviceSpec& d) { return d.uri.rfind("sim:", 0) == 0; }

}  // namespace

void record_calibration_input(calibration::CalibrationSession& session, const std::string& name, double t_s, const telemetry::RecordedInput& in,
                              std::FILE* progress) {
  namespace tm = telemetry;
  calibration::Recording& rec = session.recording;
  if (const auto* t = std::get_if<tm::TrackerSample>(&in.what)) {
    const TrackedPose pose = tracked_pose(*t);
    rec.poses[name].push_back({t_s, pose.tip_mm, pose.orientation});
  } else if (const auto* e = std::get_if<tm::EyeFixtureSample>(&in.what)) {
    rec.eyeball[name].push_back({t_s, fixture_orientation(*e)});
  } else if (const auto* p = std::get_if<tm::PedalSample>(&in.what)) {
    rec.pedals[name].push_back({t_s, p->pedal_id, {p->axes[0], p->axes[1]}});
  } else if (const auto* l = std::get_if<tm::LinkChange>(&in.what); l && l->event != tm::LinkEvent::Up) {
    char b[160];
    std::snprintf(b, sizeof b, "%s: link %s at %.3f s", name.c_str(), l->event == tm::LinkEvent::Lost ? "lost" : "stuck", t_s);
    session.events.emplace_back(b);
    std::fprintf(progress, "[%5.1f s] %s\n", t_s, b);
  }
}

void collect_time_syncs(DeviceHub& hub, calibration::Recording& rec, std::mutex& m) {
  for (std::size_t i = 0; i < hub.device_count(); ++i) {
    const std::string name = hub.name(i);
    hub.on_time_sync(i, [&rec, &m, name](std::uint64_t t1, std::uint64_t t2, std::uint64_t t3, std::uint64_t t4) {
      std::lock_guard lock(m);
      rec.clocks[name].push_back({t1, t2, t3, t4});
    });
  }
}

CalibrationRoles calibration_roles(const RigFile& rig) {
  CalibrationRoles r;
  for (const DeviceSpec& d : rig.devices) {
    if (d.role == DeviceRole::tracker) r.trackers.push_back({d.name, d.channel});
    if (d.role == DeviceRole::pedals && r.pedals.empty()) r.pedals = d.name;
    if (d.role == DeviceRole::eyeball && r.eyeball.empty()) r.eyeball = d.name;
  }
  // Instrument 0 (the tool hand) registers and measures the ports when present.
  std::stable_sort(r.trackers.begin(), r.trackers.end(), [](const auto& a, const auto& b) { return a.instrument < b.instrument; });
  return r;
}

std::string with_technician_motion(const DeviceSpec& d, const std::string& motion) {
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
  if (!have_device) out = "device " + std::string(to_string(d.role)) + "\n" + out;
  if (d.role == DeviceRole::eyeball && motion.empty()) return out + "loop 0\nkey 0 0 0 0 0 0\n";
  return out + "loop 0\n" + motion;
}

calibration::CalibrationSession run_scripted_calibration(const RigFile& rig, const calibration::Procedure& proc, std::FILE* progress) {
  for (const DeviceSpec& d : rig.devices)
    if (!is_sim(d))
      throw std::runtime_error(d.name + " (" + d.uri + ") is a real device; a scripted technician needs simulated devices (sim: URIs)");
  std::vector<DeviceSpec> specs = rig.devices;
  std::map<std::int32_t, std::string> name_of;
  for (DeviceSpec& d : specs) {
    const auto m = proc.motion.find(d.name);
    d.sim_script = with_technician_motion(d, m == proc.motion.end() ? std::string() : m->second);
    name_of[d.device_id] = d.name;
  }
  calibration::CalibrationSession session;
  session.rig = rig.name;
  session.procedure.steps = proc.steps;
  session.procedure.duration_s = proc.duration_s;
  calibration::Recording& rec = session.recording;
  std::mutex clocks_mutex;  // time syncs arrive on the hub's driver thread
  DeviceHub hub(specs, nullptr, HubMode::lockstep);
  collect_time_syncs(hub, rec, clocks_mutex);
  hub.start();
  hub.lockstep_connect();
  // The file names the units it calibrated.
  for (std::size_t i = 0; i < hub.device_count(); ++i)
    if (proc.motion.count(hub.name(i))) rec.serials[hub.name(i)] = hub.announced_serial(i);
  const std::uint64_t steps = static_cast<std::uint64_t>(proc.duration_s * 1e6 / kStepUs);
  std::vector<const calibration::ProcedureStep*> ordered;
  for (const calibration::ProcedureStep& s : proc.steps)
    if (s.kind != calibration::StepKind::clock) ordered.push_back(&s);
  std::size_t next_step = 0;
  for (std::uint64_t k = 0; k < steps; ++k) {
    const double t_s = static_cast<double>(k * kStepUs) * 1e-6;
    while (next_step < ordered.size() && ordered[next_step]->start_s <= t_s) {
      std::fprintf(progress, "[%5.1f s] %s: %s…\n", t_s, ordered[next_step]->device.c_str(), ordered[next_step]->instruction.c_str());
      ++next_step;
    }
    hub.lockstep_deliver(k, kStepUs);
    hub.take_new([&](const telemetry::RecordedInput& in) { record_calibration_input(session, name_of[in.device_id], t_s, in, progress); });
  }
  hub.stop();
  return session;
}

}  // namespace vitreo::rig
