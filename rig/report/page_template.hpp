#pragma once
// The debrief's pages (report_page.html, history_page.html) are templates with markers that the
// writer replaces with the session's data and the inlined libraries.
#include <stdexcept>
#include <string>
#include <string_view>

namespace vitreo::report {

// Replaces the one occurrence of `marker` in `page`; a template must hold each marker exactly once.
inline void fill(std::string& page, std::string_view marker, std::string_view with) {
  const auto at = page.find(marker);
  if (at == std::string::npos || page.find(marker, at + 1) != std::string::npos)
    throw std::logic_error("page template: marker " + std::string(marker) + " missing or repeated");
  page.replace(at, marker.size(), with);
}

}  // namespace vitreo::report
