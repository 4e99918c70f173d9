#include "drivers/sim/emulator.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cmath>
#include <limits>
#include <sstream>

namespace vitreo::drivers::sim {

const char* to_string(DeviceKind k) {
  switch (k) {
    case DeviceKind::tracker: return "tracker";
    case DeviceKind::pedals: return "pedals";
    case DeviceKind::eyeball: return "eyeball";
  }
  return "?";
}

namespace {
constexpr std::uint64_t kBootUs = 5'000'000;  // the device has been up 5 s when the link starts
constexpr std::uint64_t kHeartbeatUs = 100'000;

// Values per key: a pedal's axes and its switch word.
std::size_t key_width(const Script& s) {
  switch (s.kind) {
    case DeviceKind::tracker: return 7;
    case DeviceKind::pedals: return static_cast<std::size_t>(s.pedal_axes) + 1;
    case DeviceKind::eyeball: return 5;
  }
  return 0;
}

std::array<float, 4> quat_from_euler_deg(double yaw, double pitch, double roll) {
  const double d = M_PI / 180.0;
  const double cy = std::cos(yaw * d / 2), sy = std::sin(yaw * d / 2);
  const double cp = std::cos(pitch * d / 2), sp = std::sin(pitch * d / 2);
  const double cr = std::cos(roll * d / 2), sr = std::sin(roll * d / 2);
  return {float(cr * cp * cy + sr * sp * sy), float(sr * cp * cy - cr * sp * sy), float(cr * sp * cy + sr * cp * sy),
          float(cr * cp * sy - sr * sp * cy)};
}
// Hamilton product and rotation of a vector by a unit quaternion (w, x, y, z), in double.
std::array<double, 4> multiply(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3], a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1], a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}
std::array<double, 3> rotate(const std::array<double, 4>& q, const std::array<double, 3>& v) {
  const std::array<double, 4> p = {0, v[0], v[1], v[2]};
  const std::array<double, 4> r = multiply(multiply(q, p), {q[0], -q[1], -q[2], -q[3]});
  return {r[1], r[2], r[3]};
}
}  // namespace

bool Imperfections::tracker_any() const {
  for (int i = 0; i < 3; ++i)
    if (tip_offset_mm[i] != 0 || frame_ypr_deg[i] != 0 || frame_t_mm[i] != 0) return true;
  return false;
}

