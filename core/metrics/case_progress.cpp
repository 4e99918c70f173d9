#include "core/metrics/case_progress.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "core/common/validate.hpp"
#include "core/instruments/instrument_system.hpp"

namespace vitreo::core {

namespace {

double clamp01(double x) { return std::clamp(x, 0.0, 1.0); }

// Progress toward "value ≥ threshold" from 0.
double progress_up(double value, double threshold) { return threshold > 0.0 ? clamp01(value / threshold) : 1.0; }

// Progress toward "value ≤ threshold" from the value at the start.
double progress_down(double value, double start, double threshold) {
  if (value <= threshold || start <= threshold) return value <= threshold ? 1.0 : 0.0;
  return clamp01((start - value) / (start - threshold));
}

}  // namespace

double tangential_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  const Vec3 d = p - (a + t * ab);
  const double r = p.norm();
  if (!(r > 0.0)) return d.norm();
  const Vec3 n = p / r;
  return (d - d.dot(n) * n).norm();
}

MetricsCase MetricsCase::from_scene(const Scene& scene) {
  MetricsCase c;
  c.retina = scene.retina;
  c.gel = scene.gel;
  for (const auto& m : scene.membranes) c.membranes.push_back({m.name, m.surface, m.first_attachment, m.attachment_count});
  for (std::size_t i = 0; i < scene.description.detachments.size() && i < scene.detachment_forces.size(); ++i) {
    c.detachments.push_back({scene.description.detachments[i].name, scene.detachment_forces[i]});
  }
  c.guides = scene.guides;
  c.criteria = scene.description.criteria;
  return c;
}

void ProgressOptions::validate() const {
  require_range(path_tolerance_mm, 1e-4, 5.0, "metrics: path_tolerance_mm");
  require_range(sample_spacing_mm, 1e-3, 1.0, "metrics: sample_spacing_mm");
}

