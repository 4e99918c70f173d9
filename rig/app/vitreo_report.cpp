// vitreo-report: the debrief of a session. Reads the session folder the main job wrote
// (`vitreo --out DIR`): its telemetry log and its last instructor frame, and writes DIR/report.json
// (every number with its unit and the formulas' version) and DIR/report.html (one self-contained
// page: criteria, score card, tip paths over the fundus, timelines, the final fundus); with
// --compare OTHER also DIR/compare.html, this session against another side by side. With
// --trainee ID DIR: the learning curves of that trainee's sessions under DIR (history-ID.html).
//
// Exit status: 0 report written from a complete log; 3 written, but the log was truncated or
// corrupted, or has no final score (the page and the JSON say so); 1 no report (the reason is printed).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <optional>

#include "rig/report/trainee_history.hpp"
#include "rig/report/write_report.hpp"

int main(int argc, char** argv) {
  CLI::App app{"vitreo-report: writes a session's debrief (report.json, report.html) from its telemetry log"};
  std::string dir;
  vitreo::report::ReportOptions options;
  std::string trainee;
  double pass_for_all = 0;
  app.add_option("DIR", dir, "session folder (what `vitreo --out DIR` wrote); with --trainee, the folder holding session folders")->required();
  app.add_option("--trainee", trainee, "write DIR/history-ID.html/.json: that trainee's sessions under DIR, per case, as a learning curve");
  auto* pass_opt = app.add_option("--pass", pass_for_all, "with --trainee: the score a final attempt must reach to pass, for every case (default: each case's own pass score)")->check(CLI::Range(0.0, 100.0));
  app.add_option("--log", options.telemetry_log, "telemetry log to read instead of DIR/telemetry.lcmlog");
  app.add_option("--out", options.out_dir, "folder to write report.json and report.html into (default: DIR)");
  app.add_option("--compare", options.compare_dir,
                 "another session folder (e.g. the expert script's run of the same case): also writes compare.html, "
                 "this session against that one side by side");
  app.add_option("--generated", options.generated, "the generation time shown on the page (default: now, UTC)");
  CLI11_PARSE(app, argc, argv);
  try {
    if (!trainee.empty()) {
      // Unset: each case is judged against its own pass score ([proficiency] pass_score).
      const std::optional<double> pass_score = *pass_opt ? std::optional<double>(pass_for_all) : std::nullopt;
      const auto h = vitreo::report::write_history(dir, trainee, pass_score, options.out_dir, options.generated.empty() ? "now" : options.generated);
      std::printf("history of %s: %d sessions in %d cases%s\n  %s\n  %s\n", trainee.c_str(), h.sessions, h.cases,
                  h.skipped ? (", " + std::to_string(h.skipped) + " unreadable reports left out").c_str() : "", h.json_path.c_str(),
                  h.html_path.c_str());
      return 0;
    }
    const auto r = vitreo::report::write_report(dir, options);
    std::printf("report: %s — %.1f / 100 (%s)\n", r.case_id.empty() ? "unknown case" : r.case_id.c_str(), r.total,
                r.final_score ? "final" : "not final");
    if (r.survey_rating > 0) std::printf("  survey: modified Cooper-Harper rating %.1f of 10\n", r.survey_rating);
    for (const auto& n : r.notices) std::printf("  notice: %s\n", n.c_str());
    std::printf("  %s\n  %s\n", r.json_path.c_str(), r.html_path.c_str());
    if (!r.compare_path.empty()) std::printf("  %s (against %s)\n", r.compare_path.c_str(), options.compare_dir.c_str());
    return r.notices.empty() ? 0 : 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vitreo-report: %s\n", e.what());
    return 1;
  }
}
