#include "rig/session/surgical_script.hpp"
#include "rig/files/toml_lines.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <stdexcept>

#include "firmware-protocol/vp.h"
#include "rig/files/read_text_file.hpp"
#include "rig/files/toml_guard.hpp"
#include "core/common/units.hpp"

namespace vitreo::rig {
namespace {

using core::Vec3;
using core::units::kDeg;
using files::line_of;

// Reads one table's keys with file:line:key errors; refuses keys it was not asked for.
class Reader {
 public:
  Reader(const toml::table& t, std::string origin, std::string where) : t_(t), origin_(std::move(origin)), where_(std::move(where)) {}

  [[noreturn]] void fail(const toml::node& n, const std::string& key, const std::string& why) const {
    throw std::runtime_error(origin_ + ":" + std::to_string(line_of(n)) + ": " + where_ + key + ": " + why);
  }
  [[noreturn]] void fail_here(const std::string& key, const std::string& why) const { fail(t_, key, why); }

  const toml::node* get(const std::string& key) {
    seen_.insert(key);
    return t_.get(key);
  }
  std::optional<double> number(const std::string& key, double lo, double hi) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    double v;
    if (n->is_integer()) v = static_cast<double>(n->as_integer()->get());  // is_integer() first: toml++ casts floats unchecked
    else if (n->is_floating_point()) v = n->as_floating_point()->get();
    else fail(*n, key, "must be a number");
    if (!std::isfinite(v) || v < lo || v > hi) fail(*n, key, std::to_string(v) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  std::optional<std::string> string(const std::string& key) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_string() || n->as_string()->get().empty()) fail(*n, key, "must be a non-empty string");
    return n->as_string()->get();
  }
  std::optional<bool> boolean(const std::string& key) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_boolean()) fail(*n, key, "must be true or false");
    return n->as_boolean()->get();
  }
  std::optional<Vec3> vec3(const std::string& key) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3) fail(*n, key, "must be [x, y, z] in mm");
    Vec3 v;
    for (int i = 0; i < 3; ++i) {
      const toml::node& e = *a->get(static_cast<std::size_t>(i));
      if (e.is_integer()) v[i] = static_cast<double>(e.as_integer()->get());
      else if (e.is_floating_point()) v[i] = e.as_floating_point()->get();
      else fail(*n, key, "must be [x, y, z] in mm");
      if (!std::isfinite(v[i]) || std::abs(v[i]) > 50.0) fail(*n, key, "each coordinate must be within ±50 mm");
    }
    return v;
  }
  void refuse_unknown(const std::string& known) const {
    for (const auto& [k, v] : t_) {
      if (!seen_.count(std::string(k.str()))) fail(v, std::string(k.str()), "unknown key (" + known + ")");
    }
  }

 private:
  const toml::table& t_;
  std::string origin_, where_;
  std::set<std::string> seen_;
};

const std::set<std::string> kFaultKinds = {"nan", "range", "stuck", "jump", "version", "unknown", "drop", "disconnect"};

}  // namespace

