// read_text_file: a regular file up to a stated size, or a one-line reason — never a block on a
// FIFO, never gigabytes from a device.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "rig/files/read_text_file.hpp"

namespace fs = std::filesystem;
using vitreo::files::read_text_file;

TEST(ReadTextFile, ReadsARegularFileWhole) {
  const fs::path p = fs::path(::testing::TempDir()) / ("vitreo-read-" + std::to_string(::getpid()) + ".txt");
  {
    std::ofstream f(p, std::ios::binary);
    f << std::string("a\0b\nc", 5);
  }
  const auto r = read_text_file(p.string());
  ASSERT_TRUE(r.text.has_value()) << r.error;
  EXPECT_EQ(*r.text, std::string("a\0b\nc", 5));
  EXPECT_TRUE(r.error.empty());
  const auto small = read_text_file(p.string(), 4);
  EXPECT_FALSE(small.text.has_value());
  EXPECT_NE(small.error.find("larger than 4 bytes"), std::string::npos) << small.error;
  fs::remove(p);
}

TEST(ReadTextFile, RefusesDevicesFifosDirectoriesAndMissingFilesAtOnce) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("vitreo-read-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& [path, says] : {std::pair<std::string, const char*>{"/dev/zero", "not a regular file"},
                                   {(dir / "fifo").string(), "not a regular file"},
                                   {dir.string(), "is a directory"},
                                   {(dir / "none").string(), "no such file"}}) {
    const auto r = read_text_file(path);
    EXPECT_FALSE(r.text.has_value()) << path;
    EXPECT_NE(r.error.find(says), std::string::npos) << r.error;
    EXPECT_NE(r.error.find(path), std::string::npos) << r.error;
  }
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
  fs::remove_all(dir);
}
