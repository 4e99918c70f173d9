#include "rig/scene_io/scene_file.hpp"
#include "rig/files/toml_lines.hpp"

#include "core/common/status.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "rig/files/read_text_file.hpp"
#include "rig/files/toml_guard.hpp"

namespace vitreo::scene_io {

namespace {

using core::InvalidArgument;

using files::line_of;

// A TOML table being read: typed getters that record which keys were used, so finish() can refuse
// the rest; every error carries file, line and the full key.
class Tab {
 public:
  Tab(const toml::table& t, std::string path, const std::string& file) : t_(t), path_(std::move(path)), file_(file) {}

  const std::string& path() const { return path_; }
  std::string key(const std::string& k) const { return path_.empty() ? k : path_ + "." + k; }
  int line() const { return std::max(1, line_of(t_)); }
  int line(const std::string& k) const {
    const toml::node* n = t_.get(k);
    return n ? std::max(1, line_of(*n)) : line();
  }
  [[noreturn]] void fail(const std::string& k, const std::string& reason) const {
    throw SceneError(file_, line(k), k.empty() ? path_ : key(k), reason);
  }
  // Maps a core validation message to the key it names (the longest key of this table that the
  // message mentions), so range errors point at their line.
  [[noreturn]] void fail_validation(const std::string& message) const {
    std::string best;
    for (auto&& [k, v] : t_) {
      const std::string ks(k.str());
      if (message.find(ks) != std::string::npos && ks.size() > best.size()) best = ks;
    }
    if (best.empty()) throw SceneError(file_, line(), path_, message);
    fail(best, message);
  }

  bool has(const std::string& k) const { return t_.contains(k); }
  const toml::node* get(const std::string& k) {
    const toml::node* n = t_.get(k);
    if (n) used_.insert(k);
    return n;
  }

  void number(const std::string& k, double& out) {
    const toml::node* n = get(k);
    if (!n) return;
    if (n->is_integer()) {
      out = static_cast<double>(n->as_integer()->get());
    } else if (n->is_floating_point()) {
      out = n->as_floating_point()->get();
    } else {
      fail(k, "expected a number");
    }
    if (std::isnan(out)) fail(k, "must not be NaN");
  }
  void integer(const std::string& k, int& out, int lo, int hi) {
    const toml::node* n = get(k);
    if (!n) return;
    if (!n->is_integer()) fail(k, "expected an integer");
    const std::int64_t v = n->as_integer()->get();
    if (v < lo || v > hi) fail(k, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    out = static_cast<int>(v);
  }
  void u64(const std::string& k, std::uint64_t& out) {
    const toml::node* n = get(k);
    if (!n) return;
    if (!n->is_integer() || n->as_integer()->get() < 0) fail(k, "expected a non-negative integer");
    out = static_cast<std::uint64_t>(n->as_integer()->get());
  }
  void string(const std::string& k, std::string& out) {
    const toml::node* n = get(k);
    if (!n) return;
    if (!n->is_string()) fail(k, "expected a string");
    out = n->as_string()->get();
  }
  void boolean(const std::string& k, bool& out) {
    const toml::node* n = get(k);
    if (!n) return;
    if (!n->is_boolean()) fail(k, "expected true or false");
    out = n->as_boolean()->get();
  }
  std::string required_string(const std::string& k) {
    if (!has(k)) fail("", "missing key '" + k + "'");
    std::string s;
    string(k, s);
    return s;
  }
  std::optional<Tab> table(const std::string& k) {
    const toml::node* n = get(k);
    if (!n) return std::nullopt;
    if (!n->is_table()) fail(k, "expected a table");
    return Tab(*n->as_table(), key(k), file_);
  }
  // An array of tables ([[k]]).
  std::vector<Tab> tables(const std::string& k) {
    std::vector<Tab> out;
    const toml::node* n = get(k);
    if (!n) return out;
    const toml::array* a = n->as_array();
    if (!a) fail(k, "expected an array of tables ([[" + k + "]])");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::node& item = *a->get(i);
      if (!item.is_table()) throw SceneError(file_, std::max(1, line_of(item)), key(k) + "[" + std::to_string(i) + "]", "expected a table");
      out.emplace_back(*item.as_table(), key(k) + "[" + std::to_string(i) + "]", file_);
    }
    return out;
  }
  std::vector<std::string> strings(const std::string& k) {
    std::vector<std::string> out;
    const toml::node* n = get(k);
    if (!n) return out;
    const toml::array* a = n->as_array();
    if (!a) fail(k, "expected an array of strings");
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::node& item = *a->get(i);
      if (!item.is_string()) throw SceneError(file_, std::max(1, line_of(item)), key(k) + "[" + std::to_string(i) + "]", "expected a string");
      out.push_back(item.as_string()->get());
    }
    return out;
  }
  core::FundusLocation location(const std::string& k) {
    core::FundusLocation l;
    auto t = table(k);
    if (!t) fail("", "missing key '" + k + "' (a table { polar_deg = ..., azimuth_deg = ... })");
    read_location(*t, l);
    return l;
  }
  static void read_location(Tab& t, core::FundusLocation& l) {
    if (!t.has("polar_deg")) t.fail("", "missing key 'polar_deg'");
    if (!t.has("azimuth_deg")) t.fail("", "missing key 'azimuth_deg'");
    t.number("polar_deg", l.polar_deg);
    t.number("azimuth_deg", l.azimuth_deg);
    t.finish();
  }
  void finish() const {
    for (auto&& [k, v] : t_) {
      const std::string ks(k.str());
      if (!used_.count(ks)) throw SceneError(file_, std::max(1, static_cast<int>(k.source().begin.line)), key(ks), "unknown key");
    }
  }