SurgicalScript parse_surgical_script(const std::string& text, const std::string& origin) {
  if (const files::TomlProblem p = files::toml_guard(text))
    throw std::runtime_error(origin + ":" + std::to_string(p.line) + ":" + std::to_string(p.column) + ": " + p.why);
  toml::table root;
  try {
    root = toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    throw std::runtime_error(origin + ":" + std::to_string(e.source().begin.line) + ": " + std::string(e.description()));
  }
  SurgicalScript s;
  s.file = origin;
  Reader top(root, origin, "");
  const toml::node* head = top.get("script");
  if (!head || !head->is_table()) throw std::runtime_error(origin + ":1: script: no [script] table (version = " + std::to_string(kSurgicalScriptVersion) + ")");
  {
    Reader r(*head->as_table(), origin, "script.");
    const auto version = r.number("version", 0, 1e6);
    if (!version) r.fail_here("version", "missing (" + std::to_string(kSurgicalScriptVersion) + ")");
    if (*version != kSurgicalScriptVersion)
      r.fail(*r.get("version"), "version", "this is a version " + std::to_string(static_cast<long>(*version)) +
                                               " script; this vitreo reads version " + std::to_string(kSurgicalScriptVersion));
    s.kind = r.string("kind").value_or("test");
    if (s.kind != "expert" && s.kind != "clumsy" && s.kind != "idle" && s.kind != "test" && s.kind != "calibration")
      r.fail(*r.get("kind"), "kind", "must be expert, clumsy, idle, test or calibration");
    const auto name = r.string("case");
    if (s.kind == "calibration") {
      if (name) r.fail(*r.get("case"), "case", "a calibration script has no case: its landmarks are the fixture's");
    } else {
      if (!name) r.fail_here("case", "missing: the case this script is written for");
      s.case_name = *name;
    }
    s.summary = r.string("summary").value_or("");
    s.duration_s = r.number("duration_s", 0.01, 3600).value_or(s.duration_s);
    if (s.kind == "calibration" && r.get("duration_s"))
      r.fail(*r.get("duration_s"), "duration_s", "a calibration run lasts as long as the technician's motions");
    if (s.kind == "calibration" && r.get("press_mm")) r.fail(*r.get("press_mm"), "press_mm", "not in a calibration script (no tissue)");
    s.seed = static_cast<std::uint64_t>(r.number("seed", 0, 1e15).value_or(1));
    s.tremor_mm = r.number("tremor_mm", 0, 2).value_or(0);
    s.speed_scale = r.number("speed_scale", 0.05, 20).value_or(1);
    s.press_mm = r.number("press_mm", -2, 2).value_or(0);
    r.refuse_unknown("version, case, kind, summary, duration_s, seed, tremor_mm, speed_scale, press_mm");
  }
  if (const toml::node* hands = top.get("hand")) {
    const toml::array* a = hands->as_array();
    if (!a || !a->is_array_of_tables()) top.fail(*hands, "hand", "must be [[hand]] tables");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::table& t = *a->get(i)->as_table();
      const std::string where = "hand[" + std::to_string(i) + "].";
      Reader r(t, origin, where);
      ScriptHand h;
      h.line = line_of(t);
      h.tracker = static_cast<int>(r.number("tracker", 0, kTrackedInstruments - 1).value_or(0));
      if (r.get("tracker") && r.get("tracker")->is_floating_point()) r.fail(*r.get("tracker"), "tracker", "must be 0 or 1");
      for (const auto& other : s.hands)
        if (other.tracker == h.tracker) r.fail_here("tracker", "a second hand on tracker " + std::to_string(h.tracker));
      h.speed_mm_s = r.number("speed_mm_s", 0.1, 100).value_or(h.speed_mm_s);
      const toml::node* wps = r.get("waypoint");
      if (!wps || !wps->is_array_of_tables()) r.fail_here("waypoint", "a hand needs [[hand.waypoint]] tables");
      const toml::array& wa = *wps->as_array();
      for (std::size_t j = 0; j < wa.size(); ++j) {
        const toml::table& wt = *wa.get(j)->as_table();
        Reader w(wt, origin, where + "waypoint[" + std::to_string(j) + "].");
        ScriptWaypoint p;
        p.line = line_of(wt);
        const auto to = w.string("to");
        if (!to) w.fail_here("to", "missing: the landmark this waypoint goes to");
        p.to = *to;
        p.to_line = line_of(*w.get("to"));
        p.above_mm = w.number("above_mm", -10, 30).value_or(0);
        p.toward_port_mm = w.number("toward_port_mm", -15, 15).value_or(0);
        p.across_mm = w.number("across_mm", -15, 15).value_or(0);
        p.offset_mm = w.vec3("offset_mm").value_or(Vec3::Zero());
        p.standoff_mm = w.number("standoff_mm", 0, 30).value_or(0);
        p.at_s = w.number("at_s", 0, 3600);
        p.speed_mm_s = w.number("speed_mm_s", 0.1, 100);
        p.duration_s = w.number("duration_s", 0, 600);
        p.hold_s = w.number("hold_s", 0, 600).value_or(0);
        p.jaws = w.number("jaws", 0, 1);
        p.roll_deg = w.number("roll_deg", -360, 360);
        p.tool = w.string("tool");
        if (p.tool) p.tool_line = line_of(*w.get("tool"));
        if (p.tool && h.tracker != kToolTracker) w.fail(*w.get("tool"), "tool", "only the working hand (tracker 0) switches tools");
        p.vacuum = w.number("vacuum", 0, 1);
        p.cut_rate = w.number("cut_rate", 0, 1);
        p.laser = w.boolean("laser");
        p.reflux = w.boolean("reflux");
        p.air = w.boolean("air");
        p.pick = w.boolean("pick");
        p.zoom = w.number("zoom", 0.1, 40);
        p.focus_mm = w.number("focus_mm", -20, 20);
        p.light = w.number("light", 0, 1);
        p.look_at = w.string("look_at");
        if (p.look_at) p.look_at_line = line_of(*w.get("look_at"));
        p.tilt_deg = w.number("tilt_deg", -80, 80);
        if (const toml::node* n = w.get("swing_deg")) {
          const toml::array* pair = n->as_array();
          double v[2] = {0, 0};
          if (!pair || pair->size() != 2) w.fail(*n, "swing_deg", "must be [from, to]: the shaft's tilt about the resting tip, in degrees");
          for (std::size_t k = 0; k < 2; ++k) {
            const toml::node& e = *pair->get(k);
            if (e.is_integer()) v[k] = static_cast<double>(e.as_integer()->get());
            else if (e.is_floating_point()) v[k] = e.as_floating_point()->get();
            else w.fail(*n, "swing_deg", "must be [from, to] in degrees");
            if (!std::isfinite(v[k]) || v[k] < 0 || v[k] > 60) w.fail(*n, "swing_deg", "each angle must be within [0, 60] degrees");
          }
          p.swing_deg = std::make_pair(v[0], v[1]);
        }
        p.swing_period_s = w.number("swing_period_s", 0.2, 20).value_or(p.swing_period_s);
        p.records = w.string("records");
        if (p.records) p.records_line = line_of(*w.get("records"));
        p.travel = w.number("travel", 0, 1).value_or(p.travel);
        // Each kind of script takes the keys that mean something for it: a technician's hand is free
        // of ports and tools; a surgeon's is held by its port.
        const bool calibration = s.kind == "calibration";
        for (const char* k : {"tilt_deg", "swing_deg", "swing_period_s", "records", "travel"})
          if (!calibration && w.get(k)) w.fail(*w.get(k), k, "only in calibration scripts (kind = \"calibration\")");
        for (const char* k : {"above_mm", "toward_port_mm", "across_mm", "standoff_mm", "jaws", "roll_deg", "tool", "vacuum", "cut_rate",
                              "laser", "reflux", "air", "pick", "zoom", "focus_mm", "light", "look_at"})
          if (calibration && w.get(k))
            w.fail(*w.get(k), k, "not in a calibration script (no case, no port, no tool; the pedals are pressed by `records = \"pedal_travel.AXIS\"`)");
        w.refuse_unknown("to, above_mm, toward_port_mm, across_mm, offset_mm, standoff_mm, at_s, speed_mm_s, duration_s, hold_s, jaws, roll_deg, tool, vacuum, cut_rate, laser, reflux, air, pick, zoom, focus_mm, light, look_at, tilt_deg, swing_deg, swing_period_s, records, travel");
        h.waypoints.push_back(std::move(p));
      }
      r.refuse_unknown("tracker, speed_mm_s, waypoint");
      s.hands.push_back(std::move(h));
    }
  }
  if (const toml::node* faults = top.get("fault")) {
    const toml::array* a = faults->as_array();
    if (!a || !a->is_array_of_tables()) top.fail(*faults, "fault", "must be [[fault]] tables");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::table& t = *a->get(i)->as_table();
      Reader r(t, origin, "fault[" + std::to_string(i) + "].");
      ScriptFault f;
      f.line = line_of(t);
      const auto device = r.string("device");
      if (!device || (*device != "tracker-0" && *device != "tracker-1" && *device != "pedals" && *device != "eyeball"))
        r.fail_here("device", "must be tracker-0, tracker-1, pedals or eyeball");
      f.device = *device;
      const auto kind = r.string("kind");
      if (!kind || !kFaultKinds.count(*kind)) r.fail_here("kind", "must be nan, range, stuck, jump, version, unknown, drop or disconnect");
      f.kind = *kind;
      const auto at = r.number("at_s", 0, 3600);
      if (!at) r.fail_here("at_s", "missing");
      f.at_s = *at;
      f.duration_s = r.number("duration_s", 0, 3600).value_or(0);
      f.value = r.number("value", -1e6, 1e6).value_or(0);
      r.refuse_unknown("device, kind, at_s, duration_s, value");
      s.faults.push_back(f);
    }
  }
  if (const toml::node* eye = top.get("eye")) {
    const toml::array* a = eye->as_array();
    if (!a || !a->is_array_of_tables()) top.fail(*eye, "eye", "must be [[eye]] tables");
    if (s.kind == "calibration") top.fail(*eye, "eye", "a technician's script turns the eye with tilt_deg on a waypoint");
    double free_at = 0.0;  // when the last turn ends
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::table& t = *a->get(i)->as_table();
      Reader r(t, origin, "eye[" + std::to_string(i) + "].");
      ScriptEyeTurn e;
      e.line = line_of(t);
      const auto at = r.number("at_s", 0, 3600);
      if (!at) r.fail_here("at_s", "missing");
      if (*at < free_at) {
        char why[96];
        std::snprintf(why, sizeof why, "the eye is still turning then (the turn before ends at %.3f s)", free_at);
        r.fail(*r.get("at_s"), "at_s", why);
      }
      e.at_s = *at;
      e.duration_s = r.number("duration_s", 0.05, 600).value_or(e.duration_s);
      // ±25°: an eye held by the instruments in its ports is not turned farther in surgery.
      e.yaw_deg = r.number("yaw_deg", -25, 25).value_or(0);
      e.pitch_deg = r.number("pitch_deg", -25, 25).value_or(0);
      r.refuse_unknown("at_s, duration_s, yaw_deg, pitch_deg");
      free_at = e.at_s + e.duration_s;
      s.eye.push_back(e);
    }
  }
  top.refuse_unknown("script, hand, fault, eye");
  return s;
}

