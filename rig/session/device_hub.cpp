#include "rig/session/device_hub.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <variant>

#include <unistd.h>

#include "drivers/open_device.hpp"
#include "drivers/sim/simulated_peer.hpp"
#include "rig/session/device_inputs.hpp"
#include "rig/session/simulation_model.hpp"
#include "rig/telemetry/telemetry_mapping.hpp"

namespace vitreo::rig {

DeviceHub::DeviceHub(std::vector<DeviceSpec> specs, telemetry::TelemetrySource* status_out, HubMode mode)
    : status_out_(status_out), mode_(mode), clock_(mode) {
  for (auto& spec : specs) {
    auto d = std::make_unique<Device>();
    d->spec = spec;
    drivers::OpenOptions options;
    // the device at this address must be the kind its role says (and the serial, when given)
    options.session.expected_device_type = spec.role == DeviceRole::tracker  ? VP_DEVICE_TRACKER
                                           : spec.role == DeviceRole::pedals ? VP_DEVICE_PEDAL
                                                                             : VP_DEVICE_EYEBALL;
    options.session.expected_serial = spec.expected_serial;
    if (spec.sample_rate_hz > 0) options.session.sample_rate_hz = spec.sample_rate_hz;
    options.sim_script = spec.sim_script;
    options.sim_link = "/tmp/vitreo-" + std::to_string(::getpid()) + "-" + spec.name;
    std::string error;
    d->driver = drivers::open_device(spec.uri, clock_, options, &error);
    if (!d->driver) throw std::runtime_error("device " + spec.name + ": " + error);
    if (mode_ == HubMode::lockstep && !d->driver->simulated_peer())
      throw std::runtime_error("device " + spec.name + " (" + spec.uri + "): a lockstep session needs simulated devices (sim:...); a real device runs on its own clock");
    Device* raw = d.get();
    // A link change as a recorded input, with the device's type (from its DEVICE_INFO, 0 before one
    // came): only a tracker's link freezes an instrument.
    auto link_input = [this, raw](telemetry::LinkEvent event) {
      telemetry::RecordedInput link;
      link.device_id = raw->spec.device_id;
      link.channel = raw->spec.channel;
      link.host_time_us = static_cast<std::int64_t>(clock_.now_us());
      link.sequence = raw->sequence++;
      const auto& session = raw->driver->session();
      link.what = telemetry::LinkChange{event, session.has_device_info() ? session.device_info().device_type : std::uint8_t{0}};
      if (!links_.try_push(link)) spdlog::warn("device {}: link-change queue full, change dropped", raw->spec.name);
    };
    d->driver->session().set_on_sample([this, raw, link_input](const drivers::Sample& s) {
      telemetry::RecordedInput in = encode_sample(s, raw->spec.device_id, raw->sequence++);
      const drivers::SampleTime& t = std::visit([](const auto& x) -> const drivers::SampleTime& { return x.t; }, s);
      raw->window.on_sample(t.received_us, t.received_us > t.host_us ? t.received_us - t.host_us : 0);
      in.channel = raw->spec.channel;
      // A stuck sensor (the driver's verdict: bit-identical for 50 ms of device time) is reported at
      // once, ahead of its sample: physics freezes the instrument as if the tracker were lost.
      const bool stuck = std::visit([](const auto& x) { return x.stuck; }, s);
      if (stuck != raw->stuck_reported) {
        raw->stuck_reported = stuck;
        if (stuck) spdlog::warn("device {}: sensor stuck (identical samples for 50 ms) — its instrument is frozen", raw->spec.name);
        else spdlog::info("device {}: sensor moving again", raw->spec.name);
        link_input(stuck ? telemetry::LinkEvent::Stuck : telemetry::LinkEvent::Up);
      }
      raw->latest.write_slot() = in;
      raw->latest.publish();
    });
    d->driver->session().set_on_state([raw, link_input](drivers::LinkState from, drivers::LinkState to, const char* why) {
      spdlog::info("device {}: {} -> {} ({})", raw->spec.name, drivers::to_string(from), drivers::to_string(to), why ? why : "");
      const bool up = to == drivers::LinkState::streaming;
      const bool down = to == drivers::LinkState::lost;
      if (!up && !down) return;
      raw->stuck_reported = false;  // a new link starts unstuck (the driver forgets too)
      if (down) raw->window.reset();
      link_input(up ? telemetry::LinkEvent::Up : telemetry::LinkEvent::Lost);
    });
    devices_.push_back(std::move(d));
  }
}

DeviceHub::~DeviceHub() { stop(); }

void DeviceHub::start() {
  if (running_.exchange(true)) return;
  if (mode_ == HubMode::lockstep) {
    sim_thread_ = std::thread([this] { run_lockstep_sims(); });
    driver_thread_ = std::thread([this] { run_lockstep_drivers(); });
    return;
  }
  sim_thread_ = std::thread([this] { run_sims(); });
  driver_thread_ = std::thread([this] { run_drivers(); });
}

void DeviceHub::stop() {
  if (!running_.exchange(false)) return;
  if (mode_ == HubMode::lockstep) {  // wake the two threads from their waits: they see !running_
    grant_.fetch_add(1, std::memory_order_acq_rel);
    grant_.notify_all();
    emulated_.fetch_add(1, std::memory_order_acq_rel);
    emulated_.notify_all();
  }
  if (sim_thread_.joinable()) sim_thread_.join();
  if (driver_thread_.joinable()) driver_thread_.join();
}

void DeviceHub::unplug(std::size_t device) { devices_.at(device)->plug_request.store(-1); }
void DeviceHub::plug(std::size_t device) { devices_.at(device)->plug_request.store(+1); }

void DeviceHub::step_peers(std::uint64_t now) {
  for (auto& d : devices_) {
    drivers::sim::SimulatedPeer* peer = d->driver->simulated_peer();
    if (!peer) continue;
    const int request = d->plug_request.exchange(0);
    if (request < 0) peer->unplug();
    if (request > 0) peer->plug();
    peer->step(now);
  }
}

void DeviceHub::run_sims() {
  // The emulators stand in for the devices' own firmware: they run on their own thread, in real
  // time, and the drivers know nothing about them beyond the bytes on their transport.
  while (running_.load(std::memory_order_acquire)) {
    step_peers(clock_.now_us());
    std::this_thread::sleep_for(std::chrono::microseconds(250));
  }
}

void DeviceHub::run_lockstep_sims() {
  // One pass per grant, at the granted time: the emulators read what the host sent since the last
  // round, answer it, and write every frame due by now.
  std::uint64_t done = 0;
  for (;;) {
    grant_.wait(done, std::memory_order_acquire);
    if (!running_.load(std::memory_order_acquire)) return;
    const std::uint64_t g = grant_.load(std::memory_order_acquire);
    step_peers(clock_.now_us());
    done = g;
    emulated_.store(g, std::memory_order_release);
    emulated_.notify_one();
  }
}

void DeviceHub::run_lockstep_drivers() {
  // After the emulators' pass, read until each driver has counted every byte its peer wrote: a pty
  // hands bytes on through a kernel work queue, so "nothing to read yet" does not mean "all read".
  std::uint64_t done = 0;
  std::uint64_t next_status = 0;
  // Each driver opens its port first: a serial driver flushes what was written before it opened,
  // so the emulators' first words must come after.
  for (auto& d : devices_) d->driver->poll(0);
  drivers_opened_.store(true, std::memory_order_release);
  drivers_opened_.notify_one();
  for (;;) {
    emulated_.wait(done, std::memory_order_acquire);
    if (!running_.load(std::memory_order_acquire)) return;
    const std::uint64_t g = emulated_.load(std::memory_order_acquire);
    const auto started = std::chrono::steady_clock::now();
    bool changed = false;
    for (;;) {
      bool all_in = true;
      for (auto& d : devices_) {
        d->driver->poll(0);
        const std::uint64_t sent = d->driver->simulated_peer()->bytes_sent();
        if (d->driver->session().stats().bytes + d->bytes_unaccounted < sent) all_in = false;
      }
      if (all_in) break;
      if (std::chrono::steady_clock::now() - started > std::chrono::microseconds(kStallWallUs)) {
        // Bytes that will not come (a link closed or flushed with them in flight): say so, stop
        // waiting for them, and go on.
        for (auto& d : devices_) {
          const std::uint64_t sent = d->driver->simulated_peer()->bytes_sent();
          const std::uint64_t got = d->driver->session().stats().bytes + d->bytes_unaccounted;
          if (got >= sent) continue;
          spdlog::warn("device {}: lockstep: {} bytes written by its emulator never reached the driver (link {}); going on without them",
                       d->spec.name, sent - got, drivers::to_string(d->driver->session().state()));
          d->bytes_unaccounted += sent - got;
        }
        stalls_.fetch_add(1, std::memory_order_relaxed);
        break;
      }
      std::this_thread::yield();
    }
    for (auto& d : devices_) changed = changed || status_changed(*d);
    const std::uint64_t now = clock_.now_us();
    if (now >= next_status || changed) {  // 10 Hz of simulated time
      publish_status(now);
      next_status = now + 100'000;
    }
    done = g;
    delivered_.store(g, std::memory_order_release);
    delivered_.notify_one();
  }
}

std::uint64_t DeviceHub::grant_round() {
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t g = grant_.fetch_add(1, std::memory_order_acq_rel) + 1;
  grant_.notify_one();
  for (std::uint64_t seen = delivered_.load(std::memory_order_acquire); seen != g && running_.load(std::memory_order_acquire);
       seen = delivered_.load(std::memory_order_acquire)) {
    delivered_.wait(seen, std::memory_order_acquire);
  }
  const auto waited = static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
  lock_stats_.wait_ns_total += waited;
  lock_stats_.wait_ns_max = std::max(lock_stats_.wait_ns_max, waited);
  lock_stats_.stalls = stalls_.load(std::memory_order_relaxed);
  return g;
}

void DeviceHub::lockstep_connect(double wall_timeout_s) {
  if (mode_ != HubMode::lockstep) return;
  clock_.sim_us.store(HubClock::kStartUs, std::memory_order_release);
  drivers_opened_.wait(false, std::memory_order_acquire);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wall_timeout_s);
  for (;;) {
    grant_round();
    ++lock_stats_.handshake_rounds;
    std::string missing;
    for (const auto& d : devices_) {
      if (d->driver->session().state() == drivers::LinkState::streaming) continue;
      // Say why where the driver knows (the wrong unit: "device is type 1 serial 1002, expected …").
      const std::string& why = d->driver->session().last_error();
      missing += (missing.empty() ? "" : ", ") + d->spec.name + (why.empty() ? "" : " (" + why + ")");
    }
    if (missing.empty()) return;
    if (std::chrono::steady_clock::now() > deadline)
      throw std::runtime_error("lockstep: " + missing + " did not start streaming within " + std::to_string(wall_timeout_s) + " s");
  }
}

