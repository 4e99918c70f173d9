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
#include "rig/telemetry/publisher.hpp"
#include "rig/telemetry/recording.hpp"

namespace vitreo::rig {

class DeviceHub {
 public:
  // Opens every device (rig/session/rig_file.hpp); throws std::runtime_error naming the device for a
  // URI it cannot open (bad URI, bad script, a transport this process cannot offer). A device that
  // is merely absent is not an error: it shows as lost and is found when it appears.
  explicit DeviceHub(std::vector<DeviceSpec> devices, telemetry::TelemetrySource* status_out = nullptr);
  ~DeviceHub();
  DeviceHub(const DeviceHub&) = delete;
  DeviceHub& operator=(const DeviceHub&) = delete;

  void start();
  void stop();

  // Physics side (one consumer thread), wait-free: visits each device's newest sample if it is new
  // since the last call, and every link change since the last call.
  template <class F>
  void take_new(F&& f) {
    telemetry::DeviceInput link;
    while (links_.try_pop(link)) f(link);
    for (auto& d : devices_) {
      if (!d->latest.update()) continue;
      const telemetry::DeviceInput& in = d->latest.read_slot();
      if (in.sequence == d->last_taken) continue;
      d->last_taken = in.sequence;
      f(in);
    }
  }

  std::size_t device_count() const { return devices_.size(); }
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
    runtime::TripleBuffer<telemetry::DeviceInput> latest;
    std::int64_t sequence = 0;
    std::int64_t last_taken = -1;
    std::atomic<int> plug_request{0};  // +1 plug, -1 unplug
    drivers::LinkState last_state = drivers::LinkState::lost;  // as last published (driver thread)
    bool stuck_reported = false;                              // driver thread
  };
  void run_sims();
  void run_drivers();
  void publish_status(std::uint64_t now_us);

  std::vector<std::unique_ptr<Device>> devices_;
  runtime::SpscRing<telemetry::DeviceInput> links_{256};
  telemetry::TelemetrySource* status_out_;
  drivers::SteadyClock clock_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> reader_stalls_{0}, reader_stall_max_us_{0};
  std::thread sim_thread_, driver_thread_;
};

}  // namespace vitreo::rig
