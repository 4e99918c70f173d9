// Telemetry publisher against real LCM providers (memq, file). All LCM calls stay on one thread per
// test (the "telemetry thread"), as in the rig; producers only touch their ring.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <memory>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/fixed_step_loop.hpp"
#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "rig/telemetry/publisher.hpp"
#include "vitreo_lcm/controls_t.hpp"
#include "vitreo_lcm/criteria_t.hpp"
#include "vitreo_lcm/device_status_t.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/instrument_state_t.hpp"
#include "vitreo_lcm/physics_timing_t.hpp"
#include "vitreo_lcm/score_t.hpp"
#include "vitreo_lcm/session_totals_t.hpp"

using namespace vitreo::telemetry;

namespace {
template <class Msg>
struct Collector {
  std::vector<Msg> got;
  void operator()(const Msg& m) { got.push_back(m); }
};

std::string temp_path(const std::string& stem) {
  return ::testing::TempDir() + stem + "-" + std::to_string(::getpid()) + ".lcmlog";
}

InstrumentState make_state(std::int64_t step) {
  InstrumentState s;
  s.step = step;
  s.t_s = static_cast<double>(step) * 1e-3;
  s.instrument_id = 1;
  s.port_id = 0;
  copy_text(s.kind, "vitrector");
  s.tip_mm[0] = 1.5;
  s.tip_mm[1] = -2.25;
  s.tip_mm[2] = 3.0 + static_cast<double>(step);
  s.shaft_axis[2] = 1.0;
  s.insertion_mm = 7.5;
  s.actuation = 0.25;
  return s;
}
}  // namespace

TEST(TelemetryPublisher, MemqRoundTripOfEveryItemType) {
  TelemetryPublisher pub(PublisherConfig{"memq://", 64});
  TelemetrySource& physics = pub.add_source("physics");
  Collector<vitreo_lcm::instrument_state_t> states;
  Collector<vitreo_lcm::event_t> events;
  Collector<vitreo_lcm::physics_timing_t> timing;
  Collector<vitreo_lcm::device_status_t> status;
  Collector<vitreo_lcm::score_t> scores;
  auto sub1 = subscribe_to<decltype(states.got)::value_type>(pub.lcm(), kChanInstrumentState, &states);
  auto sub2 = subscribe_to<decltype(events.got)::value_type>(pub.lcm(), kChanEvent, &events);
  auto sub3 = subscribe_to<decltype(timing.got)::value_type>(pub.lcm(), kChanPhysicsTiming, &timing);
  auto sub4 = subscribe_to<decltype(status.got)::value_type>(pub.lcm(), kChanDeviceStatus, &status);
  auto sub5 = subscribe_to<decltype(scores.got)::value_type>(pub.lcm(), kChanScore, &scores);

  ASSERT_TRUE(physics.push(make_state(42)));
  Event e;
  e.step = 43;
  e.kind = EventKind::Tear;
  e.instrument_id = 0;
  e.position_mm[2] = -11.5;
  e.magnitude = 0.8;
  ASSERT_TRUE(physics.push(e));
  PhysicsTiming t;
  t.step = 44;
  t.step_p99_us = 312.5f;
  t.overruns = 2;
  ASSERT_TRUE(physics.push(t));
  DeviceStatus d;
  d.device_id = 7;
  copy_text(d.name, "tracker0");
  copy_text(d.transport, "serial:/dev/pts/3");
  d.state = vitreo_lcm::device_status_t::STATE_LOST;
  copy_text(d.detail, "no heartbeat for 250 ms");
  d.crc_errors = 3;
  ASSERT_TRUE(physics.push(d));
  Score s;
  copy_text(s.case_id, "macular-hole-01");
  s.n = 2;
  copy_text(s.name[0], "efficiency");
  s.value[0] = 80;
  copy_text(s.name[1], "tissue_treatment");
  s.value[1] = 65.5;
  s.total = 72.75;
  ASSERT_TRUE(physics.push(s));

  EXPECT_EQ(pub.pump(), 5u);
  while (pub.handle_incoming() > 0) {
  }
  ASSERT_EQ(states.got.size(), 1u);
  EXPECT_EQ(states.got[0].step, 42);
  EXPECT_EQ(states.got[0].kind, "vitrector");
  EXPECT_DOUBLE_EQ(states.got[0].tip_mm[2], 45.0);
  EXPECT_DOUBLE_EQ(states.got[0].actuation, 0.25);
  EXPECT_GT(states.got[0].utime_us, 0);
  ASSERT_EQ(events.got.size(), 1u);
  EXPECT_EQ(events.got[0].kind, +vitreo_lcm::event_t::KIND_TEAR);
  EXPECT_DOUBLE_EQ(events.got[0].position_mm[2], -11.5);
  ASSERT_EQ(timing.got.size(), 1u);
  EXPECT_FLOAT_EQ(timing.got[0].step_p99_us, 312.5f);
  EXPECT_EQ(timing.got[0].overruns, 2);
  ASSERT_EQ(status.got.size(), 1u);
  EXPECT_EQ(status.got[0].name, "tracker0");
  EXPECT_EQ(status.got[0].detail, "no heartbeat for 250 ms");
  EXPECT_EQ(status.got[0].state, +vitreo_lcm::device_status_t::STATE_LOST);
  ASSERT_EQ(scores.got.size(), 1u);
  ASSERT_EQ(scores.got[0].n, 2);
  EXPECT_EQ(scores.got[0].name[1], "tissue_treatment");
  EXPECT_DOUBLE_EQ(scores.got[0].value[1], 65.5);
  EXPECT_EQ(pub.published(), 5u);
  EXPECT_EQ(pub.dropped(), 0u);
}