CaseProgress::CaseProgress(const TissueWorld& world, MetricsCase c, ProgressOptions options)
    : case_(std::move(c)), options_(options) {
  options_.validate();
  const std::uint32_t surfaces = world.surface_count();
  const auto need_surface = [&](std::uint32_t s, const std::string& what) {
    if (s == kNone || s >= surfaces) throw InvalidArgument("metrics: " + what + " is not a surface of the world");
  };
  if (case_.retina != kNone) need_surface(case_.retina, "the retina");
  if (case_.gel != kNone) need_surface(case_.gel, "the gel");
  for (const auto& m : case_.membranes) {
    need_surface(m.surface, "membrane '" + m.name + "'");
    if (m.first_attachment + m.attachment_count > world.attachment_count()) {
      throw InvalidArgument("metrics: membrane '" + m.name + "': attachments out of range");
    }
    membrane_area_start_.push_back(world.surface(m.surface).total_rest_area());
    // membrane_freed's work space, with room for the vertices cuts add (no allocation while measuring)
    const std::size_t room = 2 * static_cast<std::size_t>(world.surface(m.surface).vertex_slots());
    piece_parent_.reserve(std::max(piece_parent_.capacity(), room));
    piece_held_.reserve(std::max(piece_held_.capacity(), room));
  }
  for (const auto& d : case_.detachments) {
    if (d.local_force >= world.local_force_count()) throw InvalidArgument("metrics: detachment '" + d.name + "': no such local force");
  }

  const auto find = [&](const auto& items, const std::string& name, const char* what) {
    for (std::uint32_t i = 0; i < items.size(); ++i) {
      if (items[i].name == name) return i;
    }
    throw InvalidArgument(std::string("metrics: no ") + what + " named '" + name + "'");
  };
  for (const auto& spec : case_.criteria) {
    CriterionProgress p;
    p.kind = spec.kind;
    p.target = spec.target;
    p.threshold = spec.threshold;
    if (!std::isfinite(spec.threshold)) throw InvalidArgument(std::string("metrics: criterion ") + to_string(spec.kind) + ": threshold");
    std::uint32_t item = 0;
    double start = 0.0;
    switch (spec.kind) {
      case CriterionKind::kGelRemoved:
        if (case_.gel == kNone) throw InvalidArgument("metrics: gel_removed needs a gel");
        if (!spec.target.empty() && spec.target != "core") throw InvalidArgument("metrics: gel_removed's target is \"core\" or none");
        break;
      case CriterionKind::kMembraneRemoved:
      case CriterionKind::kMembraneReleased:
      case CriterionKind::kMembraneFreed: item = find(case_.membranes, spec.target, "membrane"); break;
      case CriterionKind::kPathCut:
      case CriterionKind::kLaserCoverage: {
        const std::uint32_t g = find(case_.guides, spec.target, "guide");
        const Guide& guide = case_.guides[g];
        const bool laser = spec.kind == CriterionKind::kLaserCoverage;
        if (laser != (guide.kind == GuideKind::kLaserRing)) {
          throw InvalidArgument("metrics: guide '" + guide.name + "' is the wrong kind for " + to_string(spec.kind));
        }
        if (case_.retina == kNone) throw InvalidArgument(std::string("metrics: ") + to_string(spec.kind) + " needs the retina");
        if (guide.polyline_mm.size() < 2) throw InvalidArgument("metrics: guide '" + guide.name + "' has no line");
        GuideSamples s;
        s.guide = g;
        // Midpoints of equal pieces of each segment, each standing for its piece's arc length.
        for (std::size_t k = 0; k + 1 < guide.polyline_mm.size(); ++k) {
          const Vec3 a = guide.polyline_mm[k], b = guide.polyline_mm[k + 1];
          const double len = (b - a).norm();
          const int n = std::max(1, static_cast<int>(std::ceil(len / options_.sample_spacing_mm)));
          for (int j = 0; j < n; ++j) {
            s.points.push_back(a + (b - a) * ((j + 0.5) / n));
            s.weights.push_back(len / n);
          }
        }
        s.covered.assign(s.points.size(), 0);
        item = static_cast<std::uint32_t>(samples_.size());
        samples_.push_back(std::move(s));
        break;
      }
      case CriterionKind::kTargetsReached: {
        const std::uint32_t g = find(case_.guides, spec.target, "guide");
        const Guide& guide = case_.guides[g];
        if (guide.kind != GuideKind::kTarget) throw InvalidArgument("metrics: guide '" + guide.name + "' is the wrong kind for targets_reached");
        if (guide.polyline_mm.empty()) throw InvalidArgument("metrics: guide '" + guide.name + "' has no targets");
        GuideSamples s;
        s.guide = g;
        s.points = guide.polyline_mm;  // the targets themselves, in order
        s.weights.assign(s.points.size(), 1.0);
        s.covered.assign(s.points.size(), 0);
        item = static_cast<std::uint32_t>(samples_.size());
        target_samples_.push_back(item);
        samples_.push_back(std::move(s));
        break;
      }
      case CriterionKind::kDrained:
        item = find(case_.detachments, spec.target, "detachment");
        start = world.local_force_scale(case_.detachments[item].local_force);
        break;
      case CriterionKind::kRetinaFlat:
        if (case_.retina == kNone) throw InvalidArgument("metrics: retina_flat needs the retina");
        break;
      case CriterionKind::kTimeLimit:
        if (!(spec.threshold > 0.0)) throw InvalidArgument("metrics: time_limit must be positive");
        break;
    }
    criteria_.push_back(std::move(p));
    item_.push_back(item);
    scale_start_.push_back(start);
  }

  if (case_.gel != kNone) gel_start_ = gel_area(world);
  // Membrane pieces that no attachment holds at the start (islands of a coarse mesh) are not the
  // surgeon's work: membrane_freed counts from what was free then.
  membrane_free_start_.assign(case_.membranes.size(), 0.0);
  for (std::uint32_t m = 0; m < case_.membranes.size(); ++m) membrane_free_start_[m] = membrane_freed(world, m);
  if (case_.retina != kNone) {
    lift_start_mm_ = retina_lift_mm(world);
    const Surface& r = world.surface(case_.retina);
    boundary_start_.assign(r.edge_slots(), kNone);
    for (std::uint32_t e = 0; e < r.edge_slots(); ++e) {
      if (!r.edge_alive(e)) continue;
      const auto t = r.edge_triangles(e);
      if (t[0] != kNone && t[1] == kNone) boundary_start_[e] = r.edge_id(e).generation;
    }
  }
  evaluate(world, nullptr, 0.0);
}

