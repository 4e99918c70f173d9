#pragma once
// Where the rig's data is: the cases (scenes/*.toml and their scripts) and the example rig files.
//
// Run from a source checkout the data is the checkout's; installed (`cmake --install`, README
// "Installing the rig") it is PREFIX/share/vitreo, found from the running executable's own path
// (/proc/self/exe), so an installed tree works wherever it was put — a DESTDIR staging tree, /usr,
// /opt/vitreo — and never reads the build machine's source tree.
#include <string>
#include <vector>

namespace vitreo::files {

// PREFIX/share/vitreo for an executable installed in PREFIX/bin, when that folder exists; empty
// for an executable run from a build tree.
std::string installed_data_dir();

// The case folder a tool uses when none is named, first that exists of: ./scenes (a source
// checkout's root), the installed data's scenes/, the source tree this binary was built from.
// Throws std::runtime_error naming every place it looked when none exists.
std::string default_scenes_dir();

}  // namespace vitreo::files
