#pragma once
// The debrief's numbers (report.json) from a session's telemetry log: the case, its criteria, the
// score card with each category's inputs and formula, the totals the scoring accumulated, per-hand
// tip paths, timelines and events. Every number carries its unit; the formulas' version is the one
// the session scored with. The output depends on the log alone (same log, same bytes).
#include <string>

#include "rig/report/session_log.hpp"

namespace vitreo::report {

inline constexpr int kReportFormat = 1;  // the layout of report.json (README)

std::string report_json(const SessionLog& log);

}  // namespace vitreo::report
