#pragma once
// The case's anatomy under the tip paths: the optic disc, the fovea and the macula, the ora serrata,
// and the case's own features — its tears, membranes, detachments and guides — as outlines in the
// eye frame's x–y plane (the picture the tip paths are drawn in, seen from the microscope), so an
// instructor sees where the hand went relative to what was there.
//
// The telemetry log does not carry the case's geometry; the session's recording does (its header
// holds the case files' texts, which is how a replay rebuilds the case). The outlines are computed
// from the case's description alone — the eye model and its features' fundus locations, through the
// same fundus-plane mapping the scene builder places them with (core EyeModel::fundus_coords: arc
// length from the posterior pole along the azimuth) — without building or settling the tissue.
#include <optional>
#include <string>
#include <vector>

#include "core/scene/scene_description.hpp"

namespace vitreo::report {

struct FundusOutline {
  std::string name;   // "optic disc", "horseshoe (tear)", "cut_line (guide)"
  std::string kind;   // disc, fovea, macula, ora, tear, membrane, detachment, guide
  std::vector<double> x_mm, y_mm;  // a polyline; closed outlines end where they began
};

struct CaseAnatomy {
  std::string case_id;
  std::vector<FundusOutline> outlines;
};

// The macula drawn around the fovea: 5.5 mm across, the clinical macula (fovea ~1.5 mm across).
inline constexpr double kMaculaRadiusMm = 2.75;
inline constexpr double kFoveaRadiusMm = 0.75;

// Outlines of a case from its description (throws core::InvalidArgument for an eye that cannot be built).
CaseAnatomy case_anatomy(const core::SceneDescription& description);

// The anatomy of case `case_id` (or of the recording's first case when it holds none of that name)
// from a session's recording. Nothing when the recording cannot be read or its case not parsed;
// `problem` then says why.
std::optional<CaseAnatomy> anatomy_from_recording(const std::string& recording_path, const std::string& case_id, std::string& problem);

}  // namespace vitreo::report
