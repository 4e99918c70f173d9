// The only translation unit that includes FCL (~half a minute to compile: keep it that way).
#include "core/collision/collision_scene.hpp"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/ellipsoid.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "core/tissue/contact_geometry.hpp"

namespace vitreo::core {

namespace {

using Box3 = Eigen::AlignedBox3d;

struct Patch {
  std::uint32_t surface = 0;
  std::vector<std::uint32_t> triangles;
  std::vector<std::uint32_t> blocks;    // vertex sleep blocks its triangles use
  std::vector<std::uint32_t> vertices;  // its triangles' vertices, each once (for refits)
  Box3 fat;
  std::shared_ptr<fcl::Boxd> box;
  std::unique_ptr<fcl::CollisionObjectd> object;
};

bool patch_awake(const Surface& s, const Patch& p) {
  for (auto b : p.blocks) {
    if (s.block_awake(b)) return true;
  }
  return false;
}

Box3 tight_box(const Surface& s, const Patch& p) {
  Box3 box;
  box.setEmpty();
  for (auto v : p.vertices) {
    if (s.vertex_alive(v)) box.extend(s.position(v));
  }
  return box;
}

void collect_vertices(const Surface& s, Patch& p) {
  p.vertices.clear();
  for (auto t : p.triangles) {
    for (auto v : s.triangle_vertices(t)) p.vertices.push_back(v);
  }
  std::sort(p.vertices.begin(), p.vertices.end());
  p.vertices.erase(std::unique(p.vertices.begin(), p.vertices.end()), p.vertices.end());
}

Eigen::Matrix3d rotation_from_z(const Vec3& d) {
  const Vec3 z = d.normalized();
  return Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), z).toRotationMatrix();
}

fcl::Transform3d capsule_pose(const CapsuleShape& c) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  const Vec3 d = c.b - c.a;
  if (d.norm() > 0.0) tf.linear() = rotation_from_z(d);
  tf.translation() = 0.5 * (c.a + c.b);
  return tf;
}

// FCL's dynamic AABB tree calls back with (tree object, query object).
bool collect_patch(fcl::CollisionObjectd* patch, fcl::CollisionObjectd* /*query*/, void* data) {
  auto* hits = static_cast<std::vector<std::uint32_t>*>(data);
  if (hits->size() < hits->capacity()) hits->push_back(static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(patch->getUserData())));
  return false;  // keep going
}

}  // namespace

struct CollisionScene::Impl {
  // Per surface: which patch each triangle slot belongs to, so a topology change (a tear, a cut)
  // only moves the triangles whose slots changed instead of rebuilding everything.
  struct SurfaceIndex {
    std::uint64_t version = ~std::uint64_t{0};
    std::unordered_map<std::int64_t, std::uint32_t> cell_to_patch;
    std::vector<std::uint32_t> tri_patch;       // per slot, kNone when not assigned
    std::vector<std::uint32_t> tri_generation;  // generation of the slot when assigned
  };
  std::vector<Patch> patches;
  std::vector<SurfaceIndex> surfaces;
  std::unique_ptr<fcl::DynamicAABBTreeCollisionManagerd> manager;
  std::shared_ptr<fcl::Boxd> query_box;
  std::unique_ptr<fcl::CollisionObjectd> query;
  std::vector<std::uint32_t> hits;
  std::vector<std::uint32_t> collider_hits;  // patches per collider this step (flat)
  std::vector<std::uint64_t> refit_stamp, candidate_stamp;
  std::vector<fcl::CollisionObjectd*> changed;
  std::vector<std::uint32_t> dirty;  // patches whose triangle set changed
  std::vector<std::uint8_t> is_dirty;
  std::uint64_t steps = 0;
  double cell_mm = 1.5;
  double margin_mm = 0.4;

