#include "rig/report/report_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/metrics/score_card.hpp"
#include "rig/report/json_writer.hpp"
#include "rig/telemetry/event_keys.hpp"

namespace vitreo::report {

namespace {

// The unit of a criterion's value and threshold (core/metrics/README.md, Criteria).
const char* criterion_unit(const std::string& kind) {
  if (kind == "retina_flat") return "mm";
  if (kind == "time_limit") return "s";
  if (kind == "drained") return "detachment force scale";
  return "share (0..1)";
}

const char* event_kind_name(int kind) {
  switch (kind) {
    case 1: return "contact";
    case 2: return "cut";
    case 3: return "tear";
    case 4: return "burn";
    case 5: return "drain";
    case 6: return "attachment_broken";
    default: return "unknown";
  }
}

// event_t.magnitude's unit: by the simulation's event name where it has one (core/instruments/
// instrument_events.hpp), else by the telemetry kind (event_t.lcm).
const char* event_unit(const EventRecord& e) {
  const std::string& w = e.what;
  if (w == "excessive_retina_force" || w == "attachment_broken" || w == "tissue_attachment_broken") return "uN";
  if (w == "unintended_tear") return "strain";
  if (w == "laser_burn") return "mm (burn diameter)";
  if (w == "light_too_close" || w == "laser_on_detached_retina" || w == "grasp") return "mm";
  if (w == "light_toxicity") return "J/cm2";
  if (w == "instrument_collision" || w == "lens_touch" || w == "wall_contact") return "mm (depth)";
  if (w == "grasp_lost" || w == "tissue_grip_broken") return "uN";
  if (w == "tissue_tear") return "strain";  // core TissueEvent: a tear's magnitude is the strain at which it tore
  switch (e.kind) {
    case 1: return "mN";
    case 2: case 3: return "mm";
    case 4: return "mJ";
    case 5: return "mm3";
    case 6: return "mN";
    default: return "";
  }
}

// Events an instructor looks for on the fundus: harm and loss of control.
bool iatrogenic(const std::string& what) {
  return what == "excessive_retina_force" || what == "unintended_tear" || what == "laser_on_detached_retina" ||
         what == "light_too_close" || what == "light_toxicity" || what == "instrument_collision" || what == "lens_touch" ||
         what == "wall_contact";
}

template <class R>
const R* final_or_last(const std::vector<R>& v) {
  for (auto it = v.rbegin(); it != v.rend(); ++it)
    if (it->final_score) return &*it;
  return v.empty() ? nullptr : &v.back();
}

std::int32_t event_count(const TotalsRecord& t, const char* what) {
  for (const auto& [k, n] : t.events_by_kind)
    if (k == what) return n;
  return 0;
}

std::optional<core::CriterionKind> criterion_kind(const std::string& name) {
  for (int k = 0; k <= static_cast<int>(core::CriterionKind::kTargetsReached); ++k)  // the last kind
    if (name == core::to_string(static_cast<core::CriterionKind>(k))) return static_cast<core::CriterionKind>(k);
  return std::nullopt;
}

// The scoring's inputs as core::compute_scores takes them, rebuilt from the published totals.
core::SessionTotals as_core_totals(const TotalsRecord& t) {
  core::SessionTotals c;
  c.elapsed_s = t.elapsed_s;
  c.path_length_mm = t.path_length_mm;
  c.retina_contacts = static_cast<std::uint32_t>(t.retina_contacts);
  c.retina_contact_time_s = t.retina_contact_time_s;
  c.peak_retina_force_un = t.peak_retina_force_un;
  c.retina_force_impulse_un_s = t.retina_force_impulse_un_s;
  c.time_over_force_limit_s = t.time_over_force_limit_s;
  c.force_limit_un = t.force_limit_un;
  for (std::size_t k = 0; k < core::kInstrumentEventKinds; ++k)
    c.events[k] = static_cast<std::uint32_t>(std::max(0, event_count(t, telemetry::event_key(static_cast<core::InstrumentEventKind>(k)))));
  c.burns_on_target = static_cast<std::uint32_t>(t.burns_on_target);
  c.burns_elsewhere = static_cast<std::uint32_t>(t.burns_elsewhere);
  c.retina_tears = static_cast<std::uint32_t>(t.retina_tears);
  c.other_tears = static_cast<std::uint32_t>(t.other_tears);
  c.illumination_measured = t.illumination_measured;
  c.working_time_s = t.working_time_s;
  c.lit_working_time_s = t.lit_working_time_s;
  c.microscope_measured = t.microscope_measured;
  c.microscope_working_time_s = t.microscope_working_time_s;
  c.out_of_field_s = t.out_of_field_s;
  c.off_centre_s = t.off_centre_s;
  c.out_of_focus_s = t.out_of_focus_s;
  c.extreme_zoom_s = t.extreme_zoom_s;
  return c;
}

struct Recomputed {
  bool possible = false;
  core::ScoreCard card;
  double progress = 1.0;  // P
  double time_limit_s = 0;
};

Recomputed recompute(const TotalsRecord* t, const CriteriaRecord* c) {
  Recomputed r;
  if (!t || !c) return r;
  std::vector<core::CriterionProgress> criteria;
  double sum = 0;
  int goals = 0;
  for (const auto& cr : c->criteria) {
    const auto kind = criterion_kind(cr.kind);
    if (!kind) return r;
    core::CriterionProgress p;
    p.kind = *kind;
    p.target = cr.target;
    p.threshold = cr.threshold;
    p.value = cr.value;
    p.progress = cr.progress;
    p.met = cr.met;
    criteria.push_back(p);
    if (*kind == core::CriterionKind::kTimeLimit) r.time_limit_s = cr.threshold;
    else {
      sum += cr.progress;
      ++goals;
    }
  }
  r.progress = goals > 0 ? sum / goals : 1.0;
  core::compute_scores(as_core_totals(*t), criteria, r.time_limit_s, core::ScoreOptions{}, r.card);
  r.possible = true;
  return r;
}

// Each category: its formula (core/metrics/README.md) and the inputs it was computed from.
void write_category_inputs(JsonWriter& j, const std::string& name, const TotalsRecord& t, const Recomputed& r) {
  const core::ScoreOptions o;
  const double limit = t.force_limit_un > 0 ? t.force_limit_un : 1.0;
  j.key("inputs").begin_object();
  j.field("P_mean_criterion_progress", r.progress, "share (0..1)");
  if (name == "target_achievement") {
    j.key("formula").value("100 * P");
  } else if (name == "efficiency") {
    j.key("formula").value("100 * P * [0.5 * h(t/P, T) + 0.5 * h(L/P, L_half)], h(x, x_half) = 1/(1 + x/x_half)");
    j.field("t_elapsed", t.elapsed_s, "s");
    j.field("L_path_all_tips", t.path_length_mm, "mm");
    j.field("T_reference_time", r.time_limit_s > 0 ? r.time_limit_s : o.reference_time_s, "s");
    j.field("L_half_reference_path", o.reference_path_mm, "mm");
  } else if (name == "tissue_treatment") {
    j.key("formula").value("100 * P * exp(-D), D = damage in e-folds (terms below)");
    j.field("time_over_force_limit", t.time_over_force_limit_s, "s");
    j.field("retina_force_impulse", t.retina_force_impulse_un_s, "uN*s");
    j.field("peak_retina_force", t.peak_retina_force_un, "uN");
    j.field("force_limit", t.force_limit_un, "uN");
    j.field("excessive_force_entries", event_count(t, "excessive_retina_force"), "count");
    j.field("retina_tears", t.retina_tears, "count");
    j.field("lens_touches", event_count(t, "lens_touch"), "count");
    j.field("wall_contacts", event_count(t, "wall_contact"), "count");
    j.field("light_toxicity", event_count(t, "light_toxicity"), "count");
    j.field("light_too_close", event_count(t, "light_too_close"), "count");
    j.field("burns_on_detached_retina", event_count(t, "laser_on_detached_retina"), "count");
    j.field("burns_off_target", t.burns_elsewhere, "count");
    j.key("damage_terms").begin_object();
    j.field("over_limit", o.per_second_over_limit * t.time_over_force_limit_s, "e-folds");
    j.field("impulse", o.per_limit_second * t.retina_force_impulse_un_s / limit, "e-folds");
    j.field("peak", o.per_peak_squared * (t.peak_retina_force_un / limit) * (t.peak_retina_force_un / limit), "e-folds");
    j.field("excessive_force", o.per_excessive_force * event_count(t, "excessive_retina_force"), "e-folds");
    j.field("retina_tears", o.per_retina_tear * t.retina_tears, "e-folds");
    j.field("lens_touches", o.per_lens_touch * event_count(t, "lens_touch"), "e-folds");
    j.field("wall_contacts", o.per_wall_contact * event_count(t, "wall_contact"), "e-folds");
    j.field("light_toxicity", o.per_light_toxicity * (event_count(t, "light_toxicity") > 0 ? 1 : 0), "e-folds");
    j.field("light_too_close", o.per_light_too_close * (event_count(t, "light_too_close") > 0 ? 1 : 0), "e-folds");
    j.field("burns_on_detached", o.per_burn_on_detached * event_count(t, "laser_on_detached_retina"), "e-folds");
    j.field("burns_off_target", o.per_burn_off_target * t.burns_elsewhere, "e-folds");
    j.end_object();
  } else if (name == "instrument_handling") {
    j.key("formula").value("100 * P * exp(-C) * (1 - s + s * lit), C = 0.3/collision + 0.05/retinal contact + 0.2/lost grasp");
    j.field("instrument_collisions", event_count(t, "instrument_collision"), "count");
    j.field("retinal_contact_entries", t.retina_contacts, "count");
    j.field("lost_grasps", event_count(t, "grasp_lost"), "count");
    j.key("illumination_measured").value(t.illumination_measured);
    j.field("lit_share", t.working_time_s > 0 ? t.lit_working_time_s / t.working_time_s : 1.0, "share (0..1)");
    j.field("s_illumination_share", t.illumination_measured ? o.illumination_share : 0.0, "share (0..1)");
  } else if (name == "microscope_handling") {
    j.key("formula").value("100 * P * exp(-V), V = 2.0 * out_of_field + 0.5 * off_centre + 1.0 * out_of_focus + 1.0 * extreme_zoom (shares of W)");
    const double w = t.microscope_working_time_s;
    auto share = [w](double s) { return w > 0 ? std::clamp(s / w, 0.0, 1.0) : 0.0; };
    j.field("W_working_time", w, "s");
    j.field("out_of_field_share", share(t.out_of_field_s), "share (0..1)");
    j.field("off_centre_share", share(t.off_centre_s), "share (0..1): mean c^2, c = (min(r,1) - 0.5)/0.5 beyond half the field radius");
    j.field("out_of_focus_share", share(t.out_of_focus_s), "share (0..1)");
    j.field("extreme_zoom_share", share(t.extreme_zoom_s), "share (0..1)");
    j.key("view_terms").begin_object();
    j.field("out_of_field", o.per_out_of_field * share(t.out_of_field_s), "e-folds");
    j.field("off_centre", o.per_off_centre * share(t.off_centre_s), "e-folds");
    j.field("out_of_focus", o.per_out_of_focus * share(t.out_of_focus_s), "e-folds");
    j.field("extreme_zoom", o.per_extreme_zoom * share(t.extreme_zoom_s), "e-folds");
    j.end_object();
  }
  j.end_object();
}

// Every k-th sample so a series holds at most max_points (deterministic; the last one always kept).
// device_status_t::STATE_* in words.
const char* device_state_name(int state) {
  switch (state) {
    case 0: return "unconfigured";
    case 1: return "inactive";
    case 2: return "active";
    case 3: return "error";
    case 4: return "lost";
    default: return "unknown";
  }
}

// The causes a device's frames were refused for, as report.json names them and as the line below
// says them, in PROTOCOL.md's receiver order.
struct RefusalCause {
  const char* key;
  const char* words;
  std::int64_t DeviceRecord::*count;
};
constexpr RefusalCause kRefusalCauses[] = {
    {"crc", "CRC", &DeviceRecord::crc_errors},          {"framing", "framing", &DeviceRecord::framing_errors},
    {"version", "version", &DeviceRecord::version_rejected}, {"unknown_type", "type", &DeviceRecord::unknown_type_rejected},
    {"length", "length", &DeviceRecord::length_rejected}, {"range", "out of range or NaN", &DeviceRecord::range_rejected},
    {"identity", "identity", &DeviceRecord::identity_rejected}, {"protocol", "protocol", &DeviceRecord::protocol_rejected}};

// One line of what went wrong with a device ("" when nothing did): what an instructor reads before
// trusting the score, and a technician before the next session.
std::string device_fault_sentence(const DeviceRecord& d) {
  std::vector<std::string> parts;
  const auto count = [&](std::int64_t n, const char* what) {
    if (n > 0) parts.push_back(std::to_string(n) + " " + what);
  };
  std::map<std::string, int> spells;
  for (const auto& sp : d.spells) ++spells[sp.what];
  for (const auto& [what, n] : spells) parts.push_back(what + " " + std::to_string(n) + (n == 1 ? " time" : " times"));
  if (d.stuck_samples > 0) parts.push_back(std::to_string(d.stuck_samples) + " samples frozen while stuck");
  std::int64_t refused = 0;
  std::string causes;
  for (const RefusalCause& c : kRefusalCauses) {
    const std::int64_t n = d.*c.count;
    if (n == 0) continue;
    refused += n;
    causes += (causes.empty() ? "" : ", ") + std::string(c.words) + " " + std::to_string(n);
  }
  if (refused > 0) parts.push_back(std::to_string(refused) + " frames refused (" + causes + ")");
  count(d.sequence_gaps, "frames missing from the sequence (lost on the way or refused)");
  count(d.timestamp_jumps, "timestamp jumps");
  count(d.heartbeat_misses, "heartbeat misses");
  count(d.reconnects, "reconnects");
  if (d.reader_stalls > 0) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "the reader stalled %lld times (longest %.0f ms; the host was busy, not the device)",
                  static_cast<long long>(d.reader_stalls), d.reader_stall_max_ms);
    parts.push_back(buf);
  }
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) out += (i ? "; " : "") + parts[i];
  return out;
}

