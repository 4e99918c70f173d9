#include "rig/calibration/calibration_recording.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>

#include "rig/files/read_text_file.hpp"
#include "rig/files/write_file_atomically.hpp"

namespace vitreo::rig::calibration {
namespace {

constexpr const char* kMagic = "vitreo-calibration-recording";
constexpr std::size_t kMaxRecordingBytes = std::size_t{256} << 20;  // hours of 1 kHz tracking

// %.17g: every double reads back as itself.
void number(std::string& out, double v) {
  char b[40];
  std::snprintf(b, sizeof b, " %.17g", v);
  out += b;
}

void check_name(const std::string& what, const std::string& name) {
  if (name.empty() || name.find_first_of(" \t\r\n") != std::string::npos)
    throw std::runtime_error("a calibration recording cannot name the " + what + " '" + name + "' (empty or with spaces)");
}

// The words of one line, with "FILE:LINE: why" failures.
class Line {
 public:
  Line(const std::string& origin, int line, const std::string& text) : origin_(origin), line_(line) {
    std::istringstream in(text);
    for (std::string w; in >> w;) words_.push_back(w);
  }
  [[noreturn]] void fail(const std::string& why) const { throw std::runtime_error(origin_ + ":" + std::to_string(line_) + ": " + why); }
  std::size_t size() const { return words_.size(); }
  const std::string& word(std::size_t i) const {
    if (i >= words_.size()) fail("'" + words_.front() + "' line ends early");
    return words_[i];
  }
  double real(std::size_t i) const {
    const std::string& w = word(i);
    char* end = nullptr;
    const double v = std::strtod(w.c_str(), &end);
    if (!end || *end != '\0' || !std::isfinite(v)) fail("'" + w + "' is not a finite number");
    return v;
  }
  std::uint64_t unsigned_int(std::size_t i) const {
    const std::string& w = word(i);
    char* end = nullptr;
    if (w.empty() || w[0] == '-') fail("'" + w + "' is not a whole number ≥ 0");
    const unsigned long long v = std::strtoull(w.c_str(), &end, 10);
    if (!end || *end != '\0') fail("'" + w + "' is not a whole number ≥ 0");
    return v;
  }
  void exactly(std::size_t n) const {
    if (words_.size() != n) fail("'" + words_.front() + "' takes " + std::to_string(n - 1) + " fields, this line has " + std::to_string(words_.size() - 1));
  }
  // The words from i on, as one text (names and instructions with spaces).
  std::string rest(std::size_t i) const {
    std::string s;
    for (std::size_t k = i; k < words_.size(); ++k) s += (k > i ? " " : "") + words_[k];
    if (s.empty()) fail("'" + words_.front() + "' needs its text");
    return s;
  }

