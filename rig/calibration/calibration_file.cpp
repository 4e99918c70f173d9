#include "rig/calibration/calibration_file.hpp"

#include <toml++/toml.h>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>
#include <stdexcept>

#include "rig/files/read_text_file.hpp"
#include "rig/files/toml_guard.hpp"
#include "rig/files/write_file_atomically.hpp"

namespace vitreo::rig::calibration {

const InstrumentRecord* CalibrationFile::instrument(int channel) const {
  for (const InstrumentRecord& r : instruments)
    if (r.instrument == channel) return &r;
  return nullptr;
}
const PortRecord* CalibrationFile::port(int index) const {
  for (const PortRecord& r : ports)
    if (r.port == index) return &r;
  return nullptr;
}
const PedalRecord* CalibrationFile::pedal(int pedal_id, int axis) const {
  for (const PedalRecord& r : pedals)
    if (r.pedal == pedal_id && r.axis == axis) return &r;
  return nullptr;
}

namespace {

// Days since 1970-01-01 of a proleptic Gregorian date (the civil-from-days inverse is below); the
// era arithmetic follows H. Hinnant's "chrono-Compatible Low-Level Date Algorithms".
std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2 ? 1 : 0;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

void civil_from_days(std::int64_t z, std::int64_t& y, unsigned& m, unsigned& d) {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = static_cast<std::int64_t>(yoe) + era * 400 + (m <= 2 ? 1 : 0);
}

std::string num(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}
std::string vec(const core::Vec3& v, int digits) {
  return "[" + num(v.x(), digits) + ", " + num(v.y(), digits) + ", " + num(v.z(), digits) + "]";
}
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;  // control characters have no place in a name
    out += c;
  }
  return out + "\"";
}

// Reads one table's keys, each at most once, all checked; errors carry file:line: key.
class TableReader {
 public:
  TableReader(const toml::table& t, std::string origin, std::string at) : t_(t), origin_(std::move(origin)), at_(std::move(at)) {}

  [[noreturn]] void fail(const toml::node& n, const std::string& key, const std::string& why) const {
    throw std::runtime_error(origin_ + ":" + std::to_string(n.source().begin.line) + ": " + key + ": " + why);
  }
  std::string key(std::string_view k) const { return at_ + "." + std::string(k); }
  const toml::node& need(std::string_view k) {
    seen_.insert(std::string(k));
    const toml::node* n = t_.get(k);
    if (!n) {
      throw std::runtime_error(origin_ + ":" + std::to_string(t_.source().begin.line) + ": " + key(k) + ": missing");
    }
    return *n;
  }
  const toml::node* maybe(std::string_view k) {
    seen_.insert(std::string(k));
    return t_.get(k);
  }
  double number(std::string_view k, double lo, double hi) { return number_of(need(k), key(k), lo, hi); }
  double number_of(const toml::node& n, const std::string& k, double lo, double hi) const {
    double v = 0;
    if (n.is_floating_point()) v = *n.value<double>();
    else if (n.is_integer()) v = static_cast<double>(*n.value<std::int64_t>());
    else fail(n, k, "must be a number");
    if (!std::isfinite(v) || v < lo || v > hi) fail(n, k, "must be a number in [" + num(lo, 3) + ", " + num(hi, 3) + "]");
    return v;
  }
  std::int64_t integer(std::string_view k, std::int64_t lo, std::int64_t hi) {
    const toml::node& n = need(k);
    // is_integer() before value<>(): toml++ casts a float to an integer without a range check.
    if (!n.is_integer() || *n.value<std::int64_t>() < lo || *n.value<std::int64_t>() > hi)
      fail(n, key(k), "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return *n.value<std::int64_t>();
  }
  std::string string(std::string_view k) {
    const toml::node& n = need(k);
    if (!n.is_string() || n.value<std::string>()->empty()) fail(n, key(k), "must be a non-empty string");
    return *n.value<std::string>();
  }
  bool boolean(std::string_view k) {
    const toml::node& n = need(k);
    if (!n.is_boolean()) fail(n, key(k), "must be true or false");
    return *n.value<bool>();
  }
  Eigen::VectorXd numbers(std::string_view k, int count, double lo, double hi) {
    const toml::node& n = need(k);
    const toml::array* a = n.as_array();
    if (!a || static_cast<int>(a->size()) != count) fail(n, key(k), "must be an array of " + std::to_string(count) + " numbers");
    Eigen::VectorXd v(count);
    for (int i = 0; i < count; ++i) v(i) = number_of((*a)[static_cast<std::size_t>(i)], key(k), lo, hi);
    return v;
  }
  core::Vec3 vec3(std::string_view k, double limit) { return numbers(k, 3, -limit, limit); }
  // [w, x, y, z], unit length (to 1e-6: the file keeps 12 decimals), normalised.
  core::Quat unit_quaternion(std::string_view k) {
    const Eigen::VectorXd q = numbers(k, 4, -1.0, 1.0);
    const core::Quat out(q(0), q(1), q(2), q(3));
    if (std::abs(out.norm() - 1.0) > 1e-6) fail(need(k), key(k), "must be a unit quaternion");
    return out.normalized();
  }
  // Unknown keys are errors: a misspelt key must not silently leave a default in force.
  void no_others(const std::string& allowed) const {
    for (const auto& [k, v] : t_)
      if (!seen_.count(std::string(k.str()))) fail(v, key(k.str()), "unknown key (" + allowed + ")");
  }

 private:
  const toml::table& t_;
  std::string origin_, at_;
  std::set<std::string> seen_;
};

}  // namespace