bool parse_script(const std::string& text, Script& out, std::string* error) {
  Script s;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  auto fail = [&](const std::string& why) {
    if (error) *error = "line " + std::to_string(lineno) + ": " + why;
    return false;
  };
  constexpr double kMaxTimeMs = 1e9;     // 11 days of script time: far beyond any session
  constexpr double kMaxValue = 1e6;      // no tracker, pedal or fixture value comes near
  if (text.size() > (1u << 20)) return fail("a script is at most 1 MiB");
  while (std::getline(in, line)) {
    ++lineno;
    if (auto h = line.find('#'); h != std::string::npos) line.resize(h);
    std::istringstream ls(line);
    std::vector<std::string> w;
    for (std::string t; ls >> t;) w.push_back(t);
    if (w.empty()) continue;
    const std::string& word = w[0];
    // A whole token that is a finite number: "nan", "inf", "1e999", "3x" are not.
    auto num = [&](std::size_t i, double& v) {
      if (i >= w.size()) return false;
      const char* b = w[i].c_str();
      char* e = nullptr;
      errno = 0;
      v = std::strtod(b, &e);
      return e != b && *e == '\0' && errno != ERANGE && std::isfinite(v);
    };
    auto exactly = [&](std::size_t n, const std::string& usage) {
      return w.size() == n ? true : fail(w.size() < n ? usage : "unexpected '" + w[n] + "' after " + word);
    };
    double a = 0, b = 0;
    if (word == "device") {
      if (!exactly(2, "device tracker|pedals|eyeball")) return false;
      const std::string& k = w[1];
      if (k == "tracker") s.kind = DeviceKind::tracker;
      else if (k == "pedals") s.kind = DeviceKind::pedals;
      else if (k == "eyeball") s.kind = DeviceKind::eyeball;
      else return fail("unknown device '" + k + "' (tracker, pedals, eyeball)");
    } else if (word == "rate_hz") {
      if (!exactly(2, "rate_hz N") || !num(1, a) || a < 1 || a > 10000) return fail("rate_hz must be 1..10000");
      s.rate_hz = static_cast<std::uint16_t>(a);
    } else if (word == "serial") {
      if (!exactly(2, "serial N") || !num(1, a) || a < 0 || a > 4294967295.0) return fail("serial must be a 32-bit number");
      s.serial = static_cast<std::uint32_t>(a);
    } else if (word == "loop" || word == "autostream") {
      if (!exactly(2, word + " 0|1") || !num(1, a) || (a != 0 && a != 1)) return fail(word + " needs 0 or 1");
      (word == "loop" ? s.loop : s.autostream) = a != 0;
    } else if (word == "tool" || word == "instrument") {
      if (!exactly(2, word + " N") || !num(1, a) || a < 0 || a > 255) return fail(word + " must be 0..255");
      (word == "tool" ? s.tool : s.instrument) = static_cast<std::uint8_t>(a);
    } else if (word == "corrupt" || word == "drop") {
      if (!exactly(2, word + " P") || !num(1, a) || a < 0 || a > 1) return fail(word + " needs a probability 0..1");
      (word == "corrupt" ? s.corrupt_byte_prob : s.drop_frame_prob) = a;
    } else if (word == "noise") {
      if (!exactly(2, "noise SCALE") || !num(1, a) || a < 0 || a > 100)
        return fail("noise needs a scale 0..100 (1: a real sensor's jitter)");
      s.noise = a;
    } else if (word == "seed") {
      if (!exactly(2, "seed N") || !num(1, a) || a < 0 || a > 9.0e15) return fail("seed must be a non-negative number");
      s.seed = static_cast<std::uint64_t>(a);
    } else if (word == "tip_offset" || word == "tracker_frame") {
      const bool frame = word == "tracker_frame";
      if (!exactly(frame ? 7 : 4, frame ? "tracker_frame YAW PITCH ROLL X Y Z" : "tip_offset X Y Z")) return false;
      double v[6] = {};
      for (std::size_t i = 1; i < w.size(); ++i)
        if (!num(i, v[i - 1]) || std::fabs(v[i - 1]) > 1000) return fail(word + " needs finite numbers (degrees, mm; |x| <= 1000)");
      for (int i = 0; i < 3; ++i) {
        if (frame) s.imperfect.frame_ypr_deg[i] = v[i], s.imperfect.frame_t_mm[i] = v[i + 3];
        else s.imperfect.tip_offset_mm[i] = v[i];
      }
    } else if (word == "pedal_id" || word == "axes") {
      const bool id = word == "pedal_id";
      if (!exactly(2, word + " N") || !num(1, a) || a < (id ? 0 : 1) || a > (id ? 255 : 4)) return fail(id ? "pedal_id must be 0..255" : "axes must be 1..4");
      if (!s.keys.empty()) return fail(word + " must come before the first key");
      (id ? s.pedal_id : s.pedal_axes) = static_cast<std::uint8_t>(a);
    } else if (word == "pedal_range") {
      if (!exactly(4, "pedal_range AXIS LO HI") || !num(1, a) || (a != 0 && a != 1) || !num(2, b)) return fail("pedal_range AXIS(0|1) LO HI");
      double hi = 0;
      if (!num(3, hi) || b < 0 || hi > 1 || !(hi > b)) return fail("pedal_range needs 0 <= LO < HI <= 1");
      s.imperfect.pedal_lo[static_cast<int>(a)] = b, s.imperfect.pedal_hi[static_cast<int>(a)] = hi;
    } else if (word == "eye_zero") {
      if (!exactly(3, "eye_zero YAW PITCH") || !num(1, a) || !num(2, b) || std::fabs(a) > 90 || std::fabs(b) > 90)
        return fail("eye_zero needs a yaw and a pitch in degrees (-90..90)");
      s.imperfect.eye_zero_deg[0] = a, s.imperfect.eye_zero_deg[1] = b;
    } else if (word == "clock_offset_ms") {
      // The device clock must not go below zero: it has been up kBootUs (5 s) when the link starts.
      if (!exactly(2, "clock_offset_ms X") || !num(1, a) || a < -4000 || a > 1e9) return fail("clock_offset_ms must be -4000..1e9");
      s.imperfect.clock_offset_ms = a;
    } else if (word == "clock_drift_ppm") {
      if (!exactly(2, "clock_drift_ppm Y") || !num(1, a) || std::fabs(a) > 10000) return fail("clock_drift_ppm must be -10000..10000");
      s.imperfect.clock_drift_ppm = a;
    } else if (word == "key") {
      const std::size_t width = key_width(s);
      if (w.size() != width + 2)
        return fail("key for " + std::string(to_string(s.kind)) + " needs a time and " + std::to_string(width) + " values, got " +
                    std::to_string(w.size() - 1) + " numbers");
      if (!num(1, a) || a < 0 || a > kMaxTimeMs) return fail("key needs a time in ms (0.." + std::to_string(static_cast<long long>(kMaxTimeMs)) + ")");
      std::vector<double> v;
      for (std::size_t i = 2; i < w.size(); ++i) {
        if (!num(i, b) || std::fabs(b) > kMaxValue) return fail("key value '" + w[i] + "' is not a finite number of sane size");
        v.push_back(b);
      }
      if (!s.keys.empty() && static_cast<std::uint64_t>(a * 1000) <= s.keys.back().first)
        return fail("key times must increase");
      s.keys.emplace_back(static_cast<std::uint64_t>(a * 1000), std::move(v));
    } else if (word == "fault") {
      FaultEvent f;
      if (w.size() < 4 || w.size() > 5 || !num(1, a) || !num(2, b) || a < 0 || b < 0 || a > kMaxTimeMs || b > kMaxTimeMs)
        return fail("fault <t_ms> <duration_ms> <kind> [value]");
      const std::string& k = w[3];
      static const std::pair<const char*, FaultKind> kinds[] = {
          {"nan", FaultKind::nan},         {"range", FaultKind::range}, {"stuck", FaultKind::stuck},
          {"jump", FaultKind::jump},       {"version", FaultKind::version}, {"unknown", FaultKind::unknown},
          {"drop", FaultKind::drop},       {"disconnect", FaultKind::disconnect}};
      bool found = false;
      for (auto& [n, kk] : kinds)
        if (k == n) f.kind = kk, found = true;
      if (!found) return fail("unknown fault '" + k + "'");
      f.at_us = static_cast<std::uint64_t>(a * 1000);
      f.duration_us = static_cast<std::uint64_t>(b * 1000);
      if (f.kind == FaultKind::jump) {
        // How far the device clock jumps (ms); "jump nan" used to be taken as a jump of 0.
        if (w.size() != 5 || !num(4, f.value) || std::fabs(f.value) > kMaxTimeMs)
          return fail("fault ... jump needs how many ms the device clock jumps (a finite number)");
      } else if (w.size() == 5) {
        return fail("unexpected '" + w[4] + "' after fault " + k + " (only jump takes a value)");
      }
      s.faults.push_back(f);
    } else {
      return fail("unknown directive '" + word + "'");
    }
  }
  if (s.keys.empty()) return fail("a script needs at least one key");
  for (auto& k : s.keys)
    if (k.second.size() != key_width(s)) return fail("keys do not match the device kind");
  out = std::move(s);
  return true;
}

