#include "rig/report/write_report.hpp"

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>
#include <stdexcept>

#include "rig/report/atomic_file.hpp"
#include "rig/report/report_html.hpp"
#include "rig/report/trainee_history.hpp"
#include "rig/report/report_json.hpp"
#include "rig/report/session_log.hpp"
#include "rig/report/survey.hpp"

namespace vitreo::report {

namespace fs = std::filesystem;

namespace {

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S UTC", &tm);
  return buf;
}

// The instructor frame of the latest step (frames are named step_%09d_instructor.png).
fs::path last_instructor_frame(const fs::path& dir) {
  fs::path best;
  std::error_code ec;
  if (!fs::is_directory(dir / "frames", ec)) return best;
  for (const auto& e : fs::directory_iterator(dir / "frames", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("step_", 0) == 0 && name.size() > 15 && name.ends_with("_instructor.png") && e.is_regular_file(ec) &&
        (best.empty() || name > best.filename().string()))
      best = e.path();
  }
  return best;
}

// The pictures of the session's key moments (rig/session/key_moments.hpp), in step order: frames
// named moment_<9-digit step>_<slug>_instructor.png. A name that does not parse is left out.
std::vector<std::pair<std::uint64_t, fs::path>> key_moment_frames(const fs::path& dir) {
  std::vector<std::pair<std::uint64_t, fs::path>> found;
  std::error_code ec;
  if (!fs::is_directory(dir / "frames", ec)) return found;
  constexpr std::string_view kPrefix = "moment_", kSuffix = "_instructor.png";
  for (const auto& e : fs::directory_iterator(dir / "frames", ec)) {
    const std::string name = e.path().filename().string();
    if (!name.starts_with(kPrefix) || !name.ends_with(kSuffix) || name.size() < kPrefix.size() + 11 + kSuffix.size() ||
        !e.is_regular_file(ec))
      continue;
    const std::string digits = name.substr(kPrefix.size(), 9);
    if (name[kPrefix.size() + 9] != '_' || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    found.emplace_back(std::stoull(digits), e.path());
  }
  std::sort(found.begin(), found.end());
  return found;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + p.string());
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

WrittenReport write_report(const std::string& session_dir, const ReportOptions& options) {
  const fs::path dir(session_dir);
  const fs::path log_path = options.telemetry_log.empty() ? dir / "telemetry.lcmlog" : fs::path(options.telemetry_log);
  std::error_code ec;
  if (!fs::exists(log_path, ec))
    throw std::runtime_error("no telemetry log at " + log_path.string() + " (a session folder is what `vitreo --out DIR` wrote)");
  SessionLog log = read_session_log(log_path.string());
  if (!options.log_origin.empty()) log.notice = log.notice.empty() ? options.log_origin : options.log_origin + "; " + log.notice;
  // The survey filled in after the session (the page's form saves it as DIR/survey.json).
  std::optional<Survey> survey;
  std::string survey_problem;
  if (const fs::path sp = dir / "survey.json"; fs::exists(sp, ec)) {
    try {
      survey = parse_survey(read_file(sp));
    } catch (const std::exception& e) {
      survey_problem = e.what();
    }
  }
  // The case's anatomy under the tip paths, from the case files the recording carries.
  std::optional<CaseAnatomy> anatomy;
  std::string anatomy_problem;
  if (const fs::path rec = dir / "session.lcmlog"; fs::is_regular_file(rec, ec)) {
    std::string case_id;
    for (const auto& sc : log.scores) case_id = sc.case_id;
    anatomy = anatomy_from_recording(rec.string(), case_id, anatomy_problem);
  }
  const std::string json = report_json(log, survey ? &*survey : nullptr, survey_problem, read_trainee(session_dir), anatomy ? &*anatomy : nullptr);

  PageInputs page;
  page.report_json = json;
  page.generated = options.generated.empty() ? utc_now() : options.generated;
  std::string png;
  if (const fs::path frame = last_instructor_frame(dir); !frame.empty()) {
    png = read_file(frame);
    page.final_png_name = "frames/" + frame.filename().string();
  }
  page.final_png = png;
  for (const auto& [step, path] : key_moment_frames(dir)) {
    KeyMomentFrame m;
    const std::string name = path.filename().string();
    m.png = read_file(path);
    m.file = "frames/" + name;
    m.step = step;
    m.what = name.substr(17, name.size() - 17 - std::string_view("_instructor.png").size());  // after "moment_<9 digits>_"
    std::replace(m.what.begin(), m.what.end(), '-', ' ');
    page.key_moments.push_back(std::move(m));
  }
  const std::string html = report_html(page);

  const fs::path out = options.out_dir.empty() ? dir : fs::path(options.out_dir);
  fs::create_directories(out, ec);
  WrittenReport r;
  r.json_path = (out / "report.json").string();
  r.html_path = (out / "report.html").string();
  write_atomically(r.json_path, json);
  write_atomically(r.html_path, html);
  if (!options.compare_dir.empty()) {
    const fs::path other = fs::path(options.compare_dir) / "telemetry.lcmlog";
    if (!fs::exists(other, ec)) throw std::runtime_error("--compare: no telemetry log at " + other.string());
    const SessionLog other_log = read_session_log(other.string());
    const std::string other_json = report_json(other_log);
    page.compare_json = other_json;
    page.compare_label = fs::path(options.compare_dir).lexically_normal().string();
    std::string other_png;
    if (const fs::path frame = last_instructor_frame(options.compare_dir); !frame.empty()) other_png = read_file(frame);
    page.compare_png = other_png;
    r.compare_path = (out / "compare.html").string();
    write_atomically(r.compare_path, report_html(page));
    if (!other_log.notice.empty()) r.notices.push_back("compared session: " + other_log.notice);
  }

  if (!log.notice.empty()) r.notices.push_back(log.notice);
  if (!survey_problem.empty()) r.notices.push_back("survey.json not shown: " + survey_problem);
  if (!anatomy_problem.empty()) r.notices.push_back("the case's anatomy is not drawn under the tip paths: " + anatomy_problem);
  if (survey) r.survey_rating = survey->rating;
  if (log.messages_skipped > 0) r.notices.push_back(std::to_string(log.messages_skipped) + " messages did not decode");
  const ScoreRecord* score = log.scores.empty() ? nullptr : &log.scores.back();
  for (const auto& sc : log.scores)
    if (sc.final_score) score = &sc;  // the last final card, as report.json takes it
  if (score) {
    r.case_id = score->case_id;
    r.total = score->total;
    r.final_score = score->final_score;
  }
  if (log.scores.empty()) r.notices.push_back("no score card in the log");
  else if (!r.final_score) r.notices.push_back("no final score in the log: the numbers are the last running ones");
  return r;
}

}  // namespace vitreo::report
