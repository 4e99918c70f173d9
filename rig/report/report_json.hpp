#pragma once
// The debrief's numbers (report.json) from a session's telemetry log: the case, its criteria, the
// score card with each category's inputs and formula, the totals the scoring accumulated, per-hand
// tip paths, timelines and events. Every number carries its unit; the formulas' version is the one
// the session scored with. The output depends on the log alone (same log, same bytes).
#include <string>

#include "rig/report/session_log.hpp"
#include "rig/report/survey.hpp"

namespace vitreo::report {

inline constexpr int kReportFormat = 1;  // the layout of report.json (README)

// survey: the session's post-session evaluation (DIR/survey.json), or null; survey_problem: why the
// one in the folder was refused (a notice), empty when there was none or it was read.
// trainee: who did the session (DIR/trainee.txt), "" when not named.
std::string report_json(const SessionLog& log, const Survey* survey = nullptr, const std::string& survey_problem = "",
                        const std::string& trainee = "");

}  // namespace vitreo::report
