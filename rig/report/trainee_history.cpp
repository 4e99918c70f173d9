#include "rig/report/trainee_history.hpp"
#include "rig/report/page_template.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/scene/scene_description.hpp"
#include "rig/report/atomic_file.hpp"
#include "rig/report/json_writer.hpp"

namespace vitreo::report {

namespace assets {
std::string_view chartjs();
std::string_view history_page();
}  // namespace assets

namespace fs = std::filesystem;

namespace {

struct Attempt {
  std::string folder;
  std::int64_t started_us = 0;
  double total = 0;
  bool final_score = false;
  bool completed = false;            // every criterion but the time limit met (its report's case.completed)
  std::optional<double> pass_score;  // the case's, as its report carries it
  std::vector<std::pair<std::string, double>> categories;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

bool valid_trainee_id(const std::string& id) {
  if (id.empty() || id.size() > 64 || id[0] == '.') return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
  });
}

std::string read_trainee(const std::string& session_dir) {
  std::ifstream in(fs::path(session_dir) / "trainee.txt");
  std::string id;
  if (!in || !std::getline(in, id)) return "";
  return valid_trainee_id(id) ? id : "";
}

HistoryFiles write_history(const std::string& root, const std::string& trainee, std::optional<double> pass_override,
                           const std::string& out_dir, const std::string& generated) {
  if (!valid_trainee_id(trainee)) throw std::runtime_error("trainee id '" + trainee + "': 1-64 characters of A-Z a-z 0-9 . _ - please");
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw std::runtime_error("'" + root + "' is not a folder of sessions");
  HistoryFiles files;
  std::map<std::string, std::vector<Attempt>> by_case;
  std::vector<fs::path> dirs;
  for (const auto& e : fs::directory_iterator(root, ec))
    if (e.is_directory(ec) && fs::exists(e.path() / "report.json", ec)) dirs.push_back(e.path());
  std::sort(dirs.begin(), dirs.end());
  for (const auto& d : dirs) {
    try {
      const auto j = nlohmann::json::parse(slurp(d / "report.json"));
      if (j.value("trainee", std::string()) != trainee) continue;
      Attempt a;
      a.folder = d.filename().string();
      a.started_us = j.at("case").value("started_utime_us", std::int64_t{0});
      a.total = j.at("score").at("total").at("value").get<double>();
      a.final_score = j.at("score").at("final").get<bool>();
      if (j.at("case").contains("completed")) {
        a.completed = j.at("case").at("completed").get<bool>();
      } else {  // a report written before it said so: from its criteria, as the report does
        a.completed = a.final_score;
        for (const auto& c : j.at("criteria")) a.completed = a.completed && (c.at("met").get<bool>() || c.at("kind").get<std::string>() == "time_limit");
      }
      if (j.at("case").contains("pass_score")) a.pass_score = j.at("case").at("pass_score").at("value").get<double>();
      for (const auto& c : j.at("score").at("categories")) a.categories.emplace_back(c.at("name").get<std::string>(), c.at("value").at("value").get<double>());
      by_case[j.at("case").at("id").get<std::string>()].push_back(std::move(a));
      ++files.sessions;
    } catch (const std::exception&) {
      ++files.skipped;  // a report of another format or a damaged file: counted, not fatal
    }
  }
  if (files.sessions == 0) throw std::runtime_error("no session of trainee '" + trainee + "' under " + root + " (sessions name their trainee with `vitreo --trainee ID`)");
  files.cases = static_cast<int>(by_case.size());

  JsonWriter j;
  j.begin_object();
  j.key("trainee").value(trainee);
  if (pass_override) j.field("pass_score", *pass_override, "points (0..100)");
  else j.key("pass_score").value(nullptr);  // each case's own (below)
  j.key("sessions").value(files.sessions);
  j.key("skipped_folders").value(files.skipped);
  j.key("cases").begin_array();
  for (auto& [id, attempts] : by_case) {
    std::stable_sort(attempts.begin(), attempts.end(), [](const Attempt& x, const Attempt& y) { return x.started_us < y.started_us; });
    double best = 0;
    int first_pass = 0;
    // The case's pass score: the instructor's for all cases, else the newest report's (the case file
    // as it was at that session), else the default for reports that carry none.
    double pass_score = core::kDefaultPassScore;  // a report that carries none: written before cases had one
    const char* from = "default (the reports carry none)";
    if (pass_override) {
      pass_score = *pass_override;
      from = "--pass";
    } else {
      for (auto it = attempts.rbegin(); it != attempts.rend(); ++it) {
        if (it->pass_score) {
          pass_score = *it->pass_score;
          from = "case file";
          break;
        }
      }
    }
    j.begin_object();
    j.key("case").value(id);
    j.field("pass_score", pass_score, "points (0..100)");
    j.key("pass_score_from").value(from);
    j.key("attempts").begin_array();
    for (std::size_t i = 0; i < attempts.size(); ++i) {
      const Attempt& a = attempts[i];
      best = std::max(best, a.total);
      const bool passed = a.completed && a.total >= pass_score;  // completed implies a final score
      if (first_pass == 0 && passed) first_pass = static_cast<int>(i) + 1;
      j.begin_object();
      j.key("n").value(static_cast<std::int64_t>(i + 1));
      j.key("folder").value(a.folder);
      j.key("started_utime_us").value(a.started_us);
      j.field("total", a.total, "points (0..100)");
      j.key("final").value(a.final_score);
      j.key("completed").value(a.completed);
      j.key("passed").value(passed);
      j.key("categories").begin_object();
      for (const auto& [n, v] : a.categories) j.field(n, v, "points (0..100)");
      j.end_object();
      j.end_object();
    }
    j.end_array();
    j.field("best", best, "points (0..100)");
    j.key("first_passed_attempt").value(first_pass);
    j.end_object();
  }
  j.end_array();
  j.end_object();
  const std::string json = j.take() + "\n";

  std::string page(assets::history_page());
  std::string gen;
  for (const char c : generated) gen += (c == '<' || c == '>' || c == '&') ? ' ' : c;
  fill(page, "@GENERATED@", gen);
  fill(page, "/*@CHARTJS@*/", assets::chartjs());
  fill(page, "/*@HISTORY_JSON@*/", json);  // the writer escapes '<': it cannot close its script

  const fs::path out = out_dir.empty() ? fs::path(root) : fs::path(out_dir);
  fs::create_directories(out, ec);
  files.json_path = (out / ("history-" + trainee + ".json")).string();
  files.html_path = (out / ("history-" + trainee + ".html")).string();
  write_atomically(files.json_path, json);
  write_atomically(files.html_path, page);
  return files;
}

}  // namespace vitreo::report