// What the session report reads (rig/report): criteria, the scoring's totals, the pedals' controls,
// each instrument's retina force and the events' own names — every field as it was pushed.
TEST(TelemetryPublisher, MemqRoundTripOfTheDebriefItems) {
  TelemetryPublisher pub(PublisherConfig{"memq://", 64});
  TelemetrySource& physics = pub.add_source("physics");
  Collector<vitreo_lcm::instrument_state_t> states;
  Collector<vitreo_lcm::event_t> events;
  Collector<vitreo_lcm::criteria_t> criteria;
  Collector<vitreo_lcm::session_totals_t> totals;
  Collector<vitreo_lcm::controls_t> controls;
  auto sub1 = subscribe_to<decltype(states.got)::value_type>(pub.lcm(), kChanInstrumentState, &states);
  auto sub2 = subscribe_to<decltype(events.got)::value_type>(pub.lcm(), kChanEvent, &events);
  auto sub3 = subscribe_to<decltype(criteria.got)::value_type>(pub.lcm(), kChanCriteria, &criteria);
  auto sub4 = subscribe_to<decltype(totals.got)::value_type>(pub.lcm(), kChanTotals, &totals);
  auto sub5 = subscribe_to<decltype(controls.got)::value_type>(pub.lcm(), kChanControls, &controls);

  InstrumentState st = make_state(8);
  st.retina_force_un = 2750.5;
  ASSERT_TRUE(physics.push(st));
  Event e;
  e.kind = EventKind::Contact;
  copy_text(e.what, "excessive_retina_force");
  ASSERT_TRUE(physics.push(e));
  Criteria c;
  c.step = 999;
  copy_text(c.case_id, "exercise_pull_tissue");
  c.final_score = true;
  c.n = 2;
  copy_text(c.kind[0], "membrane_released");
  copy_text(c.target[0], "patch");
  c.value[0] = 0.4;
  c.threshold[0] = 1.0;
  c.progress[0] = 0.4;
  copy_text(c.kind[1], "time_limit");
  c.value[1] = 12.5;
  c.threshold[1] = 120;
  c.progress[1] = 0.9;
  c.met[1] = true;
  ASSERT_TRUE(physics.push(c));
  Totals t;
  t.step = 999;
  copy_text(t.case_id, "exercise_pull_tissue");
  t.formula_version = 1;
  t.elapsed_s = 8;
  t.path_length_mm = 33.75;
  t.retina_contacts = 4;
  t.retina_contact_time_s = 0.15;
  t.peak_retina_force_un = 22336;
  t.retina_force_impulse_un_s = 986;
  t.time_over_force_limit_s = 0.13;
  t.force_limit_un = 3000;
  t.burns_on_target = 5;
  t.burns_elsewhere = 1;
  t.retina_tears = 2;
  t.other_tears = 3;
  t.iatrogenic_events = 15;
  t.illumination_measured = true;
  t.working_time_s = 6;
  t.lit_working_time_s = 4.5;
  t.microscope_measured = true;
  t.microscope_working_time_s = 7.25;
  t.out_of_field_s = 0.5;
  t.off_centre_s = 1.125;
  t.out_of_focus_s = 0.75;
  t.extreme_zoom_s = 0.25;
  t.n_kinds = 2;
  copy_text(t.event_kind[0], "wall_contact");
  t.event_count[0] = 9;
  copy_text(t.event_kind[1], "excessive_retina_force");
  t.event_count[1] = 6;
  t.n_instruments = 1;
  copy_text(t.instrument_kind[0], "forceps");
  t.instrument_path_mm[0] = 33.75;
  t.instrument_contacts[0] = 4;
  t.instrument_peak_force_un[0] = 22336;
  t.instrument_contact_time_s[0] = 0.15;
  ASSERT_TRUE(physics.push(t));
  Controls k;
  k.step = 12;
  k.t_s = 0.012;
  k.vacuum_mmhg = 350;
  k.cut_rate_cpm = 5000;
  k.reflux = true;
  k.laser_fire = true;
  k.pick_out = true;
  k.light_level = 0.7;
  k.zoom = 1.5;
  k.laser_power_mw = 350;
  k.laser_duration_ms = 120;
  for (int a = 0; a < 4; ++a) {
    k.vitrectomy_pedal_travel[a] = 0.1 * (a + 1);
    k.microscope_pedal_travel[a] = 0.05 * (a + 1);
  }
  k.macula_light_dose_j_cm2 = 2.5;
  k.light_dose_limit_j_cm2 = 10;
  ASSERT_TRUE(physics.push(k));

  EXPECT_EQ(pub.pump(), 5u);
  while (pub.handle_incoming() > 0) {
  }
  ASSERT_EQ(states.got.size(), 1u);
  EXPECT_DOUBLE_EQ(states.got[0].retina_force_un, 2750.5);
  ASSERT_EQ(events.got.size(), 1u);
  EXPECT_EQ(events.got[0].what, "excessive_retina_force");
  ASSERT_EQ(criteria.got.size(), 1u);
  const auto& cg = criteria.got[0];
  EXPECT_EQ(cg.step, 999);
  EXPECT_EQ(cg.case_id, "exercise_pull_tissue");
  EXPECT_TRUE(cg.final_score);
  ASSERT_EQ(cg.n, 2);
  EXPECT_EQ(cg.kind[0], "membrane_released");
  EXPECT_EQ(cg.target[0], "patch");
  EXPECT_EQ(cg.target[1], "");
  EXPECT_DOUBLE_EQ(cg.value[0], 0.4);
  EXPECT_DOUBLE_EQ(cg.threshold[1], 120);
  EXPECT_DOUBLE_EQ(cg.progress[1], 0.9);
  EXPECT_FALSE(cg.met[0]);
  EXPECT_TRUE(cg.met[1]);
  ASSERT_EQ(totals.got.size(), 1u);
  const auto& tg = totals.got[0];
  EXPECT_EQ(tg.formula_version, 1);
  EXPECT_FALSE(tg.final_score);
  EXPECT_DOUBLE_EQ(tg.elapsed_s, 8);
  EXPECT_DOUBLE_EQ(tg.path_length_mm, 33.75);
  EXPECT_EQ(tg.retina_contacts, 4);
  EXPECT_DOUBLE_EQ(tg.retina_contact_time_s, 0.15);
  EXPECT_DOUBLE_EQ(tg.peak_retina_force_un, 22336);
  EXPECT_DOUBLE_EQ(tg.retina_force_impulse_un_s, 986);
  EXPECT_DOUBLE_EQ(tg.time_over_force_limit_s, 0.13);
  EXPECT_DOUBLE_EQ(tg.force_limit_un, 3000);
  EXPECT_EQ(tg.burns_on_target, 5);
  EXPECT_EQ(tg.burns_elsewhere, 1);
  EXPECT_EQ(tg.retina_tears, 2);
  EXPECT_EQ(tg.other_tears, 3);
  EXPECT_EQ(tg.iatrogenic_events, 15);
  EXPECT_TRUE(tg.illumination_measured);
  EXPECT_DOUBLE_EQ(tg.working_time_s, 6);
  EXPECT_DOUBLE_EQ(tg.lit_working_time_s, 4.5);
  EXPECT_TRUE(tg.microscope_measured);
  EXPECT_DOUBLE_EQ(tg.microscope_working_time_s, 7.25);
  EXPECT_DOUBLE_EQ(tg.out_of_field_s, 0.5);
  EXPECT_DOUBLE_EQ(tg.off_centre_s, 1.125);
  EXPECT_DOUBLE_EQ(tg.out_of_focus_s, 0.75);
  EXPECT_DOUBLE_EQ(tg.extreme_zoom_s, 0.25);
  ASSERT_EQ(tg.n_kinds, 2);
  EXPECT_EQ(tg.event_kind[1], "excessive_retina_force");
  EXPECT_EQ(tg.event_count[0], 9);
  ASSERT_EQ(tg.n_instruments, 1);
  EXPECT_EQ(tg.instrument_kind[0], "forceps");
  EXPECT_DOUBLE_EQ(tg.instrument_path_mm[0], 33.75);
  EXPECT_EQ(tg.instrument_contacts[0], 4);
  EXPECT_DOUBLE_EQ(tg.instrument_peak_force_un[0], 22336);
  EXPECT_DOUBLE_EQ(tg.instrument_contact_time_s[0], 0.15);
  ASSERT_EQ(controls.got.size(), 1u);
  const auto& kg = controls.got[0];
  EXPECT_EQ(kg.step, 12);
  EXPECT_DOUBLE_EQ(kg.t_s, 0.012);
  EXPECT_DOUBLE_EQ(kg.vacuum_mmhg, 350);
  EXPECT_DOUBLE_EQ(kg.cut_rate_cpm, 5000);
  EXPECT_TRUE(kg.reflux);
  EXPECT_TRUE(kg.laser_fire);
  EXPECT_TRUE(kg.pick_out);
  EXPECT_DOUBLE_EQ(kg.light_level, 0.7);
  EXPECT_DOUBLE_EQ(kg.zoom, 1.5);
  EXPECT_DOUBLE_EQ(kg.laser_power_mw, 350);
  EXPECT_DOUBLE_EQ(kg.laser_duration_ms, 120);
  for (int a = 0; a < 4; ++a) {
    EXPECT_DOUBLE_EQ(kg.vitrectomy_pedal_travel[a], 0.1 * (a + 1));
    EXPECT_DOUBLE_EQ(kg.microscope_pedal_travel[a], 0.05 * (a + 1));
  }
  EXPECT_DOUBLE_EQ(kg.macula_light_dose_j_cm2, 2.5);
  EXPECT_DOUBLE_EQ(kg.light_dose_limit_j_cm2, 10);
  EXPECT_GT(kg.utime_us, 0);
}