double CaseProgress::retina_lift_mm(const TissueWorld& world) const {
  // The same measure as max_retina_lift_mm (scene_builder.hpp), on the world alone.
  const Surface& rs = world.surface(case_.retina);
  double lift = 0.0;
  for (std::uint32_t v = 0; v < rs.vertex_slots(); ++v) {
    if (rs.vertex_alive(v)) lift = std::max(lift, world.wall().clearance(rs.position(v)));
  }
  return lift;
}

double CaseProgress::membrane_released(const TissueWorld& world, std::uint32_t m) const {
  const MetricsCase::Membrane& mb = case_.membranes[m];
  if (mb.attachment_count == 0) return 1.0;
  std::uint32_t released = 0;
  for (std::uint32_t a = mb.first_attachment; a < mb.first_attachment + mb.attachment_count; ++a) {
    if (!world.attachment_holds(a)) ++released;
  }
  return static_cast<double>(released) / mb.attachment_count;
}

double CaseProgress::membrane_freed(const TissueWorld& world, std::uint32_t m) const {
  // Pieces of the membrane: vertices joined through live triangles (union–find). A piece is held
  // when one of its vertices carries an attachment that holds; the rest is free — peeled off and
  // cut loose, or removed (no longer there at all).
  const MetricsCase::Membrane& mb = case_.membranes[m];
  const Surface& s = world.surface(mb.surface);
  const double start = membrane_area_start_[m];
  if (!(start > 0.0)) return 0.0;
  std::vector<std::uint32_t>& parent = piece_parent_;
  parent.resize(s.vertex_slots());  // grows only when cuts add vertices
  for (std::uint32_t v = 0; v < s.vertex_slots(); ++v) parent[v] = v;
  const auto root = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (!s.triangle_alive(t)) continue;
    const auto tv = s.triangle_vertices(t);
    const std::uint32_t r0 = root(tv[0]);
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t r = root(tv[static_cast<std::size_t>(k)]);
      if (r != r0) parent[r] = r0;
    }
  }
  std::vector<std::uint8_t>& held = piece_held_;
  held.assign(s.vertex_slots(), 0);
  for (std::uint32_t a = mb.first_attachment; a < mb.first_attachment + mb.attachment_count; ++a) {
    if (!world.attachment_holds(a)) continue;
    const std::uint32_t v = world.attachment_vertex_a(a);
    if (v < s.vertex_slots()) held[root(v)] = 1;
  }
  double held_area = 0.0;
  for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
    if (s.triangle_alive(t) && held[root(s.triangle_vertices(t)[0])]) held_area += s.triangle_rest_area(t);
  }
  const double freed = std::clamp(1.0 - held_area / start, 0.0, 1.0);
  if (m >= membrane_free_start_.size()) return freed;  // measuring the start itself
  const double before = membrane_free_start_[m];
  return before < 1.0 ? std::clamp((freed - before) / (1.0 - before), 0.0, 1.0) : 1.0;
}