void DeviceHub::lockstep_deliver(std::uint64_t step, std::uint64_t period_us) {
  if (mode_ != HubMode::lockstep) return;
  clock_.sim_us.store(HubClock::kStartUs + step * period_us, std::memory_order_release);
  grant_round();
  ++lock_stats_.grants;
}

void DeviceHub::run_drivers() {
  std::uint64_t next_status = 0;
  std::uint64_t last_pass = 0;
  while (running_.load(std::memory_order_acquire)) {
    // A pass normally follows the last within ~0.3 ms; a long gap means this thread was starved
    // (a loaded machine): the devices' bytes piled up in the kernel meanwhile.
    const std::uint64_t pass = clock_.now_us();
    if (last_pass != 0 && pass - last_pass >= kReaderStallUs) {
      reader_stalls_.fetch_add(1, std::memory_order_relaxed);
      if (pass - last_pass > reader_stall_max_us_.load(std::memory_order_relaxed))
        reader_stall_max_us_.store(pass - last_pass, std::memory_order_relaxed);
    }
    last_pass = pass;
    bool changed = false;
    for (auto& d : devices_) {
      d->driver->poll(0);
      changed = changed || status_changed(*d);
    }
    const std::uint64_t now = clock_.now_us();
    // 10 Hz (rig/telemetry/CHANNELS.md), and at once when a link changes state or the sensor sticks
    // or moves again: a loss that the driver recovers from within 100 ms must still reach the
    // technician's telemetry.
    if (now >= next_status || changed) {
      publish_status(now);
      next_status = now + 100'000;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

// A status goes out at once, not at the next 10 Hz tick, when the link's state or the sensor's
// stuck verdict differs from what the last status said.
bool DeviceHub::status_changed(const Device& d) {
  const auto& session = d.driver->session();
  return session.state() != d.last_state || session.stuck() != d.stuck_published;
}

void DeviceHub::publish_status(std::uint64_t now_us) {
  for (const auto& d : devices_) {
    const auto& session = d->driver->session();
    // A device refused at this address (another kind, serial or protocol) is said once, not only
    // shown in telemetry: it will never stream until it is replaced.
    if (session.refusal() != d->refusal_reported) {
      d->refusal_reported = session.refusal();
      if (!d->refusal_reported.empty()) spdlog::error("device {} ({}): refused: {}", d->spec.name, d->driver->uri(), d->refusal_reported);
    }
    d->last_state = session.state();
    d->stuck_published = session.stuck();
    if (!status_out_) continue;
    const SampleWindow::Measured w = d->window.measure(now_us);
    telemetry::DeviceMeasured measured;
    measured.sample_rate_hz = w.rate_hz;
    measured.latency_p50_us = w.latency_p50_us;
    measured.latency_p99_us = w.latency_p99_us;
    measured.reader_stalls = reader_stalls();
    measured.reader_stall_max_ms = static_cast<float>(reader_stall_max_us()) * 1e-3f;
    const std::uint64_t origin = session_origin_us_.load(std::memory_order_acquire);
    measured.session_t_s = origin != 0 && now_us > origin ? static_cast<double>(now_us - origin) * 1e-6 : 0.0;
    status_out_->push(
        telemetry::device_status_item(d->spec.device_id, d->spec.name, d->driver->uri(), session, now_us, measured, d->spec.calibration));
  }
}

}  // namespace vitreo::rig