TEST(TelemetryPublisher, FullRingDropsAndCountsInsteadOfWaiting) {
  TelemetryPublisher pub(PublisherConfig{"memq://", 16});
  TelemetrySource& physics = pub.add_source("physics");
  TelemetrySource& driver = pub.add_source("tracker-driver", 4);
  Collector<vitreo_lcm::instrument_state_t> states;
  auto sub6 = subscribe_to<decltype(states.got)::value_type>(pub.lcm(), kChanInstrumentState, &states);
  // The telemetry thread is "stuck": nobody pumps. Producers keep going.
  std::uint64_t accepted = 0;
  for (int i = 0; i < 100; ++i) accepted += physics.push(make_state(i)) ? 1 : 0;
  for (int i = 0; i < 10; ++i) driver.push(DeviceStatus{});
  EXPECT_EQ(accepted, 16u);
  EXPECT_EQ(physics.dropped(), 84u);
  EXPECT_EQ(driver.dropped(), 6u);
  EXPECT_EQ(pub.dropped(), 90u);
  EXPECT_EQ(pub.pump(), 20u);
  while (pub.handle_incoming() > 0) {
  }
  ASSERT_EQ(states.got.size(), 16u);
  // The oldest were kept (drop-newest): steps 0..15 in order.
  for (std::size_t i = 0; i < states.got.size(); ++i) EXPECT_EQ(states.got[i].step, static_cast<std::int64_t>(i));
}