 private:
  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

template <class F>
void validated(const Tab& t, F&& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    t.fail_validation(e.what());
  }
}

toml::table parse_toml(std::string_view text, const std::string& file) {
  // toml++ 3.3.0 has undefined behaviour on two kinds of malformed text (rig/files/toml_guard.hpp).
  if (const files::TomlProblem bad = files::toml_guard(text))
    throw SceneError(file, bad.line, "", "column " + std::to_string(bad.column) + ": " + bad.why);
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    throw SceneError(file, std::max(1, static_cast<int>(e.source().begin.line)), "", std::string(e.description()));
  }
}

// A regular file of at most 1 MiB (`library = "/dev/zero"` grew a process to gigabytes).
std::string read_file(const std::string& path, const std::string& from_file, int from_line, const std::string& key) {
  files::TextFile f = files::read_text_file(path);
  if (!f.text) throw SceneError(from_file, from_line, key, f.error);
  return std::move(*f.text);
}

// ---- Materials -----------------------------------------------------------------------------------

const std::vector<std::pair<const char*, double core::TissueMaterial::*>>& material_fields() {
  using M = core::TissueMaterial;
  static const std::vector<std::pair<const char*, double M::*>> f{
      {"density_g_per_mm3", &M::density_g_per_mm3},
      {"thickness_mm", &M::thickness_mm},
      {"membrane_modulus_pa_mm", &M::membrane_modulus_pa_mm},
      {"bending_modulus_un_mm", &M::bending_modulus_un_mm},
      {"tear_strain", &M::tear_strain},
      {"drag_pa_s_per_mm", &M::drag_pa_s_per_mm},
      {"internal_damping_s", &M::internal_damping_s},
      {"entrained_fluid_mm", &M::entrained_fluid_mm},
      {"plastic_yield_strain", &M::plastic_yield_strain},
      {"plastic_rate_per_s", &M::plastic_rate_per_s},
  };
  return f;
}

