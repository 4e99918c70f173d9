#pragma once
// What every telemetry field is, in one place: from the core's and the rig's state to the
// fixed-size items the producers push (physics and driver threads: no allocation, no encoding), and
// from those items to the lcm-gen messages the telemetry thread publishes. The .lcm files under
// lcmtypes/ document the fields (frame, units, direction, names); CHANNELS.md the channels and
// rates; tests/rig/session/telemetry_contract_test.cpp decodes what a session published and checks
// it against them.
//
// Data flows one way: core/rig state → item → message. Nothing here reads a clock; the producers
// pass the step, the simulation time and (for devices) the host time in.
#include <cstdint>
#include <string_view>
#include <vector>

#include "core/instruments/instrument_events.hpp"
#include "core/instruments/instrument_system.hpp"
#include "core/metrics/session_metrics.hpp"
#include "core/tissue/tissue_world.hpp"
#include "drivers/session.hpp"
#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/telemetry/items.hpp"
#include "vitreo_lcm/controls_t.hpp"
#include "vitreo_lcm/criteria_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/physics_timing_t.hpp"
#include "vitreo_lcm/score_t.hpp"
#include "vitreo_lcm/session_totals_t.hpp"

namespace vitreo::telemetry {

// ---- State → items (producer threads) ------------------------------------------------------------

// One tracked hand as the rig sees it: which tracker (0 the working hand, 1 the light-pipe hand),
// the eye's port its instrument goes through (0 infusion, 1 working_1, 2 working_2), what it holds
// (core's name of the instrument kind) and whether its tracker is lost or stuck (frozen).
struct Hand {
  int tracker = 0;
  int eye_port = -1;
  const char* holds = "";
  bool frozen = false;
};

// instrument_state_t: the simulated instrument the hand drives, as the core placed it — in the eye
// frame (the fixture's reading turned by the eye's rotation, so it agrees with the picture), the
// shaft axis from the tip toward the handle, the port -1 while the tip is outside the globe.
InstrumentState instrument_state_item(const Hand& hand, const core::InstrumentState& sim, std::int64_t step, double t_s);

// event_t from an instrument event; `hand` is the tracker whose instrument caused it (-1: none).
Event instrument_event_item(const core::InstrumentEvent& e, int hand, std::int64_t step, double t_s);
// event_t from a tissue event that no instrument event reports (see tissue_event_passed_on()).
Event tissue_event_item(const core::TissueEvent& e, std::int64_t step, double t_s);
// One event_t per occurrence: the instruments pass some tissue events on as their own (a broken
// attachment, a grip that slipped, a tear of the retina, with who caused it), and such a tissue
// event is not published a second time. Matched by surface, place and magnitude, not by kind, so
// whatever the instruments pass on is recognised.
bool tissue_event_passed_on(const core::TissueEvent& e, const std::vector<core::InstrumentEvent>& instrument_events);

// One step's event_t items, each occurrence once: the tissue's events that no instrument event
// reports (a rolled-back step reports none of its own), then the instruments' events with the hand
// each came from (hand_of(core instrument index) → tracker, -1 for none). push(Event) per item.
template <class HandOf, class Push>
void step_event_items(const std::vector<core::TissueEvent>& tissue_events, const std::vector<core::InstrumentEvent>& instrument_events,
                      std::int64_t step, double t_s, HandOf&& hand_of, Push&& push) {
  for (const core::TissueEvent& e : tissue_events) {
    if (e.kind == core::TissueEventKind::kRolledBack || tissue_event_passed_on(e, instrument_events)) continue;
    push(tissue_event_item(e, step, t_s));
  }
  for (const core::InstrumentEvent& e : instrument_events)
    push(instrument_event_item(e, e.instrument == core::kNone ? -1 : hand_of(e.instrument), step, t_s));
}

// score_t, criteria_t and session_totals_t of the current case (score() and criteria() as the
// metrics measured them last).
// pass_score: the case's ([proficiency] pass_score), carried on every card.
Score score_item(const core::ScoreCard& card, std::string_view case_id, std::int64_t step, bool final_score, double pass_score);
Criteria criteria_item(const std::vector<core::CriterionProgress>& criteria, std::string_view case_id, std::int64_t step, bool final_score);
Totals totals_item(const core::SessionMetrics& metrics, std::string_view case_id, std::int64_t step, bool final_score);

// controls_t: what the pedal mapping set (rig/input/controls.hpp), passed as plain numbers so this
// file needs no rig/input header; and the endolaser console's next shot.
struct ControlsState {
  double vacuum_mmhg = 0, cut_rate_cpm = 0;
  bool reflux = false, laser_fire = false, pick_out = false;
  double light_level = 0, zoom = 1;
  double laser_power_mw = 0, laser_duration_ms = 0;
  const double* vitrectomy_pedal_travel = nullptr;  // 4 axes each; null: all 0
  const double* microscope_pedal_travel = nullptr;
  double macula_light_dose_j_cm2 = 0, light_dose_limit_j_cm2 = 0;
};
Controls controls_item(const ControlsState& c, std::int64_t step, double t_s);

// physics_timing_t over one window of steps (FixedStepLoop::window_stats()): the histograms' steps
// and quantiles are the window's, the counters cumulative.
PhysicsTiming timing_item(const runtime::LoopStats& window, std::uint64_t last_step, std::int64_t period_ns, bool paused);

// device_status_t of one device, on its driver thread. What the session alone does not know — the
// sample rate and latency measured over the last samples, the driver thread's stalls — comes in
// `measured`.
struct DeviceMeasured {
  float sample_rate_hz = 0;     // samples per second over the last second
  float latency_p50_us = 0, latency_p99_us = 0;
  std::uint64_t reader_stalls = 0;
  float reader_stall_max_ms = 0;
  double session_t_s = 0;  // the hub's clock since the session's first step (device_status_t.t_s)
};
DeviceStatus device_status_item(std::int32_t device_id, std::string_view name, std::string_view transport,
                                const drivers::DeviceSession& session, std::uint64_t now_us, const DeviceMeasured& measured,
                                std::string_view calibration = {});
// device_status_t's lifecycle code of a link state (a refused device is STATE_ERROR whatever its
// link does).
std::int8_t device_state_code(drivers::LinkState s, bool refused);

// ---- Items → messages (the telemetry thread) ------------------------------------------------------
// utime_us: the host's wall clock at publish (LCM's convention). physics_timing_t's
// telemetry_dropped is the publisher's to fill.
vitreo_lcm::instrument_state_t to_lcm(const InstrumentState& v, std::int64_t utime_us);
vitreo_lcm::event_t to_lcm(const Event& v, std::int64_t utime_us);
vitreo_lcm::physics_timing_t to_lcm(const PhysicsTiming& v, std::int64_t utime_us);
vitreo_lcm::device_status_t to_lcm(const DeviceStatus& v, std::int64_t utime_us);
vitreo_lcm::score_t to_lcm(const Score& v, std::int64_t utime_us);
vitreo_lcm::criteria_t to_lcm(const Criteria& v, std::int64_t utime_us);
vitreo_lcm::session_totals_t to_lcm(const Totals& v, std::int64_t utime_us);
vitreo_lcm::controls_t to_lcm(const Controls& v, std::int64_t utime_us);

}  // namespace vitreo::telemetry