double CaseProgress::path_cut_fraction(const TissueWorld& world, GuideSamples& g) const {
  // A cut leaves boundary springs (one triangle) along it; those that were not boundary at the
  // start (the ora serrata, tears cut by the scene) are new. Springs split later are new too.
  std::fill(g.covered.begin(), g.covered.end(), 0);
  const Surface& r = world.surface(case_.retina);
  const double tol = options_.path_tolerance_mm;
  for (std::uint32_t e = 0; e < r.edge_slots(); ++e) {
    if (!r.edge_alive(e) || r.edge_is_line(e)) continue;
    const auto t = r.edge_triangles(e);
    if (t[0] == kNone || t[1] != kNone) continue;
    if (e < boundary_start_.size() && boundary_start_[e] == r.edge_id(e).generation) continue;
    const auto ends = r.edge_vertices(e);
    const Vec3& a = r.position(ends[0]);
    const Vec3& b = r.position(ends[1]);
    const Vec3 mid = 0.5 * (a + b);
    const double reach = 0.5 * (b - a).norm() + tol + 1.0;  // cheap reject: the radial offset is < 1 mm
    for (std::size_t k = 0; k < g.points.size(); ++k) {
      if (g.covered[k] || (g.points[k] - mid).squaredNorm() > reach * reach) continue;
      if (tangential_distance(g.points[k], a, b) <= tol) g.covered[k] = 1;
    }
  }
  double covered = 0.0, total = 0.0;
  for (std::size_t k = 0; k < g.points.size(); ++k) {
    total += g.weights[k];
    if (g.covered[k]) covered += g.weights[k];
  }
  return total > 0.0 ? covered / total : 0.0;
}

void CaseProgress::observe_tip(const TissueWorld& world, const Vec3& tip_mm) {
  for (const std::uint32_t i : target_samples_) {
    GuideSamples& g = samples_[i];
    const auto next = static_cast<std::size_t>(std::find(g.covered.begin(), g.covered.end(), 0) - g.covered.begin());
    if (next == g.points.size()) continue;
    const Vec3& target = g.points[next];
    // Height above the wall along the direction from the globe's centre (the target lies on it).
    const Vec3 c = world.wall().center();
    const Vec3 dir = (tip_mm - c).normalized();
    const double height = world.wall().radius_toward(dir) - (tip_mm - c).norm();
    if (tangential_distance(tip_mm, target, target) <= options_.target_reach_mm && height <= options_.target_hover_mm) g.covered[next] = 1;
  }
}

double CaseProgress::reached_fraction(const GuideSamples& g) {
  std::size_t n = 0;
  while (n < g.covered.size() && g.covered[n]) ++n;
  return g.covered.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(g.covered.size());
}

double CaseProgress::laser_fraction(const TissueWorld& world, const InstrumentSystem* instruments, GuideSamples& g) const {
  (void)world;
  std::fill(g.covered.begin(), g.covered.end(), 0);
  if (instruments) {
    for (const BurnSpot& b : instruments->burns()) {
      // Only a burn that made a scar seals the retina (a burn on detached retina does not).
      if (!b.adhered || b.surface != case_.retina) continue;
      const Vec3 at = instruments->burn_position(b);
      const double r = 0.5 * b.diameter_mm;
      for (std::size_t k = 0; k < g.points.size(); ++k) {
        if (!g.covered[k] && tangential_distance(g.points[k], at, at) <= r) g.covered[k] = 1;
      }
    }
  }
  double covered = 0.0, total = 0.0;
  for (std::size_t k = 0; k < g.points.size(); ++k) {
    total += g.weights[k];
    if (g.covered[k]) covered += g.weights[k];
  }
  return total > 0.0 ? covered / total : 0.0;
}

