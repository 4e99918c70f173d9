#pragma once
// Writes a session folder's report: DIR/report.json and DIR/report.html from DIR/telemetry.lcmlog
// (the main job's output folder) and the last instructor frame in DIR/frames. Each file is written
// beside its final name and renamed into place, so a reader never sees half a report.
#include <string>
#include <vector>

namespace vitreo::report {

struct WrittenReport {
  std::string json_path, html_path;
  std::string compare_path;          // compare.html, when another session was given
  std::vector<std::string> notices;  // what the report says is missing or wrong in the log
  std::string case_id;
  double total = 0;
  bool final_score = false;
  double survey_rating = 0;          // the survey's modified Cooper-Harper rating, 0 without a survey
};

struct ReportOptions {
  std::string telemetry_log;  // default: DIR/telemetry.lcmlog
  std::string out_dir;        // default: DIR
  std::string generated;      // the page's generation time; default: now (UTC)
  // Another session folder (e.g. the case's expert script run) to show side by side: also writes
  // OUT/compare.html, this session (A) against that one (B).
  std::string compare_dir;
  // Where the log came from when it is not what the session itself wrote (vitreo-report regenerates
  // a missing one from the recording): shown as a notice on the page and in the JSON.
  std::string log_origin;
};

// Throws std::runtime_error with a reason an instructor can act on (no log, nothing readable,
// folder not writable).
WrittenReport write_report(const std::string& session_dir, const ReportOptions& options = {});

}  // namespace vitreo::report
