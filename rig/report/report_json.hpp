#pragma once
// The debrief's numbers (report.json) from a session's telemetry log: the case, its criteria, the
// score card with each category's inputs and formula, the totals the scoring accumulated, per-hand
// tip paths, timelines and events. Every number carries its unit; the formulas' version is the one
// the session scored with. The output depends on the log (same log, same bytes) and, for the outlines
// of the case's anatomy under the tip paths, on the case the session's recording holds.
#include <string>

#include "rig/report/case_anatomy.hpp"
#include "rig/report/session_log.hpp"
#include "rig/report/survey.hpp"

namespace vitreo::report {

inline constexpr int kReportFormat = 1;  // the layout of report.json (README)

// survey: the session's post-session evaluation (DIR/survey.json), or null; survey_problem: why the
// one in the folder was refused (a notice), empty when there was none or it was read.
// trainee: who did the session (DIR/trainee.txt), "" when not named. anatomy: the case's outlines
// (case_anatomy.hpp), or null: "anatomy" is then null in the JSON.
std::string report_json(const SessionLog& log, const Survey* survey = nullptr, const std::string& survey_problem = "",
                        const std::string& trainee = "", const CaseAnatomy* anatomy = nullptr);

}  // namespace vitreo::report
