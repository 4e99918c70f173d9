#pragma once
// Writes a file beside its final name and renames it into place, so a reader (a browser refreshing
// the report) never sees half of one. Throws std::runtime_error on failure.
#include <string>

namespace vitreo::report {

void write_atomically(const std::string& path, const std::string& text);

}  // namespace vitreo::report
