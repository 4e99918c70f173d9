#include "rig/scene_io/case_loader.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/scene/snapshot.hpp"
#include "rig/scene_io/scene_file.hpp"

namespace vitreo::scene_io {

namespace {

// Bump when the builder changes what a description builds into.
constexpr int kBuilderVersion = 1;

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 0xcbf29ce484222325ULL) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace

std::string case_cache_key(const std::string& path) {
  const core::SceneDescription d = load_scene_file(path);
  std::uint64_t h = fnv1a(slurp(path));
  const auto lib = std::filesystem::path(path).parent_path() / "materials.toml";
  std::error_code ec;
  if (std::filesystem::is_regular_file(lib, ec)) h = fnv1a(slurp(lib.string()), h);
  h = fnv1a(std::to_string(kBuilderVersion) + "/" + std::to_string(core::kSnapshotVersion) + "/" +
                std::to_string(core::kSceneFormatVersion),
            h);
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return d.name + "-" + buf;
}

LoadedCase load_case(const std::string& path, const CaseLoadOptions& options) {
  const core::SceneDescription d = load_scene_file(path);
  core::BuildOptions build;
  build.textures = options.textures;
  if (options.cache_dir.empty()) return LoadedCase{core::build_scene(d, build), false, ""};

  const std::string file = (std::filesystem::path(options.cache_dir) / (case_cache_key(path) + ".snap")).string();
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
