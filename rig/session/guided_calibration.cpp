#include "rig/session/guided_calibration.hpp"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>

#include "rig/calibration/pivot.hpp"
#include "rig/session/calibration_run.hpp"
#include "rig/session/device_hub.hpp"

namespace vitreo::rig {
namespace {

using calibration::ProcedureStep;
using calibration::StepKind;

// When a step has what it needs (guided_calibration.hpp says why these).
constexpr double kRestS = 1.2;              // eye and pedals left alone this long
constexpr double kHoldS = 0.4;              // a touch held still this long…
constexpr double kHoldRmsMm = 0.10;         // …within this RMS (0.05 mm of tracker noise per axis alone gives 0.087)
constexpr double kTouchApartMm = 2.0;       // and this far from the last point taken
constexpr double kPivotS = 3.0;             // the pivot: this long…
constexpr std::size_t kPivotPoses = 300;    // …with at least this many poses (a loaded machine hands over fewer)…
constexpr double kPivotSpreadDeg = 40.0;    // …this widely spread, with a sound fit
constexpr std::size_t kHoldPoses = 20;      // a touch's hold: at least this many poses in its 0.4 s
constexpr double kPressDepth = 0.3;         // a pedal press: down at least this much of its raw reading…
constexpr double kPressBack = 0.03;         // …and back within this of its lowest for 0.2 s
constexpr double kFeedbackPeriodS = 0.5;

// The technician's answers: lines read without blocking, so the devices are read meanwhile.
class LineInput {
 public:
  explicit LineInput(int fd) : fd_(fd) {}
  // A whole line (without its newline) when one arrived within timeout_ms.
  std::optional<std::string> poll_line(int timeout_ms) {
    if (auto l = take()) return l;
    if (ended_) return std::nullopt;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return std::nullopt;
    char buf[256];
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n <= 0) {
      ended_ = true;
      return std::nullopt;
    }
    pending_.append(buf, static_cast<std::size_t>(n));
    return take();
  }
  bool ended() const { return ended_ && pending_.find('\n') == std::string::npos; }

