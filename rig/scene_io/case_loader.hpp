#pragma once
// Loading a case the way the rig does: parse the scene file, build it, and start from its settled
// equilibrium — from a stored snapshot when one matches (fast), else by settling and storing one.
//
//   auto c = vitreo::scene_io::load_case("scenes/rhegmatogenous_u_tear.toml", {.cache_dir = "/var/cache/vitreo"});
//   c.scene.world.step(0.001);  ...  c.scene.eye.static_meshes, c.scene.textures
//
// The cache key is a hash of the scene file, its materials library, the resolution overrides and
// the builder/snapshot versions, so an edited case never starts from a stale equilibrium.
//
// A case can also be loaded from its text (CaseText: the file's and its library's contents), which
// is how a recording rebuilds the case it was made on even after scenes/ has changed.
#include <string>

#include "core/scene/scene_builder.hpp"

namespace vitreo::scene_io {

struct CaseLoadOptions {
  std::string cache_dir;  // empty: always settle, store nothing
  bool textures = true;
  // Overrides of the case's own resolution (0 = the case's): a lighter retina for a machine that
  // cannot step the full one at 1 kHz, small textures for tests.
  int retina_vertices = 0;
  int texture_size_px = 0;
  // Threads of the tissue step's worker pool (core::TissueWorld::set_worker_threads, 1..64). Not
  // recorded: the state is the same bit for bit at any count, so a replay may use another.
  unsigned physics_threads = 1;
};

// A case file as text: enough to rebuild it anywhere.
struct CaseText {
  std::string file_name;     // for messages (and the library's directory when library_text is unset)
  std::string text;          // the scene file
  std::string library_text;  // its materials library ("" when the case names none)
};

// Reads a scene file and its library; throws SceneError for a missing or bad file.
CaseText read_case_text(const std::string& path);

struct LoadedCase {
  core::Scene scene;
  bool from_cache = false;
  std::string cache_file;  // the snapshot used or written ("" without a cache)
};

// Throws SceneError for a bad file, core::InvalidArgument when it cannot be built. A cache that
// cannot be read or written is ignored (the case is settled instead).
LoadedCase load_case(const std::string& path, const CaseLoadOptions& options = {});
LoadedCase load_case(const CaseText& text, const CaseLoadOptions& options = {});

// The parsed description with the options' overrides applied (what load_case builds).
core::SceneDescription case_description(const CaseText& text, const CaseLoadOptions& options = {});

// The cache key of a scene file (hex), as used in the snapshot name.
std::string case_cache_key(const std::string& path);
std::string case_cache_key(const CaseText& text, const CaseLoadOptions& options = {});

}  // namespace vitreo::scene_io
