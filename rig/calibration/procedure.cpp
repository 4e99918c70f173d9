#include "rig/calibration/procedure.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace vitreo::rig::calibration {

Fixture default_fixture() {
  Fixture f;
  const double r = 12.0;
  for (int k = 0; k < 6; ++k) {
    const double a = k * std::numbers::pi / 3.0;
    f.fiducials_mm.emplace_back(0.8 * r * std::cos(a), 0.8 * r * std::sin(a), 0.6 * r);
  }
  f.fiducials_mm.emplace_back(0.0, 0.0, r);
  f.fiducials_mm.emplace_back(r + 1.0, 0.0, 0.0);
  // Pars plana: 3.5 mm behind a 5.75 mm-radius limbus on the 12 mm globe, at 10 and 2 o'clock.
  const double z = 4.6, rho = std::sqrt(r * r - z * z);
  f.ports_mm.emplace_back(-rho * std::cos(std::numbers::pi / 6), rho * std::sin(std::numbers::pi / 6), z);
  f.ports_mm.emplace_back(rho * std::cos(std::numbers::pi / 6), rho * std::sin(std::numbers::pi / 6), z);
  return f;
}

namespace {

// fixed(v, n): v with n decimals (the feedback's numbers).
std::string fixed(double v, int digits) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

const char* const kStepKindNames[] = {"pivot", "fiducial", "port", "pedal_rest", "pedal_travel", "eye_zero", "clock"};

}  // namespace

bool same_step(const ProcedureStep& a, const ProcedureStep& b) { return a.kind == b.kind && a.device == b.device && a.index == b.index; }

std::string step_kind_name(StepKind k) { return kStepKindNames[static_cast<int>(k)]; }

bool step_kind_from_name(const std::string& name, StepKind& k) {
  for (int i = 0; i < 7; ++i)
    if (name == kStepKindNames[i]) return k = static_cast<StepKind>(i), true;
  return false;
}

std::vector<ProcedureStep> plan_steps(const Fixture& fixture, const std::vector<TrackerRole>& trackers, const std::string& pedals,
                                      const std::string& eyeball) {
  std::vector<ProcedureStep> steps;
  auto step = [&](StepKind kind, const std::string& device, int index, const std::string& instruction) {
    steps.push_back({kind, device, index, 0.0, 0.0, instruction});
  };
  if (!eyeball.empty()) step(StepKind::eye_zero, eyeball, 0, "leave the eye in its rest position");
  if (!pedals.empty()) {
    step(StepKind::pedal_rest, pedals, 0, "leave both pedals alone");
    step(StepKind::pedal_travel, pedals, 0, "press the pedal all the way and let it back");
    step(StepKind::pedal_travel, pedals, 1, "tilt the pedal sideways all the way and let it back");
  }
  for (const TrackerRole& t : trackers)
    step(StepKind::pivot, t.device, t.instrument,
         "rest the tip of instrument " + std::to_string(t.instrument) + " in the divot and swing the handle round it in widening circles");
  if (!trackers.empty()) {
    const std::string& first = trackers.front().device;
    for (std::size_t i = 0; i < fixture.fiducials_mm.size(); ++i)
      step(StepKind::fiducial, first, static_cast<int>(i),
           "touch fiducial " + std::to_string(i + 1) + " of " + std::to_string(fixture.fiducials_mm.size()) + " and hold still");
    for (std::size_t i = 0; i < fixture.ports_mm.size(); ++i)
      step(StepKind::port, first, static_cast<int>(i), "hold the tip in port " + std::to_string(i) + "'s trocar");
  }
  for (const TrackerRole& t : trackers) step(StepKind::clock, t.device, 0, "keep the devices connected");
  for (const std::string& d : {pedals, eyeball})
    if (!d.empty()) step(StepKind::clock, d, 0, "keep the devices connected");
  return steps;
}

std::vector<std::string> missing_steps(const std::vector<ProcedureStep>& planned, const std::vector<ProcedureStep>& done) {
  std::vector<std::string> out;
  for (const ProcedureStep& p : planned) {
    bool found = false;
    for (const ProcedureStep& d : done) found = found || same_step(p, d);
    if (!found) out.push_back(p.device + ": " + p.instruction);
  }
  return out;
}

namespace {

template <class T>
std::vector<T> in_window(const std::vector<T>& all, double a, double b) {
  std::vector<T> out;
  for (const T& x : all)
    if (x.t_s >= a && x.t_s <= b) out.push_back(x);
  return out;
}

std::string vec_text(const core::Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "(%.3f, %.3f, %.3f)", v.x(), v.y(), v.z());
  return b;
}