std::vector<std::size_t> decimate(std::size_t n, std::size_t max_points) {
  std::vector<std::size_t> idx;
  if (n == 0) return idx;
  const std::size_t k = n <= max_points ? 1 : (n + max_points - 1) / max_points;
  for (std::size_t i = 0; i < n; i += k) idx.push_back(i);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  return idx;
}

constexpr std::size_t kMaxSeriesPoints = 2500;

void write_array(JsonWriter& j, const std::vector<double>& v, const std::vector<std::size_t>& idx) {
  j.begin_array();
  for (const std::size_t i : idx) j.value(v[i]);
  j.end_array();
}

}  // namespace

std::string report_json(const SessionLog& log, const Survey* survey, const std::string& survey_problem, const std::string& trainee,
                        const CaseAnatomy* anatomy) {
  JsonWriter j;
  const ScoreRecord* score = final_or_last(log.scores);
  const CriteriaRecord* criteria = final_or_last(log.criteria);
  const TotalsRecord* totals = final_or_last(log.totals);
  const Recomputed re = recompute(totals, criteria);

  std::vector<std::string> notices;
  if (!log.notice.empty()) notices.push_back(log.notice);
  if (log.messages_skipped > 0)
    notices.push_back(std::to_string(log.messages_skipped) + " messages in the log did not decode and were left out");
  if (!score) notices.push_back("the log holds no score card: the session ended before its first score (1 s)");
  else if (!score->final_score)
    notices.push_back("no final score in the log: the session did not end normally; the numbers are the last running ones, at step " +
                      std::to_string(score->step));
  if (!survey_problem.empty()) notices.push_back("survey.json not shown: " + survey_problem);
  for (const auto& d : log.devices) {
    // A device that was lost, stuck, stale or refused during the session: the score was made with
    // that instrument, pedal or fixture not (or not truly) following the hand.
    if (!d.spells.empty()) notices.push_back(d.name + " during the session: " + device_fault_sentence(d));
  }
  if (totals && totals->formula_version != core::kScoreFormulaVersion)
    notices.push_back("the session scored with formulas version " + std::to_string(totals->formula_version) + "; this report knows version " +
                      std::to_string(core::kScoreFormulaVersion) + " (the inputs' recomputation is not comparable)");

  j.begin_object();
  j.key("report_format").value(kReportFormat);
  j.key("formula_version").value(totals ? totals->formula_version : 0);
  j.key("formulas").value("core/metrics/README.md, section Scores");
  j.key("source").begin_object();
  j.key("telemetry_log").value(log.path.substr(log.path.find_last_of('/') + 1));
  j.field("bytes", static_cast<double>(log.file_bytes), "bytes");
  j.key("events_read").value(static_cast<std::int64_t>(log.events_read));
  j.key("messages_skipped").value(static_cast<std::int64_t>(log.messages_skipped));
  j.key("complete").value(log.complete);
  j.end_object();
  j.key("trainee").value(trainee);
  j.key("notices").begin_array();
  for (const auto& n : notices) j.value(n);
  j.end_array();

  // The case and how far the session got.
  double last_t = 0;
  std::int64_t last_step = 0;
  for (const auto& s : log.tips) last_t = std::max(last_t, s.t_s), last_step = std::max(last_step, s.step);
  j.key("case").begin_object();
  j.key("id").value(score ? score->case_id : criteria ? criteria->case_id : "");
  j.key("ended").value(score && score->final_score);
  j.key("score_step").value(score ? score->step : 0);
  j.field("elapsed_scored", totals ? totals->elapsed_s : 0.0, "s");
  j.field("session_length", last_t, "s");
  j.key("last_step").value(last_step);
  j.key("started_utime_us").value(log.first_utime_us);  // the log's first event (wall clock, µs since the epoch)
  // Whether the case was completed: every criterion but the time limit met, as the criteria were
  // published with the (final) score — what ended the case early (core/metrics/README.md, "The end
  // of a case"); false for a session cut short.
  bool completed = score && score->final_score && criteria;
  if (criteria) {
    for (const auto& c : criteria->criteria) completed = completed && (c.met || c.kind == "time_limit");
  }
  j.key("completed").value(completed);
  // The case's pass score (its file's [proficiency] pass_score) and whether this attempt passed: the
  // case completed, with a final score at or above it (a high score on a case left unfinished does
  // not pass).
  if (score) j.field("pass_score", score->pass_score, "points (0..100)");
  j.key("passed").value(completed && score->total >= score->pass_score);
  // The physics period, from the samples' own time and step (1 ms when the log has none).
  j.field("step_period", last_step > 0 ? last_t / static_cast<double>(last_step) : 0.001, "s");
  j.end_object();

  // Criteria, as the rig measured them with the (final) score.
  j.key("criteria").begin_array();
  if (criteria) {
    for (const auto& c : criteria->criteria) {
      j.begin_object();
      j.key("kind").value(c.kind);
      j.key("target").value(c.target);
      j.field("value", c.value, criterion_unit(c.kind));
      j.field("threshold", c.threshold, criterion_unit(c.kind));
      j.field("progress", c.progress, "share (0..1)");
      j.key("met").value(c.met);
      j.end_object();
    }
  }
  j.end_array();

  // The score card: what the rig published, each category's formula and inputs, and whether the
  // inputs reproduce the published values (core::compute_scores on the published totals).
  j.key("score").begin_object();
  j.field("total", score ? score->total : 0.0, "points (0..100)");
  j.key("final").value(score && score->final_score);
  j.key("step").value(score ? score->step : 0);
  j.key("categories").begin_array();
  if (score) {
    for (const auto& [name, value] : score->categories) {
      j.begin_object();
      j.key("name").value(name);
      j.field("value", value, "points (0..100)");
      const core::ScoreEntry* e = re.possible ? re.card.find(name) : nullptr;
      j.key("weight").value(e ? e->weight : 0.0);
      j.field("recomputed", e ? e->value : std::nan(""), "points (0..100)");
      if (totals) write_category_inputs(j, name, *totals, re);
      j.end_object();
    }
  }
  j.end_array();
  bool reproduced = re.possible && score && std::abs(re.card.total - score->total) < 1e-6;
  for (const auto& [name, value] : score ? score->categories : std::vector<std::pair<std::string, double>>{}) {
    const core::ScoreEntry* e = re.possible ? re.card.find(name) : nullptr;
    reproduced = reproduced && e && std::abs(e->value - value) < 1e-6;
  }
  j.key("inputs_reproduce_published_score").value(reproduced);
  j.end_object();

  // The scoring's totals (the odometer, retinal contacts, forces, events).
  j.key("totals").begin_object();
  if (totals) {
    const TotalsRecord& t = *totals;
    j.field("elapsed", t.elapsed_s, "s");
    j.field("path_length", t.path_length_mm, "mm");
    j.field("retina_contacts", t.retina_contacts, "count");
    j.field("retina_contact_time", t.retina_contact_time_s, "s");
    j.field("peak_retina_force", t.peak_retina_force_un, "uN");
    j.field("retina_force_impulse", t.retina_force_impulse_un_s, "uN*s");
    j.field("time_over_force_limit", t.time_over_force_limit_s, "s");
    j.field("force_limit", t.force_limit_un, "uN");
    j.field("burns_on_target", t.burns_on_target, "count");
    j.field("burns_elsewhere", t.burns_elsewhere, "count");
    j.field("retina_tears", t.retina_tears, "count");
    j.field("other_tears", t.other_tears, "count");
    j.field("iatrogenic_events", t.iatrogenic_events, "count");
    j.field("working_time", t.working_time_s, "s");
    j.field("lit_working_time", t.lit_working_time_s, "s");
    j.key("microscope_measured").value(t.microscope_measured);
    j.field("microscope_working_time", t.microscope_working_time_s, "s");
    j.field("out_of_field", t.out_of_field_s, "s");
    j.field("off_centre", t.off_centre_s, "s (integral of c^2)");
    j.field("out_of_focus", t.out_of_focus_s, "s");
    j.field("extreme_zoom", t.extreme_zoom_s, "s");
    j.key("events_by_kind").begin_object();
    for (const auto& [k, n] : t.events_by_kind) j.field(k, n, "count");
    j.end_object();
    j.key("instruments").begin_array();
    for (const auto& in : t.instruments) {
      j.begin_object();
      j.key("kind").value(in.kind);
      j.field("path_length", in.path_mm, "mm");
      j.field("retina_contacts", in.contacts, "count");
      j.field("retina_contact_time", in.contact_time_s, "s");
      j.field("peak_retina_force", in.peak_force_un, "uN");
      j.end_object();
    }
    j.end_array();
  }
  j.end_object();

  // Per hand (tracker): the tip's path inside the eye with its speed, the retina force it felt.
  std::map<int, std::vector<const TipSample*>> hands;
  for (const auto& s : log.tips) hands[s.instrument].push_back(&s);
  // The case's anatomy under the tip paths (from the session's recording).
  j.key("anatomy");
  if (anatomy) {
    j.begin_object();
    j.key("case").value(anatomy->case_id);
    j.key("units").begin_object();
    j.key("x").value("mm");
    j.key("y").value("mm");
    j.end_object();
    j.key("outlines").begin_array();
    for (const FundusOutline& o : anatomy->outlines) {
      j.begin_object();
      j.key("name").value(o.name);
      j.key("kind").value(o.kind);
      std::vector<std::size_t> all(o.x_mm.size());
      for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
      j.key("x");
      write_array(j, o.x_mm, all);
      j.key("y");
      write_array(j, o.y_mm, all);
      j.end_object();
    }
    j.end_array();
    j.end_object();
  } else {
    j.value(nullptr);
  }

  j.key("hands").begin_array();
  for (const auto& [id, samples] : hands) {
    std::vector<double> t, x, y, z, speed, force, actuation;
    std::vector<std::string> kinds;
    double drawn = 0, vmax = 0, fmax = 0;
    const TipSample* prev = nullptr;
    for (const TipSample* s : samples) {
      t.push_back(s->t_s);
      x.push_back(s->tip_mm[0]);
      y.push_back(s->tip_mm[1]);
      z.push_back(s->tip_mm[2]);
      force.push_back(s->retina_force_un);
      actuation.push_back(s->actuation);
      fmax = std::max(fmax, s->retina_force_un);
      double v = 0;
      const bool inside = s->port >= 0 && s->insertion_mm > 0;
      if (prev && inside && prev->port >= 0 && prev->insertion_mm > 0 && s->t_s > prev->t_s) {
        const double d = std::hypot(s->tip_mm[0] - prev->tip_mm[0], s->tip_mm[1] - prev->tip_mm[1], s->tip_mm[2] - prev->tip_mm[2]);
        drawn += d;
        v = d / (s->t_s - prev->t_s);
      }
      speed.push_back(inside ? v : std::nan(""));  // null: outside the eye, no path drawn
      vmax = std::max(vmax, v);
      if (std::find(kinds.begin(), kinds.end(), s->kind) == kinds.end()) kinds.push_back(s->kind);
      prev = s;
    }
    const auto idx = decimate(t.size(), kMaxSeriesPoints);
    j.begin_object();
    j.key("tracker").value(id);
    j.key("instrument_kinds").begin_array();
    for (const auto& k : kinds) j.value(k);
    j.end_array();
    j.key("samples").value(static_cast<std::int64_t>(samples.size()));
    j.field("sampled_path_length", drawn, "mm");
    j.field("max_speed", vmax, "mm/s");
    j.field("peak_retina_force", fmax, "uN");
    j.key("series").begin_object();
    j.key("units").begin_object();
    j.key("t").value("s");
    j.key("x").value("mm");
    j.key("y").value("mm");
    j.key("z").value("mm");
    j.key("speed").value("mm/s");
    j.key("retina_force").value("uN");
    j.key("actuation").value("share (0..1)");
    j.end_object();
    j.key("t");
    write_array(j, t, idx);
    j.key("x");
    write_array(j, x, idx);
    j.key("y");
    write_array(j, y, idx);
    j.key("z");
    write_array(j, z, idx);
    j.key("speed");
    write_array(j, speed, idx);
    j.key("retina_force");
    write_array(j, force, idx);
    j.key("actuation");
    write_array(j, actuation, idx);
    j.end_object();
    j.end_object();
  }
  j.end_array();

  // The pedals' controls over time, the travel that set them, the macula's light dose.
  {
    std::vector<double> t, vac, cut, light, dose;
    std::vector<double> vit_travel[4], mic_travel[4];
    double dose_limit = 0.0;
    for (const auto& c : log.controls) {
      t.push_back(c.t_s);
      vac.push_back(c.vacuum_mmhg);
      cut.push_back(c.cut_rate_cpm);
      light.push_back(c.light_level);
      dose.push_back(c.macula_dose_j_cm2);
      dose_limit = c.dose_limit_j_cm2;
      for (int a = 0; a < 4; ++a) {
        vit_travel[a].push_back(c.vitrectomy_travel[a]);
        mic_travel[a].push_back(c.microscope_travel[a]);
      }
    }
    const auto idx = decimate(t.size(), kMaxSeriesPoints);
    j.key("controls").begin_object();
    j.key("units").begin_object();
    j.key("t").value("s");
    j.key("vacuum").value("mmHg");
    j.key("cut_rate").value("cuts/min");
    j.key("light_level").value("share (0..1)");
    j.key("vitrectomy_pedal_travel").value("share of each axis' travel (0..1)");
    j.key("microscope_pedal_travel").value("share of each axis' travel (0..1)");
    j.key("macula_light_dose").value("J/cm2");
    j.key("light_dose_limit").value("J/cm2");
    j.end_object();
    j.key("t");
    write_array(j, t, idx);
    j.key("vacuum");
    write_array(j, vac, idx);
    j.key("cut_rate");
    write_array(j, cut, idx);
    j.key("light_level");
    write_array(j, light, idx);
    for (const auto& [name, axes] : {std::pair{"vitrectomy_pedal_travel", &vit_travel}, std::pair{"microscope_pedal_travel", &mic_travel}}) {
      j.key(name).begin_array();
      for (const auto& axis : *axes) write_array(j, axis, idx);
      j.end_array();
    }
    j.key("macula_light_dose");
    write_array(j, dose, idx);
    j.key("light_dose_limit").value(dose_limit);
    j.end_object();
  }

  // The running score (1 Hz and final).
  j.key("score_timeline").begin_array();
  for (const auto& s : log.scores) {
    j.begin_object();
    j.key("step").value(s.step);
    j.key("final").value(s.final_score);
    j.key("total").value(s.total);
    for (const auto& [name, value] : s.categories) j.key(name).value(value);
    j.end_object();
  }
  j.end_array();

  // Events, each with where and when; counts by the simulation's name.
  std::map<std::string, std::int64_t> counts;
  for (const auto& e : log.events) ++counts[e.what.empty() ? event_kind_name(e.kind) : e.what];
  j.key("event_counts").begin_object();
  for (const auto& [k, n] : counts) j.field(k, static_cast<double>(n), "count");
  j.end_object();
  j.key("events").begin_array();
  for (const auto& e : log.events) {
    j.begin_object();
    j.key("t").measure(e.t_s, "s");
    j.key("step").value(e.step);
    j.key("kind").value(event_kind_name(e.kind));
    j.key("what").value(e.what);
    j.key("iatrogenic").value(iatrogenic(e.what));
    j.key("instrument").value(e.instrument);
    j.key("tissue").value(e.tissue);
    j.key("position_mm").begin_array().value(e.position_mm[0]).value(e.position_mm[1]).value(e.position_mm[2]).end_array();
    j.field("magnitude", e.magnitude, event_unit(e));
    j.end_object();
  }
  j.end_array();

  // The devices: link and sensor faults, as the rig reported them (device_status_t), so the
  // instructor sees when a score was made on a stuck or lost tracker, and the technician what failed.
  j.key("devices").begin_array();
  for (const auto& d : log.devices) {
    j.begin_object();
    j.key("device_id").value(d.device_id);
    j.key("name").value(d.name);
    j.key("transport").value(d.transport);
    j.key("calibration").value(d.calibration);
    j.key("state").value(device_state_name(d.state));
    j.key("detail").value(d.detail);
    j.key("status_messages").value(static_cast<std::int64_t>(d.status_messages));
    j.key("frames_rx").value(d.frames_rx);
    j.key("refused").begin_object();
    for (const RefusalCause& c : kRefusalCauses) j.key(c.key).value(d.*c.count);
    j.end_object();
    j.key("sequence_gaps").value(d.sequence_gaps);
    j.key("heartbeat_misses").value(d.heartbeat_misses);
    j.key("reconnects").value(d.reconnects);
    j.key("stuck_episodes").value(d.stuck_episodes);
    j.key("stuck_samples").value(d.stuck_samples);
    j.key("timestamp_jumps").value(d.timestamp_jumps);
    j.key("reader_stalls").value(d.reader_stalls);
    j.field("reader_stall_max", d.reader_stall_max_ms, "ms");
    j.key("spells").begin_array();
    for (const auto& sp : d.spells) {
      j.begin_object();
      j.key("what").value(sp.what);
      j.field("from", sp.from_s, "s");
      if (sp.to_s >= 0) j.field("to", sp.to_s, "s");
      else j.key("to").value(nullptr);  // still so at the end of the log
      j.key("detail").value(sp.detail);
      j.end_object();
    }
    j.end_array();
    j.key("faults").value(device_fault_sentence(d));
    j.end_object();
  }
  j.end_array();

  // The post-session survey (Appendix C of the thesis), when the folder has one.
  if (survey) {
    const Survey& v = *survey;
    j.key("survey").begin_object();
    j.key("format").value(kSurveyFormat);
    j.key("subject").value(v.subject);
    j.key("date").value(v.date);
    j.field("cooper_harper_rating", v.rating, "modified Cooper-Harper (1 very easy .. 10 impossible)");
    j.key("rating_text").value(v.rating_text);
    j.key("accomplished").value(v.accomplished);
    if (v.errors_small) j.key("errors_small").value(*v.errors_small);
    if (v.workload_acceptable) j.key("workload_acceptable").value(*v.workload_acceptable);
    j.key("page").value(v.page);
    j.key("level").value(v.level);
    j.key("categories").begin_object();
    for (const auto& [k, level] : v.categories) j.key(k).value(level);
    j.end_object();
    j.key("instruments").begin_object();
    for (const auto& [k, r] : v.instruments) {
      j.key(k).begin_object();
      j.key("rating").value(r.rating);
      j.key("comment").value(r.comment);
      j.end_object();
    }
    j.end_object();
    j.key("comments").value(v.comments);
    j.end_object();
  } else {
    j.key("survey").value(nullptr);
  }
  j.end_object();
  std::string out = j.take();
  out += '\n';
  return out;
}

}  // namespace vitreo::report
