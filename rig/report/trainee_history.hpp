#pragma once
// A trainee's history: every session folder under ROOT whose report names the trainee, per case in
// the order the sessions started — the learning curve, against a pass score (EyeSi shows progress
// the same way). Reads the report.json files the sessions' reports wrote (the main job writes one
// at the end of every session; `vitreo --trainee ID` names the trainee, kept in DIR/trainee.txt).
// Each case is judged against its own pass score (its file's [proficiency] pass_score, which every
// report carries), unless the instructor gives one for all cases.
#include <optional>
#include <string>

namespace vitreo::report {

// 1–64 characters of [A-Za-z0-9._-], not starting with '.': safe in a file name.
bool valid_trainee_id(const std::string& id);

// The trainee named in DIR/trainee.txt ("" when there is none or it is not a valid id).
std::string read_trainee(const std::string& session_dir);

struct HistoryFiles {
  std::string json_path, html_path;
  int sessions = 0, cases = 0;
  int skipped = 0;  // folders with a report.json that could not be read
};

// Writes OUT/history-ID.json and OUT/history-ID.html. pass_override: one pass score for every case
// instead of each case's own. Throws std::runtime_error for an invalid id, an unreadable ROOT, or no
// session of that trainee under it.
HistoryFiles write_history(const std::string& root, const std::string& trainee, std::optional<double> pass_override,
                           const std::string& out_dir, const std::string& generated);

}  // namespace vitreo::report