SurgicalScript read_surgical_script(const std::string& path) {
  const auto file = files::read_text_file(path);
  if (!file.text) throw std::runtime_error(path + ": " + file.error);
  return parse_surgical_script(*file.text, path);
}

namespace {

// Where a landmark lies and which way is "up" from the tissue there (toward the globe centre).
struct Landmark {
  Vec3 at = Vec3::Zero();
  Vec3 inward = Vec3::UnitZ();
};

std::vector<Vec3> alive_positions(const core::TissueWorld& w, std::uint32_t surface) {
  const auto& s = w.surface(surface);
  std::vector<Vec3> out;
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v)
    if (s.vertex_alive(v)) out.push_back(s.position(v));
  return out;
}

Vec3 centroid(const std::vector<Vec3>& pts) {
  Vec3 c = Vec3::Zero();
  for (const auto& p : pts) c += p;
  return pts.empty() ? c : Vec3(c / static_cast<double>(pts.size()));
}

// The point of the globe wall on the ray from its centre through p, and the inward normal there.
Landmark wall_under(const core::Scene& scene, const Vec3& p) {
  const Vec3 centre = scene.eye.wall.center();
  const Vec3 dir = (p - centre).normalized();
  return Landmark{centre + dir * scene.eye.wall.radius_toward(dir), -dir};
}

class LandmarkResolver {
 public:
  LandmarkResolver(const PreparedCase& c, const SurgicalScript& s) : c_(c), s_(s) {}

  Landmark resolve(const std::string& name, int tracker, int line, const std::string& key) const {
    const core::Scene& scene = *c_.scene;
    const Vec3 centre = scene.eye.wall.center();
    auto on_fundus = [&](const Vec3& p) { return Landmark{p, (centre - p).normalized()}; };
    auto wall = [&](const core::FundusLocation& at) { return on_fundus(core::wall_point_at(scene.eye, at)); };
    const auto dot = name.find('.');
    const std::string head = name.substr(0, dot);
    const std::string rest = dot == std::string::npos ? "" : name.substr(dot + 1);
    const auto dot2 = rest.find('.');
    const std::string item = rest.substr(0, dot2);
    const std::string part = dot2 == std::string::npos ? "" : rest.substr(dot2 + 1);
    const Port& port = c_.tracker_ports[tracker];
    if (name == "port") return Landmark{port.position_mm, -port.outward};
    if (name == "fovea") return on_fundus(scene.eye.fovea_mm);
    if (name == "disc") return on_fundus(scene.eye.optic_disc_mm);
    if (name == "roi") return on_fundus(c_.focus_mm);
    if (head == "membrane") {
      for (const auto& m : scene.membranes) {
        if (m.name != item) continue;
        const auto pts = alive_positions(scene.world, m.surface);
        const Vec3 c = centroid(pts);
        const Landmark mid = on_fundus(c);
        // The fundus direction toward the hand's port, and toward the disc, at the membrane.
        auto tangent_to = [&](const Vec3& p) {
          Vec3 d = p - c;
          d -= d.dot(mid.inward) * mid.inward;
          return d.norm() > 1e-9 ? Vec3(d.normalized()) : Vec3::UnitX();
        };
        double radius = 0.0;
        for (const auto& p : pts) radius = std::max(radius, (p - c).norm());
        auto extreme = [&](const Vec3& dir, double fraction) {
          // the membrane vertex farthest along dir within `fraction` of the radius
          Vec3 best = c;
          double best_d = -1e300;
          for (const auto& p : pts) {
            if ((p - c).norm() > fraction * radius + 1e-9) continue;
            const double d = (p - c).dot(dir);
            if (d > best_d) best_d = d, best = p;
          }
          return on_fundus(best);
        };
        if (part.rfind("site.", 0) == 0) return site(m, part.substr(5), line, key);
        if (part.empty() || part == "centre") return on_fundus(c);
        if (part == "edge") return extreme(tangent_to(port.position_mm), 1.0);
        if (part == "mid") return extreme(tangent_to(port.position_mm), 0.5);
        if (part == "far_edge") return extreme(-tangent_to(port.position_mm), 1.0);
        if (part == "disc_edge") return extreme(tangent_to(scene.eye.optic_disc_mm), 1.0);
        fail(line, key, "membrane." + item + "." + part + ": no such part (centre, edge, mid, far_edge, disc_edge, site.N)");
      }
      fail(line, key, "the case has no membrane '" + item + "'");
    }
    if (head == "tear") {
      for (std::size_t i = 0; i < scene.description.tears.size(); ++i) {
        const auto& t = scene.description.tears[i];
        if (t.name != item) continue;
        if (part.empty()) return wall(t.center);
        if (part == "flap" && i < scene.tears.size() && scene.retina != core::kNone) {
          const auto& surf = scene.world.surface(scene.retina);
          std::vector<Vec3> pts;
          for (auto v : scene.tears[i].flap_vertices)
            if (surf.vertex_alive(v)) pts.push_back(surf.position(v));
          if (!pts.empty()) return on_fundus(centroid(pts));
        }
        if (part == "hinge") {  // the U's open end lies anterior (toward the ora) of its centre
          core::FundusLocation h = t.center;
          h.polar_deg += 0.5 * t.length_mm / (scene.eye.parameters.globe_diameter_mm * 0.5) / kDeg;
          return wall(h);
        }
        fail(line, key, "tear." + item + "." + part + ": no such part (flap, hinge)");
      }
      fail(line, key, "the case has no tear '" + item + "'");
    }
    if (head == "detachment") {
      for (const auto& d : scene.description.detachments)
        if (d.name == item) return wall(d.center);
      fail(line, key, "the case has no detachment '" + item + "'");
    }
    if (head == "guide") {
      for (const auto& g : scene.guides) {
        if (g.name != item) continue;
        if (g.polyline_mm.empty()) fail(line, key, "guide '" + item + "' has no points");
        if (part.empty()) return on_fundus(centroid(g.polyline_mm));
        if (part == "start") return on_fundus(g.polyline_mm.front());
        if (part == "end") return on_fundus(g.polyline_mm.back());
        char* end = nullptr;
        const long k = std::strtol(part.c_str(), &end, 10);
        if (end && *end == '\0' && k >= 0 && k < static_cast<long>(g.polyline_mm.size())) return on_fundus(g.polyline_mm[static_cast<std::size_t>(k)]);
        fail(line, key, "guide." + item + "." + part + ": no such point (start, end, 0.." + std::to_string(g.polyline_mm.size() - 1) + ")");
      }
      fail(line, key, "the case has no guide '" + item + "'");
    }
    fail(line, key, "unknown landmark '" + name + "' (port, fovea, disc, roi, membrane.NAME…, tear.NAME…, detachment.NAME, guide.NAME…)");
  }