 private:
  const std::string& origin_;
  int line_;
  std::vector<std::string> words_;
};

}  // namespace

void write_calibration_recording(const std::string& path, const CalibrationSession& session) {
  std::string out = std::string(kMagic) + " " + std::to_string(kCalibrationRecordingVersion) + "\n";
  out += "rig " + session.rig + "\nfixture default\nduration";
  number(out, session.procedure.duration_s);
  out += "\n";
  for (const auto& [name, serial] : session.recording.serials) {
    check_name("device", name);
    out += "serial " + name + " " + std::to_string(serial) + "\n";
  }
  for (const ProcedureStep& s : session.procedure.steps) {
    check_name("device", s.device);
    out += "step " + step_kind_name(s.kind) + " " + s.device + " " + std::to_string(s.index);
    number(out, s.start_s);
    number(out, s.end_s);
    out += " " + s.instruction + "\n";
  }
  for (const auto& [name, poses] : session.recording.poses) {
    check_name("device", name);
    for (const TimedPose& p : poses) {
      out += "pose " + name;
      for (double v : {p.t_s, p.position_mm.x(), p.position_mm.y(), p.position_mm.z(), p.orientation.w(), p.orientation.x(),
                       p.orientation.y(), p.orientation.z()})
        number(out, v);
      out += "\n";
    }
  }
  for (const auto& [name, samples] : session.recording.eyeball) {
    check_name("device", name);
    for (const TimedOrientation& e : samples) {
      out += "eye " + name;
      for (double v : {e.t_s, e.orientation.w(), e.orientation.x(), e.orientation.y(), e.orientation.z()}) number(out, v);
      out += "\n";
    }
  }
  for (const auto& [name, samples] : session.recording.pedals) {
    check_name("device", name);
    for (const TimedPedal& p : samples) {
      out += "pedal " + name;
      number(out, p.t_s);
      out += " " + std::to_string(p.pedal_id);
      number(out, p.axes[0]);
      number(out, p.axes[1]);
      out += "\n";
    }
  }
  for (const auto& [name, exchanges] : session.recording.clocks) {
    check_name("device", name);
    for (const TimeSyncExchange& x : exchanges)
      out += "sync " + name + " " + std::to_string(x.host_tx_us) + " " + std::to_string(x.device_rx_us) + " " + std::to_string(x.device_tx_us) +
             " " + std::to_string(x.host_rx_us) + "\n";
  }
  for (const std::string& e : session.events) out += "event " + e + "\n";
  if (const std::string why = files::write_file_atomically(path, out); !why.empty()) throw std::runtime_error(why);
}

CalibrationSession parse_calibration_recording(const std::string& text, const std::string& origin) {
  CalibrationSession s;
  std::istringstream in(text);
  std::string raw;
  int n = 0;
  bool have_duration = false;
  std::map<std::string, double> last_t;  // per device and kind: samples come in time order
  while (std::getline(in, raw)) {
    ++n;
    if (raw.find_first_not_of(" \t\r") == std::string::npos) continue;
    const Line l(origin, n, raw);
    const std::string& kind = l.word(0);
    if (n == 1) {
      if (kind != kMagic) l.fail("not a vitreo calibration recording (it starts '" + std::string(kMagic) + " VERSION')");
      l.exactly(2);
      const std::uint64_t v = l.unsigned_int(1);
      if (v != kCalibrationRecordingVersion)
        l.fail("this is a version " + std::to_string(v) + " calibration recording; this vitreo-calibrate reads version " +
               std::to_string(kCalibrationRecordingVersion));
      continue;
    }
    auto in_order = [&](const std::string& key, double t) {
      auto [it, fresh] = last_t.emplace(key, t);
      if (!fresh && t < it->second) l.fail("time " + std::to_string(t) + " s goes back (the previous was " + std::to_string(it->second) + " s)");
      it->second = t;
    };
    if (kind == "rig") {
      s.rig = l.rest(1);
    } else if (kind == "fixture") {
      l.exactly(2);
      if (l.word(1) != "default") l.fail("fixture '" + l.word(1) + "': this vitreo-calibrate knows the default fixture only");
    } else if (kind == "duration") {
      l.exactly(2);
      s.procedure.duration_s = l.real(1);
      have_duration = true;
    } else if (kind == "serial") {
      l.exactly(3);
      const std::uint64_t v = l.unsigned_int(2);
      if (v > 0xffffffffu) l.fail("serial number " + l.word(2) + " is larger than 32 bits");
      s.recording.serials[l.word(1)] = static_cast<std::uint32_t>(v);
    } else if (kind == "step") {
      ProcedureStep st;
      if (!step_kind_from_name(l.word(1), st.kind)) l.fail("unknown step '" + l.word(1) + "'");
      st.device = l.word(2);
      st.index = static_cast<int>(l.unsigned_int(3));
      st.start_s = l.real(4);
      st.end_s = l.real(5);
      if (!(st.start_s <= st.end_s)) l.fail("the step's window ends before it starts");
      st.instruction = l.rest(6);
      s.procedure.steps.push_back(std::move(st));
    } else if (kind == "pose") {
      l.exactly(10);
      TimedPose p;
      p.t_s = l.real(2);
      p.position_mm = core::Vec3(l.real(3), l.real(4), l.real(5));
      p.orientation = core::Quat(l.real(6), l.real(7), l.real(8), l.real(9));
      if (std::abs(p.orientation.norm() - 1.0) > 1e-3) l.fail("the orientation is not a unit quaternion");
      in_order("pose " + l.word(1), p.t_s);
      s.recording.poses[l.word(1)].push_back(p);
    } else if (kind == "eye") {
      l.exactly(7);
      TimedOrientation e;
      e.t_s = l.real(2);
      e.orientation = core::Quat(l.real(3), l.real(4), l.real(5), l.real(6));
      if (std::abs(e.orientation.norm() - 1.0) > 1e-3) l.fail("the orientation is not a unit quaternion");
      in_order("eye " + l.word(1), e.t_s);
      s.recording.eyeball[l.word(1)].push_back(e);
    } else if (kind == "pedal") {
      l.exactly(6);
      TimedPedal p;
      p.t_s = l.real(2);
      p.pedal_id = static_cast<int>(l.unsigned_int(3));
      p.axes[0] = l.real(4);
      p.axes[1] = l.real(5);
      in_order("pedal " + l.word(1), p.t_s);
      s.recording.pedals[l.word(1)].push_back(p);
    } else if (kind == "sync") {
      l.exactly(6);
      s.recording.clocks[l.word(1)].push_back({l.unsigned_int(2), l.unsigned_int(3), l.unsigned_int(4), l.unsigned_int(5)});
    } else if (kind == "event") {
      s.events.push_back(l.rest(1));
    } else {
      l.fail("unknown line '" + kind + "' (rig, fixture, duration, serial, step, pose, eye, pedal, sync, event)");
    }
  }
  if (n == 0) throw std::runtime_error(origin + ":1: empty: not a vitreo calibration recording");
  if (!have_duration) throw std::runtime_error(origin + ":" + std::to_string(n) + ": no 'duration' line");
  if (s.procedure.steps.empty()) throw std::runtime_error(origin + ":" + std::to_string(n) + ": no 'step' line: nothing to analyse");
  return s;
}

CalibrationSession read_calibration_recording(const std::string& path) {
  const files::TextFile f = files::read_text_file(path, kMaxRecordingBytes);
  if (!f.text) throw std::runtime_error(path + ": " + f.error);
  return parse_calibration_recording(*f.text, path);
}

}  // namespace vitreo::rig::calibration