std::string utc_timestamp(std::int64_t unix_s) {
  const std::int64_t days = (unix_s >= 0 ? unix_s : unix_s - 86399) / 86400;
  const std::int64_t secs = unix_s - days * 86400;
  std::int64_t y;
  unsigned m, d;
  civil_from_days(days, y, m, d);
  char buf[40];
  std::snprintf(buf, sizeof buf, "%04" PRId64 "-%02u-%02uT%02d:%02d:%02dZ", y, m, d, static_cast<int>(secs / 3600),
                static_cast<int>(secs / 60 % 60), static_cast<int>(secs % 60));
  return buf;
}

std::string format_calibration(const CalibrationFile& c) {
  std::string s;
  s += "# vitreo sensor calibration, written by " + c.tool + ".\n";
  s += "# The rig applies it with `vitreo --calibration FILE` or the rig file's [calibration] file;\n";
  s += "# rig/calibration/README.md describes every field.\n";
  s += "[calibration]\nversion = " + std::to_string(kCalibrationFileVersion) + "\n";
  s += "created = " + utc_timestamp(c.created_unix_s) + "\n";
  s += "tool = " + quoted(c.tool) + "\n";
  s += "rig = " + quoted(c.rig) + "\n";
  for (const DeviceSerial& d : c.devices)
    s += "\n[[device]]\nname = " + quoted(d.name) + "\nserial = " + std::to_string(d.serial) + "\n";
  if (c.registration) {
    const RegistrationRecord& r = *c.registration;
    const core::Quat q = r.rig_to_eye.normalized();
    s += "\n[registration]  # tracker frame -> eye fixture frame (globe centre, +z anterior)\n";
    s += "rig_to_eye_wxyz = [" + num(q.w(), 12) + ", " + num(q.x(), 12) + ", " + num(q.y(), 12) + ", " + num(q.z(), 12) + "]\n";
    s += "eye_center_in_rig_mm = " + vec(r.eye_center_in_rig_mm, 6) + "\n";
    s += "fiducials = " + std::to_string(r.fiducials) + "\n";
    s += "fre_mm = " + num(r.fre_mm, 6) + "\n";
    s += "tre_mm = " + num(r.tre_mm, 6) + "\n";
    s += std::string("tre_measured = ") + (r.tre_measured ? "true" : "false") + "  # false: predicted at the posterior pole\n";
  }
  for (const InstrumentRecord& i : c.instruments) {
    s += "\n[[instrument]]  # tip pivot\ninstrument = " + std::to_string(i.instrument) + "\n";
    s += "tip_offset_mm = " + vec(i.tip_offset_mm, 6) + "\n";
    s += "poses = " + std::to_string(i.poses) + "\nspread_deg = " + num(i.spread_deg, 3) + "\nrms_mm = " + num(i.rms_mm, 6) + "\n";
  }
  for (const PortRecord& p : c.ports) {
    s += "\n[[port]]\nport = " + std::to_string(p.port) + "\nposition_mm = " + vec(p.position_mm, 6) + "\n";
    s += "outward = " + vec(p.outward, 9) + "\nsamples = " + std::to_string(p.samples) + "\nspread_mm = " + num(p.spread_mm, 6) + "\n";
  }
  for (const PedalRecord& p : c.pedals) {
    s += "\n[[pedal]]\npedal = " + std::to_string(p.pedal) + "\naxis = " + std::to_string(p.axis) + "\n";
    s += "lo = " + num(p.range.lo, 6) + "\nhi = " + num(p.range.hi, 6) + "\ndead_zone = " + num(p.range.dead_zone, 6) + "\n";
  }
  if (c.eye_zero) {
    const core::Quat q = c.eye_zero->zero.normalized();
    s += "\n[eyeball]  # the fixture's reading with the eye at rest: the rig's zero\n";
    s += "zero_wxyz = [" + num(q.w(), 12) + ", " + num(q.x(), 12) + ", " + num(q.y(), 12) + ", " + num(q.z(), 12) + "]\n";
    s += "samples = " + std::to_string(c.eye_zero->samples) + "\nspread_deg = " + num(c.eye_zero->spread_deg, 4) + "\n";
  }
  if (c.eyepieces) {
    const EyepieceRecord& e = *c.eyepieces;
    s += "\n[eyepieces]  # the stereo displays: each eye's image shift (pixels, x right, y up) and the stereo geometry\n";
    s += "left_offset_px = [" + num(e.offset_px[0][0], 2) + ", " + num(e.offset_px[0][1], 2) + "]\n";
    s += "right_offset_px = [" + num(e.offset_px[1][0], 2) + ", " + num(e.offset_px[1][1], 2) + "]\n";
    s += "stereo_base_mm = " + num(e.stereo_base_mm, 3) + "\nconvergence_mm = " + num(e.convergence_mm, 3) + "  # 0: the working plane\n";
  }
  for (const ClockRecord& k : c.clocks) {
    s += "\n[[clock]]\ndevice = " + quoted(k.device) + "\noffset_ms = " + num(k.offset_ms, 6) + "\n";
    s += "drift_ppm = " + num(k.drift_ppm, 3) + "\nlatency_ms = " + num(k.latency_ms, 6) + "\nrms_ms = " + num(k.rms_ms, 6) + "\n";
  }
  return s;
}