  [[noreturn]] void fail(int line, const std::string& key, const std::string& why) const {
    throw std::runtime_error(s_.file + ":" + std::to_string(line) + ": " + key + ": " + why);
  }

  // membrane.NAME.site.N: the globe wall under the retina end of the attachment at the membrane's
  // lattice site N (scene_builder.cpp numbers the sites from the case alone, so N is the same stalk
  // at every resolution); inward toward the centre.
  Landmark site(const core::BuiltMembrane& m, const std::string& index, int line, const std::string& key) const {
    const core::Scene& scene = *c_.scene;
    char* end = nullptr;
    const long n = std::strtol(index.c_str(), &end, 10);
    const std::string name = "membrane." + m.name + ".site." + index;
    if (index.empty() || !end || *end != '\0' || n < 0 || n >= static_cast<long>(m.sites.size())) {
      fail(line, key, name + ": no such site (0.." + std::to_string(static_cast<long>(m.sites.size()) - 1) + ")");
    }
    const std::uint32_t a = m.sites[static_cast<std::size_t>(n)];
    if (a == core::kNone) fail(line, key, name + ": no vertex of this resolution's mesh stands at that site");
    return wall_under(scene, scene.world.surface(scene.retina).position(scene.world.attachment_vertex_b(a)));
  }

 private:
  const PreparedCase& c_;
  const SurgicalScript& s_;
};

// The tracker's orientation for a twist `roll_deg` about the shaft from `port` to `tip`, as the Z-Y-X
// Euler angles the emulator takes: the instrument's x axis at roll_deg from the eye's +z projected
// across the shaft (rig/input/port_pivot.cpp measures it the same way), its z axis along the shaft.
// A rotation's Z-Y-X Euler angles in degrees (yaw, pitch, roll), the emulator's tracker convention.
Vec3 euler_zyx_deg(const Eigen::Matrix3d& m) {
  return Vec3(std::atan2(m(1, 0), m(0, 0)), std::asin(std::clamp(-m(2, 0), -1.0, 1.0)), std::atan2(m(2, 1), m(2, 2))) / kDeg;
}

Vec3 euler_for_roll(const Vec3& port, const Vec3& tip, double roll_deg) {
  Vec3 axis = tip - port;
  if (axis.norm() < 1e-9) return Vec3::Zero();
  axis.normalize();
  Vec3 ref = Vec3::UnitZ() - Vec3::UnitZ().dot(axis) * axis;
  if (ref.norm() < 1e-6) ref = Vec3::UnitX() - Vec3::UnitX().dot(axis) * axis;
  ref.normalize();
  const double r = roll_deg * kDeg;
  const Vec3 x = std::cos(r) * ref + std::sin(r) * axis.cross(ref);
  const Vec3 y = axis.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = axis;
  return euler_zyx_deg(R);
}

std::string tracker_key(double t_ms, const Vec3& p, double jaws, const Vec3& euler_deg = Vec3::Zero()) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "key %.1f %.4f %.4f %.4f %.3f %.3f %.3f %.3f\n", t_ms, p.x(), p.y(), p.z(), euler_deg.x(), euler_deg.y(),
                euler_deg.z(), jaws);
  return buf;
}

// The eye as the script turns it: the fixture's yaw and pitch at time t (linear through each turn),
// and a hand's key as its tracker reads it with the eye so turned — the instruments sit in the eye's
// ports, so the tip and the handle turn with it about the globe centre (the eye frame's origin),
// as core/instruments/stage_place.cpp turns them back.
class EyeTurns {
 public:
  explicit EyeTurns(const std::vector<ScriptEyeTurn>& turns) : turns_(turns) {}
  bool any() const { return !turns_.empty(); }
  double last_end_s() const { return turns_.empty() ? 0.0 : turns_.back().at_s + turns_.back().duration_s; }
  bool turning_during(double t0, double t1) const {
    for (const auto& e : turns_)
      if (e.at_s < t1 && e.at_s + e.duration_s > t0) return true;
    return false;
  }
  // (yaw, pitch) in degrees at t.
  std::pair<double, double> angles_at(double t) const {
    double yaw = 0.0, pitch = 0.0;
    for (const auto& e : turns_) {
      if (t <= e.at_s) break;
      const double f = std::min(1.0, (t - e.at_s) / e.duration_s);
      yaw += f * (e.yaw_deg - yaw);
      pitch += f * (e.pitch_deg - pitch);
    }
    return {yaw, pitch};
  }
  // The fixture's orientation for those angles, as the eyeball emulator encodes them (Z then Y).
  static core::Quat rotation(double yaw_deg, double pitch_deg) {
    return core::Quat(Eigen::AngleAxisd(yaw_deg * kDeg, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch_deg * kDeg, Vec3::UnitY()));
  }
  std::string key(double t_s, const Vec3& p, double jaws, const Vec3& euler_deg) const {
    if (turns_.empty()) return tracker_key(t_s * 1e3, p, jaws, euler_deg);
    const auto [yaw, pitch] = angles_at(t_s);
    const core::Quat r = rotation(yaw, pitch);
    const core::Quat hand = Eigen::AngleAxisd(euler_deg.x() * kDeg, Vec3::UnitZ()) * Eigen::AngleAxisd(euler_deg.y() * kDeg, Vec3::UnitY()) *
                            Eigen::AngleAxisd(euler_deg.z() * kDeg, Vec3::UnitX());
    return tracker_key(t_s * 1e3, r * p, jaws, euler_zyx_deg((r * hand).toRotationMatrix()));
  }

