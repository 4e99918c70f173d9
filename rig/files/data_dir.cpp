#include "rig/files/data_dir.hpp"

#include <filesystem>
#include <stdexcept>

// Set by rig/files/CMakeLists.txt: the installed data folder relative to the installed binaries
// (GNUInstallDirs: bin/ → ../share/vitreo), and the source tree's scenes/ for a build-tree binary.
#ifndef VITREO_BIN_TO_DATA_DIR
#error "VITREO_BIN_TO_DATA_DIR must be defined (rig/files/CMakeLists.txt)"
#endif
#ifndef VITREO_SOURCE_SCENES_DIR
#error "VITREO_SOURCE_SCENES_DIR must be defined (rig/files/CMakeLists.txt)"
#endif

namespace vitreo::files {

namespace fs = std::filesystem;

std::string installed_data_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec || exe.empty()) return {};
  const fs::path data = (exe.parent_path() / VITREO_BIN_TO_DATA_DIR).lexically_normal();
  return fs::is_directory(data, ec) ? data.string() : std::string();
}

std::string default_scenes_dir() {
  std::error_code ec;
  if (fs::is_directory("scenes", ec)) return "scenes";
  const std::string installed = installed_data_dir();
  if (!installed.empty() && fs::is_directory(fs::path(installed) / "scenes", ec)) return (fs::path(installed) / "scenes").string();
  if (fs::is_directory(VITREO_SOURCE_SCENES_DIR, ec)) return VITREO_SOURCE_SCENES_DIR;
  throw std::runtime_error(std::string("no case folder: not ./scenes, not the installed ") +
                           (installed.empty() ? "data (no share/vitreo beside this executable's bin/)" : installed + "/scenes") +
                           ", not the source tree's " + VITREO_SOURCE_SCENES_DIR + " (name one: --cases DIR or --case FILE)");
}

}  // namespace vitreo::files
