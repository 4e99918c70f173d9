#include "rig/session/rig_file.hpp"
#include "rig/files/toml_lines.hpp"

#include <toml++/toml.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <spdlog/fmt/fmt.h>

#include "drivers/device_uri.hpp"

namespace vitreo::rig {

const char* to_string(DeviceRole r) {
  switch (r) {
    case DeviceRole::tracker: return "tracker";
    case DeviceRole::pedals: return "pedals";
    case DeviceRole::eyeball: return "eyeball";
  }
  return "?";
}

namespace {

using files::line_of;

std::string read_text(const std::string& path, const std::string& what) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path + ": cannot read " + what);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

}  // namespace

RigFile parse_rig_file(const std::string& text, const std::string& origin, const std::string& base_dir) {
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(origin + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  auto fail = [&](const toml::node& n, const std::string& key, const std::string& why) {
    throw std::runtime_error(origin + ":" + std::to_string(line_of(n)) + ": " + key + ": " + why);
  };
  for (const auto& [k, v] : root) {
    if (k != "rig" && k != "device" && k != "pedals" && k != "laser" && k != "calibration")
      fail(v, std::string(k.str()), "unknown key (rig, device, pedals, laser, calibration)");
  }
  RigFile out;
  const toml::table* rig = root["rig"].as_table();
  if (!rig) throw std::runtime_error(origin + ": no [rig] table (version = " + std::to_string(kRigFileVersion) + ")");
  bool have_version = false;
  for (const auto& [k, v] : *rig) {
    const std::string key = "rig." + std::string(k.str());
    if (k == "version") {
      // is_integer() before value<>(): toml++ casts a float to an integer without a range check.
      if (!v.is_integer()) fail(v, key, "must be an integer");
      const auto version = v.value<std::int64_t>();
      if (*version != kRigFileVersion) {
        fail(v, key, "this is a version " + std::to_string(*version) + " rig file; this vitreo reads version " +
                         std::to_string(kRigFileVersion));
      }
      have_version = true;
    } else if (k == "name") {
      if (!v.is_string()) fail(v, key, "must be a string");
      out.name = *v.value<std::string>();
    } else {
      fail(v, key, "unknown key (version, name)");
    }
  }
  if (!have_version) throw std::runtime_error(origin + ": rig.version missing (" + std::to_string(kRigFileVersion) + ")");

  const toml::array* devices = root["device"].as_array();
  if (!devices || devices->empty()) throw std::runtime_error(origin + ": no [[device]] entries");
  std::set<std::string> names;
  std::set<std::int32_t> ids;
  std::set<std::string> uris;
  for (std::size_t i = 0; i < devices->size(); ++i) {
    const toml::table* d = (*devices)[i].as_table();
    const std::string at = "device[" + std::to_string(i) + "]";
    if (!d) fail((*devices)[i], at, "must be a table");
    DeviceSpec spec;
    bool have_name = false, have_role = false, have_uri = false, have_id = false, have_instrument = false;
    std::string script_file;
    auto integer = [&](const toml::node& v, const std::string& key, std::int64_t lo, std::int64_t hi) {
      if (!v.is_integer()) fail(v, key, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
      const auto n = v.value<std::int64_t>();
      if (!n || *n < lo || *n > hi) {
        fail(v, key, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
      }
      return *n;
    };
    auto string = [&](const toml::node& v, const std::string& key) {
      if (!v.is_string() || v.value<std::string>()->empty()) fail(v, key, "must be a non-empty string");
      return *v.value<std::string>();
    };
    for (const auto& [k, v] : *d) {
      const std::string key = at + "." + std::string(k.str());
      if (k == "name") {
        spec.name = string(v, key);
        for (char c : spec.name) {
          if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') {
            fail(v, key, "'" + spec.name + "': letters, digits, '-' and '_' only (it names /dev/vitreo/" + spec.name + ")");
          }
        }
        if (spec.name.size() > 23) fail(v, key, "at most 23 characters (telemetry's name field)");
        if (!names.insert(spec.name).second) fail(v, key, "'" + spec.name + "' names two devices");
        have_name = true;
      } else if (k == "role") {
        const std::string role = string(v, key);
        if (role == "tracker") spec.role = DeviceRole::tracker;
        else if (role == "pedals") spec.role = DeviceRole::pedals;
        else if (role == "eyeball") spec.role = DeviceRole::eyeball;
        else fail(v, key, "'" + role + "': must be tracker, pedals or eyeball");
        have_role = true;
      } else if (k == "uri") {
        spec.uri = string(v, key);
        drivers::DeviceUri uri;
        std::string why;
        if (!drivers::parse_device_uri(spec.uri, uri, &why)) fail(v, key, why);
        spec.uri = drivers::to_string(uri);
        if (!uris.insert(spec.uri).second) fail(v, key, "'" + spec.uri + "' is given for two devices");
        have_uri = true;
      } else if (k == "id") {
        spec.device_id = static_cast<std::int32_t>(integer(v, key, 1, 1'000'000));
        if (!ids.insert(spec.device_id).second) fail(v, key, std::to_string(spec.device_id) + " is the id of two devices");
        have_id = true;
      } else if (k == "serial") {
        spec.expected_serial = static_cast<std::uint32_t>(integer(v, key, 0, 0xFFFFFFFFLL));
      } else if (k == "instrument") {
        spec.channel = static_cast<int>(integer(v, key, 0, 3));
        have_instrument = true;
      } else if (k == "rate_hz") {
        spec.sample_rate_hz = static_cast<std::uint16_t>(integer(v, key, 1, 10000));
      } else if (k == "script") {
        script_file = string(v, key);
      } else {
        fail(v, key, "unknown key (name, role, uri, id, serial, instrument, rate_hz, script)");
      }
    }
    const toml::node& here = (*devices)[i];
    if (!have_name) fail(here, at, "no name");
    if (!have_role) fail(here, at + " (" + spec.name + ")", "no role (tracker, pedals or eyeball)");
    if (!have_uri) fail(here, at + " (" + spec.name + ")", "no uri");
    if (!have_id) fail(here, at + " (" + spec.name + ")", "no id");
    if (have_instrument && spec.role != DeviceRole::tracker) fail(here, at + ".instrument", "only trackers carry an instrument");
    const bool simulated = spec.uri.rfind("sim:", 0) == 0;
    if (simulated) {
      // a simulated device must simulate the role it stands in for
      if (spec.uri.rfind(std::string("sim:") + to_string(spec.role) + "?", 0) != 0) {
        fail(here, at + ".uri", "'" + spec.uri + "' simulates another kind of device than its role, " + to_string(spec.role));
      }
    } else if (!script_file.empty()) {
      fail(here, at + ".script", "only simulated devices (sim: URIs) run a script");
    }
    if (!script_file.empty()) {
      const std::filesystem::path p = std::filesystem::path(script_file).is_absolute()
                                          ? std::filesystem::path(script_file)
                                          : std::filesystem::path(base_dir) / script_file;
      try {
        spec.sim_script = read_text(p.string(), "the device's script");
      } catch (const std::exception& e) {
        fail(here, at + ".script", e.what());
      }
    }
    out.devices.push_back(std::move(spec));
  }
  if (root["pedals"]) out.pedals = parse_pedal_mapping(text, origin);
  if (const toml::node* l = root.get("laser")) {
    if (!l->is_table()) fail(*l, "laser", "must be a table (power_mw, duration_ms)");
    const telemetry::CommandLimits limits;  // the operator commands' ranges
    LaserSettings laser;
    for (const auto& [k, v] : *l->as_table()) {
      const std::string key = "laser." + std::string(k.str());
      const std::optional<double> x = v.is_integer() ? std::optional<double>(static_cast<double>(*v.value<std::int64_t>()))
                                      : v.is_floating_point() ? v.value<double>() : std::nullopt;
      if (k == "power_mw") {
        if (!x || !laser_power_in_range(x.value_or(NAN), limits))
          fail(v, key, fmt::format("must be a power in [{:g}, {:g}] mW", limits.laser_power_min_mw, limits.laser_power_max_mw));
        laser.power_mw = *x;
      } else if (k == "duration_ms") {
        if (!x || !laser_duration_in_range(x.value_or(NAN), limits))
          fail(v, key, fmt::format("must be a pulse duration in [{:g}, {:g}] ms (one pulse per shot: no continuous mode)",
                                   limits.laser_duration_min_ms, limits.laser_duration_max_ms));
        laser.duration_ms = *x;
      } else {
        fail(v, key, "unknown key (power_mw, duration_ms)");
      }
    }
    out.laser = laser;
  }
  if (const toml::node* c = root.get("calibration")) {
    if (!c->is_table()) fail(*c, "calibration", "must be a table (file, max_age_days)");
    for (const auto& [k, v] : *c->as_table()) {
      const std::string key = "calibration." + std::string(k.str());
      if (k == "file") {
        if (!v.is_string() || v.value<std::string>()->empty()) fail(v, key, "must be a non-empty string");
        const std::filesystem::path p(*v.value<std::string>());
        out.calibration_path = (p.is_absolute() ? p : std::filesystem::path(base_dir) / p).string();
      } else if (k == "max_age_days") {
        const std::optional<double> d = v.is_integer() ? std::optional<double>(static_cast<double>(*v.value<std::int64_t>()))
                                                       : v.is_floating_point() ? v.value<double>() : std::nullopt;
        if (!d || !(*d > 0.0) || *d > 36500.0) fail(v, key, "must be a number of days in (0, 36500]");
        out.calibration_max_age_days = *d;
      } else {
        fail(v, key, "unknown key (file, max_age_days)");
      }
    }
    if (out.calibration_path.empty()) fail(*c, "calibration.file", "missing");
  }
  return out;
}

RigFile read_rig_file(const std::string& path) {
  const std::string text = read_text(path, "the rig file");
  return parse_rig_file(text, path, std::filesystem::path(path).parent_path().string());
}

}  // namespace vitreo::rig
