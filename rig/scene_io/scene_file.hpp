#pragma once
// Scene files: TOML → core::SceneDescription, validated, with errors that name file, line and key.
//
//   auto d = vitreo::scene_io::load_scene_file("scenes/rhegmatogenous_u_tear.toml");
//   auto scene = vitreo::core::build_scene(d);
//
// Unknown keys are errors (a misspelt key must not be silently ignored). Materials come from a
// library file (`[materials] library = "materials.toml"`, relative to the scene) and may be
// overridden per scene; every material value needs a `source`. The format is described in
// scenes/README.md.
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/scene/scene_description.hpp"

namespace vitreo::scene_io {

class SceneError : public std::runtime_error {
 public:
  SceneError(std::string file, int line, std::string key, const std::string& reason)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + (key.empty() ? "" : key + ": ") + reason),
        file_(std::move(file)), line_(line), key_(std::move(key)) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& key() const { return key_; }

 private:
  std::string file_;
  int line_;
  std::string key_;
};

// Throws SceneError (never anything else for bad input).
core::SceneDescription load_scene_file(const std::string& path);
// `file_name` is used in messages and to resolve the materials library (its directory).
core::SceneDescription parse_scene(std::string_view text, const std::string& file_name);
// The same with the materials library's text given (a recording carries it, so a replay does not
// depend on the library file as it is today); nullptr reads the file as above. `library_text_used`
// (optional) receives the library text that was used ("" when the case names none).
core::SceneDescription parse_scene(std::string_view text, const std::string& file_name, const std::string* library_text,
                                   std::string* library_text_used = nullptr);

}  // namespace vitreo::scene_io
