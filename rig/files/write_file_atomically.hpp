#pragma once
// Writing a file that must never be seen half-written (a calibration, a configuration): the text
// goes to a temporary file in the same directory, is fsync'ed, then renamed over the target (atomic
// on POSIX file systems), and the directory is fsync'ed so the rename itself survives a power cut.
// A process killed at any point leaves either the old file or the new one — at worst a stray
// "<name>.tmp.<pid>" beside it, never a truncated target.
#include <string>
#include <string_view>

namespace vitreo::files {

// Returns an empty string on success, else why not (the target is then untouched).
std::string write_file_atomically(const std::string& path, std::string_view text);

}  // namespace vitreo::files