Script default_script(DeviceKind k) {
  const char* text = nullptr;
  switch (k) {
    case DeviceKind::tracker:
      // forceps through a port: approach, grasp, peel sideways, release, withdraw
      text = "device tracker\nrate_hz 1000\nserial 1001\ntool 3\n"
             "key 0 0 0 25 0 0 0 0\nkey 1000 1 0.5 14 5 -10 0 0\nkey 1500 1.2 0.6 12.5 5 -10 0 1\n"
             "key 2500 3 1.5 12.8 8 -12 20 1\nkey 3000 3 1.5 13 8 -12 20 0\nkey 4000 0 0 25 0 0 0 0\n";
      break;
    case DeviceKind::pedals:
      text = "device pedals\nrate_hz 500\nserial 2001\n"
             "key 0 0 0 0\nkey 500 0.6 0 0\nkey 1500 1 0 1\nkey 2000 0.2 0 0\nkey 3000 0 0.5 4\nkey 4000 0 0 0\n";
      break;
    case DeviceKind::eyeball:
      text = "device eyeball\nrate_hz 250\nserial 3001\n"
             "key 0 0 0 0 0 0\nkey 1000 0 0 12 0 10\nkey 2000 15 -5 14 0 10\nkey 3000 -10 8 14 3 10\nkey 4000 0 0 0 0 0\n";
      break;
  }
  Script s;
  std::string err;
  parse_script(text, s, &err);
  return s;
}

