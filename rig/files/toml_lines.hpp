#pragma once
// The line a TOML node came from (beside toml_guard.hpp): every file a person writes (cases, rig
// files, surgical scripts) reports its errors as file:line: key.
#include <toml++/toml.h>

namespace vitreo::files {

inline int line_of(const toml::node& n) { return static_cast<int>(n.source().begin.line); }

}  // namespace vitreo::files