  std::uint32_t patch_for(std::uint32_t si, const Surface& s, std::uint32_t t) {
    const auto tv = s.triangle_vertices(t);
    const Vec3 c = (s.rest_position(tv[0]) + s.rest_position(tv[1]) + s.rest_position(tv[2])) / 3.0;
    auto cell = [&](double x) { return static_cast<std::int64_t>(std::floor(x / cell_mm)) & 0x1FFFFF; };
    const std::int64_t key = (cell(c.x()) << 42) | (cell(c.y()) << 21) | cell(c.z());
    auto [it, inserted] = surfaces[si].cell_to_patch.try_emplace(key, static_cast<std::uint32_t>(patches.size()));
    if (inserted) {
      patches.emplace_back();
      Patch& p = patches.back();
      p.surface = si;
      p.fat.setEmpty();
      p.box = std::make_shared<fcl::Boxd>(1.0, 1.0, 1.0);
      p.object = std::make_unique<fcl::CollisionObjectd>(p.box);
      p.object->setUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(patches.size() - 1)));
      is_dirty.push_back(0);
      refit_stamp.push_back(0);
      candidate_stamp.push_back(0);
    }
    return it->second;
  }

  void mark_dirty(std::uint32_t pi) {
    if (!is_dirty[pi]) {
      is_dirty[pi] = 1;
      dirty.push_back(pi);
    }
  }

  // Brings the patches of surface si up to date with its triangle slots.
  void sync(std::uint32_t si, const Surface& s) {
    SurfaceIndex& ix = surfaces[si];
    if (ix.version == s.topology_version()) return;
    ix.version = s.topology_version();
    if (ix.tri_patch.size() < s.triangle_slots()) {
      ix.tri_patch.resize(s.triangle_slots(), kNone);
      ix.tri_generation.resize(s.triangle_slots(), 0);
    }
    for (std::uint32_t t = 0; t < s.triangle_slots(); ++t) {
      const bool alive = s.triangle_alive(t);
      const std::uint32_t old = ix.tri_patch[t];
      if (alive && old != kNone && ix.tri_generation[t] == s.triangle_id(t).generation) continue;
      if (!alive && old == kNone) continue;
      if (old != kNone) {  // freed or reused slot: out of its old patch
        auto& list = patches[old].triangles;
        list.erase(std::find(list.begin(), list.end(), t));
        ix.tri_patch[t] = kNone;
        mark_dirty(old);
      }
      if (!alive) continue;
      const std::uint32_t pi = patch_for(si, s, t);
      Patch& p = patches[pi];
      p.triangles.push_back(t);
      for (auto v : s.triangle_vertices(t)) {
        const std::uint32_t b = v / Surface::kSleepBlock;
        if (std::find(p.blocks.begin(), p.blocks.end(), b) == p.blocks.end()) p.blocks.push_back(b);
      }
      ix.tri_patch[t] = pi;
      ix.tri_generation[t] = s.triangle_id(t).generation;
      mark_dirty(pi);
    }
  }

  // Refits the patches whose triangle sets changed; new patches join the broad phase.
  void refit_dirty(const TissueWorld& world) {
    for (auto pi : dirty) {
      is_dirty[pi] = 0;
      Patch& p = patches[pi];
      collect_vertices(world.surface(p.surface), p);
      const bool registered = !p.fat.isEmpty();
      Box3 tight = tight_box(world.surface(p.surface), p);
      if (tight.isEmpty()) tight = registered ? p.fat : Box3(Vec3::Zero(), Vec3::Zero());
      p.fat = tight;
      p.fat.min().array() -= margin_mm;
      p.fat.max().array() += margin_mm;
      p.box->side = p.fat.sizes();
      p.box->computeLocalAABB();
      p.object->setTranslation(p.fat.center());
      p.object->computeAABB();
      if (registered) {
        changed.push_back(p.object.get());
      } else {
        manager->registerObject(p.object.get());
      }
    }
    dirty.clear();
  }

  void build(const TissueWorld& world, const CollisionOptions& o) {
    cell_mm = o.patch_cell_mm;
    margin_mm = o.margin_mm;
    manager = std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>();
    surfaces.assign(world.surface_count(), {});
    for (std::uint32_t si = 0; si < world.surface_count(); ++si) sync(si, world.surface(si));
    refit_dirty(world);
    manager->setup();
    hits.reserve(2 * patches.size() + 1024);
    collider_hits.reserve(8 * patches.size() + 4096);
    changed.reserve(2 * patches.size() + 1024);
  }

  void refit(const Surface& s, Patch& p, double margin) {
    const Box3 tight = tight_box(s, p);
    if (tight.isEmpty() || p.fat.contains(tight)) return;
    p.fat = tight;
    p.fat.min().array() -= margin;
    p.fat.max().array() += margin;
    p.box->side = p.fat.sizes();
    p.box->computeLocalAABB();
    p.object->setTranslation(p.fat.center());
    p.object->computeAABB();
    changed.push_back(p.object.get());
  }

  // One tree update for all refit patches: FCL's single-object update rebalances the tree each call.
  void commit() {
    if (changed.empty()) return;
    manager->update(changed);
    changed.clear();
  }

  // Patches whose fat box overlaps `box` (FCL broad phase).
  void query_box_hits(const Box3& box) {
    hits.clear();
    query_box->side = box.sizes().cwiseMax(1e-6);
    query_box->computeLocalAABB();
    query->setTranslation(box.center());
    query->computeAABB();
    manager->collide(query.get(), &hits, collect_patch);
    std::sort(hits.begin(), hits.end());  // deterministic order
  }
};