TEST(TelemetryPublisher, FileProviderWritesALogThatLogFileReads) {
  const std::string path = temp_path("telemetry-file");
  {
    TelemetryPublisher pub(PublisherConfig{"file://" + path + "?mode=w", 256});
    TelemetrySource& physics = pub.add_source("physics");
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(physics.push(make_state(i)));
    EXPECT_EQ(pub.pump(), 100u);
  }
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  int n = 0;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    ASSERT_EQ(ev->channel, kChanInstrumentState);
    vitreo_lcm::instrument_state_t m;
    ASSERT_GE(m.decode(ev->data, 0, ev->datalen), 0);
    EXPECT_EQ(m.step, n);
    EXPECT_DOUBLE_EQ(m.tip_mm[2], 3.0 + n);
    ++n;
  }
  EXPECT_EQ(n, 100);
  std::remove(path.c_str());
}

TEST(TimingReporter, PublishesWindowedLoopTimingEveryNSteps) {
  TelemetryPublisher pub(PublisherConfig{"memq://", 64});
  TelemetrySource& physics = pub.add_source("physics");
  Collector<vitreo_lcm::physics_timing_t> timing;
  auto sub7 = subscribe_to<vitreo_lcm::physics_timing_t>(pub.lcm(), kChanPhysicsTiming, &timing);
  vitreo::runtime::SimulatedClock clock;
  vitreo::runtime::FixedStepLoop* loop_ptr = nullptr;
  std::unique_ptr<TimingReporter> reporter;
  vitreo::runtime::FixedStepLoop loop(clock, vitreo::runtime::LoopConfig{}, [&](std::uint64_t k, double) {
    // Steps 0-9 take 200 µs, steps 10-19 take 1.5 ms (overruns), 20-29 take 100 µs.
    clock.advance(k < 10 ? 200'000 : (k < 20 ? 1'500'000 : 100'000));
    reporter->on_step(k, k >= 20);
  });
  loop_ptr = &loop;
  reporter = std::make_unique<TimingReporter>(*loop_ptr, physics, 10);
  loop.run(30);
  pub.pump();
  while (pub.handle_incoming() > 0) {
  }
  ASSERT_EQ(timing.got.size(), 3u);
  // A report is made inside step 10n+9, before that step's own time is recorded: the first window
  // holds steps 0-8, later ones the ten steps before the reporting one.
  EXPECT_EQ(timing.got[0].step, 9);
  EXPECT_EQ(timing.got[0].window_steps, 9);
  EXPECT_FLOAT_EQ(timing.got[0].step_max_us, 200.0f);
  EXPECT_EQ(timing.got[0].overruns, 0);
  EXPECT_EQ(timing.got[1].window_steps, 10);
  EXPECT_FLOAT_EQ(timing.got[1].step_p50_us, 1500.0f);
  EXPECT_EQ(timing.got[1].overruns, 9);  // cumulative: steps 10-18 recorded so far
  EXPECT_FALSE(timing.got[1].paused);
  EXPECT_EQ(timing.got[2].step, 29);
  EXPECT_FLOAT_EQ(timing.got[2].step_p50_us, 100.0f);
  EXPECT_FLOAT_EQ(timing.got[2].step_max_us, 1500.0f);  // step 19 is in this window
  EXPECT_GT(timing.got[2].late_steps, 0);
  EXPECT_TRUE(timing.got[2].paused);
  EXPECT_EQ(timing.got[2].period_us, 1000);
  // The windows do not take the session's own statistics with them: the summary still sees all 30.
  EXPECT_EQ(loop.stats().window_steps, 30u);
  EXPECT_EQ(loop.stats().step_max_ns, 1'500'000);
  EXPECT_EQ(TimingReporter::steps_for_rate(1'000'000, 10.0), 100u);  // 10 Hz at 1 kHz
  EXPECT_EQ(TimingReporter::steps_for_rate(4'000'000, 10.0), 25u);
}

