#include "rig/session/case_runtime.hpp"

#include <numbers>
#include <sstream>

#include "core/common/status.hpp"
#include "firmware-protocol/vp.h"

namespace vitreo::rig {

namespace {


// Where the surgeon will look first: the case's own choice, else the pathology it is about.
core::Vec3 region_of_interest(const core::Scene& s) {
  const auto& d = s.description;
  if (d.view.region_of_interest) return core::wall_point_at(s.eye, *d.view.region_of_interest);
  if (!d.tears.empty()) return core::wall_point_at(s.eye, d.tears.front().center);
  if (!d.membranes.empty()) return core::wall_point_at(s.eye, d.membranes.front().center);
  if (!d.detachments.empty()) return core::wall_point_at(s.eye, d.detachments.front().center);
  for (const auto& g : d.guides) {
    if (!g.points.empty()) {
      // The middle of the path, so the whole of it is in the field.
      core::Vec3 sum = core::Vec3::Zero();
      for (const auto& p : g.points) sum += core::wall_point_at(s.eye, p);
      const core::Vec3 mean = sum / static_cast<double>(g.points.size());
      return s.eye.wall.radius_toward(mean) * mean.normalized();
    }
    if (g.around.empty()) return core::wall_point_at(s.eye, g.center);
  }
  return s.eye.fovea_mm;
}

const core::SclerotomyPort* find_port(const core::EyeModel& eye, const char* name) {
  for (const auto& p : eye.ports) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

// The pivot of an instrument in a sclerotomy: the middle of the cannula through the wall.
Port pivot_of(const core::SclerotomyPort& p) {
  Port out;
  out.position_mm = 0.5 * (p.outer_mm + p.inner_mm);
  out.outward = -p.axis;
  return out;
}

}  // namespace

bool instrument_kind(const std::string& name, core::InstrumentKind& out) {
  using K = core::InstrumentKind;
  if (name == "vitrector") out = K::kVitrector;
  else if (name == "forceps") out = K::kForceps;
  else if (name == "scissors") out = K::kScissors;
  else if (name == "pick") out = K::kPick;
  else if (name == "laser") out = K::kEndolaser;
  else if (name == "light_pipe") out = K::kLightPipe;
  else if (name == "backflush") out = K::kDrainageNeedle;  // soft-tip flute needle
  else if (name == "blade") out = K::kBlade;
  else if (name == "sideways_blade") out = K::kSidewaysBlade;
  else return false;                                      // "infusion": a cannula, not held
  return true;
}

bool instrument_kind_of_tool_type(int tool_type, core::InstrumentKind& out) {
  using K = core::InstrumentKind;
  switch (tool_type) {
    case VP_TOOL_LIGHT_PIPE: out = K::kLightPipe; return true;
    case VP_TOOL_VITRECTOR: out = K::kVitrector; return true;
    case VP_TOOL_FORCEPS: out = K::kForceps; return true;
    case VP_TOOL_SCISSORS: out = K::kScissors; return true;
    case VP_TOOL_LASER: out = K::kEndolaser; return true;
    case VP_TOOL_PICK: out = K::kPick; return true;
    case VP_TOOL_FLUTE: out = K::kDrainageNeedle; return true;  // the scene files' "backflush"
    case VP_TOOL_BLADE: out = K::kBlade; return true;
    case VP_TOOL_SIDEWAYS_BLADE: out = K::kSidewaysBlade; return true;
    default: return false;  // 0: a universal handpiece names no tool; 8: the infusion is not held
  }
}

int tool_type_of(core::InstrumentKind kind) {
  for (int type = 1; type < 64; ++type) {
    core::InstrumentKind k;
    if (instrument_kind_of_tool_type(type, k) && k == kind) return type;
  }
  return VP_TOOL_NONE;
}

std::unique_ptr<PreparedCase> prepare_case(const std::vector<scene_io::CaseText>& cases, int index,
                                           const scene_io::CaseLoadOptions& options) {
  if (index < 0 || index >= static_cast<int>(cases.size())) {
    throw core::InvalidArgument("case index " + std::to_string(index) + " outside the case list (" +
                                std::to_string(cases.size()) + " cases)");
  }
  auto out = std::make_unique<PreparedCase>();
  out->index = index;
  scene_io::LoadedCase loaded = scene_io::load_case(cases[static_cast<std::size_t>(index)], options);
  out->from_cache = loaded.from_cache;
  out->scene = std::make_unique<core::Scene>(std::move(loaded.scene));
  out->scene->world.set_worker_threads(options.physics_threads);
  core::Scene& s = *out->scene;
  out->start_hash = s.world.state_hash();
  out->focus_mm = region_of_interest(s);

  const core::SclerotomyPort* infusion = find_port(s.eye, "infusion");
  const core::SclerotomyPort* w1 = find_port(s.eye, "working_1");
  const core::SclerotomyPort* w2 = find_port(s.eye, "working_2");
  if (!infusion || !w1 || !w2) throw core::InvalidArgument("case " + s.description.name + ": the eye has no three-port layout");
  const bool swapped = s.description.working_port == "working_2";
  out->tracker_port_names[kToolTracker] = swapped ? "working_2" : "working_1";
  out->tracker_port_names[kSecondHandTracker] = swapped ? "working_1" : "working_2";
  out->tracker_port_ids[kToolTracker] = swapped ? 2 : 1;
  out->tracker_port_ids[kSecondHandTracker] = swapped ? 1 : 2;
  out->tracker_ports[kToolTracker] = pivot_of(swapped ? *w2 : *w1);
  out->tracker_ports[kSecondHandTracker] = pivot_of(swapped ? *w1 : *w2);

  core::InstrumentSceneOptions o;
  o.ports_mm = {pivot_of(*infusion).position_mm, out->tracker_ports[0].position_mm, out->tracker_ports[1].position_mm};
  o.retina_surface = s.retina;
  o.vitreous_surface = s.gel;
  o.macula_mm = s.eye.fovea_mm;
  o.anatomy.has_lens = true;
  o.anatomy.lens_center_mm = core::Vec3(0.0, 0.0, s.eye.lens_center_z_mm);
  const auto& a = s.description.anatomy;
  o.anatomy.lens_semi_axes_mm = core::Vec3(0.5 * a.lens_diameter_mm, 0.5 * a.lens_diameter_mm, 0.5 * a.lens_thickness_mm);
  o.anatomy.retina_thickness_mm = a.retina_thickness_mm;
  // Subretinal fluid drains through the break: the case's tear when it has one, else the centre.
  for (std::size_t i = 0; i < s.detachment_forces.size() && i < s.description.detachments.size(); ++i) {
    core::DrainageSite site;
    site.local_force = s.detachment_forces[i];
    site.break_point_mm = s.description.tears.empty() ? core::wall_point_at(s.eye, s.description.detachments[i].center)
                                                      : core::wall_point_at(s.eye, s.description.tears.front().center);
    o.drainage_sites.push_back(site);
  }
  std::vector<core::InstrumentDescription> instruments;
  bool light = false;
  for (const auto& name : s.description.instruments) {
    core::InstrumentKind k;
    if (!instrument_kind(name, k)) continue;
    if (k == core::InstrumentKind::kLightPipe) {
      light = true;
      continue;
    }
    out->tools.push_back(k);
    core::InstrumentDescription d;
    d.kind = k;
    d.port = 1;
    instruments.push_back(d);
  }
  // The other hand: the light pipe when the case offers one, or its second-hand instrument (an
  // instance of its own: the working hand may hold forceps too).
  core::InstrumentKind second = core::InstrumentKind::kLightPipe;
  const bool second_tool = s.description.second_hand != "light_pipe";
  if (second_tool && !instrument_kind(s.description.second_hand, second))
    throw core::InvalidArgument("case " + s.description.name + ": the other hand cannot hold '" + s.description.second_hand + "'");
  if (light || second_tool) {
    core::InstrumentDescription d;
    d.kind = second;
    d.port = 2;
    out->second_hand = static_cast<int>(instruments.size());
    out->second_hand_kind = second;
    instruments.push_back(d);
  }
  std::vector<std::uint32_t> surfaces;
  for (std::uint32_t i = 0; i < s.world.surface_count(); ++i) surfaces.push_back(i);
  out->topology = std::make_unique<core::TopologyAdapter>(s.world, surfaces, surfaces, core::CutSettings{}, o.vitrector, s.gel);
  out->sim = std::make_unique<core::Simulation>(s.world, o, instruments);
  out->sim->set_topology(out->topology.get());
  out->metrics = std::make_unique<core::SessionMetrics>(s, out->sim.get());
  out->sim->set_observer(out->metrics.get());  // the step's last stage
  return out;
}

std::string describe_instruments(const PreparedCase& c) {
  std::ostringstream ss;
  ss << "tracker 0 (" << c.tracker_port_names[kToolTracker] << "): ";
  for (std::size_t i = 0; i < c.tools.size(); ++i) ss << (i ? ", " : "") << core::to_string(c.tools[i]);
  if (c.tools.empty()) ss << "none";
  ss << " (the handpiece's tool type, else the instrument switch, picks); tracker 1 (" << c.tracker_port_names[kSecondHandTracker] << "): " << (c.second_hand < 0 ? std::string("none") : c.second_hand_is_light_pipe() ? std::string("light pipe") : std::string(core::to_string(c.second_hand_kind)) + " (lit by the chandelier)");
  return ss.str();
}

}  // namespace vitreo::rig