CollisionScene::CollisionScene(const TissueWorld& world, CollisionOptions options, RigidAnatomy anatomy)
    : impl_(std::make_unique<Impl>()), options_(options), anatomy_(anatomy) {
  if (!(options_.patch_cell_mm > 0.0) || !(options_.margin_mm >= 0.0) || options_.far_refit_period == 0) {
    throw InvalidArgument("collision: patch_cell_mm > 0, margin_mm >= 0 and far_refit_period >= 1 required");
  }
  impl_->query_box = std::make_shared<fcl::Boxd>(1.0, 1.0, 1.0);
  impl_->query = std::make_unique<fcl::CollisionObjectd>(impl_->query_box);
  impl_->build(world, options_);
  stats_.patches = static_cast<std::uint32_t>(impl_->patches.size());
}

CollisionScene::~CollisionScene() = default;

void CollisionScene::update(const TissueWorld& world, std::span<const ColliderCapsule> colliders, std::vector<ContactCandidate>& out) {
  Impl& m = *impl_;
  out.clear();
  stats_ = {};
  if (world.surface_count() != m.surfaces.size()) {
    m.build(world, options_);  // a surface was added: start over (allocates)
  } else {
    // Tears and cuts since the last step: move only the triangles whose slots changed.
    for (std::uint32_t si = 0; si < world.surface_count(); ++si) m.sync(si, world.surface(si));
    m.refit_dirty(world);
    m.commit();
  }
  stats_.patches = static_cast<std::uint32_t>(m.patches.size());
  const std::uint64_t step = ++m.steps;

  // Each collider's sweep, cut into short pieces so that a long oblique shaft is bounded by a few
  // small boxes instead of one large one.
  constexpr double kChunk_mm = 1.5;
  constexpr double kSlack_mm = 0.1;  // tissue moves a little within the step
  const std::uint32_t n = static_cast<std::uint32_t>(std::min<std::size_t>(colliders.size(), TissueWorld::kMaxColliders));
  auto for_each_chunk = [&](const ColliderCapsule& c, double inflate, auto&& f) {
    const double len = std::max((c.b1 - c.a1).norm(), (c.b0 - c.a0).norm());
    const int pieces = std::clamp(static_cast<int>(std::ceil(len / kChunk_mm)), 1, 64);
    for (int k = 0; k < pieces; ++k) {
      const double s0 = static_cast<double>(k) / pieces, s1 = static_cast<double>(k + 1) / pieces;
      Box3 b(c.a0 + s0 * (c.b0 - c.a0));
      b.extend(c.a0 + s1 * (c.b0 - c.a0)).extend(c.a1 + s0 * (c.b1 - c.a1)).extend(c.a1 + s1 * (c.b1 - c.a1));
      b.min().array() -= c.radius_mm + inflate;
      b.max().array() += c.radius_mm + inflate;
      f(b);
    }
  };

  // Refit: awake patches near a sweep now; other awake patches round-robin (the fat margin covers
  // their motion in between); sleeping patches have not moved.
  auto refit_if_awake = [&](std::uint32_t pi) {
    if (m.refit_stamp[pi] == step) return;
    m.refit_stamp[pi] = step;
    Patch& p = m.patches[pi];
    const Surface& s = world.surface(p.surface);
    if (!patch_awake(s, p)) return;
    m.refit(s, p, options_.margin_mm);
    ++stats_.patches_refit;
  };
  // One broad-phase query per chunk: the patches it returns are refit (if awake) and later scanned
  // for candidates. Their fat boxes contain their triangles, so a patch missed by the inflated chunk
  // box has no triangle within reach of it.
  m.collider_hits.clear();
  std::array<std::uint32_t, TissueWorld::kMaxColliders + 1> begin{};
  const double inflate = std::max(options_.near_mm, kSlack_mm);
  for (std::uint32_t k = 0; k < n; ++k) {
    begin[k] = static_cast<std::uint32_t>(m.collider_hits.size());
    const std::uint64_t stamp = step * TissueWorld::kMaxColliders + k + 1;
    for_each_chunk(colliders[k], inflate, [&](const Box3& b) {
      m.query_box_hits(b);
      stats_.patches_hit += static_cast<std::uint32_t>(m.hits.size());
      for (auto pi : m.hits) {
        if (m.candidate_stamp[pi] == stamp) continue;
        m.candidate_stamp[pi] = stamp;
        refit_if_awake(pi);
        if (m.collider_hits.size() < m.collider_hits.capacity()) m.collider_hits.push_back(pi);
      }
    });
  }
  begin[n] = static_cast<std::uint32_t>(m.collider_hits.size());
  for (std::size_t i = step % options_.far_refit_period; i < m.patches.size(); i += options_.far_refit_period) {
    refit_if_awake(static_cast<std::uint32_t>(i));
  }
  m.commit();

  // Candidates: triangles of those patches whose bounding sphere comes within reach of the swept
  // axis.
  for (std::uint32_t k = 0; k < n; ++k) {
    const auto& c = colliders[k];
    const Vec3 motion_a = c.a1 - c.a0, motion_b = c.b1 - c.b0;
    const double motion = std::max(motion_a.norm(), motion_b.norm());
    for (std::uint32_t h = begin[k]; h < begin[k + 1]; ++h) {
      const Patch& p = m.patches[m.collider_hits[h]];
      if (p.surface < 32 && ((options_.pass_through_mask >> p.surface) & 1u) != 0) continue;
      {  // the patch's bounding sphere first
        double sp = 0.0, tq = 0.0;
        const Vec3 center = p.fat.center();
        const double d2 = contact::closest_segment_segment(c.a1, c.b1, center, center, sp, tq);
        const double reach = c.radius_mm + 0.5 * p.fat.diagonal().norm() + kSlack_mm + motion;
        if (d2 > reach * reach) continue;
      }
      const Surface& s = world.surface(p.surface);
      for (auto t : p.triangles) {
        if (!s.triangle_alive(t)) continue;
        const auto tv = s.triangle_vertices(t);
        const Vec3& x0 = s.position(tv[0]);
        const Vec3& x1 = s.position(tv[1]);
        const Vec3& x2 = s.position(tv[2]);
        const Vec3 centroid = (x0 + x1 + x2) / 3.0;
        const double tri_r = std::sqrt(std::max({(x0 - centroid).squaredNorm(), (x1 - centroid).squaredNorm(), (x2 - centroid).squaredNorm()}));
        double sp = 0.0, tq = 0.0;
        const double d2 = contact::closest_segment_segment(c.a1, c.b1, centroid, centroid, sp, tq);
        const double reach = c.radius_mm + tri_r + kSlack_mm + motion;
        if (d2 > reach * reach) continue;
        if (out.size() == out.capacity()) {
          stats_.candidates_truncated = true;
          continue;
        }
        // The side the instrument is on before the step (only used if it would cross the
        // triangle); a crossing, which the solver never leaves behind, falls back to the port
        // end, which is always on the entry side.
        const Vec3 normal = (x1 - x0).cross(x2 - x0);
        const auto st = contact::closest_segment_triangle(c.a0, c.b0, x0, x1, x2);
        const double side = st.crossing || st.distance < 1e-9 ? normal.dot(c.a0 - x0) : normal.dot(st.on_segment - st.on_triangle);
        out.push_back({k, p.surface, t, static_cast<std::int8_t>(side < 0.0 ? -1 : 1)});
      }
    }
  }
  stats_.candidates = static_cast<std::uint32_t>(out.size());
}

