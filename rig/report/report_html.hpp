#pragma once
// report.html: one self-contained page — the report's JSON, Chart.js and the page's own script
// inlined, the final fundus frame as a data: URL — that opens offline in any browser.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace vitreo::report {

// A picture of a key moment of the session (rig/session/key_moments.hpp), as the session wrote it.
struct KeyMomentFrame {
  std::string png;      // the instructor view's PNG bytes
  std::string file;     // "frames/moment_000004321_unintended-tear_instructor.png"
  std::uint64_t step = 0;
  std::string what;     // "unintended tear", "case end"
};

struct PageInputs {
  std::string_view report_json;    // report_json()'s text
  std::string_view final_png;      // the last instructor frame's PNG bytes, empty when there is none
  std::string final_png_name;      // its file name (shown under the picture)
  std::string generated;           // when the page was made (the only thing that differs between two runs)
  // Another session's report_json() to show side by side (empty: a report of one session).
  std::string_view compare_json;
  std::string compare_label;       // what to call it on the page (its folder)
  std::string_view compare_png;    // its last instructor frame
  std::vector<KeyMomentFrame> key_moments;  // in step order; empty: the section says there are none
};

std::string report_html(const PageInputs& in);

}  // namespace vitreo::report