CalibrationFile parse_calibration(const std::string& text, const std::string& origin) {
  if (const files::TomlProblem bad = files::toml_guard(text))
    throw std::runtime_error(origin + ":" + std::to_string(bad.line) + ": " + bad.why);
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(origin + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  TableReader top(root, origin, "");
  auto fail_at = [&](const toml::node& n, const std::string& key, const std::string& why) { top.fail(n, key, why); };
  CalibrationFile c;
  const toml::table* head = root["calibration"].as_table();
  if (!head) throw std::runtime_error(origin + ":1: calibration: no [calibration] table (is this a calibration file?)");
  {
    TableReader t(*head, origin, "calibration");
    const toml::node& v = t.need("version");
    if (!v.is_integer() || *v.value<std::int64_t>() != kCalibrationFileVersion)
      t.fail(v, "calibration.version", "this vitreo reads calibration files of version " + std::to_string(kCalibrationFileVersion));
    const toml::node& created = t.need("created");
    const toml::date_time* dt = created.as_date_time() ? &created.as_date_time()->get() : nullptr;
    if (!dt || !dt->offset)
      t.fail(created, "calibration.created", "must be a date and time with its UTC offset (2026-11-26T05:55:00Z)");
    c.created_unix_s = days_from_civil(dt->date.year, dt->date.month, dt->date.day) * 86400 + dt->time.hour * 3600 +
                       dt->time.minute * 60 + dt->time.second - dt->offset->minutes * 60;
    c.tool = t.string("tool");
    c.rig = t.string("rig");
    t.no_others("version, created, tool, rig");
  }
  auto each = [&](const char* name, const std::function<void(TableReader&)>& read) {
    const toml::node* n = root.get(name);
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a || !a->is_array_of_tables()) fail_at(*n, name, std::string("must be [[") + name + "]] tables");
    for (std::size_t i = 0; i < a->size(); ++i) {
      TableReader t(*(*a)[i].as_table(), origin, std::string(name) + "[" + std::to_string(i) + "]");
      read(t);
    }
  };
  std::set<std::string> names;
  each("device", [&](TableReader& t) {
    DeviceSerial d{t.string("name"), static_cast<std::uint32_t>(t.integer("serial", 0, 0xffffffffLL))};
    if (!names.insert(d.name).second) t.fail(t.need("name"), t.key("name"), "'" + d.name + "' is listed twice");
    c.devices.push_back(d);
    t.no_others("name, serial");
  });
  auto table = [&](const char* name, const std::function<void(TableReader&)>& read) {
    const toml::node* n = root.get(name);
    if (!n) return;
    if (!n->as_table()) fail_at(*n, name, "must be a table");
    TableReader t(*n->as_table(), origin, name);
    read(t);
  };
  table("registration", [&](TableReader& t) {
    RegistrationRecord r;
    r.rig_to_eye = t.unit_quaternion("rig_to_eye_wxyz");
    r.eye_center_in_rig_mm = t.vec3("eye_center_in_rig_mm", 5000.0);
    r.fiducials = static_cast<std::size_t>(t.integer("fiducials", 3, 1000));
    r.fre_mm = t.number("fre_mm", 0.0, 100.0);
    r.tre_mm = t.number("tre_mm", 0.0, 100.0);
    r.tre_measured = t.boolean("tre_measured");
    t.no_others("rig_to_eye_wxyz, eye_center_in_rig_mm, fiducials, fre_mm, tre_mm, tre_measured");
    c.registration = r;
  });
  each("instrument", [&](TableReader& t) {
    InstrumentRecord r;
    r.instrument = static_cast<int>(t.integer("instrument", 0, 255));
    if (c.instrument(r.instrument)) t.fail(t.need("instrument"), t.key("instrument"), "calibrated twice");
    r.tip_offset_mm = t.vec3("tip_offset_mm", 500.0);
    r.poses = static_cast<std::size_t>(t.integer("poses", 0, 100'000'000));
    r.spread_deg = t.number("spread_deg", 0.0, 180.0);
    r.rms_mm = t.number("rms_mm", 0.0, 100.0);
    t.no_others("instrument, tip_offset_mm, poses, spread_deg, rms_mm");
    c.instruments.push_back(r);
  });
  each("port", [&](TableReader& t) {
    PortRecord r;
    r.port = static_cast<int>(t.integer("port", 0, 15));
    if (c.port(r.port)) t.fail(t.need("port"), t.key("port"), "measured twice");
    r.position_mm = t.vec3("position_mm", 100.0);
    r.outward = t.vec3("outward", 1.0 + 1e-6);
    if (std::abs(r.outward.norm() - 1.0) > 1e-6) t.fail(t.need("outward"), t.key("outward"), "must be a unit vector");
    r.samples = static_cast<std::size_t>(t.integer("samples", 0, 100'000'000));
    r.spread_mm = t.number("spread_mm", 0.0, 100.0);
    t.no_others("port, position_mm, outward, samples, spread_mm");
    c.ports.push_back(r);
  });
  each("pedal", [&](TableReader& t) {
    PedalRecord r;
    r.pedal = static_cast<int>(t.integer("pedal", 0, 255));
    r.axis = static_cast<int>(t.integer("axis", 0, 3));
    if (c.pedal(r.pedal, r.axis)) t.fail(t.need("axis"), t.key("axis"), "this pedal's axis is calibrated twice");
    r.range.lo = t.number("lo", 0.0, 1.0);
    r.range.hi = t.number("hi", 0.0, 1.0);
    if (!(r.range.hi > r.range.lo)) t.fail(t.need("hi"), t.key("hi"), "must be above lo");
    r.range.dead_zone = t.number("dead_zone", 0.0, 0.5);
    t.no_others("pedal, axis, lo, hi, dead_zone");
    c.pedals.push_back(r);
  });
  table("eyeball", [&](TableReader& t) {
    EyeZeroRecord r;
    r.zero = t.unit_quaternion("zero_wxyz");
    r.samples = static_cast<std::size_t>(t.integer("samples", 0, 100'000'000));
    r.spread_deg = t.number("spread_deg", 0.0, 180.0);
    t.no_others("zero_wxyz, samples, spread_deg");
    c.eye_zero = r;
  });
  each("clock", [&](TableReader& t) {
    ClockRecord r;
    r.device = t.string("device");
    r.offset_ms = t.number("offset_ms", -1e15, 1e15);
    r.drift_ppm = t.number("drift_ppm", -1e5, 1e5);
    r.latency_ms = t.number("latency_ms", 0.0, 1e6);
    r.rms_ms = t.number("rms_ms", 0.0, 1e6);
    t.no_others("device, offset_ms, drift_ppm, latency_ms, rms_ms");
    c.clocks.push_back(r);
  });
  table("eyepieces", [&](TableReader& t) {
    EyepieceRecord r;
    const Eigen::VectorXd left = t.numbers("left_offset_px", 2, -2000.0, 2000.0), right = t.numbers("right_offset_px", 2, -2000.0, 2000.0);
    for (int k = 0; k < 2; ++k) r.offset_px[0][k] = left(k), r.offset_px[1][k] = right(k);
    r.stereo_base_mm = t.number("stereo_base_mm", 1.0, 100.0);
    r.convergence_mm = t.number("convergence_mm", 0.0, 2000.0);
    t.no_others("left_offset_px, right_offset_px, stereo_base_mm, convergence_mm");
    c.eyepieces = r;
  });
  for (const auto& [k, v] : root) {
    const std::string key(k.str());
    if (key != "calibration" && key != "device" && key != "registration" && key != "instrument" && key != "port" &&
        key != "pedal" && key != "eyeball" && key != "clock" && key != "eyepieces")
      fail_at(v, key, "unknown table (calibration, device, registration, instrument, port, pedal, eyeball, clock, eyepieces)");
  }
  return c;
}