FirmwareEmulator::FirmwareEmulator(Script s) : s_(std::move(s)), rng_(s_.seed), noise_rng_(s_.seed ^ 0x9e3779b97f4a7c15ULL) {
  streaming_ = s_.autostream;
  device_offset_us_ = 0;
}

void FirmwareEmulator::reset_link() {
  streaming_ = s_.autostream;
  replies_.clear();
}

std::uint64_t FirmwareEmulator::device_time_us(std::uint64_t now_us) const {
  const std::uint64_t elapsed = started_ ? now_us - start_us_ : 0;
  std::uint64_t t = elapsed + kBootUs;
  if (s_.imperfect.clock_any()) {  // only then, so an ideal clock's arithmetic stays integer and exact
    t = static_cast<std::uint64_t>(static_cast<double>(elapsed) * (1.0 + s_.imperfect.clock_drift_ppm * 1e-6) +
                                   static_cast<double>(kBootUs) + s_.imperfect.clock_offset_ms * 1000.0);
  }
  for (auto& f : s_.faults)
    if (f.kind == FaultKind::jump && t >= f.at_us + kBootUs) t = static_cast<std::uint64_t>(static_cast<double>(t) + f.value * 1000);
  return t;
}

bool FirmwareEmulator::in_fault(FaultKind k, std::uint64_t t_us) const {
  for (auto& f : s_.faults)
    if (f.kind == k && t_us >= f.at_us && t_us < f.at_us + f.duration_us) return true;
  return false;
}

bool FirmwareEmulator::disconnected(std::uint64_t now_us) const {
  return started_ && in_fault(FaultKind::disconnect, now_us - start_us_);
}

void FirmwareEmulator::on_host_message(const vp_message& m, std::uint64_t now_us) {
  ++c_.host_messages;
  vp_message r{};
  switch (m.type) {
    case VP_MSG_CONFIG:
      if (m.u.config.op == VP_CFG_GET && m.u.config.key == VP_CFG_KEY_IDENTIFY) {
        r.type = VP_MSG_DEVICE_INFO;
        auto& d = r.u.device_info;
        d.device_type = s_.kind == DeviceKind::tracker ? VP_DEVICE_TRACKER
                        : s_.kind == DeviceKind::pedals ? VP_DEVICE_PEDAL
                                                        : VP_DEVICE_EYEBALL;
        d.hw_revision = 1;
        d.serial = s_.serial;
        d.fw_major = 0, d.fw_minor = 9, d.fw_patch = 0;
        d.proto_major = VP_PROTO_MAJOR, d.proto_minor = VP_PROTO_MINOR;
        d.sample_rate_hz = s_.rate_hz;
      } else if (m.u.config.op == VP_CFG_SET) {
        r.type = VP_MSG_CONFIG;
        r.u.config = m.u.config;
        r.u.config.op = VP_CFG_ACK;
        if (m.u.config.key == VP_CFG_KEY_STREAMING) {
          streaming_ = m.u.config.value != 0;
        } else if (m.u.config.key == VP_CFG_KEY_SAMPLE_RATE_HZ) {
          if (m.u.config.value >= 1 && m.u.config.value <= 10000) {
            s_.rate_hz = static_cast<std::uint16_t>(m.u.config.value);
          } else {
            r.u.config.op = VP_CFG_NAK;
          }
        } else {
          r.u.config.op = VP_CFG_NAK;
        }
      } else {
        return;
      }
      break;
    case VP_MSG_TIME_SYNC:
      if (m.u.time_sync.phase != 0) return;
      r.type = VP_MSG_TIME_SYNC;
      r.u.time_sync = m.u.time_sync;
      r.u.time_sync.phase = 1;
      r.u.time_sync.device_rx_us = device_time_us(now_us);
      r.u.time_sync.device_tx_us = device_time_us(now_us);
      break;
    case VP_MSG_CALIB_REQUEST:
      r.type = VP_MSG_CALIB_RESULT;
      r.u.calib_result.procedure = m.u.calib_request.procedure;
      r.u.calib_result.instrument_id = m.u.calib_request.instrument_id;
      r.u.calib_result.token = m.u.calib_request.token;
      r.u.calib_result.residual_mm = 0.05f;
      break;
    default: return;
  }
  replies_.push_back(r);
}

