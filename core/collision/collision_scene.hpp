#pragma once
// Collision detection for the instruments, with FCL 0.7 kept behind this one small interface (one
// translation unit includes FCL: collision_scene.cpp).
//
// FCL's deformable-mesh path is too slow for a 1 kHz step (PLATFORM-NOTES: refitting a 20k-triangle
// BVH costs 1.4–56 ms, AABB mesh–shape collide copies the model, AABB–capsule distance is missing).
// So the tissue is split into many small spatial patches (triangles grouped by the cell of their rest
// centroid), each an FCL CollisionObject whose geometry is its fattened bounding box, all in one FCL
// dynamic-AABB-tree broad-phase manager. Each step only patches that can have moved (they hold an
// awake vertex) and lie near an instrument are refit at once; other awake patches are refit round-
// robin, which the fat margin covers; sleeping tissue does not move and costs nothing. The
// instruments' swept volumes query the manager; the triangles of the patches it returns become the
// contact candidates that the solver resolves exactly in every substep (core/tissue/
// stage_instruments.cpp). Rigid parts — instrument–instrument capsules and the lens — go through
// FCL's narrow phase directly.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/common/types.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

struct CapsuleShape {
  Vec3 a = Vec3::Zero();  // proximal end (toward the port)
  Vec3 b = Vec3::Zero();  // distal end (the tip)
  double radius_mm = 0.0;
};

// Rigid anatomy the instruments must not enter (besides the globe wall, which is exact in GlobeWall).
struct RigidAnatomy {
  bool has_lens = false;
  Vec3 lens_center_mm = Vec3::Zero();
  Vec3 lens_semi_axes_mm{4.5, 4.5, 2.0};  // axis-aligned ellipsoid (the crystalline lens)
  // The simulated retina is a surface laid on the globe wall, without thickness; a real one is
  // ~0.25 mm thick. An instrument reaches the wall (choroid, sclera) only after pressing this deep
  // into the retina — touching the retina to grasp a membrane on it is not a wall contact.
  double retina_thickness_mm = 0.0;
};

struct CollisionOptions {
  double patch_cell_mm = 1.5;     // edge of the rest-space cells that group triangles into patches
  double margin_mm = 0.4;         // fattening of patch boxes
  double near_mm = 0.5;           // patches this close to an instrument's sweep are refit every step
  // Other awake patches are refit every this many steps (round-robin): the margin must cover how far
  // tissue away from the instruments moves in that time (0.4 mm in 32 ms: up to 12 mm/s).
  std::uint32_t far_refit_period = 32;
  // Surfaces the instruments pass through (bit i: surface i): no contact candidates are made on
  // them. The vitreous gel's shells stand in for a gel volume that is 99 % water; a shaft moves
  // through it instead of pushing a sheet ahead of it (InstrumentSystem sets the gel's bit).
  std::uint32_t pass_through_mask = 0;
};

struct CollisionStats {
  std::uint32_t patches = 0;
  std::uint32_t patches_refit = 0;
  std::uint32_t patches_hit = 0;
  std::uint32_t candidates = 0;
  bool candidates_truncated = false;
};

struct RayHit {
  bool hit = false;
  std::uint32_t surface = 0;
  std::uint32_t triangle = 0;
  Vec3 bary = Vec3::Zero();
  Vec3 point = Vec3::Zero();
  double t = 0.0;  // distance along the (unit) ray
};

struct SurfacePoint {
  bool found = false;
  std::uint32_t surface = 0;
  std::uint32_t triangle = 0;
  Vec3 bary = Vec3::Zero();
  Vec3 point = Vec3::Zero();
  double distance = 0.0;
};

class CollisionScene {
 public:
  // Builds the patches of every surface of `world` (allocates; before the loop).
  CollisionScene(const TissueWorld& world, CollisionOptions options = {}, RigidAnatomy anatomy = {});
  ~CollisionScene();
  CollisionScene(const CollisionScene&) = delete;
  CollisionScene& operator=(const CollisionScene&) = delete;

  // Once per step, before TissueWorld::step: refits the patches that need it and collects the
  // triangles each collider's sweep (a0b0 → a1b1, radius) may touch, with the side each was on at
  // the start. `out` must have its capacity reserved; entries beyond it are dropped (stats say so).
  // After a topology change of a surface its patches are rebuilt (that call allocates).
  void update(const TissueWorld& world, std::span<const ColliderCapsule> colliders, std::vector<ContactCandidate>& out);
  const CollisionStats& stats() const { return stats_; }

  // The surface point nearest to `center` within `radius` (grasping); surfaces with mask bit unset
  // are skipped.
  SurfacePoint nearest_point(const TissueWorld& world, const Vec3& center, double radius, std::uint32_t surface_mask = ~0u) const;
  // The first hit of a ray (unit direction) on the deformed tissue within max_t.
  RayHit raycast(const TissueWorld& world, const Vec3& origin, const Vec3& direction, double max_t,
                 std::uint32_t surface_mask = ~0u) const;

  // Wakes the tissue within `radius` of `center` (the patches the broad phase finds there): cheap,
  // unlike a scan of every vertex.
  void wake_near(TissueWorld& world, const Vec3& center, double radius) const;

  // FCL narrow phase between two instrument capsules: distance between surfaces (negative: depth
  // of penetration); `witness` receives a point midway between the closest points.
  double capsule_distance(const CapsuleShape& p, const CapsuleShape& q, Vec3* witness = nullptr) const;
  // FCL narrow phase of a capsule against the lens (infinity without a lens; ≤ 0 when touching).
  double lens_distance(const CapsuleShape& c) const;
  const RigidAnatomy& anatomy() const { return anatomy_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  CollisionOptions options_;
  RigidAnatomy anatomy_;
  CollisionStats stats_;
};

}  // namespace vitreo::core
