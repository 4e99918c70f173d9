// libFuzzer target: scene and materials files (parse_scene) behind the TOML guard, with toml++
// compiled header-only here with its own assertions on and UBSan watching (the Debian library is a
// release build, where the same faults are silent undefined behaviour). The input is the scene text,
// then a NUL, then the materials library text. Only SceneError may come out.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "rig/scene_io/scene_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string all(reinterpret_cast<const char*>(data), size);
  const std::size_t nul = all.find('\0');
  const std::string scene = all.substr(0, nul);
  const std::string library = nul == std::string::npos ? std::string() : all.substr(nul + 1);
  try {
    (void)vitreo::scene_io::parse_scene(scene, "/nonexistent/fuzz.toml", &library);
  } catch (const vitreo::scene_io::SceneError& e) {
    if (std::string(e.what()).empty()) std::abort();
  }
  return 0;
}