vp_message FirmwareEmulator::make_sample(std::uint64_t t_script_us, std::uint64_t device_us) {
  const auto& keys = s_.keys;
  std::uint64_t span = keys.back().first;
  std::uint64_t t = t_script_us;
  if (s_.loop && span > 0) t %= span;
  // linear interpolation between keyframes (pedal switches: held from the earlier key)
  std::vector<double> v = keys.back().second;
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    if (t >= keys[i].first && t < keys[i + 1].first) {
      double a = double(t - keys[i].first) / double(keys[i + 1].first - keys[i].first);
      for (std::size_t j = 0; j < v.size(); ++j) v[j] = keys[i].second[j] + a * (keys[i + 1].second[j] - keys[i].second[j]);
      if (s_.kind == DeviceKind::pedals) v[s_.pedal_axes] = keys[i].second[s_.pedal_axes];
      break;
    }
  }
  if (t < keys.front().first) v = keys.front().second;
  vp_message m{};
  switch (s_.kind) {
    case DeviceKind::tracker: {
      m.type = VP_MSG_POSE_SAMPLE;
      auto& p = m.u.pose;
      p.timestamp_us = device_us;
      p.instrument_id = s_.instrument;
      p.tool_type = s_.tool;
      // seeded sensor noise, as a real tracker has (and the stuck detector expects)
      std::normal_distribution<double> tip(0.0, 0.005 * s_.noise), angle(0.0, 0.01 * s_.noise);
      for (int i = 0; i < 3; ++i) p.tip_mm[i] = static_cast<float>(v[static_cast<std::size_t>(i)] + (s_.noise > 0 ? tip(noise_rng_) : 0.0));
      const double jy = s_.noise > 0 ? angle(noise_rng_) : 0.0, jp = s_.noise > 0 ? angle(noise_rng_) : 0.0, jr = s_.noise > 0 ? angle(noise_rng_) : 0.0;
      auto q = quat_from_euler_deg(v[3] + jy, v[4] + jp, v[5] + jr);
      if (s_.imperfect.tracker_any()) {
        // The real tip (the keys) → the tracked point behind it → the tracker's own frame.
        const Imperfections& im = s_.imperfect;
        const std::array<double, 4> qd = {q[0], q[1], q[2], q[3]};
        const std::array<float, 4> ff = quat_from_euler_deg(im.frame_ypr_deg[0], im.frame_ypr_deg[1], im.frame_ypr_deg[2]);
        const std::array<double, 4> f = {ff[0], ff[1], ff[2], ff[3]};
        double marker[3];
        const std::array<double, 3> off = rotate(qd, {im.tip_offset_mm[0], im.tip_offset_mm[1], im.tip_offset_mm[2]});
        for (int i = 0; i < 3; ++i) marker[i] = static_cast<double>(p.tip_mm[i]) - off[static_cast<std::size_t>(i)];
        const std::array<double, 3> r = rotate(f, {marker[0], marker[1], marker[2]});
        for (int i = 0; i < 3; ++i) p.tip_mm[i] = static_cast<float>(r[static_cast<std::size_t>(i)] + im.frame_t_mm[i]);
        const std::array<double, 4> fq = multiply(f, qd);
        for (int i = 0; i < 4; ++i) q[static_cast<std::size_t>(i)] = static_cast<float>(fq[static_cast<std::size_t>(i)]);
      }
      for (int i = 0; i < 4; ++i) p.q_wxyz[i] = q[static_cast<std::size_t>(i)];
      p.actuation = static_cast<std::uint16_t>(std::clamp(v[6], 0.0, 1.0) * 65535.0 + 0.5);
      p.quality_pct = 98;
      break;
    }
    case DeviceKind::pedals: {
      m.type = VP_MSG_PEDAL_STATE;
      auto& p = m.u.pedal;
      p.timestamp_us = device_us;
      p.pedal_id = s_.pedal_id;
      p.axis_count = s_.pedal_axes;
      // The keys are the pedal's travel; its potentiometer maps that onto lo..hi (0..1 when ideal).
      const Imperfections& im = s_.imperfect;
      for (int a = 0; a < s_.pedal_axes; ++a) {
        const double travel = std::clamp(v[static_cast<std::size_t>(a)], 0.0, 1.0);
        const bool ideal = a >= 2 || (im.pedal_lo[a] == 0 && im.pedal_hi[a] == 1);
        const double raw = ideal ? travel : im.pedal_lo[a] + (im.pedal_hi[a] - im.pedal_lo[a]) * travel;
        p.axes[a] = static_cast<std::uint16_t>(raw * 65535.0 + 0.5);
      }
      // A script may say anything up to ±1e6 (parse_script): the switch word is 16 bits.
      p.switches = static_cast<std::uint16_t>(std::clamp(v[s_.pedal_axes], 0.0, 65535.0));
      break;
    }
    case DeviceKind::eyeball: {
      m.type = VP_MSG_EYEBALL_STATE;
      auto& p = m.u.eyeball;
      p.timestamp_us = device_us;
      std::normal_distribution<double> angle(0.0, 0.01 * s_.noise), depth(0.0, 0.002 * s_.noise);
      const double jy = s_.noise > 0 ? angle(noise_rng_) : 0.0, jp = s_.noise > 0 ? angle(noise_rng_) : 0.0, jr = s_.noise > 0 ? angle(noise_rng_) : 0.0;
      auto q = quat_from_euler_deg(v[0] + jy, v[1] + jp, jr);
      if (s_.imperfect.eye_zero_deg[0] != 0 || s_.imperfect.eye_zero_deg[1] != 0) {
        const std::array<float, 4> zf = quat_from_euler_deg(s_.imperfect.eye_zero_deg[0], s_.imperfect.eye_zero_deg[1], 0.0);
        const std::array<double, 4> zq = multiply({zf[0], zf[1], zf[2], zf[3]}, {q[0], q[1], q[2], q[3]});
        for (int i = 0; i < 4; ++i) q[static_cast<std::size_t>(i)] = static_cast<float>(zq[static_cast<std::size_t>(i)]);
      }
      for (int i = 0; i < 4; ++i) p.q_wxyz[i] = q[static_cast<std::size_t>(i)];
      p.port_count = 3;
      for (int i = 0; i < 3; ++i) {
        double d = std::clamp(v[2 + static_cast<std::size_t>(i)], 0.0, 40.0);
        if (d > 0 && s_.noise > 0) d = std::max(1e-3, d + depth(noise_rng_));
        p.ports[i].flags = d > 0 ? 1 : 0;
        p.ports[i].depth_mm = d > 0 ? static_cast<float>(d) : 0.0f;
      }
      break;
    }
  }
  return m;
}

