#include "rig/scene_io/case_loader.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/scene/snapshot.hpp"
#include "core/tissue/tissue_world.hpp"
#include "rig/files/read_text_file.hpp"
#include "rig/scene_io/scene_file.hpp"

namespace vitreo::scene_io {

namespace {

// Bump when the builder changes what a description builds into (or settles into: 2, the solver's
// tears clean up after themselves, core/topology/clean_topology.hpp; 3, the perpendicular traction
// plane contracts along its height only; 4, attachments scale with the area they stand for).
constexpr int kBuilderVersion = 5;


std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 0xcbf29ce484222325ULL) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace

CaseText read_case_text(const std::string& path) {
  // A regular file of at most 1 MiB: not a directory ("no such scene file" was wrong for one), not
  // a device or a FIFO, not 100 MB that would be carried into every recording.
  files::TextFile f = files::read_text_file(path);
  if (!f.text) throw SceneError(path, 0, "", f.error);
  CaseText c;
  c.file_name = path;
  c.text = std::move(*f.text);
  // Parsing reads the library the case names (relative to it) and tells us its text.
  (void)parse_scene(c.text, path, nullptr, &c.library_text);
  return c;
}

core::SceneDescription case_description(const CaseText& text, const CaseLoadOptions& options) {
  core::SceneDescription d =
      parse_scene(text.text, text.file_name, text.library_text.empty() ? nullptr : &text.library_text);
  if (options.retina_vertices > 0) d.anatomy.retina_vertices = options.retina_vertices;
  if (options.texture_size_px > 0) d.texture_size_px = options.texture_size_px;
  d.validate();
  return d;
}

std::string case_cache_key(const CaseText& text, const CaseLoadOptions& options) {
  const core::SceneDescription d = case_description(text, options);
  std::uint64_t h = fnv1a(text.text);
  h = fnv1a(text.library_text, h);
  h = fnv1a(std::to_string(kBuilderVersion) + "/" + std::to_string(core::kSnapshotVersion) + "/" +
                std::to_string(core::kSceneFormatVersion) + "/" + std::to_string(core::kSolverRevision) + "/" +
                std::to_string(options.retina_vertices),
            h);
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return d.name + "-" + buf;
}

std::string case_cache_key(const std::string& path) { return case_cache_key(read_case_text(path)); }

LoadedCase load_case(const std::string& path, const CaseLoadOptions& options) {
  return load_case(read_case_text(path), options);
}

LoadedCase load_case(const CaseText& text, const CaseLoadOptions& options) {
  const core::SceneDescription d = case_description(text, options);
  core::BuildOptions build;
  build.textures = options.textures;
  if (options.cache_dir.empty()) return LoadedCase{core::build_scene(d, build), false, ""};

  const std::string file = (std::filesystem::path(options.cache_dir) / (case_cache_key(text, options) + ".snap")).string();
  std::error_code ec;
  if (std::filesystem::is_regular_file(file, ec)) {
    build.settle = false;
    LoadedCase c{core::build_scene(d, build), true, file};
    core::SnapshotInfo info;
    if (core::load_snapshot(c.scene.world, file, &info).is_ok() && info.scene_name == d.name) {
      c.scene.settle.settled = true;
      return c;
    }
  }
  build.settle = true;
  LoadedCase c{core::build_scene(d, build), false, file};
  std::filesystem::create_directories(options.cache_dir, ec);
  if (!core::save_snapshot(c.scene.world, d.name, file).is_ok()) c.cache_file.clear();
  return c;
}

}  // namespace vitreo::scene_io