 private:
  const std::vector<ScriptEyeTurn>& turns_;
};

// A change of the microscope pedal a waypoint asks for, from its start on.
struct MicroscopeChange {
  double t_s;
  std::optional<double> zoom, focus_mm, light;
  std::optional<core::Vec2> look_at;  // fundus plane: where the field's centre goes
  int line;
  std::string key;
};

// The simulated microscope pedal's emulator script: zoom and focus axes set to what each change
// asks, the light switches pressed as many times as the light's steps need, the joystick deflected toward each look_at target for as long as the pan takes at the
// zoom then in force (core::Microscope: pan_speed_mm_s / zoom at full deflection), then let go; a
// target beyond the microscope's reach takes the field as far as it goes (its centre stays within
// pan_travel_mm of the posterior pole). Open loop like the rest
// of the script: the zoom is taken as reached when the pan starts (the zoom motor needs about
// 0.3 s per doubling), so a look_at right after a zoom change lands a little short or long.
std::string microscope_pedal_script(std::vector<MicroscopeChange> changes, const PreparedCase& c, const PedalMapping& m,
                                    const core::MicroscopeSettings& settings, const SurgicalScript& script) {
  auto fail = [&](const MicroscopeChange& ch, const std::string& key, const std::string& why) -> void {
    throw std::runtime_error(script.file + ":" + std::to_string(ch.line) + ": " + ch.key + "." + key + ": " + why);
  };
  std::stable_sort(changes.begin(), changes.end(), [](const MicroscopeChange& a, const MicroscopeChange& b) { return a.t_s < b.t_s; });
  double axes[4] = {0.0, 0.5, 0.5, 0.5};  // by role: zoom travel, focus travel, joystick x, y (centred)
  double zoom = m.zoom_min, light = SurgicalControls{}.light_level;
  core::Vec2 centre = c.scene->eye.fundus_coords(c.focus_mm);  // the microscope starts on the region of interest
  std::string keys;
  double last_ms = -1.0;
  auto key = [&](double t_ms, unsigned switches = 0) {
    t_ms = std::max(t_ms, last_ms + 0.5);
    double v[4] = {0.0, 0.0, 0.0, 0.0};
    const int index[4] = {m.zoom_axis, m.focus_axis, m.pan_x_axis, m.pan_y_axis};
    for (int r = 0; r < 4; ++r)
      if (index[r] >= 0 && index[r] < 4) v[index[r]] = axes[r];
    char b[128];
    std::snprintf(b, sizeof b, "key %.1f %.6f %.6f %.6f %.6f %u\n", t_ms, v[0], v[1], v[2], v[3], switches);
    keys += b;
    last_ms = t_ms;
  };
  key(0.0);
  double pan_ends_s = 0.0;
  for (const MicroscopeChange& ch : changes) {
    if (ch.t_s < pan_ends_s)
      fail(ch, "look_at", "the field is still panning to the last look_at until " + std::to_string(pan_ends_s) + " s; change the microscope after that");
    key(ch.t_s * 1e3);  // hold what was set until now
    if (ch.zoom) {
      if (m.zoom_axis < 0 || *ch.zoom < m.zoom_min - 1e-9 || *ch.zoom > m.zoom_max + 1e-9)
        fail(ch, "zoom", "the microscope pedal zooms " + std::to_string(m.zoom_min) + " .. " + std::to_string(m.zoom_max));
      axes[0] = (*ch.zoom - m.zoom_min) / std::max(m.zoom_max - m.zoom_min, 1e-9);
      zoom = *ch.zoom;
    }
    if (ch.focus_mm) {
      if (m.focus_axis < 0 || std::abs(*ch.focus_mm) > 0.5 * m.focus_range_mm + 1e-9)
        fail(ch, "focus_mm", "the microscope pedal focuses ±" + std::to_string(0.5 * m.focus_range_mm) + " mm");
      axes[1] = 0.5 + *ch.focus_mm / m.focus_range_mm;
    }
    key(ch.t_s * 1e3 + 1.0);
    if (ch.light) {
      // The light source in its steps: a press (50 ms down, 50 ms up) of the up or down switch each.
      const int presses = static_cast<int>(std::lround((*ch.light - light) / m.light_step));
      const int sw = presses > 0 ? m.light_up_switch : m.light_down_switch;
      if (presses != 0 && (sw < 0 || sw > 15 || !(m.light_step > 0.0))) fail(ch, "light", "the pedal mapping has no light switch");
      for (int k = 0; k < std::abs(presses); ++k) {
        const double at = last_ms + 1.0;
        key(at, 1u << sw);
        key(at + 49.0, 1u << sw);
        key(at + 50.0);
        key(at + 99.0);
      }
      light = std::clamp(light + presses * m.light_step, 0.0, 1.0);
    }
    if (ch.look_at) {
      if (m.pan_x_axis < 0 || m.pan_y_axis < 0) fail(ch, "look_at", "the pedal mapping has no X–Y joystick");
      // As far as the microscope reaches: its field's centre stays within pan_travel_mm of the pole.
      core::Vec2 to = *ch.look_at;
      if (to.norm() > settings.pan_travel_mm) to *= settings.pan_travel_mm / to.norm();
      const core::Vec2 d = to - centre;
      const double dist = d.norm(), speed = settings.pan_speed_mm_s / zoom;
      if (dist > 1e-6) {
        // Each axis deflected by the direction's component, past the joystick's dead band.
        const core::Vec2 dir = d / dist;
        for (int k = 0; k < 2; ++k) {
          const double q = dir[k], raw = q == 0.0 ? 0.0 : std::copysign(m.pan_deadband + std::abs(q) * (1.0 - m.pan_deadband), q);
          axes[2 + k] = 0.5 + 0.5 * raw;
        }
        // Held from start to end (the emulator interpolates between keys: a key each side of a change).
        const double start_ms = last_ms + 1.0, end_ms = start_ms + 1e3 * dist / speed;
        key(start_ms);
        key(end_ms - 0.5);
        axes[2] = axes[3] = 0.5;
        key(end_ms + 0.5);
        pan_ends_s = end_ms * 1e-3;
        centre = to;
      }
    }
  }
  key(std::max(last_ms + 1.0, script.duration_s * 1e3));
  return "device pedals\nrate_hz 500\nserial 2101\npedal_id " + std::to_string(m.microscope_pedal_id) + "\naxes 4\nloop 0\nseed " +
         std::to_string(script.seed + 30) + "\n" + keys;
}