void FirmwareEmulator::emit(vp_message m, std::vector<proto::Bytes>& packets, std::uint64_t script_us, bool valid) {
  m.seq = seq_++;  // a dropped frame still consumes its sequence number: that is how drops show
  m.version_minor = VP_PROTO_MINOR;
  std::bernoulli_distribution drop(s_.drop_frame_prob);
  if (in_fault(FaultKind::drop, script_us) || (s_.drop_frame_prob > 0 && drop(rng_))) {
    ++c_.frames_dropped;
    return;
  }
  proto::Bytes p = proto::encode_packet(m);
  if (in_fault(FaultKind::version, script_us)) {
    p[0] = static_cast<std::uint8_t>(0x20 | (p[0] & 0x0F));
    valid = false;
    ++c_.invalid_injected;
  } else if (in_fault(FaultKind::unknown, script_us)) {
    p[1] = 0x7E;
    valid = false;
    ++c_.invalid_injected;
  }
  if (valid && on_sent_ && (m.type == VP_MSG_POSE_SAMPLE || m.type == VP_MSG_PEDAL_STATE || m.type == VP_MSG_EYEBALL_STATE))
    on_sent_(m);
  if (valid && (m.type == VP_MSG_POSE_SAMPLE || m.type == VP_MSG_PEDAL_STATE || m.type == VP_MSG_EYEBALL_STATE))
    ++c_.samples_sent;
  ++c_.frames_sent;
  packets.push_back(std::move(p));
}