PivotPlot pivot_plot(const ProcedureStep& s, const std::vector<PivotPose>& poses, const PivotResult& r) {
  PivotPlot p;
  p.device = s.device;
  p.instrument = s.index;
  p.ok = r.ok;
  p.residuals_mm = r.residuals_mm;
  p.rms_mm = r.rms_mm;
  p.spread_deg = r.spread_deg;
  if (poses.empty()) return p;
  // The shafts' mean direction and two directions across it: each pose's tilt off the mean.
  core::Vec3 mean = core::Vec3::Zero();
  for (const PivotPose& q : poses) mean += q.orientation.normalized() * core::Vec3::UnitZ();
  if (mean.norm() < 1e-9) return p;
  mean.normalize();
  const core::Vec3 u = mean.unitOrthogonal(), v = mean.cross(u);
  for (const PivotPose& q : poses) {
    const core::Vec3 axis = q.orientation.normalized() * core::Vec3::UnitZ();
    p.tilt_x_deg.push_back(std::atan2(axis.dot(u), axis.dot(mean)) * 180.0 / std::numbers::pi);
    p.tilt_y_deg.push_back(std::atan2(axis.dot(v), axis.dot(mean)) * 180.0 / std::numbers::pi);
  }
  return p;
}

}  // namespace

Analysis analyse(const Procedure& proc, const Fixture& fixture, const Recording& rec, const Limits& limits) {
  Analysis a;
  a.limits = limits;
  std::map<std::string, core::Vec3> tip_offset;  // by device, once its pivot passed
  std::vector<core::Vec3> touched;               // fiducials, tracker frame
  std::vector<std::vector<core::Vec3>> port_tips_rig(fixture.ports_mm.size());
  std::string port_device;
  std::map<std::string, std::vector<double>> rest[2];
  static const std::vector<TimedPose> kNoPoses;
  static const std::vector<TimedPedal> kNoPedals;
  auto poses_of = [&](const std::string& d) -> const std::vector<TimedPose>& {
    const auto it = rec.poses.find(d);
    return it == rec.poses.end() ? kNoPoses : it->second;
  };
  auto pedals_of = [&](const std::string& d) -> const std::vector<TimedPedal>& {
    const auto it = rec.pedals.find(d);
    return it == rec.pedals.end() ? kNoPedals : it->second;
  };
  auto outcome = [&](const ProcedureStep& s, bool ok, const std::string& feedback) {
    a.steps.push_back({&s, ok, feedback});
    if (!ok) a.errors.push_back(s.device + ": " + s.instruction + ": " + feedback);
  };
  for (const ProcedureStep& s : proc.steps) {
    switch (s.kind) {
      case StepKind::pivot: {
        std::vector<PivotPose> poses;
        for (const TimedPose& p : in_window(poses_of(s.device), s.start_s, s.end_s)) poses.push_back({p.position_mm, p.orientation});
        const PivotResult r = calibrate_pivot(poses, limits.pivot);
        a.pivots.push_back(pivot_plot(s, poses, r));
        std::string fb = std::to_string(r.poses) + " samples, spread " + (fixed(r.spread_deg, 1) + "°") + ", RMS " +
                         (fixed(r.rms_mm, 3) + " mm") + (" (limit " + fixed(limits.pivot.max_rms_mm, 3) + " mm)");
        if (r.ok) {
          tip_offset[s.device] = r.tip_offset_mm;
          a.file.instruments.push_back({s.index, r.tip_offset_mm, r.poses, r.spread_deg, r.rms_mm});
          fb += ", tip offset " + vec_text(r.tip_offset_mm) + " mm";
        }
        outcome(s, r.ok, r.ok ? fb : r.error + " — " + fb);
        break;
      }
      case StepKind::fiducial:
      case StepKind::port: {
        const auto t = tip_offset.find(s.device);
        if (t == tip_offset.end()) {
          outcome(s, false, "needs this instrument's pivot calibration first");
          break;
        }
        std::vector<core::Vec3> tips;
        for (const TimedPose& p : in_window(poses_of(s.device), s.start_s, s.end_s))
          tips.push_back(p.position_mm + p.orientation.normalized() * t->second);
        if (tips.size() < limits.port.min_samples) {
          outcome(s, false, "only " + std::to_string(tips.size()) + " samples while holding (need " +
                                std::to_string(limits.port.min_samples) + "): did the tracker stop?");
          break;
        }
        const HeldPoint held = held_point(tips);
        const core::Vec3& mean = held.mean_mm;
        const double spread = held.spread_mm;
        const std::string fb = std::to_string(tips.size()) + " samples, held within " + (fixed(spread, 3) + " mm");
        if (s.kind == StepKind::fiducial) {
          const bool still = spread <= limits.port.max_spread_mm;
          if (still) touched.push_back(mean);
          outcome(s, still, still ? fb : "the tip moved while touching: " + fb);
        } else {
          port_tips_rig[static_cast<std::size_t>(s.index)] = tips;
          port_device = s.device;
          outcome(s, true, fb);
        }
        break;
      }
      case StepKind::pedal_rest: {
        const auto samples = in_window(pedals_of(s.device), s.start_s, s.end_s);
        for (const TimedPedal& p : samples)
          for (int ax = 0; ax < 2; ++ax) rest[ax][s.device].push_back(p.axes[ax]);
        const bool ok = samples.size() >= limits.pedal.min_rest_samples;
        outcome(s, ok, std::to_string(samples.size()) + " samples at rest" + (ok ? "" : ": did the pedals stop?"));
        break;
      }
      case StepKind::pedal_travel: {
        const auto samples = in_window(pedals_of(s.device), s.start_s, s.end_s);
        std::vector<double> travel;
        for (const TimedPedal& p : samples) travel.push_back(p.axes[s.index]);
        const PedalRangeResult r = measure_pedal_range(rest[s.index][s.device], travel, limits.pedal);
        const std::string fb = std::to_string(travel.size()) + " samples, reads " + (fixed(r.range.lo, 3)) + " at rest to " +
                               (fixed(r.range.hi, 3)) + " fully, dead zone " + (fixed(r.range.dead_zone, 3));
        if (r.ok) a.file.pedals.push_back({samples.empty() ? 0 : samples.front().pedal_id, s.index, r.range});
        outcome(s, r.ok, r.ok ? fb : r.error);
        break;
      }
      case StepKind::eye_zero: {
        const auto it = rec.eyeball.find(s.device);
        std::vector<TimedOrientation> samples = in_window(it == rec.eyeball.end() ? std::vector<TimedOrientation>{} : it->second,
                                                          s.start_s, s.end_s);
        if (samples.size() < limits.eye_zero.min_samples) {
          outcome(s, false, "only " + std::to_string(samples.size()) + " samples at rest (need " +
                                std::to_string(limits.eye_zero.min_samples) + "): did the fixture stop?");
          break;
        }
        // The mean of nearby unit quaternions: their sign-aligned sum, normalised (accurate to
        // second order in the spread, which is checked to be small).
        Eigen::Vector4d sum = Eigen::Vector4d::Zero();
        const Eigen::Vector4d first = samples.front().orientation.coeffs();
        for (const TimedOrientation& o : samples) sum += o.orientation.coeffs().dot(first) < 0 ? -o.orientation.coeffs() : o.orientation.coeffs();
        core::Quat mean;
        mean.coeffs() = sum.normalized();
        double spread = 0.0;
        for (const TimedOrientation& o : samples) spread = std::max(spread, mean.angularDistance(o.orientation) * 180.0 / std::numbers::pi);
        const Eigen::AngleAxisd aa(mean);
        const std::string fb = std::to_string(samples.size()) + " samples, zero " + fixed(aa.angle() * 180.0 / std::numbers::pi, 3) +
                               "° from the fixture's, still within " + fixed(spread, 3) + "°";
        const bool still = spread <= limits.eye_zero.max_spread_deg;
        if (still) a.file.eye_zero = EyeZeroRecord{mean, samples.size(), spread};
        outcome(s, still, still ? fb : "the eye moved: " + fb);
        break;
      }
      case StepKind::clock: {
        const auto it = rec.clocks.find(s.device);
        const ClockResult r = estimate_clock(it == rec.clocks.end() ? std::vector<TimeSyncExchange>{} : it->second, limits.clock);
        if (r.ok) a.file.clocks.push_back({s.device, r.offset_ms, r.drift_ppm, r.latency_ms, r.rms_ms});
        outcome(s, r.ok,
                r.ok ? std::to_string(r.used) + " of " + std::to_string(r.exchanges) + " time syncs: offset " +
                           (fixed(r.offset_ms, 3) + " ms") + ", drift " + (fixed(r.drift_ppm, 1) + " ppm") + ", latency " +
                           (fixed(r.latency_ms, 3) + " ms")
                     : r.error);
        break;
      }
    }
  }
  // Registration from the touched fiducials, then the ports through it.
  if (touched.size() == fixture.fiducials_mm.size()) {
    const RegistrationResult r = register_points(touched, fixture.fiducials_mm, limits.registration);
    a.fiducial_residuals_mm = r.residuals_mm;
    if (r.ok) {
      RegistrationRecord rr;
      rr.rig_to_eye = r.rig_to_eye.rotation;
      rr.eye_center_in_rig_mm = -(r.rig_to_eye.rotation.conjugate() * r.rig_to_eye.translation_mm);
      rr.fiducials = r.points;
      rr.fre_mm = r.fre_mm;
      rr.tre_mm = predicted_tre_mm(fixture.fiducials_mm, fle_from_fre(r.fre_mm, r.points), fixture.tre_target_mm);
      a.file.registration = rr;
      for (std::size_t i = 0; i < port_tips_rig.size(); ++i) {
        if (port_tips_rig[i].empty()) continue;
        std::vector<core::Vec3> in_eye;
        for (const core::Vec3& p : port_tips_rig[i]) in_eye.push_back(r.rig_to_eye.apply(p));
        const PortResult pr = measure_port(in_eye, limits.port);
        if (pr.ok) a.file.ports.push_back({static_cast<int>(i), pr.position_mm, pr.outward, pr.samples, pr.spread_mm});
        else a.errors.push_back(port_device + ": port " + std::to_string(i) + ": " + pr.error);
      }
    } else {
      a.errors.push_back("registration: " + r.error);
    }
  } else if (!fixture.fiducials_mm.empty() && !touched.empty()) {
    a.errors.push_back("registration: " + std::to_string(touched.size()) + " of " + std::to_string(fixture.fiducials_mm.size()) +
                       " fiducials were touched; registration needs them all");
  }
  for (const auto& [name, serial] : rec.serials) a.file.devices.push_back({name, serial});
  a.ok = a.errors.empty();
  return a;
}