// The pedal's state as the emulator plays it: two axes and a switch word.
struct PedalState {
  double vacuum = 0.0, cut_rate = 0.0;
  unsigned switches = 0;
};

}  // namespace

bool works_microscope(const SurgicalScript& script) {
  for (const ScriptHand& h : script.hands)
    for (const ScriptWaypoint& w : h.waypoints)
      if (w.zoom || w.focus_mm || w.light || w.look_at) return true;
  return false;
}

ResolvedScript resolve_script(const SurgicalScript& script, const PreparedCase& c, const PedalMapping& pedals,
                              const core::MicroscopeSettings& microscope) {
  const core::Scene& scene = *c.scene;
  if (script.kind == "calibration")
    throw std::runtime_error(script.file + ": script.kind: a calibration script is a technician's, played by vitreo-calibrate --technician-script");
  if (!scene.description.name.empty() && script.case_name != scene.description.name)
    throw std::runtime_error(script.file + ": script.case: written for '" + script.case_name + "', not for '" + scene.description.name + "'");
  LandmarkResolver landmarks(c, script);
  const EyeTurns eye(script.eye);
  ResolvedScript out;
  out.duration_s = script.duration_s;
  // The working hand's tools in the order the instrument switch cycles through them.
  std::vector<std::string> tools;
  for (const auto& name : scene.description.instruments) {
    core::InstrumentKind k;
    if (instrument_kind(name, k) && k != core::InstrumentKind::kLightPipe) tools.push_back(name);
  }
  const Vec3 centre = scene.eye.wall.center();
  struct PedalChange {
    double t_s;
    std::optional<double> vacuum, cut_rate;
    std::optional<bool> laser, reflux, air;
    int presses = 0;  // instrument switch
    std::optional<bool> pick;
    int line;
  };
  std::vector<PedalChange> changes;
  std::vector<MicroscopeChange> microscope_changes;
  std::mt19937_64 rng(script.seed * 7919 + 17);
  std::normal_distribution<double> tremor(0.0, 1.0);

  for (const ScriptHand& hand : script.hands) {
    const std::string hand_key = "hand[" + std::to_string(&hand - script.hands.data()) + "]";
    if (hand.tracker == kSecondHandTracker && c.second_hand < 0)
      landmarks.fail(hand.line, hand_key + ".tracker", "the case has nothing for the second hand (no light pipe, no instruments.second_hand)");
    if (hand.tracker == kToolTracker && tools.empty()) landmarks.fail(hand.line, hand_key + ".tracker", "the case has no tools for the working hand");
    const Port& port = c.tracker_ports[hand.tracker];
    Vec3 pos = port.position_mm + 2.0 * port.outward;  // the tip waits outside its cannula
    double jaws = 0.0, t = 0.0;
    std::optional<double> roll;  // unset: the tracker's neutral orientation
    int tool = 0;
    std::string keys = eye.key(0, pos, 0, Vec3::Zero());
    auto orientation = [&](const Vec3& p, std::optional<double> r) { return r ? euler_for_roll(port.position_mm, p, *r) : Vec3::Zero(); };
    auto add_segment = [&](const Vec3& to, double to_jaws, double duration, std::optional<double> to_roll) {
      // Tremor: seeded offsets at 20 Hz along the way (none while the hand is outside the eye).
      // While the eye turns, keys at 20 Hz too: the tracker sees the tip turn with the eye.
      const bool sampled = script.tremor_mm > 0.0 || eye.turning_during(t, t + duration);
      const int n = sampled ? std::max(1, static_cast<int>(duration * 20.0)) : 1;
      const std::optional<double> from_roll = roll ? roll : (to_roll ? std::optional<double>(0.0) : std::nullopt);
      for (int i = 1; i <= n; ++i) {
        const double f = static_cast<double>(i) / n;
        Vec3 p = pos + f * (to - pos);
        if (script.tremor_mm > 0.0 && i < n) p += script.tremor_mm * Vec3(tremor(rng), tremor(rng), tremor(rng));
        const std::optional<double> r = to_roll ? std::optional<double>(*from_roll + f * (*to_roll - *from_roll)) : from_roll;
        keys += eye.key(t + f * duration, p, jaws + f * (to_jaws - jaws), orientation(p, r));
      }
      out.path_mm[hand.tracker] += (to - pos).norm();
      t += duration;
      pos = to;
      jaws = to_jaws;
      if (to_roll) roll = to_roll;
    };
    for (std::size_t i = 0; i < hand.waypoints.size(); ++i) {
      const ScriptWaypoint& w = hand.waypoints[i];
      const std::string key = hand_key + ".waypoint[" + std::to_string(i) + "]";
      if (w.at_s && *w.at_s > t) add_segment(pos, jaws, *w.at_s - t, std::nullopt);  // wait in place
      PedalChange ch{t, w.vacuum, w.cut_rate, w.laser, w.reflux, w.air, 0, w.pick, w.line};
      // The microscope from the waypoint's start on; look_at = "target" centres the field on where
      // this waypoint goes (known below, once its target is).
      std::optional<MicroscopeChange> mc;
      if (w.zoom || w.focus_mm || w.light || w.look_at) {
        mc = MicroscopeChange{t, w.zoom, w.focus_mm, w.light, std::nullopt, w.line, key};
        if (w.look_at && *w.look_at != "target")
          mc->look_at = scene.eye.fundus_coords(landmarks.resolve(*w.look_at, hand.tracker, w.look_at_line, key + ".look_at").at);
      }
      if (w.tool) {
        const auto it = std::find(tools.begin(), tools.end(), *w.tool);
        if (it == tools.end()) landmarks.fail(w.tool_line, key + ".tool", "the case offers no " + *w.tool + " to the working hand");
        const int want = static_cast<int>(it - tools.begin());
        ch.presses = (want - tool + static_cast<int>(tools.size())) % static_cast<int>(tools.size());
        tool = want;
        // a press takes 100 ms (down, up) and the hand waits for the switch
        if (ch.presses > 0) add_segment(pos, jaws, 0.1 * ch.presses + 0.05, std::nullopt);
      }
      if (ch.vacuum || ch.cut_rate || ch.laser || ch.reflux || ch.air || ch.pick || ch.presses) changes.push_back(ch);
      Landmark l = landmarks.resolve(w.to, hand.tracker, w.to_line, key + ".to");
      Vec3 tangent_to_port = port.position_mm - l.at;
      tangent_to_port -= tangent_to_port.dot(l.inward) * l.inward;
      tangent_to_port = tangent_to_port.norm() > 1e-9 ? Vec3(tangent_to_port.normalized()) : Vec3::Zero();
      if (w.to != "port" && (w.toward_port_mm != 0.0 || w.across_mm != 0.0)) {
        // Along the fundus: step in the tangent plane, then back onto the curved wall at the
        // landmark's own height above it (a raster over a membrane follows the globe's curve).
        const Vec3 from_c = l.at - centre;
        const double height = scene.eye.wall.radius_toward(from_c.normalized()) - from_c.norm();
        const Vec3 moved = l.at + w.toward_port_mm * tangent_to_port + w.across_mm * l.inward.cross(tangent_to_port);
        const Vec3 dir = (moved - centre).normalized();
        l.at = centre + dir * (scene.eye.wall.radius_toward(dir) - height);
        l.inward = -dir;
      }
      // Pressing harder: every waypoint at or within 0.5 mm of tissue goes press_mm deeper.
      const bool touching = w.to != "port" && w.above_mm <= 0.5;
      const double above = w.above_mm - (touching ? script.press_mm : 0.0);
      const Vec3 aimed = l.at + above * l.inward + w.offset_mm;
      const Vec3 target = aimed - w.standoff_mm * (aimed - port.position_mm).normalized();
      // Reachable: inside the globe, and no farther from the port than a 32 mm shaft reaches.
      if (w.to != "port" || w.above_mm > 0.0) {
        const Vec3 d = target - centre;
        const double wall_r = scene.eye.wall.radius_toward(d.normalized());
        if (d.norm() > wall_r + 0.3) landmarks.fail(w.to_line, key, "unreachable: " + std::to_string(d.norm() - wall_r) + " mm beyond the eye wall");
        if ((target - port.position_mm).norm() > 32.0) landmarks.fail(w.to_line, key, "unreachable: farther than a 32 mm shaft from the port");
      }
      if (mc) {
        if (w.look_at && *w.look_at == "target") mc->look_at = scene.eye.fundus_coords(target);
        microscope_changes.push_back(*mc);
      }
      const double dist = (target - pos).norm();
      const double speed = w.speed_mm_s.value_or(hand.speed_mm_s) * script.speed_scale;
      const double duration = w.duration_s ? *w.duration_s / script.speed_scale : dist / speed;
      add_segment(target, w.jaws.value_or(jaws), std::max(duration, 0.001), w.roll_deg);
      if (w.hold_s > 0.0) add_segment(pos, jaws, w.hold_s / script.speed_scale, std::nullopt);
    }
    // A hand done before the eye stops turning stays where it is in the eye, turning with it.
    if (eye.any() && t < eye.last_end_s()) add_segment(pos, jaws, eye.last_end_s() - t, std::nullopt);
    const std::string name = "tracker-" + std::to_string(hand.tracker);
    // The working hand holds a universal handpiece (tool type 0): the script's `tool =` picks the
    // tool with instrument-switch presses. The other hand's handpiece is its instrument's own.
    const int tool_type = hand.tracker == kToolTracker ? VP_TOOL_NONE : tool_type_of(c.second_hand_kind);
    std::string header = "device tracker\nrate_hz 1000\nserial " + std::to_string(1001 + hand.tracker) + "\ntool " +
                         std::to_string(tool_type) + "\ninstrument " +
                         std::to_string(hand.tracker) + "\nloop 0\nseed " + std::to_string(script.seed + static_cast<std::uint64_t>(hand.tracker)) + "\n";
    out.device_scripts[name] = header + keys;
  }

  if (!out.device_scripts.count("tracker-0")) {  // no working hand scripted: it stays outside the eye
    const Port& port = c.tracker_ports[kToolTracker];
    out.device_scripts["tracker-0"] = "device tracker\nrate_hz 1000\nserial 1001\ntool 0\ninstrument 0\nloop 0\nseed " +
                                      std::to_string(script.seed) + "\n" + eye.key(0, port.position_mm + 2.0 * port.outward, 0, Vec3::Zero());
  }

  // The pedals: changes in time order, each a step (two keys 1 ms apart); a switch press is 50 ms
  // down, 50 ms up. Laser, reflux and air hold their switch while on; the air switch toggles.
  std::stable_sort(changes.begin(), changes.end(), [](const PedalChange& a, const PedalChange& b) { return a.t_s < b.t_s; });
  auto bit = [](int b) { return b >= 0 && b < 16 ? 1u << b : 0u; };
  PedalState st;
  bool air = false;
  std::string pkeys;
  auto pedal_key = [&](double t_ms, const PedalState& p) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "key %.1f %.3f %.3f %u\n", t_ms, p.vacuum, p.cut_rate, p.switches);
    pkeys += buf;
  };
  pedal_key(0, st);
  double last_ms = 0.0;
  for (const auto& ch : changes) {
    double t_ms = std::max(ch.t_s * 1e3, last_ms + 1.0);
    pedal_key(t_ms, st);
    PedalState next = st;
    if (ch.vacuum) next.vacuum = *ch.vacuum;
    if (ch.cut_rate) next.cut_rate = *ch.cut_rate;
    if (ch.laser) next.switches = *ch.laser ? next.switches | bit(pedals.laser_switch) : next.switches & ~bit(pedals.laser_switch);
    if (ch.reflux) next.switches = *ch.reflux ? next.switches | bit(pedals.reflux_switch) : next.switches & ~bit(pedals.reflux_switch);
    if (ch.pick) next.switches = *ch.pick ? next.switches | bit(pedals.pick_switch) : next.switches & ~bit(pedals.pick_switch);
    for (int i = 0; i < ch.presses; ++i) {
      pedal_key(t_ms + 1.0, PedalState{st.vacuum, st.cut_rate, st.switches | bit(pedals.instrument_switch)});
      pedal_key(t_ms + 50.0, PedalState{st.vacuum, st.cut_rate, st.switches | bit(pedals.instrument_switch)});
      pedal_key(t_ms + 51.0, st);
      t_ms += 100.0;
      pedal_key(t_ms, st);
    }
    if (ch.air && *ch.air != air) {  // one press toggles fluid ↔ air
      air = *ch.air;
      pedal_key(t_ms + 1.0, PedalState{st.vacuum, st.cut_rate, st.switches | bit(pedals.air_switch)});
      pedal_key(t_ms + 50.0, PedalState{st.vacuum, st.cut_rate, st.switches | bit(pedals.air_switch)});
      pedal_key(t_ms + 51.0, st);
      t_ms += 52.0;
    }
    pedal_key(t_ms + 1.0, next);
    st = next;
    last_ms = t_ms + 1.0;
  }
  pedal_key(std::max(last_ms + 1.0, script.duration_s * 1e3), st);
  out.device_scripts["pedals"] = "device pedals\nrate_hz 500\nserial 2001\nloop 0\nseed " + std::to_string(script.seed + 10) + "\n" + pkeys;
  if (!microscope_changes.empty()) out.device_scripts[kMicroscopePedalDevice] = microscope_pedal_script(microscope_changes, c, pedals, microscope, script);
  // The eyeball fixture: at rest, or turned as the script's [[eye]] turns say (a key where each turn
  // starts and ends; the emulator interpolates between them). No port depths: the trackers carry
  // the instruments.
  std::string ekeys = "key 0 0 0 0 0 0\n";
  for (const ScriptEyeTurn& e : script.eye) {
    char buf[128];
    const auto [yaw0, pitch0] = eye.angles_at(e.at_s);
    std::snprintf(buf, sizeof buf, "key %.1f %.4f %.4f 0 0 0\nkey %.1f %.4f %.4f 0 0 0\n", e.at_s * 1e3, yaw0, pitch0,
                  (e.at_s + e.duration_s) * 1e3, e.yaw_deg, e.pitch_deg);
    ekeys += buf;
  }
  const auto [yaw_end, pitch_end] = eye.angles_at(script.duration_s);
  char last[96];
  std::snprintf(last, sizeof last, "key %ld %.4f %.4f 0 0 0\n", static_cast<long>(std::max(script.duration_s, eye.last_end_s()) * 1e3) + 1,
                yaw_end, pitch_end);
  out.device_scripts["eyeball"] = "device eyeball\nrate_hz 250\nserial 3001\nloop 0\nseed " + std::to_string(script.seed + 20) + "\n" +
                                  (script.eye.empty() ? std::string("key 0 0 0 0 0 0\nkey ") + std::to_string(static_cast<long>(script.duration_s * 1e3) + 1) +
                                                            " 0 0 0 0 0\n"
                                                      : ekeys + last);
  for (const ScriptFault& f : script.faults) {
    auto it = out.device_scripts.find(f.device);
    if (it == out.device_scripts.end())
      throw std::runtime_error(script.file + ":" + std::to_string(f.line) + ": fault.device: " + f.device + " is not played by this script");
    // The emulator's line (drivers/sim): only a clock jump takes a value, its size in ms.
    char buf[128];
    if (f.kind == "jump") std::snprintf(buf, sizeof buf, "fault %.1f %.1f jump %g\n", f.at_s * 1e3, f.duration_s * 1e3, f.value);
    else std::snprintf(buf, sizeof buf, "fault %.1f %.1f %s\n", f.at_s * 1e3, f.duration_s * 1e3, f.kind.c_str());
    it->second += buf;
  }
  return out;
}

}  // namespace vitreo::rig

