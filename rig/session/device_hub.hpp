#pragma once
// The rig's devices on their own threads: drivers turn bytes into samples, samples into the
// recorded input form, and hand them to physics through wait-free mailboxes — the newest sample per
// device (a late physics step takes the latest, never a queue of stale ones) and a small ring of
// link changes (each one must reach physics exactly once, to be recorded and replayed).
//
// Each device is a drivers::Device opened from its URI (drivers/open_device.hpp): serial, CAN or
// USB, or simulated — a firmware emulator behind one of those transports (drivers/sim), whose
// emulators the hub runs on their own thread, so the drivers talk to the same bytes over the same
// kind of link as on the rig.
//
// Two ways to run (HubMode):
// - real time (the rig's way, and the default): emulators and drivers run on the steady wall
//   clock; physics takes whatever arrived by the time its step starts and never waits.
// - lockstep (scripted sessions, hardware-in-the-loop tests): the hub's clock is the simulation's.
//   Before physics step k takes its inputs, it grants time t_k to the emulators: they make every
//   frame due by t_k and write it to their transport, the drivers read until they have counted every
//   byte written (SimulatedPeer::bytes_sent), and only then does physics go on. Heartbeats, the
//   stale and lost timeouts, time sync and latency all read that clock, so a loaded machine slows a
//   scripted session down but never changes what it receives at which step (the lockstep of
//   ArduPilot's SITL and Gazebo). Every device must be simulated. The handshake (identify,
//   configure) happens at the start time itself, before step 0, so each script's time 0 is the
//   session's step 0.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "drivers/device.hpp"
#include "rig/runtime/spsc_ring.hpp"
#include "rig/runtime/triple_buffer.hpp"
#include "rig/session/rig_file.hpp"
#include "rig/session/sample_window.hpp"
#include "rig/telemetry/publisher.hpp"
#include "rig/telemetry/recording.hpp"

namespace vitreo::rig {

enum class HubMode { realtime, lockstep };

// Lockstep's counters, for the session summary.
struct LockstepStats {
  std::uint64_t grants = 0;        // steps granted to the emulators
  std::uint64_t handshake_rounds = 0;  // rounds at the start time until every device streamed
  std::uint64_t stalls = 0;        // grants whose bytes did not all arrive within kStallWallUs
  std::uint64_t wait_ns_total = 0;  // physics' wall time spent waiting for its inputs
  std::uint64_t wait_ns_max = 0;
};

class DeviceHub {
 public:
  // Opens every device (rig/session/rig_file.hpp); throws std::runtime_error naming the device for a
  // URI it cannot open (bad URI, bad script, a transport this process cannot offer). A device that
  // is merely absent is not an error: it shows as lost and is found when it appears.
  explicit DeviceHub(std::vector<DeviceSpec> devices, telemetry::TelemetrySource* status_out = nullptr,
                     HubMode mode = HubMode::realtime);
  ~DeviceHub();
  DeviceHub(const DeviceHub&) = delete;
  DeviceHub& operator=(const DeviceHub&) = delete;

  void start();
  void stop();

  // Physics side (one consumer thread), wait-free: visits each device's newest sample if it is new
  // since the last call, and every link change since the last call.
  template <class F>
  void take_new(F&& f) {
    telemetry::RecordedInput link;
    while (links_.try_pop(link)) f(link);
    for (auto& d : devices_) {
      if (!d->latest.update()) continue;
      const telemetry::RecordedInput& in = d->latest.read_slot();
      if (in.sequence == d->last_taken) continue;
      d->last_taken = in.sequence;
      f(in);
    }
  }

  // Lockstep, physics side. connect(): after start(), runs handshake rounds at the start time until
  // every device streams; throws naming the devices that did not within wall_timeout_s.
  // deliver(k): grants step k's time (start + k·period) and returns once every byte the emulators
  // wrote for it has been read and decoded, so take_new() then sees exactly step k's inputs.
  void lockstep_connect(double wall_timeout_s = 10.0);
  void lockstep_deliver(std::uint64_t step, std::uint64_t period_us);
  HubMode mode() const { return mode_; }
  LockstepStats lockstep_stats() const { return lock_stats_; }  // physics thread, or after stop()
  // Wall time one grant may take before the hub stops waiting for bytes that will not come (a link
  // that closed with bytes in flight): it warns, counts a stall and goes on.
  static constexpr std::uint64_t kStallWallUs = 200'000;

