// Where the tools look for cases when none are named (rig/files/data_dir.hpp). The installed
// layout (PREFIX/bin → PREFIX/share/vitreo) is checked on a real install by
// tests/install/installed_vitreo_test.sh; here the two cases a build tree meets.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "rig/files/data_dir.hpp"

namespace fs = std::filesystem;

namespace {
// Runs the test body from another working folder and comes back.
class InFolder {
 public:
  explicit InFolder(const fs::path& p) : back_(fs::current_path()) { fs::current_path(p); }
  ~InFolder() { fs::current_path(back_); }
  InFolder(const InFolder&) = delete;
  InFolder& operator=(const InFolder&) = delete;

 private:
  fs::path back_;
};

fs::path fresh_folder(const char* name) {
  const fs::path p = fs::temp_directory_path() / (std::string(name) + "-" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
}  // namespace

TEST(DataDir, AScenesFolderInTheWorkingFolderComesFirst) {
  const fs::path dir = fresh_folder("vitreo-data-dir-cwd");
  fs::create_directory(dir / "scenes");
  {
    InFolder in(dir);
    EXPECT_EQ(vitreo::files::default_scenes_dir(), "scenes");
  }
  fs::remove_all(dir);
}

TEST(DataDir, ABuildTreeBinaryElsewhereUsesItsSourceTreesCases) {
  const fs::path dir = fresh_folder("vitreo-data-dir-elsewhere");
  {
    InFolder in(dir);
    EXPECT_EQ(vitreo::files::installed_data_dir(), "") << "a build tree has no share/vitreo beside its bin/";
    EXPECT_EQ(fs::path(vitreo::files::default_scenes_dir()), fs::path(VITREO_SOURCE_DIR) / "scenes");
  }
  fs::remove_all(dir);
}
