#pragma once
// The calibration report a technician files (issue 18): vitreo-calibrate writes it beside the
// calibration file, whether the calibration passed or not — calibration.json (every result with its
// unit and tolerance) and one self-contained page (Chart.js and the numbers inlined, like the
// session debrief) with the step-by-step outcome, the text summary and plots: each pivot's residual
// per pose against its limit, where the shaft pointed during the pivot (the spread), the residual
// at each fiducial with FRE and its limit, the pedals' measured ranges and dead zones, and the
// devices' clock offsets.
#include <string>

#include "rig/calibration/procedure.hpp"

namespace vitreo::report {

inline constexpr int kCalibrationReportFormat = 1;

struct CalibrationReportInputs {
  const rig::calibration::Analysis* analysis = nullptr;  // with the file's created/tool/rig filled in
  std::string calibration_file;  // where it was written; empty when the calibration failed (nothing written)
  std::string generated;         // the page's generation time
};

std::string calibration_report_json(const CalibrationReportInputs& in);
std::string calibration_report_html(const CalibrationReportInputs& in);

struct WrittenCalibrationReport {
  std::string json_path, html_path;
};
// Writes <base>.report.json and <base>.report.html atomically (base: the calibration file's path
// without its .toml). Throws std::runtime_error when it cannot.
WrittenCalibrationReport write_calibration_report(const std::string& base, const CalibrationReportInputs& in);

}  // namespace vitreo::report