  std::size_t device_count() const { return devices_.size(); }
  // The clock the devices' samples are stamped with (host monotonic µs; in lockstep the granted
  // simulation time): what the rig stamps its own inputs with, so a recording's host times agree.
  std::uint64_t now_us() { return clock_.now_us(); }
  // Physics side, at the session's first step: the origin of the session time the device statuses
  // carry (device_status_t.t_s) — in lockstep the start time, so a status's time is its step's k · dt.
  void mark_session_start() { session_origin_us_.store(clock_.now_us(), std::memory_order_release); }
  // Before start(): called on the driver thread for each completed time-sync exchange of `device`
  // (vitreo-calibrate's clock calibration).
  void on_time_sync(std::size_t device, drivers::DeviceSession::TimeSyncFn f) {
    devices_[device]->driver->session().set_on_time_sync(std::move(f));
  }
  // The serial number the device announced (0 before it identified); read it while the driver
  // thread is quiet (lockstep, between grants) or after stop().
  std::uint32_t announced_serial(std::size_t device) const {
    const auto& s = devices_[device]->driver->session();
    return s.has_device_info() ? s.device_info().serial : 0;
  }
  // Cable pull / re-plug of a simulated device (tests, demonstrations); no effect on a real one.
  // Thread-safe.
  void unplug(std::size_t device);
  void plug(std::size_t device);
  // Link statistics (driver thread's view; copied under no lock, for summaries after stop()).
  const drivers::LinkStats& stats(std::size_t device) const { return devices_[device]->driver->session().stats(); }
  const std::string& name(std::size_t device) const { return devices_[device]->spec.name; }
  std::string uri(std::size_t device) const { return devices_[device]->driver->uri(); }
  std::uint64_t link_events_dropped() const { return links_.dropped(); }
  // The driver thread's starvation: passes that came >= kReaderStallUs after the previous one.
  static constexpr std::uint64_t kReaderStallUs = 20'000;
  std::uint64_t reader_stalls() const { return reader_stalls_.load(std::memory_order_relaxed); }
  std::uint64_t reader_stall_max_us() const { return reader_stall_max_us_.load(std::memory_order_relaxed); }

 private:
  struct Device {
    DeviceSpec spec;
    std::unique_ptr<drivers::Device> driver;
    runtime::TripleBuffer<telemetry::RecordedInput> latest;
    std::int64_t sequence = 0;
    std::int64_t last_taken = -1;
    std::atomic<int> plug_request{0};  // +1 plug, -1 unplug
    drivers::LinkState last_state = drivers::LinkState::lost;  // as last published (driver thread)
    bool stuck_reported = false;                              // driver thread
    bool stuck_published = false;                             // as last published (driver thread)
    std::uint64_t bytes_unaccounted = 0;  // lockstep: bytes a stalled grant gave up on (driver thread)
    SampleWindow window;                  // rate and latency of the last second (driver thread)
    std::string refusal_reported;         // the refusal last logged (driver thread)
  };
  void run_sims();
  void run_drivers();
  void run_lockstep_sims();
  void run_lockstep_drivers();
  void step_peers(std::uint64_t now_us);
  std::uint64_t grant_round();  // lockstep: one round at the clock's current time; returns its number
  void publish_status(std::uint64_t now_us);
  static bool status_changed(const Device& d);

  // The drivers' clock: the steady wall clock, or in lockstep the granted simulation time.
  class HubClock final : public drivers::Clock {
   public:
    explicit HubClock(HubMode mode) : lockstep_(mode == HubMode::lockstep) {}
    std::uint64_t now_us() override { return lockstep_ ? sim_us.load(std::memory_order_acquire) : wall_.now_us(); }
    static constexpr std::uint64_t kStartUs = 1'000'000;  // the lockstep session's t = 0
    std::atomic<std::uint64_t> sim_us{kStartUs};

   private:
    bool lockstep_;
    drivers::SteadyClock wall_;
  };

  std::vector<std::unique_ptr<Device>> devices_;
  runtime::SpscRing<telemetry::RecordedInput> links_{256};
  telemetry::TelemetrySource* status_out_;
  HubMode mode_;
  HubClock clock_;
  std::atomic<bool> running_{false};
  // Lockstep rounds: physics raises grant_, the emulator thread answers with emulated_, the driver
  // thread with delivered_ (C++20 atomic wait/notify, futexes underneath).
  std::atomic<std::uint64_t> grant_{0}, emulated_{0}, delivered_{0};
  std::atomic<std::uint64_t> stalls_{0};
  std::atomic<bool> drivers_opened_{false};  // lockstep: the drivers opened their ports before round 1
  LockstepStats lock_stats_;
  std::atomic<std::uint64_t> reader_stalls_{0}, reader_stall_max_us_{0};
  std::atomic<std::uint64_t> session_origin_us_{0};  // 0 until the session's first step
  std::thread sim_thread_, driver_thread_;
};

}  // namespace vitreo::rig
