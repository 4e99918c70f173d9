#include "rig/session/technician_script.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>

namespace vitreo::rig {
namespace {

using calibration::ProcedureStep;
using calibration::StepKind;
using core::Vec3;

constexpr double kSettle = 0.15;     // s cut off each end of a hold: the hand settling, then leaving
constexpr double kKeyPeriod = 0.05;  // s between keys while the handle swings or the hand trembles

struct FixtureLandmark {
  Vec3 at = Vec3::Zero();
  StepKind kind = StepKind::clock;  // what a hold here can record (clock: nothing)
  int index = 0;
};

// One device's keyframes at the emulator's 0.1 ms resolution: a key at the same time as the one
// before it (a hold of zero, a press right after the last) adds nothing, since key times must increase.
class Keys {
 public:
  explicit Keys(std::string& out) : out_(out) {}
  void tracker(double t_s, const Vec3& p, double yaw, double pitch, double roll) {
    char b[160];
    std::snprintf(b, sizeof b, "%.4f %.4f %.4f %.3f %.3f %.3f 0", p.x(), p.y(), p.z(), yaw, pitch, roll);
    add(t_s, b);
  }
  void pedals(double t_s, double a0, double a1) {
    char b[64];
    std::snprintf(b, sizeof b, "%.3f %.3f 0", a0, a1);
    add(t_s, b);
  }

 private:
  void add(double t_s, const char* values) {
    const long tenths = std::lround(t_s * 1e4);
    if (tenths <= last_) return;
    last_ = tenths;
    char b[32];
    std::snprintf(b, sizeof b, "key %.1f ", static_cast<double>(tenths) / 10.0);
    out_ += b + std::string(values) + "\n";
  }
  std::string& out_;
  long last_ = -1;
};

class Resolver {
 public:
  Resolver(const SurgicalScript& s, const calibration::Fixture& f) : s_(s), f_(f) {}

  [[noreturn]] void fail(int line, const std::string& key, const std::string& why) const {
    throw std::runtime_error(s_.file + ":" + std::to_string(line) + ": " + key + ": " + why);
  }

  FixtureLandmark landmark(const std::string& name, int line, const std::string& key) const {
    if (name == "rest") return {f_.rest_mm, StepKind::clock, 0};
    if (name == "divot") return {f_.divot_mm, StepKind::pivot, 0};
    const auto dot = name.find('.');
    const std::string head = name.substr(0, dot), tail = dot == std::string::npos ? "" : name.substr(dot + 1);
    char* end = nullptr;
    const long k = std::strtol(tail.c_str(), &end, 10);
    const bool number = !tail.empty() && end && *end == '\0';
    const long fiducials = static_cast<long>(f_.fiducials_mm.size()), ports = static_cast<long>(f_.ports_mm.size());
    if (head == "fiducial") {
      if (!number || k < 1 || k > fiducials) fail(line, key, "the fixture's fiducials are fiducial.1 … fiducial." + std::to_string(fiducials));
      return {f_.fiducials_mm[static_cast<std::size_t>(k - 1)], StepKind::fiducial, static_cast<int>(k - 1)};
    }
    if (head == "port") {
      if (!number || k < 0 || k >= ports) fail(line, key, "the fixture's ports are port.0 … port." + std::to_string(ports - 1));
      return {f_.ports_mm[static_cast<std::size_t>(k)], StepKind::port, static_cast<int>(k)};
    }
    fail(line, key, "unknown landmark '" + name + "' (rest, divot, fiducial.N, port.N: a calibration script's are the fixture's)");
  }

