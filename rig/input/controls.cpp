#include "rig/input/controls.hpp"

#include <toml++/toml.h>

#include "rig/files/toml_guard.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <stdexcept>

namespace vitreo::rig {

namespace {
bool bit(std::uint16_t switches, int index) { return index >= 0 && index < 16 && ((switches >> index) & 1u) != 0; }
}  // namespace

double AxisRange::apply(double raw) const {
  const double span = hi - lo;
  if (!(span > 0.0) || !std::isfinite(raw)) return 0.0;
  const double n = std::clamp((raw - lo) / span, 0.0, 1.0);
  if (n <= dead_zone) return 0.0;
  return dead_zone < 1.0 ? (n - dead_zone) / (1.0 - dead_zone) : 0.0;
}

bool PedalMapper::apply(const PedalReading& raw) {
  if (raw.axis_count < 0 || raw.axis_count > 4) return false;
  for (int i = 0; i < raw.axis_count; ++i) {
    if (!std::isfinite(raw.axes[i]) || raw.axes[i] < 0.0 || raw.axes[i] > 1.0) return false;
  }
  PedalReading r = raw;
  for (const AxisRange& a : m_.axis_ranges)
    if (a.pedal_id == r.pedal_id && a.axis >= 0 && a.axis < r.axis_count) r.axes[a.axis] = a.apply(r.axes[a.axis]);
  auto axis = [&](int index) { return index >= 0 && index < r.axis_count ? r.axes[index] : 0.0; };
  auto keep_travel = [&](double (&travel)[4]) {
    for (int i = 0; i < 4; ++i) travel[i] = axis(i);
  };
  if (r.pedal_id == m_.vitrectomy_pedal_id) {
    keep_travel(c_.vitrectomy_travel);
    c_.vacuum_mmhg = axis(m_.vacuum_axis) * m_.vacuum_max_mmhg;
    const double travel = m_.cut_rate_axis >= 0 ? axis(m_.cut_rate_axis) : 1.0;
    c_.cut_rate_cpm = c_.vacuum_mmhg > 0.0 ? m_.cut_rate_min_cpm + travel * (m_.cut_rate_max_cpm - m_.cut_rate_min_cpm) : 0.0;
    c_.reflux = bit(r.switches, m_.reflux_switch);
    c_.laser_fire = bit(r.switches, m_.laser_switch);
    c_.pick_out = bit(r.switches, m_.pick_switch);
    if (bit(r.switches, m_.instrument_switch) && !bit(last_switches_[0], m_.instrument_switch)) ++c_.instrument_changes;
    if (bit(r.switches, m_.air_switch) && !bit(last_switches_[0], m_.air_switch)) c_.air_infusion = !c_.air_infusion;
    last_switches_[0] = r.switches;
  } else if (r.pedal_id == m_.microscope_pedal_id) {
    keep_travel(c_.microscope_travel);
    c_.zoom = m_.zoom_min + axis(m_.zoom_axis) * (m_.zoom_max - m_.zoom_min);
    c_.focus_offset_mm = (axis(m_.focus_axis) - 0.5) * m_.focus_range_mm;
    // Joystick axes read 0.5 when absent: centred, so a two-axis pedal never drifts the field.
    auto deflection = [&](int index) {
      const double d = 2.0 * ((index >= 0 && index < r.axis_count ? r.axes[index] : 0.5) - 0.5);
      const double beyond = std::max(0.0, std::abs(d) - m_.pan_deadband) / (1.0 - m_.pan_deadband);
      return d < 0.0 ? -beyond : beyond;
    };
    c_.pan_x = deflection(m_.pan_x_axis);
    c_.pan_y = deflection(m_.pan_y_axis);
    if (bit(r.switches, m_.light_up_switch) && !bit(last_switches_[1], m_.light_up_switch)) {
      c_.light_level = std::min(1.0, c_.light_level + m_.light_step);
    }
    if (bit(r.switches, m_.light_down_switch) && !bit(last_switches_[1], m_.light_down_switch)) {
      c_.light_level = std::max(0.0, c_.light_level - m_.light_step);
    }
    last_switches_[1] = r.switches;
  }
  return true;
}

PedalMapping parse_pedal_mapping(const std::string& toml_text, const std::string& origin) {
  // toml++ 3.3.0 has undefined behaviour on two kinds of malformed text (rig/files/toml_guard.hpp).
  if (const files::TomlProblem bad = files::toml_guard(toml_text))
    throw std::runtime_error(origin + ":" + std::to_string(bad.line) + ": column " + std::to_string(bad.column) + ": " + bad.why);
  toml::table root;
  try {
    root = toml::parse(toml_text, origin);
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(origin + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  PedalMapping m;
  const toml::table* pedals = root["pedals"].as_table();
  if (!pedals) throw std::runtime_error(origin + ": missing [pedals] section");
  struct Field {
    double* real = nullptr;
    int* integer = nullptr;
    double lo, hi;
  };
  const std::map<std::string, Field> fields = {
      {"vitrectomy_pedal_id", {nullptr, &m.vitrectomy_pedal_id, 0, 255}},
      {"vacuum_axis", {nullptr, &m.vacuum_axis, 0, 3}},
      {"vacuum_max_mmhg", {&m.vacuum_max_mmhg, nullptr, 0, 800}},
      {"cut_rate_axis", {nullptr, &m.cut_rate_axis, -1, 3}},
      {"cut_rate_min_cpm", {&m.cut_rate_min_cpm, nullptr, 0, 20000}},
      {"cut_rate_max_cpm", {&m.cut_rate_max_cpm, nullptr, 0, 20000}},
      {"reflux_switch", {nullptr, &m.reflux_switch, -1, 15}},
      {"laser_switch", {nullptr, &m.laser_switch, -1, 15}},
      {"instrument_switch", {nullptr, &m.instrument_switch, -1, 15}},
      {"air_switch", {nullptr, &m.air_switch, -1, 15}},
      {"pick_switch", {nullptr, &m.pick_switch, -1, 15}},
      {"microscope_pedal_id", {nullptr, &m.microscope_pedal_id, 0, 255}},
      {"zoom_axis", {nullptr, &m.zoom_axis, -1, 3}},
      {"focus_axis", {nullptr, &m.focus_axis, -1, 3}},
      {"zoom_min", {&m.zoom_min, nullptr, 0.1, 40}},
      {"zoom_max", {&m.zoom_max, nullptr, 0.1, 40}},
      {"focus_range_mm", {&m.focus_range_mm, nullptr, 0, 40}},
      {"pan_x_axis", {nullptr, &m.pan_x_axis, -1, 3}},
      {"pan_y_axis", {nullptr, &m.pan_y_axis, -1, 3}},
      {"pan_deadband", {&m.pan_deadband, nullptr, 0, 0.9}},
      {"light_up_switch", {nullptr, &m.light_up_switch, -1, 15}},
      {"light_down_switch", {nullptr, &m.light_down_switch, -1, 15}},
      {"light_step", {&m.light_step, nullptr, 0, 1}},
  };
  for (const auto& [key, node] : *pedals) {
    const std::string where = origin + ":" + std::to_string(node.source().begin.line) + ": pedals." + std::string(key.str());
    const auto it = fields.find(std::string(key.str()));
    if (it == fields.end()) throw std::runtime_error(where + ": unknown key");
    const Field& f = it->second;
    double value;
    // is_integer() first: toml++ converts a float node to an integer by a plain cast, undefined
    // behaviour for one out of range (found by the pedal-config fuzzer).
    if (node.is_integer()) {
      value = static_cast<double>(*node.value<std::int64_t>());
    } else if (auto d = node.value<double>(); d && f.real) {
      value = *d;
    } else {
      throw std::runtime_error(where + (f.integer ? ": must be an integer" : ": must be a number"));
    }
    if (!std::isfinite(value) || value < f.lo || value > f.hi) {
      throw std::runtime_error(where + ": " + std::to_string(value) + " is outside [" + std::to_string(f.lo) + ", " +
                               std::to_string(f.hi) + "]");
    }
    if (f.integer) {
      *f.integer = static_cast<int>(value);
    } else {
      *f.real = value;
    }
  }
  if (m.zoom_max < m.zoom_min) throw std::runtime_error(origin + ": pedals.zoom_max is below zoom_min");
  // One switch or axis doing two jobs on the same pedal would fire both at once (reflux with every
  // laser shot): refused, with both names. -1 means "none" and may repeat.
  auto distinct = [&](const char* what, std::initializer_list<std::pair<const char*, int>> uses) {
    for (auto a = uses.begin(); a != uses.end(); ++a) {
      for (auto b = a + 1; b != uses.end(); ++b) {
        if (a->second >= 0 && a->second == b->second)
          throw std::runtime_error(origin + ": pedals." + a->first + " and pedals." + b->first + " are the same " + what + " (" +
                                   std::to_string(a->second) + ")");
      }
    }
  };
  distinct("switch", {{"reflux_switch", m.reflux_switch}, {"laser_switch", m.laser_switch},
                      {"instrument_switch", m.instrument_switch}, {"air_switch", m.air_switch}, {"pick_switch", m.pick_switch}});
  distinct("axis", {{"vacuum_axis", m.vacuum_axis}, {"cut_rate_axis", m.cut_rate_axis}});
  distinct("switch", {{"light_up_switch", m.light_up_switch}, {"light_down_switch", m.light_down_switch}});
  distinct("axis", {{"zoom_axis", m.zoom_axis}, {"focus_axis", m.focus_axis}});
  distinct("pedal id", {{"vitrectomy_pedal_id", m.vitrectomy_pedal_id}, {"microscope_pedal_id", m.microscope_pedal_id}});
  if (m.cut_rate_max_cpm < m.cut_rate_min_cpm) throw std::runtime_error(origin + ": pedals.cut_rate_max_cpm is below cut_rate_min_cpm");
  return m;
}

}  // namespace vitreo::rig
