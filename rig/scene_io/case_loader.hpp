#pragma once
// Loading a case the way the rig does: parse the scene file, build it, and start from its settled
// equilibrium — from a stored snapshot when one matches (fast), else by settling and storing one.
//
//   auto c = vitreo::scene_io::load_case("scenes/rhegmatogenous_u_tear.toml", {.cache_dir = "/var/cache/vitreo"});
//   c.scene.world.step(0.001);  ...  c.scene.eye.static_meshes, c.scene.textures
//
// The cache key is a hash of the scene file, its materials library and the builder/snapshot
// versions, so an edited case never starts from a stale equilibrium.
#include <string>

#include "core/scene/scene_builder.hpp"

namespace vitreo::scene_io {

struct CaseLoadOptions {
  std::string cache_dir;  // empty: always settle, store nothing
  bool textures = true;
};

struct LoadedCase {
  core::Scene scene;
  bool from_cache = false;
  std::string cache_file;  // the snapshot used or written ("" without a cache)
};

// Throws SceneError for a bad file, core::InvalidArgument when it cannot be built. A cache that
// cannot be read or written is ignored (the case is settled instead).
LoadedCase load_case(const std::string& path, const CaseLoadOptions& options = {});

// The cache key of a scene file (hex), as used in the snapshot name.
std::string case_cache_key(const std::string& path);

}  // namespace vitreo::scene_io