void FirmwareEmulator::step(std::uint64_t now_us, std::vector<proto::Bytes>& packets) {
  if (!started_) {
    started_ = true;
    start_us_ = now_us;
    next_sample_us_ = now_us;
    next_heartbeat_us_ = now_us;
  }
  const std::uint64_t script_now = now_us - start_us_;
  if (in_fault(FaultKind::disconnect, script_now)) return;
  for (auto& r : replies_) emit(r, packets, script_now, true);
  replies_.clear();
  if (now_us >= next_heartbeat_us_) {
    vp_message h{};
    h.type = VP_MSG_HEARTBEAT;
    h.u.heartbeat.uptime_us = device_time_us(now_us);
    h.u.heartbeat.device_state = streaming_ ? 1 : 0;
    emit(h, packets, script_now, true);
    next_heartbeat_us_ = now_us + kHeartbeatUs;
  }
  if (!streaming_) {
    next_sample_us_ = now_us;
    return;
  }
  const std::uint64_t period = 1'000'000u / s_.rate_hz;
  int burst = 0;
  while (next_sample_us_ <= now_us && burst++ < 50) {
    const std::uint64_t t = next_sample_us_ - start_us_;
    next_sample_us_ += period;
    vp_message m = make_sample(t, device_time_us(t + start_us_));
    bool valid = true;
    if (in_fault(FaultKind::stuck, t)) {
      if (!have_stuck_) stuck_ = m, have_stuck_ = true;
      std::uint64_t ts = m.type == VP_MSG_POSE_SAMPLE ? m.u.pose.timestamp_us
                         : m.type == VP_MSG_PEDAL_STATE ? m.u.pedal.timestamp_us
                                                        : m.u.eyeball.timestamp_us;
      m = stuck_;  // frozen values, live timestamps: what a hung sensor behind a live MCU sends
      if (m.type == VP_MSG_POSE_SAMPLE) m.u.pose.timestamp_us = ts;
      if (m.type == VP_MSG_PEDAL_STATE) m.u.pedal.timestamp_us = ts;
      if (m.type == VP_MSG_EYEBALL_STATE) m.u.eyeball.timestamp_us = ts;
    } else {
      have_stuck_ = false;
    }
    const bool nan = in_fault(FaultKind::nan, t), range = in_fault(FaultKind::range, t);
    if (nan || range) {
      const float bad = nan ? std::numeric_limits<float>::quiet_NaN() : 900.0f;
      if (m.type == VP_MSG_POSE_SAMPLE) m.u.pose.tip_mm[0] = bad;
      if (m.type == VP_MSG_EYEBALL_STATE) m.u.eyeball.q_wxyz[1] = bad;
      if (m.type == VP_MSG_PEDAL_STATE) m.u.pedal.axis_count = 7;  // integers cannot be NaN: out of range
      valid = false;
      ++c_.invalid_injected;
    }
    emit(m, packets, t, valid);
  }
}

void FirmwareEmulator::corrupt(proto::Bytes& frame) {
  if (s_.corrupt_byte_prob <= 0) return;
  std::bernoulli_distribution hit(s_.corrupt_byte_prob);
  std::uniform_int_distribution<int> flip(1, 255);
  bool any = false;
  for (auto& b : frame)
    if (hit(rng_)) {
      b = static_cast<std::uint8_t>(b ^ flip(rng_));
      ++c_.bytes_corrupted;
      any = true;
    }
  c_.frames_corrupted += any;
}

}  // namespace vitreo::drivers::sim