SurfacePoint CollisionScene::nearest_point(const TissueWorld& world, const Vec3& center, double radius, std::uint32_t mask) const {
  SurfacePoint best;
  best.distance = radius;
  Box3 box(center);
  box.min().array() -= radius;
  box.max().array() += radius;
  impl_->query_box_hits(box);
  for (auto pi : impl_->hits) {
    const Patch& p = impl_->patches[pi];
    if (p.surface < 32 && !(mask & (1u << p.surface))) continue;
    const Surface& s = world.surface(p.surface);
    for (auto t : p.triangles) {
      if (!s.triangle_alive(t)) continue;
      const auto tv = s.triangle_vertices(t);
      if (s.is_fixed(tv[0]) && s.is_fixed(tv[1]) && s.is_fixed(tv[2])) continue;  // anchored: cannot be taken
      Vec3 bary;
      const Vec3 q = contact::closest_on_triangle(center, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), bary);
      const double d = (q - center).norm();
      if (d <= best.distance) {
        best = {true, p.surface, t, bary, q, d};
      }
    }
  }
  return best;
}

RayHit CollisionScene::raycast(const TissueWorld& world, const Vec3& origin, const Vec3& direction, double max_t, std::uint32_t mask) const {
  RayHit best;
  best.t = max_t;
  const Vec3 d = direction.normalized();
  const Vec3 inv = d.cwiseInverse();
  for (const Patch& p : impl_->patches) {
    if (p.surface < 32 && !(mask & (1u << p.surface))) continue;
    // Slab test against the fat box.
    double t0 = 0.0, t1 = best.t;
    for (int a = 0; a < 3; ++a) {
      double ta = (p.fat.min()[a] - origin[a]) * inv[a];
      double tb = (p.fat.max()[a] - origin[a]) * inv[a];
      if (std::isnan(ta) || std::isnan(tb)) { ta = -std::numeric_limits<double>::infinity(); tb = -ta; }
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 > t1) continue;
    const Surface& s = world.surface(p.surface);
    for (auto t : p.triangles) {
      if (!s.triangle_alive(t)) continue;
      const auto tv = s.triangle_vertices(t);
      Vec3 bary;
      const double th = contact::ray_triangle(origin, d, s.position(tv[0]), s.position(tv[1]), s.position(tv[2]), bary);
      if (th >= 0.0 && th < best.t) {
        best = {true, p.surface, t, bary, origin + th * d, th};
      }
    }
  }
  return best;
}