std::string summary_text(const Analysis& a) {
  std::string s = "calibration summary\n";
  const CalibrationFile& f = a.file;
  for (const DeviceSerial& d : f.devices) s += "  device " + d.name + ": serial " + std::to_string(d.serial) + "\n";
  for (const InstrumentRecord& i : f.instruments)
    s += "  instrument " + std::to_string(i.instrument) + " tip offset " + vec_text(i.tip_offset_mm) + " mm: pivot RMS " +
         (fixed(i.rms_mm, 3) + " mm") + " over " + std::to_string(i.poses) + " poses, spread " + (fixed(i.spread_deg, 1) + "°") + "\n";
  if (f.registration) {
    const RegistrationRecord& r = *f.registration;
    s += "  registration: " + std::to_string(r.fiducials) + " fiducials, FRE " + (fixed(r.fre_mm, 3) + " mm") + ", TRE " +
         (fixed(r.tre_mm, 3) + " mm") + (r.tre_measured ? " (measured)" : " (predicted at the posterior pole)") + "\n";
    s += "    residual per fiducial (mm):";
    for (double e : a.fiducial_residuals_mm) s += (" " + fixed(e, 3));
    s += "\n";
  }
  for (const PortRecord& p : f.ports)
    s += "  port " + std::to_string(p.port) + " at " + vec_text(p.position_mm) + " mm (eye frame), held within " +
         (fixed(p.spread_mm, 3) + " mm") + "\n";
  for (const PedalRecord& p : f.pedals)
    s += "  pedal " + std::to_string(p.pedal) + " axis " + std::to_string(p.axis) + ": " + (fixed(p.range.lo, 3)) + " .. " +
         (fixed(p.range.hi, 3)) + ", dead zone " + (fixed(p.range.dead_zone, 3)) + "\n";
  if (f.eye_zero)
    s += "  eyeball zero: " + fixed(Eigen::AngleAxisd(f.eye_zero->zero).angle() * 180.0 / std::numbers::pi, 3) +
         "° from the fixture's own, still within " + fixed(f.eye_zero->spread_deg, 3) + "°\n";
  for (const ClockRecord& c : f.clocks)
    s += "  clock " + c.device + ": offset " + (fixed(c.offset_ms, 3) + " ms") + ", drift " + (fixed(c.drift_ppm, 1) + " ppm") +
         ", latency " + (fixed(c.latency_ms, 3) + " ms") + "\n";
  s += a.ok ? "  result: PASS\n" : "  result: FAIL\n";
  for (const std::string& e : a.errors) s += "    " + e + "\n";
  return s;
}

}  // namespace vitreo::rig::calibration