void read_material(Tab& t, core::TissueMaterial& m, std::map<std::string, std::string>& sources) {
  std::map<std::string, std::string> given;
  if (auto src = t.table("source")) {
    for (const auto& [name, member] : material_fields()) {
      std::string s;
      src->string(name, s);
      if (src->has(name) && s.empty()) src->fail(name, "source must not be empty");
      if (!s.empty()) given[name] = s;
    }
    src->finish();
  }
  for (const auto& [name, member] : material_fields()) {
    if (!t.has(name)) continue;
    t.number(name, m.*member);
    if (!given.count(name)) t.fail(name, "no source given (add it under [" + t.path() + ".source])");
  }
  for (const auto& [name, s] : given) {
    if (!t.has(name)) t.fail("source", "source for '" + name + "' but no value");
    sources[name] = s;
  }
  t.finish();
  validated(t, [&] { m.validate(); });
}

void read_material_set(Tab& root, core::SceneMaterials& mats) {
  core::TissueMaterial* targets[] = {&mats.retina, &mats.gel, &mats.membrane};
  const char* names[] = {"retina", "gel", "membrane"};
  for (int i = 0; i < 3; ++i) {
    if (auto t = root.table(names[i])) read_material(*t, *targets[i], mats.sources[names[i]]);
  }
}

core::MembraneKind membrane_kind(Tab& t) {
  std::string s = "epiretinal";
  t.string("kind", s);
  if (s == "perpendicular") return core::MembraneKind::kPerpendicular;
  if (s == "circumferential") return core::MembraneKind::kCircumferential;
  if (s == "anteroposterior") return core::MembraneKind::kAnteroposterior;
  if (s == "epiretinal") return core::MembraneKind::kEpiretinal;
  t.fail("kind", "must be one of perpendicular, circumferential, anteroposterior, epiretinal (got '" + s + "')");
}

core::AttachmentStrength strength(Tab& t) {
  std::string s = "mixed";
  t.string("attachments", s);
  if (s == "weak") return core::AttachmentStrength::kWeak;
  if (s == "strong") return core::AttachmentStrength::kStrong;
  if (s == "mixed") return core::AttachmentStrength::kMixed;
  t.fail("attachments", "must be weak, strong or mixed (got '" + s + "')");
}

core::GuideKind guide_kind(Tab& t) {
  const std::string s = t.required_string("kind");
  if (s == "cut_path") return core::GuideKind::kCutPath;
  if (s == "laser_ring") return core::GuideKind::kLaserRing;
  if (s == "target") return core::GuideKind::kTarget;
  t.fail("kind", "must be cut_path, laser_ring or target (got '" + s + "')");
}

core::CriterionKind criterion_kind(Tab& t) {
  const std::string s = t.required_string("kind");
  using K = core::CriterionKind;
  for (K k : {K::kGelRemoved, K::kMembraneRemoved, K::kMembraneReleased, K::kMembraneFreed, K::kPathCut, K::kLaserCoverage, K::kDrained,
              K::kRetinaFlat, K::kTimeLimit, K::kTargetsReached}) {
    if (s == core::to_string(k)) return k;
  }
  t.fail("kind", "unknown criterion '" + s + "'");
}

}  // namespace

core::SceneDescription parse_scene(std::string_view text, const std::string& file) {
  return parse_scene(text, file, nullptr, nullptr);
}

