#pragma once
// Writes a session folder's report: DIR/report.json and DIR/report.html from DIR/telemetry.lcmlog
// (the main job's output folder) and the last instructor frame in DIR/frames. Each file is written
// beside its final name and renamed into place, so a reader never sees half a report.
#include <string>
#include <vector>

namespace vitreo::report {

struct WrittenReport {
  std::string json_path, html_path;
  std::vector<std::string> notices;  // what the report says is missing or wrong in the log
  std::string case_id;
  double total = 0;
  bool final_score = false;
};

struct ReportOptions {
  std::string telemetry_log;  // default: DIR/telemetry.lcmlog
  std::string out_dir;        // default: DIR
  std::string generated;      // the page's generation time; default: now (UTC)
};

// Throws std::runtime_error with a reason an instructor can act on (no log, nothing readable,
// folder not writable).
WrittenReport write_report(const std::string& session_dir, const ReportOptions& options = {});

}  // namespace vitreo::report