 private:
  std::optional<std::string> take() {
    const auto nl = pending_.find('\n');
    if (nl == std::string::npos) return std::nullopt;
    std::string line = pending_.substr(0, nl);
    pending_.erase(0, nl + 1);
    line.erase(0, line.find_first_not_of(" \t\r"));
    line.erase(line.find_last_not_of(" \t\r") + 1);
    return line;
  }
  int fd_;
  std::string pending_;
  bool ended_ = false;
};

std::string fixed(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

}  // namespace

GuidedOutcome run_guided_calibration(const RigFile& rig, const std::vector<ProcedureStep>& planned, int input_fd, std::FILE* out) {
  GuidedOutcome result;
  calibration::CalibrationSession& session = result.session;
  session.rig = rig.name;
  calibration::Recording& rec = session.recording;
  const calibration::Fixture fixture = calibration::default_fixture();
  std::map<std::int32_t, std::string> name_of;
  for (const DeviceSpec& d : rig.devices) name_of[d.device_id] = d.name;

  std::mutex clocks_mutex;  // time syncs arrive on the hub's driver thread
  DeviceHub hub(rig.devices, nullptr, HubMode::realtime);
  collect_time_syncs(hub, rec, clocks_mutex);
  hub.start();
  const std::int64_t t0 = static_cast<std::int64_t>(hub.now_us());
  auto now_s = [&] { return static_cast<double>(static_cast<std::int64_t>(hub.now_us()) - t0) * 1e-6; };
  // Samples are timed when this loop takes them, on the clock the steps' windows are cut by, so a
  // window never misses a sample it has already seen (the drivers' own stamps can run ahead of it).
  auto pump = [&] {
    const double at = now_s();
    hub.take_new([&](const telemetry::RecordedInput& in) { record_calibration_input(session, name_of[in.device_id], at, in, out); });
  };
  LineInput input(input_fd);
  // Waits for the technician's line, reading the devices meanwhile; nothing when the input ended.
  auto answer = [&]() -> std::optional<std::string> {
    for (;;) {
      pump();
      if (auto l = input.poll_line(1)) return l;
      if (input.ended()) return std::nullopt;
    }
  };
  auto stop = [&] {
    hub.stop();
    for (std::size_t i = 0; i < hub.device_count(); ++i)
      for (const ProcedureStep& s : planned)
        if (s.device == hub.name(i)) rec.serials[s.device] = hub.announced_serial(i);
  };

  std::vector<const ProcedureStep*> todo;
  for (const ProcedureStep& s : planned)
    if (s.kind != StepKind::clock) todo.push_back(&s);
  std::fprintf(out,
               "vitreo-calibrate: guided calibration of %s (%zu devices, %zu steps). For each step: do what it says, press "
               "Enter to start taking samples; the step ends by itself once it has what it needs (or press Enter to end it). "
               "q gives up (nothing is written).\n",
               rig.name.c_str(), rig.devices.size(), todo.size());
  std::vector<ProcedureStep> done;
  std::map<std::string, core::Vec3> tip_offset, last_point;  // by device: the pivot's result, the last point taken
  for (std::size_t i = 0; i < todo.size(); ++i) {
    const ProcedureStep& plan = *todo[i];
    for (;;) {
      std::fprintf(out, "\nstep %zu of %zu [%6.1f s] %s: %s\n  Enter to start (q: give up)\n", i + 1, todo.size(), now_s(), plan.device.c_str(),
                   plan.instruction.c_str());
      std::fflush(out);
      const auto go = answer();
      if (!go || *go == "q") {
        stop();
        return result;
      }
      ProcedureStep s = plan;
      s.start_s = now_s();
      double next_feedback = s.start_s + kFeedbackPeriodS;
      bool ended = false;
      std::string live;
      while (!ended) {
        pump();
        if (auto l = input.poll_line(1)) {
          if (*l == "q") {
            stop();
            return result;
          }
          ended = true;  // Enter: the technician ends the step
        }
        const double t = now_s();
        s.end_s = t;
        switch (s.kind) {
          case StepKind::eye_zero:
          case StepKind::pedal_rest: {
            const std::size_t n = s.kind == StepKind::eye_zero ? rec.eyeball[s.device].size() : rec.pedals[s.device].size();
            live = std::to_string(n) + " samples";
            ended = ended || t - s.start_s >= kRestS;
            break;
          }
          case StepKind::pedal_travel: {
            double lo = 1e9, hi = -1e9, now = 0.0;
            bool back = true;
            for (auto it = rec.pedals[s.device].rbegin(); it != rec.pedals[s.device].rend() && it->t_s >= s.start_s; ++it) {
              lo = std::min(lo, it->axes[s.index]);
              hi = std::max(hi, it->axes[s.index]);
            }
            for (auto it = rec.pedals[s.device].rbegin(); it != rec.pedals[s.device].rend() && it->t_s >= t - 0.2; ++it)
              back = back && it->axes[s.index] <= lo + kPressBack;
            if (!rec.pedals[s.device].empty()) now = rec.pedals[s.device].back().axes[s.index];
            live = "reads " + fixed(now, 3) + " (lowest " + fixed(lo, 3) + ", highest " + fixed(hi, 3) + ")";
            ended = ended || (hi - lo >= kPressDepth && back && t - s.start_s > 0.3);
            break;
          }
          case StepKind::pivot: {
            if (t < next_feedback && !ended) break;  // the fit is redone twice a second
            // The live fit on at most ~1500 of the poses (its spread is O(n²), and the devices wait
            // meanwhile); the step's outcome below fits them all.
            std::size_t taken = 0;
            for (const calibration::TimedPose& p : rec.poses[s.device]) taken += p.t_s >= s.start_s;
            const std::size_t stride = std::max<std::size_t>(1, taken / 1500);
            std::vector<calibration::PivotPose> poses;
            std::size_t k = 0;
            for (const calibration::TimedPose& p : rec.poses[s.device])
              if (p.t_s >= s.start_s && k++ % stride == 0) poses.push_back({p.position_mm, p.orientation});
            const calibration::PivotResult r = calibration::calibrate_pivot(poses, {});
            live = std::to_string(taken) + " samples, spread " + fixed(r.spread_deg, 1) + "°, RMS " + fixed(r.rms_mm, 3) + " mm";
            if (r.ok) {
              tip_offset[s.device] = r.tip_offset_mm;
              last_point[s.device] = r.pivot_mm;
            }
            ended = ended || (r.ok && t - s.start_s >= kPivotS && taken >= kPivotPoses && r.spread_deg >= kPivotSpreadDeg);
            break;
          }
          case StepKind::fiducial:
          case StepKind::port: {
            const auto offset = tip_offset.find(s.device);
            if (offset == tip_offset.end()) {
              ended = true;  // the analysis says why: no pivot calibration for this instrument
              break;
            }
            std::vector<core::Vec3> tips;
            for (auto it = rec.poses[s.device].rbegin(); it != rec.poses[s.device].rend() && it->t_s >= t - kHoldS; ++it)
              tips.push_back(it->position_mm + it->orientation.normalized() * offset->second);
            if (tips.size() < kHoldPoses || t - kHoldS < s.start_s) {
              live = "moving";
              break;
            }
            const calibration::HeldPoint held = calibration::held_point(tips);
            const core::Vec3& mean = held.mean_mm;
            const double rms = held.spread_mm;
            const auto last = last_point.find(s.device);
            const bool apart = last == last_point.end() || (mean - last->second).norm() >= kTouchApartMm;
            live = rms <= kHoldRmsMm ? (apart ? "held still" : "still on the last point: move to the next") : "moving (" + fixed(rms, 2) + " mm)";
            if (rms <= kHoldRmsMm && apart) {
              s.start_s = t - kHoldS;
              last_point[s.device] = mean;
              ended = true;
            }
            break;
          }
          case StepKind::clock:
            ended = true;
            break;
        }
        if (t >= next_feedback && !ended) {
          std::fprintf(out, "  [%6.1f s] %s\n", t, live.c_str());
          std::fflush(out);
          next_feedback = t + kFeedbackPeriodS;
        }
      }
      // The step's outcome, judged as the whole run will be.
      std::erase_if(done, [&](const ProcedureStep& d) { return calibration::same_step(d, s); });
      done.push_back(s);
      calibration::Procedure so_far;
      so_far.steps = done;
      const calibration::Analysis a = calibration::analyse(so_far, fixture, rec);
      bool ok = false;
      for (const calibration::StepOutcome& o : a.steps) {
        if (!calibration::same_step(*o.step, s)) continue;
        ok = o.ok;
        std::fprintf(out, "  %s %s\n", o.ok ? "ok  " : "FAIL", o.feedback.c_str());
      }
      if (ok) break;
      std::fprintf(out, "  Enter: do it again, s: skip it (the calibration then fails), q: give up\n");
      std::fflush(out);
      const auto again = answer();
      if (!again || *again == "q") {
        stop();
        return result;
      }
      if (*again == "s") break;
    }
  }
  const double end_s = now_s();
  stop();
  std::lock_guard lock(clocks_mutex);
  for (const ProcedureStep& s : planned)
    if (s.kind == StepKind::clock) done.push_back({s.kind, s.device, s.index, 0.0, end_s, s.instruction});
  session.procedure.steps = done;
  session.procedure.duration_s = end_s;
  result.completed = true;
  return result;
}

}  // namespace vitreo::rig
