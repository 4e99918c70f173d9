// The session's case list as one text (a recording's header carries it) and back: see
// simulation_model.hpp (encode_case_list / decode_case_list) and rig/telemetry/RECORDING.md.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string_view>

#include "rig/session/calibration_in_force.hpp"
#include "rig/session/simulation_model.hpp"

namespace vitreo::rig {

// ---- The case list as text ----------------------------------------------------------------------
// "vitreo-cases 1\n" then "key value\n" lines, then per case "case <name bytes> <text bytes>
// <library bytes>\n" followed by exactly those bytes. Lengths, not delimiters: the texts are free.

std::string encode_case_list(const ModelConfig& c) {
  std::string out = "vitreo-cases 1\n";
  out += "first_case " + std::to_string(c.first_case) + "\n";
  out += "retina_vertices " + std::to_string(c.load.retina_vertices) + "\n";
  out += "texture_size_px " + std::to_string(c.load.texture_size_px) + "\n";
  for (const auto& t : c.cases) {
    out += "case " + std::to_string(t.file_name.size()) + " " + std::to_string(t.text.size()) + " " +
           std::to_string(t.library_text.size()) + "\n";
    out += t.file_name;
    out += t.text;
    out += t.library_text;
  }
  // The laser's start settings, only where the rig file changed them (recordings without them are
  // unchanged); %.17g gives back the same double.
  auto exact = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return std::string(buf);
  };
  if (c.laser.power_mw != LaserSettings{}.power_mw) out += "laser_power_mw " + exact(c.laser.power_mw) + "\n";
  if (c.laser.duration_ms != LaserSettings{}.duration_ms) out += "laser_duration_ms " + exact(c.laser.duration_ms) + "\n";
  // The calibration in force, only when there is one (recordings without it are unchanged).
  if (!c.calibration_text.empty()) out += "calibration " + std::to_string(c.calibration_text.size()) + "\n" + c.calibration_text;
  return out;
}

namespace {
// A decimal number in [lo, hi], the whole token: no sign games, no overflow, no trailing bytes.
bool parse_count(std::string_view token, long long lo, long long hi, long long& out) {
  if (token.empty() || token.size() > 19) return false;
  long long v = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (ec != std::errc() || end != token.data() + token.size() || v < lo || v > hi) return false;
  out = v;
  return true;
}

// A finite decimal number, the whole token.
bool parse_number(std::string_view token, double& out) {
  if (token.empty() || token.size() > 40) return false;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
  if (ec != std::errc() || end != token.data() + token.size() || !std::isfinite(v)) return false;
  out = v;
  return true;
}

std::vector<std::string_view> words(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t at = 0;
  while (at < line.size()) {
    const std::size_t sp = line.find(' ', at);
    out.push_back(line.substr(at, sp == std::string_view::npos ? std::string_view::npos : sp - at));
    if (sp == std::string_view::npos) break;
    at = sp + 1;
  }
  return out;
}
}  // namespace

void decode_case_list(const std::string& text, ModelConfig& config) {
  auto fail = [](const std::string& why) { throw std::runtime_error("recording's case list: " + why); };
  std::size_t at = 0;
  auto line = [&]() {
    const std::size_t nl = text.find('\n', at);
    if (nl == std::string::npos) fail("truncated");
    std::string_view l(text.data() + at, nl - at);
    at = nl + 1;
    return l;
  };
  if (line() != "vitreo-cases 1") fail("not a vitreo case list (or a newer version)");
  ModelConfig out = config;
  out.cases.clear();
  // The recording alone says which calibration mapped its inputs: none unless it carries one.
  out.calibration = {};
  out.measured_ports = {};
  out.calibration_text.clear();
  out.eye_zero = core::Quat::Identity();
  out.pedals.axis_ranges.clear();
  out.laser = {};  // the console's defaults unless the recording says otherwise
  long long first_case = 0;
  constexpr long long kMaxCases = 4096;
  while (at < text.size()) {
    const std::string_view l = line();
    const std::vector<std::string_view> w = words(l);
    const std::string shown(l.substr(0, 60));
    long long a = 0, b = 0, c = 0;
    if (w.size() == 4 && w[0] == "case") {
      // Each length is at most what is left of the text, so their sum cannot overflow.
      const auto left = static_cast<long long>(text.size() - at);
      if (!parse_count(w[1], 0, left, a) || !parse_count(w[2], 0, left, b) || !parse_count(w[3], 0, left, c))
        fail("bad case line '" + shown + "'");
      if (a + b + c > left) fail("case text truncated");
      if (static_cast<long long>(out.cases.size()) >= kMaxCases) fail("more than 4096 cases");
      scene_io::CaseText t;
      t.file_name = text.substr(at, static_cast<std::size_t>(a));
      t.text = text.substr(at + static_cast<std::size_t>(a), static_cast<std::size_t>(b));
      t.library_text = text.substr(at + static_cast<std::size_t>(a + b), static_cast<std::size_t>(c));
      at += static_cast<std::size_t>(a + b + c);
      out.cases.push_back(std::move(t));
    } else if (w.size() == 2 && w[0] == "calibration") {
      const auto left = static_cast<long long>(text.size() - at);
      if (!parse_count(w[1], 1, left, a)) fail("bad calibration line '" + shown + "'");
      const std::string cal = text.substr(at, static_cast<std::size_t>(a));
      at += static_cast<std::size_t>(a);
      try {
        apply_calibration(cal, "recording's calibration", out);
      } catch (const std::exception& e) {
        fail(e.what());
      }
    } else if (w.size() == 2 && w[0] == "first_case") {
      if (!parse_count(w[1], 0, kMaxCases - 1, first_case)) fail("first_case out of range in '" + shown + "'");
    } else if (w.size() == 2 && w[0] == "laser_power_mw") {
      if (!parse_number(w[1], out.laser.power_mw) || !laser_power_in_range(out.laser.power_mw))
        fail("laser_power_mw out of range in '" + shown + "'");
    } else if (w.size() == 2 && w[0] == "laser_duration_ms") {
      if (!parse_number(w[1], out.laser.duration_ms) || !laser_duration_in_range(out.laser.duration_ms))
        fail("laser_duration_ms out of range in '" + shown + "'");
    } else if (w.size() == 2 && w[0] == "retina_vertices") {
      if (!parse_count(w[1], 0, 2'000'000, a)) fail("retina_vertices out of range in '" + shown + "'");
      out.load.retina_vertices = static_cast<int>(a);
    } else if (w.size() == 2 && w[0] == "texture_size_px") {
      if (!parse_count(w[1], 0, 8192, a)) fail("texture_size_px out of range in '" + shown + "'");
      out.load.texture_size_px = static_cast<int>(a);
    } else {
      fail("bad line '" + shown + "'");
    }
  }
  if (out.cases.empty()) fail("no cases");
  if (first_case >= static_cast<long long>(out.cases.size())) fail("first case out of range");
  out.first_case = static_cast<int>(first_case);
  config = std::move(out);
}

}  // namespace vitreo::rig