void CollisionScene::wake_near(TissueWorld& world, const Vec3& center, double radius) const {
  Box3 box(center);
  box.min().array() -= radius;
  box.max().array() += radius;
  impl_->query_box_hits(box);
  const double r2 = radius * radius;
  for (auto pi : impl_->hits) {
    const Patch& p = impl_->patches[pi];
    Surface& s = world.surface(p.surface);
    for (auto t : p.triangles) {
      if (!s.triangle_alive(t)) continue;
      for (auto v : s.triangle_vertices(t)) {
        if (!s.vertex_awake(v) && (s.position(v) - center).squaredNorm() <= r2) s.wake_vertex(v);
      }
    }
  }
}

double CollisionScene::capsule_distance(const CapsuleShape& p, const CapsuleShape& q, Vec3* witness) const {
  const fcl::Capsuled cp(p.radius_mm, std::max((p.b - p.a).norm(), 1e-9));
  const fcl::Capsuled cq(q.radius_mm, std::max((q.b - q.a).norm(), 1e-9));
  fcl::DistanceRequestd request(true);
  fcl::DistanceResultd result;
  fcl::distance(&cp, capsule_pose(p), &cq, capsule_pose(q), request, result);
  double dist = result.min_distance;
  Vec3 w = 0.5 * (result.nearest_points[0] + result.nearest_points[1]);
  if (!(dist > 0.0)) {
    // Overlapping: FCL reports no depth for capsule pairs; the axes' distance gives it exactly.
    double s = 0, t = 0;
    const double d2 = contact::closest_segment_segment(p.a, p.b, q.a, q.b, s, t);
    dist = std::sqrt(d2) - p.radius_mm - q.radius_mm;
    w = 0.5 * ((p.a + s * (p.b - p.a)) + (q.a + t * (q.b - q.a)));
  }
  if (witness) *witness = w;
  return dist;
}

double CollisionScene::lens_distance(const CapsuleShape& c) const {
  if (!anatomy_.has_lens) return std::numeric_limits<double>::infinity();
  const fcl::Ellipsoidd lens(anatomy_.lens_semi_axes_mm);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = anatomy_.lens_center_mm;
  const fcl::Capsuled cap(c.radius_mm, std::max((c.b - c.a).norm(), 1e-9));
  fcl::DistanceRequestd request(false);
  fcl::DistanceResultd result;
  fcl::distance(&cap, capsule_pose(c), &lens, tf, request, result);
  return result.min_distance;
}

}  // namespace vitreo::core