void CaseProgress::evaluate(const TissueWorld& world, const InstrumentSystem* instruments, double elapsed_s) {
  for (std::size_t i = 0; i < criteria_.size(); ++i) {
    CriterionProgress& p = criteria_[i];
    const std::uint32_t item = item_[i];
    switch (p.kind) {
      case CriterionKind::kGelRemoved: {
        const GelArea now = gel_area(world);
        const bool core = p.target == "core";
        const double start = core ? gel_start_.core_mm2 : gel_start_.all_mm2;
        p.value = start > 0.0 ? std::clamp(1.0 - (core ? now.core_mm2 : now.all_mm2) / start, 0.0, 1.0) : 0.0;
        break;
      }
      case CriterionKind::kMembraneRemoved: {
        const double start = membrane_area_start_[item];
        const double now = world.surface(case_.membranes[item].surface).total_rest_area();
        p.value = start > 0.0 ? std::clamp(1.0 - now / start, 0.0, 1.0) : 0.0;
        break;
      }
      case CriterionKind::kMembraneReleased: p.value = membrane_released(world, item); break;
      case CriterionKind::kMembraneFreed: p.value = membrane_freed(world, item); break;
      case CriterionKind::kPathCut: p.value = path_cut_fraction(world, samples_[item]); break;
      case CriterionKind::kLaserCoverage: p.value = laser_fraction(world, instruments, samples_[item]); break;
      case CriterionKind::kDrained: p.value = world.local_force_scale(case_.detachments[item].local_force); break;
      case CriterionKind::kRetinaFlat: p.value = retina_lift_mm(world); break;
      case CriterionKind::kTimeLimit: p.value = elapsed_s; break;
      case CriterionKind::kTargetsReached: p.value = reached_fraction(samples_[item]); break;
    }
    switch (p.kind) {
      case CriterionKind::kDrained:
        p.met = p.value <= p.threshold;
        p.progress = progress_down(p.value, scale_start_[i], p.threshold);
        break;
      case CriterionKind::kRetinaFlat:
        p.met = p.value <= p.threshold;
        p.progress = progress_down(p.value, lift_start_mm_, p.threshold);
        break;
      case CriterionKind::kTimeLimit:
        p.met = p.value <= p.threshold;
        p.progress = clamp01(1.0 - p.value / p.threshold);
        break;
      default:
        p.met = p.value >= p.threshold;
        p.progress = progress_up(p.value, p.threshold);
        break;
    }
  }
}

CaseProgress::GelArea CaseProgress::gel_area(const TissueWorld& world) const {
  // By rest area, not by vertices: the vitrector's clipping inserts vertices and its aspiration takes
  // whole triangles, and a count of vertices would depend on the mesh's resolution. Where a piece of
  // gel lies is judged at rest (its place in the eye before anything pulled it), so gel drawn toward
  // the port does not change sides. Recomputed only when the gel's topology changed.
  const Surface& g = world.surface(case_.gel);
  if (g.topology_version() == gel_now_version_) return gel_now_;
  GelArea a;
  for (std::uint32_t t = 0; t < g.triangle_slots(); ++t) {
    if (!g.triangle_alive(t)) continue;
    const auto tv = g.triangle_vertices(t);
    const Vec3 centroid = (g.rest_position(tv[0]) + g.rest_position(tv[1]) + g.rest_position(tv[2])) / 3.0;
    const double area = g.triangle_rest_area(t);
    a.all_mm2 += area;
    const bool central = world.wall().clearance(centroid) > kCoreGelDepth_mm && centroid.z() < world.wall().center().z();
    if (central) a.core_mm2 += area;
  }
  gel_now_ = a;
  gel_now_version_ = g.topology_version();
  return a;
}

TissueProgress CaseProgress::tissue(const TissueWorld& world) const {
  TissueProgress t;
  if (case_.gel != kNone) {
    t.gel_area_initial_mm2 = gel_start_.all_mm2;
    t.gel_area_removed_mm2 = std::max(0.0, gel_start_.all_mm2 - gel_area(world).all_mm2);
  }
  for (std::size_t m = 0; m < case_.membranes.size(); ++m) {
    const MetricsCase::Membrane& mb = case_.membranes[m];
    t.membrane_area_initial_mm2 += membrane_area_start_[m];
    t.membrane_area_removed_mm2 += std::max(0.0, membrane_area_start_[m] - world.surface(mb.surface).total_rest_area());
    t.membrane_attachments += mb.attachment_count;
    for (std::uint32_t a = mb.first_attachment; a < mb.first_attachment + mb.attachment_count; ++a) {
      if (!world.attachment_holds(a)) ++t.membrane_attachments_released;
    }
  }
  return t;
}

double CaseProgress::distance_to_laser_ring(const Vec3& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const Guide& g : case_.guides) {
    if (g.kind != GuideKind::kLaserRing) continue;
    for (std::size_t k = 0; k + 1 < g.polyline_mm.size(); ++k) {
      best = std::min(best, tangential_distance(p, g.polyline_mm[k], g.polyline_mm[k + 1]));
    }
  }
  return best;
}

}  // namespace vitreo::core