 private:
  const SurgicalScript& s_;
  const calibration::Fixture& f_;
};

struct Press {
  double start_s, end_s;
  int axis;
  double travel;
  int line;
};

}  // namespace

calibration::Procedure resolve_technician_script(const SurgicalScript& script, const calibration::Fixture& fixture,
                                                 const TechnicianDevices& devices, const std::vector<ProcedureStep>& planned) {
  if (script.kind != "calibration")
    throw std::runtime_error(script.file + ": script.kind: '" + script.kind + "' is a surgeon's script; a technician's is kind = \"calibration\"");
  const Resolver resolver(script, fixture);
  calibration::Procedure proc;
  std::vector<Press> presses;
  std::mt19937_64 rng(script.seed * 7919 + 31);
  std::normal_distribution<double> tremor(0.0, 1.0);
  double end_s = 0.0;

  auto instruction_of = [&](const ProcedureStep& s) {
    for (const ProcedureStep& p : planned)
      if (calibration::same_step(p, s)) return p.instruction;
    return std::string();
  };
  auto record = [&](ProcedureStep s, int line, const std::string& key) {
    s.instruction = instruction_of(s);
    if (s.instruction.empty()) resolver.fail(line, key, "this rig's procedure has no such step (" + calibration::step_kind_name(s.kind) + " on " + s.device + ")");
    for (const ProcedureStep& d : proc.steps)
      if (calibration::same_step(d, s)) resolver.fail(line, key, "recorded twice: " + s.instruction);
    proc.steps.push_back(std::move(s));
  };

  for (std::size_t h = 0; h < script.hands.size(); ++h) {
    const ScriptHand& hand = script.hands[h];
    const std::string hand_key = "hand[" + std::to_string(h) + "]";
    std::string device;
    for (const calibration::TrackerRole& t : devices.trackers)
      if (t.instrument == hand.tracker) device = t.device;
    if (device.empty()) resolver.fail(hand.line, hand_key + ".tracker", "the rig has no tracker for instrument " + std::to_string(hand.tracker));
    Keys keys(proc.motion[device]);
    Vec3 pos = fixture.rest_mm;
    double t = 0.0, tilt = 0.0;
    keys.tracker(0.0, pos, 0.0, 0.0, 0.0);
    for (std::size_t i = 0; i < hand.waypoints.size(); ++i) {
      const ScriptWaypoint& w = hand.waypoints[i];
      const std::string key = hand_key + ".waypoint[" + std::to_string(i) + "]";
      if (w.at_s && *w.at_s > t) {  // wait in place
        t = *w.at_s;
        keys.tracker(t, pos, 0.0, tilt, 0.0);
      }
      const FixtureLandmark l = resolver.landmark(w.to, w.to_line, key + ".to");
      const Vec3 target = l.at + w.offset_mm;
      const double speed = w.speed_mm_s.value_or(hand.speed_mm_s) * script.speed_scale;
      const double move = w.duration_s ? *w.duration_s / script.speed_scale : (target - pos).norm() / speed;
      tilt = w.tilt_deg.value_or(tilt);
      t += std::max(move, 0.001);
      pos = target;
      keys.tracker(t, pos, 0.0, tilt, 0.0);
      const double arrive = t, hold = w.hold_s / script.speed_scale;
      // The hold: the handle swings about the resting tip, or the hand trembles, or it is still.
      const int inner_keys = static_cast<int>(std::floor(hold / kKeyPeriod - 1e-6));
      for (int k = 1; k <= inner_keys; ++k) {
        const double s = k * kKeyPeriod;
        if (w.swing_deg) {
          const auto [from, to] = *w.swing_deg;
          const double amplitude = from + (to - from) * s / hold, phase = 2.0 * std::numbers::pi * s / w.swing_period_s;
          // A hand also turns the handle a little about its shaft while it circles.
          keys.tracker(arrive + s, pos, 15.0 * std::sin(0.7 * s), tilt + amplitude * std::sin(phase), amplitude * std::cos(phase));
        } else if (script.tremor_mm > 0.0) {
          keys.tracker(arrive + s, pos + script.tremor_mm * Vec3(tremor(rng), tremor(rng), tremor(rng)), 0.0, tilt, 0.0);
        }
      }
      t = arrive + hold;
      keys.tracker(t, pos, 0.0, tilt, 0.0);
      if (!w.records) continue;
      const std::string rkey = key + ".records";
      const std::string& what = *w.records;
      if (hold < 2.0 * kSettle + 0.1) resolver.fail(w.records_line, rkey, "a recorded hold needs hold_s ≥ " + std::to_string(2.0 * kSettle + 0.1) + " s");
      ProcedureStep s;
      s.start_s = arrive + kSettle;
      s.end_s = arrive + hold - kSettle;
      if (what == "pivot" || what == "fiducial" || what == "port") {
        calibration::step_kind_from_name(what, s.kind);
        if (l.kind != s.kind)
          resolver.fail(w.records_line, rkey, "a " + what + " is recorded at " + (what == "pivot" ? std::string("the divot") : what + ".N") + ", not at " + w.to);
        if (what == "pivot" && !w.swing_deg) resolver.fail(w.records_line, rkey, "a pivot needs swing_deg = [from, to]: the handle swung about the tip");
        s.device = device;
        s.index = what == "pivot" ? hand.tracker : l.index;
      } else if (what == "eye_zero") {
        if (devices.eyeball.empty()) resolver.fail(w.records_line, rkey, "the rig has no eyeball fixture");
        s.kind = StepKind::eye_zero;
        s.device = devices.eyeball;
      } else if (what == "pedal_rest" || what.rfind("pedal_travel.", 0) == 0) {
        if (devices.pedals.empty()) resolver.fail(w.records_line, rkey, "the rig has no pedals");
        s.device = devices.pedals;
        s.kind = what == "pedal_rest" ? StepKind::pedal_rest : StepKind::pedal_travel;
        if (s.kind == StepKind::pedal_travel) {
          const std::string axis = what.substr(13);
          if (axis != "0" && axis != "1") resolver.fail(w.records_line, rkey, "the pedal's axes are pedal_travel.0 (down) and pedal_travel.1 (sideways)");
          s.index = axis[0] - '0';
          s.start_s = arrive;  // the whole press counts: rest, down, held, back
          s.end_s = arrive + hold;
          presses.push_back({arrive, arrive + hold, s.index, w.travel, w.records_line});
        }
      } else {
        resolver.fail(w.records_line, rkey, "'" + what + "': records one of pivot, fiducial, port, eye_zero, pedal_rest, pedal_travel.0, pedal_travel.1");
      }
      record(std::move(s), w.records_line, rkey);
    }
    end_s = std::max(end_s, t);
  }

  // The feet: each press ramps down over 40 % of its hold, stays 20 %, and comes back.
  std::sort(presses.begin(), presses.end(), [](const Press& a, const Press& b) { return a.start_s < b.start_s; });
  if (!devices.pedals.empty()) {
    Keys keys(proc.motion[devices.pedals]);
    keys.pedals(0.0, 0.0, 0.0);
    double free_from = 0.0;
    for (const Press& p : presses) {
      if (p.start_s < free_from) resolver.fail(p.line, "records", "this press starts before the previous one has ended");
      const double d = p.end_s - p.start_s;
      const double v[2] = {p.axis == 0 ? p.travel : 0.0, p.axis == 1 ? p.travel : 0.0};
      keys.pedals(p.start_s, 0.0, 0.0);
      keys.pedals(p.start_s + 0.4 * d, v[0], v[1]);
      keys.pedals(p.start_s + 0.6 * d, v[0], v[1]);
      keys.pedals(p.end_s, 0.0, 0.0);
      free_from = p.end_s;
    }
  }
  if (!devices.eyeball.empty()) proc.motion[devices.eyeball] = "key 0 0 0 0 0 0\n";  // the eye is left alone

  proc.duration_s = end_s + 0.5;
  for (auto& [device, keys] : proc.motion) {
    (void)keys;
    ProcedureStep clock{StepKind::clock, device, 0, 0.0, proc.duration_s, ""};
    clock.instruction = instruction_of(clock);
    if (!clock.instruction.empty()) proc.steps.push_back(clock);
  }
  // In the order the technician does them; the clocks, measured throughout, last.
  std::stable_sort(proc.steps.begin(), proc.steps.end(), [](const ProcedureStep& a, const ProcedureStep& b) {
    const bool ca = a.kind == StepKind::clock, cb = b.kind == StepKind::clock;
    return ca != cb ? cb : (!ca && a.start_s < b.start_s);
  });
  return proc;
}

}  // namespace vitreo::rig
