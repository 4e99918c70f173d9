// Every shipped case played by its scripted surgeons through the whole stack — firmware emulators →
// ptys → drivers → rig → core → metrics, in lockstep — at the rig's resolution (5000 retina
// vertices): the expert completes the case, the clumsy surgeon scores below the expert, an idle run
// does not complete and scores at most 15 with no target achievement and no iatrogenic event
// (issue 15's acceptance table). Cases whose expert script is not written yet are reported, not
// passed. The margins are printed per category. With VITREO_LONG_TESTS=1, the same acceptance at
// each case's own resolution (ScriptedCaseOwnResolution: 8k–20k vertices, an hour or more here; run
// the binary with --gtest_filter='*OwnResolution*/CASE' case by case, ctest's 900 s would cut it),
// and a degradation sweep: the expert scripts of three cases with a growing tremor score lower at
// every step.
//
// And the lockstep's promise: the same script twice, the second time with the other cores busy, reaches
// the same final state bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include "rig/report/write_report.hpp"
#include "rig/scene_io/case_loader.hpp"
#include "rig/session/rig_session.hpp"
#include "rig/session/scripted_session.hpp"

namespace vitreo::rig {
namespace {

namespace fs = std::filesystem;

const fs::path kScenes = fs::path(VITREO_SOURCE_DIR) / "scenes";

[[maybe_unused]] std::vector<std::string> case_names() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(kScenes)) {
    if (e.path().extension() == ".toml" && e.path().filename() != "materials.toml") out.push_back(e.path().stem().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

fs::path script_path(const std::string& case_name, const std::string& kind) {
  return kScenes / "scripts" / (case_name + "." + kind + ".toml");
}

struct Played {
  SessionSummary summary;
  SurgicalScript script;
  fs::path dir;  // the session's folder: its telemetry log (and, once written, its report)
};

// The rig's resolution on this 2-core machine; 0 plays the case at its own ([anatomy] retina_vertices).
constexpr int kRigVertices = 5000;
constexpr int kCaseOwnVertices = 0;

// tremor_mm, when given, replaces the script's tremor σ: the degradation sweep plays the expert's
// motions with a shakier hand. typed: operator commands typed on the rig's terminal at the start.
Played play(const std::string& case_name, const fs::path& script_file, const std::string& tag, double tremor_mm = -1.0,
            const std::string& typed = "", int retina_vertices = kRigVertices) {
  Played out;
  out.script = read_surgical_script(script_file.string());
  if (tremor_mm >= 0.0) out.script.tremor_mm = tremor_mm;
  // The resolution in the folder's name: the rig's and the case's own runs of a script may play at once.
  const std::string resolution = retina_vertices == kCaseOwnVertices ? "own" : std::to_string(retina_vertices);
  const fs::path dir = fs::path(::testing::TempDir()) / ("scripted-" + case_name + "-" + tag + "-" + resolution);
  fs::remove_all(dir);
  fs::create_directories(dir);
  SessionConfig config;
  config.model.cases.push_back(scene_io::read_case_text((kScenes / (case_name + ".toml")).string()));
  config.model.load.retina_vertices = retina_vertices;
  config.model.load.cache_dir = std::string(VITREO_CASE_CACHE_DIR);
  config.devices = simulated_devices(out.script);
  config.adapt_devices = play_script(out.script, config.model.pedals, config.model.microscope);
  config.device_mode = HubMode::lockstep;
  config.unpaced = true;
  config.steps = static_cast<std::uint64_t>(std::llround(out.script.duration_s / config.model.dt_s));
  config.end_at_case_over = true;  // the score is frozen there; the rest of the script would only follow it
  config.lcm_url = "file://" + (dir / "telemetry.lcmlog").string() + "?mode=w";
  config.command_echo = nullptr;
  int fds[2] = {-1, -1};
  if (!typed.empty()) {
    EXPECT_EQ(::pipe(fds), 0);
    EXPECT_EQ(::write(fds[1], typed.data(), typed.size()), static_cast<ssize_t>(typed.size()));
    ::close(fds[1]);
    config.command_fd = fds[0];
    config.command_echo = std::tmpfile();  // the terminal's acks (it needs somewhere to print them)
  }
  out.summary = run_session(config);
  out.dir = dir;
  if (fds[0] >= 0) ::close(fds[0]);
  if (config.command_echo) std::fclose(config.command_echo);
  return out;
}

double category(const SessionSummary& s, const char* name) {
  const core::ScoreEntry* e = s.score.find(name);
  return e ? e->value : -1.0;
}

[[maybe_unused]] std::string line(const char* who, const SessionSummary& s) {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "%-7s total %5.1f  target %5.1f  efficiency %5.1f  tissue %5.1f  handling %5.1f  microscope %5.1f  iatrogenic %u  %s",
                who, s.score.total, category(s, "target_achievement"), category(s, "efficiency"), category(s, "tissue_treatment"),
                category(s, "instrument_handling"), category(s, "microscope_handling"), static_cast<unsigned>(s.totals.iatrogenic_events()),
                s.case_completed ? "COMPLETED" : "not completed");
  // Microscope handling's inputs: shares of the working time out of the field, off centre, out of focus.
  const double w = s.totals.microscope_working_time_s;
  if (w > 0.0) {
    char more[128];
    std::snprintf(more, sizeof more, "  (work %.1f s: out of field %.0f%%, off centre %.0f%%, out of focus %.0f%%)", w,
                  100.0 * s.totals.out_of_field_s / w, 100.0 * s.totals.off_centre_s / w, 100.0 * s.totals.out_of_focus_s / w);
    return std::string(buf) + more;
  }
  return buf;
}

#ifndef VITREO_LOCKSTEP_ONLY
// Issue 17's bar: every scripted run gets its debrief (vitreo-report's writer on the run's telemetry
// log), whose score is the one the session ended with; with `against`, also compare.html, this run
// side by side with that one.
void check_report(const Played& run, const Played* against = nullptr) {
  report::ReportOptions options;
  options.generated = "test";
  if (against) options.compare_dir = against->dir.string();
  const report::WrittenReport r = report::write_report(run.dir.string(), options);
  EXPECT_TRUE(fs::file_size(r.json_path) > 0 && fs::file_size(r.html_path) > 0) << run.dir;
  EXPECT_TRUE(r.final_score) << run.dir << ": the report has the session's final score";
  EXPECT_NEAR(r.total, run.summary.score.total, 1e-9) << run.dir << ": the report's total is the session's";
  if (against) {
    EXPECT_FALSE(r.compare_path.empty());
    EXPECT_GT(fs::file_size(r.compare_path), fs::file_size(r.html_path)) << "compare.html holds both sessions";
  }
}

class ScriptedCase : public ::testing::TestWithParam<std::string> {};

// Issue 15's acceptance for one case at `vertices` retina vertices: expert completes, clumsy lower,
// idle nothing.
void check_case(const std::string& name, int vertices) {
  const bool have_expert = fs::exists(script_path(name, "expert"));
  const bool have_clumsy = fs::exists(script_path(name, "clumsy"));
  ASSERT_TRUE(fs::exists(script_path(name, "idle"))) << name << ": no idle script";

  const Played idle = play(name, script_path(name, "idle"), "idle", -1.0, "", vertices);
  std::printf("%s at %s\n  %s\n", name.c_str(), vertices > 0 ? (std::to_string(vertices) + " vertices").c_str() : "its own resolution",
              line("idle", idle.summary).c_str());
  EXPECT_FALSE(idle.summary.case_completed);
  EXPECT_LE(idle.summary.score.total, 15.0);
  // Nothing to the tenth of a point the debrief shows: a detachment left alone still settles by a
  // micrometre or so (exercise_drain_tear's lift 2.4446 -> 2.4435 mm in 12.5 s), which retina_flat's
  // progress counts.
  EXPECT_LT(category(idle.summary, "target_achievement"), 0.05);
  EXPECT_EQ(idle.summary.totals.iatrogenic_events(), 0u);
  EXPECT_EQ(idle.summary.totals.retina_tears, 0u);
  check_report(idle);

  // A case nobody has written a completing expert for yet is reported as skipped (its idle run is
  // still checked above): the list of open cases is in the test's output, never hidden in a pass.
  if (!have_expert) GTEST_SKIP() << name << ": no expert script yet (" << script_path(name, "expert").string() << ")";
  const Played expert = play(name, script_path(name, "expert"), "expert", -1.0, "", vertices);
  std::printf("  %s\n", line("expert", expert.summary).c_str());
  EXPECT_TRUE(expert.summary.case_completed) << name << ": the expert script does not complete the case";
  EXPECT_EQ(expert.summary.totals.retina_tears, 0u);
  EXPECT_GT(expert.summary.score.total, idle.summary.score.total);
  // An expert that works the microscope (look_at, zoom, focus: the scripted rig's microscope pedal)
  // keeps the work in the field, centred and in focus.
  if (works_microscope(read_surgical_script(script_path(name, "expert").string()))) {
    EXPECT_GT(category(expert.summary, "microscope_handling"), 80.0) << name << ": its expert's field does not follow the work";
  }
  check_report(expert);

  if (!have_clumsy) GTEST_SKIP() << name << ": the expert completes; no clumsy script yet";
  const Played clumsy = play(name, script_path(name, "clumsy"), "clumsy", -1.0, "", vertices);
  std::printf("  %s\n", line("clumsy", clumsy.summary).c_str());
  std::printf("  margins (expert − clumsy): total %+.1f", expert.summary.score.total - clumsy.summary.score.total);
  for (const auto& e : expert.summary.score.categories) {
    std::printf(", %s %+.1f", e.name, e.value - category(clumsy.summary, e.name));
  }
  std::printf("\n");
  // The clumsy run's debrief beside the expert's (compare.html): where its points went.
  check_report(clumsy, &expert);
  const core::ScoreEntry* lost_most = nullptr;
  for (const auto& e : expert.summary.score.categories) {
    if (!lost_most || e.value - category(clumsy.summary, e.name) > lost_most->value - category(clumsy.summary, lost_most->name)) lost_most = &e;
  }
  if (lost_most) std::printf("  clumsy lost most in %s (see %s)\n", lost_most->name, (clumsy.dir / "compare.html").c_str());
  // A clumsy surgeon still completes the case unless its script says why it cannot ("does not
  // complete: …" in its summary): there the gap to the expert must be plain.
  if (clumsy.script.summary.find("does not complete") == std::string::npos) {
    EXPECT_TRUE(clumsy.summary.case_completed) << name << ": the clumsy script should still complete the case";
  } else {
    EXPECT_FALSE(clumsy.summary.case_completed) << name << ": the clumsy script says it does not complete, but it does";
    EXPECT_GT(expert.summary.score.total, clumsy.summary.score.total + 10.0);
  }
  EXPECT_LE(expert.summary.totals.iatrogenic_events(), clumsy.summary.totals.iatrogenic_events());
  EXPECT_GT(expert.summary.score.total, clumsy.summary.score.total);
  bool worse_somewhere = false;
  for (const auto& e : expert.summary.score.categories) {
    // The clumsy surgeon is below the expert where it is clumsy, and nowhere clearly better: a point
    // is the scores' resolution (a category it does not aim at, like illumination with a light pipe
    // nobody moves, may differ by a fraction).
    EXPECT_GE(e.value + 1.0, category(clumsy.summary, e.name)) << name << ": the clumsy script beats the expert in " << e.name;
    worse_somewhere = worse_somewhere || category(clumsy.summary, e.name) < e.value - 1.0;
  }
  EXPECT_TRUE(worse_somewhere) << name << ": the clumsy script is not clearly worse in any category";
}

TEST_P(ScriptedCase, ExpertCompletesClumsyScoresLowerIdleScoresNothing) { check_case(GetParam(), kRigVertices); }

INSTANTIATE_TEST_SUITE_P(EveryCase, ScriptedCase, ::testing::ValuesIn(case_names()), [](const auto& p) { return p.param; });

// The same acceptance at each case's own resolution ([anatomy] retina_vertices: 8k–20k), which the
// rig PC runs and this 2-core machine cannot in real time: three sessions a case, up to 20k vertices,
// so it runs with VITREO_LONG_TESTS=1 (an hour or more here, lockstep: the outcome does not depend on
// the wait).
class ScriptedCaseOwnResolution : public ::testing::TestWithParam<std::string> {};

TEST_P(ScriptedCaseOwnResolution, ExpertCompletesClumsyScoresLowerIdleScoresNothing) {
  if (!std::getenv("VITREO_LONG_TESTS")) GTEST_SKIP() << "three sessions at up to 20k vertices; VITREO_LONG_TESTS=1";
  check_case(GetParam(), kCaseOwnVertices);
}

INSTANTIATE_TEST_SUITE_P(EveryCase, ScriptedCaseOwnResolution, ::testing::ValuesIn(case_names()),
                         [](const auto& p) { return p.param; });

// Microscope handling through the whole stack: the expert's cut with the field where the case puts
// it, and the same hands after the operator pans the field 8 mm off the path at the start (the
// terminal's `pan`, before the blade reaches the work): the work out of the field scores lower.
TEST(MicroscopeHandling, TheExpertsWorkOutOfTheFieldScoresLower) {
  const std::string name = "exercise_cut_path";
  const Played centred = play(name, script_path(name, "expert"), "centred");
  const Played off = play(name, script_path(name, "expert"), "field-off", -1.0, "pan 8 8\n");
  std::printf("  %s\n  %s\n", line("centred", centred.summary).c_str(), line("off", off.summary).c_str());
  EXPECT_TRUE(centred.summary.case_completed);
  EXPECT_GT(category(centred.summary, "microscope_handling"), 80.0) << "the expert keeps the work in the field";
  EXPECT_EQ(centred.summary.totals.out_of_field_s, 0.0);
  EXPECT_GT(off.summary.totals.out_of_field_s, 0.5 * off.summary.totals.microscope_working_time_s);
  EXPECT_LT(category(off.summary, "microscope_handling"), category(centred.summary, "microscope_handling") - 30.0);
  EXPECT_LT(off.summary.score.total, centred.summary.score.total);
}

// The expert's script with a growing tremor (σ of the hand's position noise, 20 Hz): the score falls
// at every step of the sweep. Four full sessions a case, so it runs with VITREO_LONG_TESTS=1.
class DegradationSweep : public ::testing::TestWithParam<std::string> {};

TEST_P(DegradationSweep, TheScoreFallsAsTheTremorGrows) {
  if (!std::getenv("VITREO_LONG_TESTS")) GTEST_SKIP() << "four sessions a case; VITREO_LONG_TESTS=1";
  const std::string name = GetParam();
  double previous = 101.0;
  for (const double tremor : {0.0, 0.1, 0.2, 0.4}) {
    const Played p = play(name, script_path(name, "expert"), "tremor", tremor);
    char who[32];
    std::snprintf(who, sizeof who, "%.1fmm", tremor);
    std::printf("%s tremor %s\n", name.c_str(), line(who, p.summary).c_str());
    EXPECT_LT(p.summary.score.total, previous) << name << ": tremor " << tremor << " mm does not score below the steadier hand";
    previous = p.summary.score.total;
  }
}

INSTANTIATE_TEST_SUITE_P(ThreeCases, DegradationSweep,
                         ::testing::Values("exercise_navigation", "exercise_laser_tear", "rhegmatogenous_u_tear"),
                         [](const auto& p) { return p.param; });
#else

// Lockstep: a loaded machine slows a scripted session down but changes nothing it receives.
TEST(Lockstep, SameScriptSameFinalStateWithTheCoresBusy) {
  const std::string name = "exercise_pull_tissue";
  const Played quiet = play(name, script_path(name, "expert"), "quiet");
  std::atomic<bool> stop{false};
  std::vector<std::thread> burners;
  // the other core busy (all but one on a bigger machine)
  const unsigned n = std::max(1u, std::thread::hardware_concurrency() - 1);
  for (unsigned i = 0; i < n; ++i) {
    burners.emplace_back([&stop] {
      volatile std::uint64_t x = 0;
      while (!stop.load(std::memory_order_relaxed)) x = x + 1;
    });
  }
  const Played busy = play(name, script_path(name, "expert"), "busy");
  stop = true;
  for (auto& t : burners) t.join();
  std::printf("quiet: state %016llx, physics waited %s\nbusy:  state %016llx, physics waited %s\n",
              static_cast<unsigned long long>(quiet.summary.state_hash), quiet.summary.lockstep_line.c_str(),
              static_cast<unsigned long long>(busy.summary.state_hash), busy.summary.lockstep_line.c_str());
  EXPECT_EQ(quiet.summary.state_hash, busy.summary.state_hash);
  EXPECT_EQ(quiet.summary.score.total, busy.summary.score.total);
  EXPECT_EQ(quiet.summary.inputs_applied, busy.summary.inputs_applied);
}
#endif

}  // namespace
}  // namespace vitreo::rig