core::SceneDescription parse_scene(std::string_view text, const std::string& file, const std::string* library_text,
                                   std::string* library_text_used) {
  const toml::table doc = parse_toml(text, file);
  Tab root(doc, "", file);
  core::SceneDescription d;
  d.source_file = file;
  d.materials = core::default_materials();

  if (!root.has("format_version")) root.fail("", "missing key 'format_version'");
  root.integer("format_version", d.format_version, 0, 1000000);
  if (d.format_version != core::kSceneFormatVersion) {
    root.fail("format_version", "version " + std::to_string(d.format_version) + " is not supported (this build reads " +
                                    std::to_string(core::kSceneFormatVersion) + ")");
  }
  d.name = root.required_string("name");
  if (d.name.empty()) root.fail("name", "must not be empty");
  root.string("title", d.title);
  root.string("summary", d.summary);
  root.string("category", d.category);
  if (d.category != "case" && d.category != "exercise") root.fail("category", "must be \"case\" or \"exercise\"");

  if (auto a = root.table("anatomy")) {
    auto& p = d.anatomy;
    const std::pair<const char*, double*> doubles[] = {
        {"axial_length_mm", &p.axial_length_mm},
        {"globe_diameter_mm", &p.globe_diameter_mm},
        {"sclera_thickness_mm", &p.sclera_thickness_mm},
        {"choroid_thickness_mm", &p.choroid_thickness_mm},
        {"retina_thickness_mm", &p.retina_thickness_mm},
        {"cornea_radius_mm", &p.cornea_radius_mm},
        {"cornea_diameter_mm", &p.cornea_diameter_mm},
        {"cornea_thickness_mm", &p.cornea_thickness_mm},
        {"pars_plicata_end_mm", &p.pars_plicata_end_mm},
        {"ora_serrata_mm", &p.ora_serrata_mm},
        {"ports_mm", &p.ports_mm},
        {"infusion_port_deg", &p.infusion_port_deg},
        {"working_port_1_deg", &p.working_port_1_deg},
        {"working_port_2_deg", &p.working_port_2_deg},
        {"optic_disc_offset_deg", &p.optic_disc_offset_deg},
        {"optic_disc_radius_mm", &p.optic_disc_radius_mm},
        {"fovea_radius_mm", &p.fovea_radius_mm},
        {"macula_radius_mm", &p.macula_radius_mm},
        {"anterior_chamber_depth_mm", &p.anterior_chamber_depth_mm},
        {"lens_diameter_mm", &p.lens_diameter_mm},
        {"lens_thickness_mm", &p.lens_thickness_mm},
        {"pupil_diameter_mm", &p.pupil_diameter_mm},
        {"iris_depth_mm", &p.iris_depth_mm},
        {"ciliary_process_height_mm", &p.ciliary_process_height_mm},
        {"gel_vertex_ratio", &p.gel_vertex_ratio},
        {"gel_shell_spacing_mm", &p.gel_shell_spacing_mm},
        {"vitreous_base_mm", &p.vitreous_base_mm},
    };
    for (const auto& [k, ptr] : doubles) a->number(k, *ptr);
    a->integer("ciliary_processes", p.ciliary_processes, 0, 120);
    a->integer("retina_vertices", p.retina_vertices, 500, 200000);
    a->integer("gel_shells", p.gel_shells, 0, 4);
    a->finish();
    validated(*a, [&] { p.validate(); });
  }
  if (auto t = root.table("textures")) {
    t->u64("seed", d.texture_seed);
    t->integer("size_px", d.texture_size_px, 64, 8192);
    t->finish();
  }
  if (auto t = root.table("environment")) {
    t->number("intraocular_pressure_mmhg", d.intraocular_pressure_mmhg);
    t->integer("substeps", d.substeps, 1, 64);
    t->finish();
    if (d.intraocular_pressure_mmhg < 0.0 || d.intraocular_pressure_mmhg > 80.0) {
      t->fail("intraocular_pressure_mmhg", "must be in [0, 80]");
    }
  }
  if (auto t = root.table("vitreous")) {
    t->number("adhesion_break_force_un", d.gel_adhesion_break_force_un);
    t->integer("adhesion_stride", d.gel_adhesion_stride, 1, 100);
    t->finish();
    if (!(d.gel_adhesion_break_force_un > 0.0)) t->fail("adhesion_break_force_un", "must be > 0");
  }
  if (auto m = root.table("materials")) {
    std::string library;
    m->string("library", library);
    if (!library.empty()) {
      const std::filesystem::path base = std::filesystem::path(file).parent_path();
      const std::string lib_path = (base / library).string();
      const std::string lib_text =
          library_text ? *library_text : read_file(lib_path, file, m->line("library"), m->key("library"));
      if (library_text_used) *library_text_used = lib_text;
      const toml::table lib = parse_toml(lib_text, lib_path);
      Tab lt(lib, "", lib_path);
      int version = 0;
      if (!lt.has("format_version")) lt.fail("", "missing key 'format_version'");
      lt.integer("format_version", version, 0, 1000000);
      if (version != core::kSceneFormatVersion) lt.fail("format_version", "unsupported materials library version");
      read_material_set(lt, d.materials);
      lt.finish();
    }
    read_material_set(*m, d.materials);
    m->finish();
  }
  if (auto t = root.table("instruments")) {
    d.instruments = t->strings("available");
    t->string("working_port", d.working_port);
    if (d.working_port != "working_1" && d.working_port != "working_2") t->fail("working_port", "expected \"working_1\" or \"working_2\"");
    t->string("second_hand", d.second_hand);
    const auto& holdable = core::second_hand_instruments();
    if (std::find(holdable.begin(), holdable.end(), d.second_hand) == holdable.end())
      t->fail("second_hand", "expected \"light_pipe\", \"forceps\", \"pick\" or \"scissors\"");
    t->finish();
    const auto& known = core::known_instruments();
    for (const auto& i : d.instruments) {
      if (std::find(known.begin(), known.end(), i) == known.end()) t->fail("available", "unknown instrument '" + i + "'");
    }
  }
  std::set<std::string> names;
  const auto unique_name = [&](Tab& t) {
    const std::string n = t.required_string("name");
    if (n.empty()) t.fail("name", "must not be empty");
    if (!names.insert(n).second) t.fail("name", "'" + n + "' is used twice");
    return n;
  };
  const auto check_item = [&](const Tab& t, auto fill) {
    core::SceneDescription probe;
    probe.name = "probe";
    fill(probe);
    validated(t, [&] { probe.validate(); });
  };
  for (auto& t : root.tables("detachment")) {
    core::DetachmentSpec s;
    s.name = unique_name(t);
    s.center = t.location("center");
    t.number("radius_deg", s.radius_deg);
    t.number("pressure_pa", s.pressure_pa);
    t.finish();
    check_item(t, [&](core::SceneDescription& p) { p.detachments = {s}; });
    d.detachments.push_back(s);
  }
  for (auto& t : root.tables("tear")) {
    core::TearSpec s;
    s.name = unique_name(t);
    s.center = t.location("center");
    t.number("width_mm", s.width_mm);
    t.number("length_mm", s.length_mm);
    t.number("lift_mm", s.lift_mm);
    t.finish();
    check_item(t, [&](core::SceneDescription& p) { p.tears = {s}; });
    d.tears.push_back(s);
  }
  for (auto& t : root.tables("membrane")) {
    core::MembraneSpec s;
    s.name = unique_name(t);
    s.kind = membrane_kind(t);
    s.center = t.location("center");
    t.number("size_mm", s.size_mm);
    t.number("width_mm", s.width_mm);
    t.number("height_mm", s.height_mm);
    t.number("rest_length_scale", s.rest_length_scale);
    s.strength = strength(t);
    t.number("strong_fraction", s.strong_fraction);
    t.number("attachment_spacing_mm", s.attachment_spacing_mm);
    t.number("weak_break_force_un", s.weak_break_force_un);
    t.number("strong_break_force_un", s.strong_break_force_un);
    t.number("detach_radius_mm", s.detach_radius_mm);
    t.number("elevation_mm", s.elevation_mm);
    t.finish();
    check_item(t, [&](core::SceneDescription& p) { p.membranes = {s}; });
    d.membranes.push_back(s);
  }
  std::vector<std::pair<int, std::string>> guide_lines;
  for (auto& t : root.tables("guide")) {
    core::GuideSpec s;
    s.name = unique_name(t);
    s.kind = guide_kind(t);
    for (auto& p : t.tables("points")) {
      core::FundusLocation l;
      Tab::read_location(p, l);
      s.points.push_back(l);
    }
    if (t.has("center")) s.center = t.location("center");
    t.number("radius_mm", s.radius_mm);
    t.string("around", s.around);
    t.finish();
    if (s.kind == core::GuideKind::kLaserRing && s.around.empty() && !t.has("center")) {
      t.fail("", "a laser_ring needs 'around' (a tear) or 'center'");
    }
    if (!s.around.empty() &&
        std::none_of(d.tears.begin(), d.tears.end(), [&](const auto& x) { return x.name == s.around; })) {
      t.fail("around", "no tear named '" + s.around + "'");
    }
    check_item(t, [&](core::SceneDescription& p) {
      p.tears = d.tears;
      p.guides = {s};
    });
    d.guides.push_back(s);
  }
  for (auto& t : root.tables("criterion")) {
    core::CriterionSpec s;
    s.kind = criterion_kind(t);
    t.string("target", s.target);
    if (!t.has("threshold")) t.fail("", "missing key 'threshold'");
    t.number("threshold", s.threshold);
    t.finish();
    check_item(t, [&](core::SceneDescription& p) {
      p.anatomy = d.anatomy;
      p.membranes = d.membranes;
      p.guides = d.guides;
      p.tears = d.tears;
      p.detachments = d.detachments;
      p.criteria = {s};
    });
    d.criteria.push_back(s);
  }
  if (auto t = root.table("view")) {
    if (t->has("region_of_interest")) d.view.region_of_interest = t->location("region_of_interest");
    std::string stain = core::to_string(d.view.gel_stain);
    t->string("gel_stain", stain);
    if (stain == "none") d.view.gel_stain = core::GelStain::kClear;
    else if (stain == "triamcinolone") d.view.gel_stain = core::GelStain::kTriamcinolone;
    else t->fail("gel_stain", "must be \"none\" or \"triamcinolone\"");
    t->boolean("wide_angle", d.view.wide_angle);
    t->boolean("chandelier", d.view.chandelier);
    t->finish();
    validated(*t, [&] {
      core::SceneDescription probe;
      probe.name = "probe";
      probe.anatomy = d.anatomy;
      probe.view = d.view;
      probe.validate();
    });
  }
  if (auto t = root.table("proficiency")) {
    t->number("pass_score", d.pass_score);
    t->finish();
    validated(*t, [&] {
      core::SceneDescription probe;
      probe.name = "probe";
      probe.pass_score = d.pass_score;
      probe.validate();
    });
  }
  if (auto t = root.table("settle")) {
    t->integer("max_steps", d.settle.max_steps, 0, 20000);
    t->integer("min_steps", d.settle.min_steps, 0, 20000);
    t->number("dt_s", d.settle.dt_s);
    t->number("damping_per_s", d.settle.damping_per_s);
    t->number("max_speed_mm_s", d.settle.max_speed_mm_s);
    t->finish();
    validated(*t, [&] {
      core::SceneDescription probe;
      probe.name = "probe";
      probe.settle = d.settle;
      probe.validate();
    });
  }
  root.finish();
  // The other hand's instrument needs the chandelier's light (two tables, one rule): said at the key.
  if (d.second_hand != "light_pipe") {
    if (auto t = root.table("instruments")) {
      if (!d.view.chandelier) t->fail("second_hand", "the other hand holds the " + d.second_hand + ", so no light pipe lights the cavity: set [view] chandelier = true");
      if (std::find(d.instruments.begin(), d.instruments.end(), "light_pipe") != d.instruments.end())
        t->fail("available", "'light_pipe' has no hand: the other hand holds the " + d.second_hand);
    }
  }
  validated(root, [&] { d.validate(); });
  return d;
}

core::SceneDescription load_scene_file(const std::string& path) {
  // read_file says which it is: no such file, a directory, a device, over 1 MiB.
  return parse_scene(read_file(path, path, 0, ""), path);
}

}  // namespace vitreo::scene_io