namespace vitreo::rig {

namespace {

// Height of p above the globe wall (negative: beyond it).
double height_above_wall(const core::Scene& scene, const Vec3& p) {
  const Vec3 d = p - scene.eye.wall.center();
  return scene.eye.wall.radius_toward(d.normalized()) - d.norm();
}

// Where p lies in the frame a waypoint's toward_port_mm / across_mm step in from landmark l (the
// inverse of resolve_script's step: the ray from the globe centre through p met with l's tangent plane).
std::pair<double, double> toward_across(const core::Scene& scene, const Landmark& l, const Vec3& port, const Vec3& p) {
  Vec3 toward = port - l.at;
  toward -= toward.dot(l.inward) * l.inward;
  toward.normalize();
  const Vec3 across = l.inward.cross(toward);
  const Vec3 c = scene.eye.wall.center();
  const Vec3 ray = (p - c).normalized();
  const double s = (l.at - c).dot(l.inward) / ray.dot(l.inward);
  const Vec3 on_plane = c + s * ray - l.at;
  return {on_plane.dot(toward), on_plane.dot(across)};
}

}  // namespace

std::string describe_membrane_sites(const PreparedCase& c, const std::string& membrane, double height_mm) {
  const core::Scene& scene = *c.scene;
  const core::BuiltMembrane* m = nullptr;
  for (const auto& b : scene.membranes)
    if (b.name == membrane) m = &b;
  if (!m) throw std::runtime_error("the case has no membrane '" + membrane + "'");
  const Vec3 port = c.tracker_ports[kToolTracker].position_mm;
  const core::Surface& retina = scene.world.surface(scene.retina);
  const core::Surface& band = scene.world.surface(m->surface);
  const Vec3 centre = centroid(alive_positions(scene.world, m->surface));
  const Landmark mid{centre, (scene.eye.wall.center() - centre).normalized()};
  char line[256];
  std::string out;
  std::snprintf(line, sizeof line, "# membrane %s: %zu sites, %u attachments; its centre %.4f mm above the wall; strands crossing %.3f mm above it\n",
                membrane.c_str(), m->sites.size(), m->attachment_count, height_above_wall(scene, centre), height_mm);
  out += line;
  out += "# site attachment state strength | from the site: toward_port_mm across_mm | from the centre: toward_port_mm across_mm | foot: height, x y z (eye frame, mm)\n";
  for (std::size_t n = 0; n < m->sites.size(); ++n) {
    const std::uint32_t a = m->sites[n];
    if (a == core::kNone) {
      std::snprintf(line, sizeof line, "site %zu none\n", n);
      out += line;
      continue;
    }
    const Vec3 foot = retina.position(scene.world.attachment_vertex_b(a));
    const Vec3 top = band.position(scene.world.attachment_vertex_a(a));
    // The strand's point at height_mm above the wall (bisection: the height grows from foot to top).
    double lo = 0.0, hi = 1.0;
    if (height_above_wall(scene, foot) >= height_mm) hi = 0.0;
    for (int i = 0; i < 60 && hi > 0.0; ++i) {
      const double s = 0.5 * (lo + hi);
      (height_above_wall(scene, foot + s * (top - foot)) < height_mm ? lo : hi) = s;
    }
    const Vec3 cross = foot + hi * (top - foot);
    const auto [ts, as] = toward_across(scene, wall_under(scene, foot), port, cross);
    const auto [tc, ac] = toward_across(scene, mid, port, cross);
    const bool strong = scene.world.attachment_break_force(a) == std::numeric_limits<double>::infinity();
    std::snprintf(line, sizeof line, "site %zu %u %s %s %.4f %.4f %.4f %.4f %.4f %.4f %.4f %.4f\n", n, a,
                  scene.world.attachment_holds(a) ? "holds" : "gone", strong ? "strong" : "weak", ts, as, tc, ac, height_above_wall(scene, foot),
                  foot.x(), foot.y(), foot.z());
    out += line;
  }
  return out;
}

}  // namespace vitreo::rig