CalibrationFile read_calibration_file(const std::string& path) {
  const files::TextFile f = files::read_text_file(path);
  if (!f.text) throw std::runtime_error(path + ": " + f.error);
  return parse_calibration(*f.text, path);
}

void write_calibration_file(const std::string& path, const CalibrationFile& c) {
  if (const std::string why = files::write_file_atomically(path, format_calibration(c)); !why.empty())
    throw std::runtime_error("cannot write the calibration file: " + why);
}

std::string check_devices(const CalibrationFile& c, const std::vector<DeviceSerial>& rig) {
  std::string out;
  for (const DeviceSerial& d : c.devices) {
    const DeviceSerial* found = nullptr;
    for (const DeviceSerial& r : rig)
      if (r.name == d.name) found = &r;
    if (!found) {
      out += (out.empty() ? "" : "; ") + std::string("it calibrated a device '") + d.name + "' this rig does not have";
    } else if (found->serial != d.serial) {
      out += (out.empty() ? "" : "; ") + std::string("it was made for ") + d.name + " serial " + std::to_string(d.serial) +
             ", this rig's " + d.name + " is serial " + std::to_string(found->serial);
    }
  }
  return out;
}

std::optional<std::string> age_warning(const CalibrationFile& c, std::int64_t now_unix_s, double max_age_days) {
  const double age_days = static_cast<double>(now_unix_s - c.created_unix_s) / 86400.0;
  if (age_days < -1.0 / 24.0)
    return "the calibration of " + utc_timestamp(c.created_unix_s) + " is dated in the future; check the clock";
  if (age_days > max_age_days)
    return "the calibration of " + utc_timestamp(c.created_unix_s) + " is " + num(age_days, 1) + " days old (more than " +
           num(max_age_days, 0) + "); recalibrate the rig";
  return std::nullopt;
}

}  // namespace vitreo::rig::calibration