TEST(TelemetryPublisher, DefaultUrlNeverLeavesThisMachine) {
  // ttl=0: multicast datagrams are not forwarded off the host. Changing this is a deliberate act.
  EXPECT_STREQ(kDefaultLcmUrl, "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_STREQ(PublisherConfig{}.url.c_str(), kDefaultLcmUrl);
}

TEST(TelemetryPublisher, BadUrlIsReportedNotIgnored) {
  EXPECT_THROW(TelemetryPublisher(PublisherConfig{"nosuchprovider://x", 16}), std::runtime_error);
}

// The physics thread pushes at ~10 kHz while the telemetry thread publishes on memq and dispatches
// to a subscriber. In the second phase that subscriber stalls the telemetry thread for the whole
// phase. The physics-side push time must not change: the ring fills and items are dropped.
TEST(TelemetryPublisher, StalledSubscriberDoesNotSlowThePhysicsSide) {
  struct Phase {
    std::vector<std::int64_t> push_ns;
    std::uint64_t dropped = 0;
  };
  auto run_phase = [](bool stall) {
    TelemetryPublisher pub(PublisherConfig{"memq://", 1024});
    TelemetrySource& physics = pub.add_source("physics");
    std::atomic<bool> physics_done{false};
    std::atomic<bool> in_handler{false};
    struct Sub {
      bool stall;
      std::atomic<bool>* done;
      std::atomic<bool>* in_handler;
      void operator()(const vitreo_lcm::instrument_state_t&) {
        in_handler->store(true, std::memory_order_release);
        while (stall && !done->load(std::memory_order_acquire)) std::this_thread::yield();
      }
    } sub{stall, &physics_done, &in_handler};
    auto sub8 = subscribe_to<vitreo_lcm::instrument_state_t>(pub.lcm(), kChanInstrumentState, &sub);
    std::thread telemetry([&] {
      while (!physics_done.load(std::memory_order_acquire)) {
        pub.pump();
        pub.handle_incoming();
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      }
      pub.pump();
      pub.handle_incoming(1 << 20);
    });
    Phase p;
    p.push_ns.reserve(3000);
    vitreo::runtime::SteadyClock clock;
    // Wait (off the measured path) until the telemetry thread is dispatching, so the stall is real.
    physics.push(make_state(0));
    while (!in_handler.load(std::memory_order_acquire)) std::this_thread::yield();
    for (int i = 1; i <= 3000; ++i) {
      const InstrumentState s = make_state(i);
      const std::int64_t t0 = clock.now_ns();
      physics.push(s);
      p.push_ns.push_back(clock.now_ns() - t0);
      clock.sleep_until_ns(clock.now_ns() + 100'000);
    }
    physics_done.store(true, std::memory_order_release);
    telemetry.join();
    p.dropped = physics.dropped();
    EXPECT_EQ(pub.published() + physics.dropped(), 3001u) << "every push is published or counted";
    return p;
  };
  auto pct = [](std::vector<std::int64_t> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
  };
  const Phase free_run = run_phase(false);
  const Phase stalled = run_phase(true);
  const double p50_free = static_cast<double>(pct(free_run.push_ns, 0.5));
  const double p50_stall = static_cast<double>(pct(stalled.push_ns, 0.5));
  const double p99_free = static_cast<double>(pct(free_run.push_ns, 0.99));
  const double p99_stall = static_cast<double>(pct(stalled.push_ns, 0.99));
  const double max_stall = static_cast<double>(pct(stalled.push_ns, 1.0));
  std::printf("physics-side push: no stall p50 %.0f ns p99 %.0f ns | stalled subscriber p50 %.0f ns p99 %.0f ns "
              "max %.0f ns | p99 ratio stalled/free = %.2f | dropped while stalled: %llu of 3000\n",
              p50_free, p99_free, p50_stall, p99_stall, max_stall, p99_stall / std::max(p99_free, 1.0),
              static_cast<unsigned long long>(stalled.dropped));
  EXPECT_EQ(free_run.dropped, 0u);
  EXPECT_GT(stalled.dropped, 1900u) << "the stall filled the ring, so the stall really happened";
  // The stall lasted ~300 ms; a push that waited for the subscriber would take that long. 5 ms
  // leaves room for this shared machine's preemptions.
  EXPECT_LT(max_stall, 5e6);
}
