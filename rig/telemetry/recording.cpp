#include "rig/telemetry/recording.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/lcm_decode.hpp"
#include "rig/telemetry/publisher.hpp"
#include "vitreo_lcm/device_input_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"

namespace vitreo::telemetry {
namespace {

std::int64_t monotonic_us() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

vitreo_lcm::device_input_t to_lcm(const DeviceInput& in) {
  vitreo_lcm::device_input_t m;
  m.host_time_us = in.host_time_us;
  m.device_time_us = in.device_time_us;
  m.step = in.step;
  m.device_id = in.device_id;
  m.device_kind = in.device_kind;
  m.channel = in.channel;
  m.sequence = in.sequence;
  const std::size_t nv = std::min<std::size_t>(in.n_values, DeviceInput::kMaxValues);
  const std::size_t nr = std::min<std::size_t>(in.n_raw, DeviceInput::kMaxRaw);
  m.n_values = static_cast<std::int16_t>(nv);
  m.values.assign(in.values, in.values + nv);
  m.n_raw = static_cast<std::int16_t>(nr);
  m.raw.assign(in.raw, in.raw + nr);
  return m;
}

bool from_lcm(const vitreo_lcm::device_input_t& m, DeviceInput& in) {
  if (m.n_values < 0 || static_cast<std::size_t>(m.n_values) > DeviceInput::kMaxValues) return false;
  if (m.n_raw < 0 || static_cast<std::size_t>(m.n_raw) > DeviceInput::kMaxRaw) return false;
  in = DeviceInput{};
  in.host_time_us = m.host_time_us;
  in.device_time_us = m.device_time_us;
  in.step = m.step;
  in.device_id = m.device_id;
  in.device_kind = m.device_kind;
  in.channel = m.channel;
  in.sequence = m.sequence;
  in.n_values = static_cast<std::uint8_t>(m.n_values);
  std::copy(m.values.begin(), m.values.end(), in.values);
  in.n_raw = static_cast<std::uint8_t>(m.n_raw);
  std::copy(m.raw.begin(), m.raw.end(), in.raw);
  return true;
}

template <class Msg>
void encode(const Msg& m, std::vector<std::uint8_t>& buf) {
  buf.resize(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0) throw std::runtime_error("LCM encode failed");
}

}  // namespace

bool operator==(const DeviceInput& a, const DeviceInput& b) noexcept {
  if (a.host_time_us != b.host_time_us || a.device_time_us != b.device_time_us || a.step != b.step ||
      a.device_id != b.device_id || a.device_kind != b.device_kind || a.channel != b.channel ||
      a.sequence != b.sequence || a.n_values != b.n_values || a.n_raw != b.n_raw)
    return false;
  // Bit patterns, not values: replay must be bit-identical (NaN == NaN, -0 != +0 here).
  return std::memcmp(a.values, b.values, sizeof(double) * std::min<std::size_t>(a.n_values, DeviceInput::kMaxValues)) == 0 &&
         std::memcmp(a.raw, b.raw, std::min<std::size_t>(a.n_raw, DeviceInput::kMaxRaw)) == 0;
}

Recorder::Recorder(const std::string& path, RecordingHeader header, RecorderConfig config)
    : path_(path), config_(config), ring_(config.ring_capacity) {
  log_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!log_->good()) throw std::runtime_error("recorder: cannot create '" + path + "': " + std::strerror(errno));
  wall_minus_mono_us_ = wall_time_us() - monotonic_us();
  header.utime_us = wall_time_us();
  vitreo_lcm::recording_header_t h;
  h.utime_us = header.utime_us;
  h.format_version = vitreo_lcm::recording_header_t::FORMAT_VERSION;
  h.software_version = header.software_version;
  h.case_id = header.case_id;
  h.step_period_us = header.step_period_us;
  h.config_name = header.config_name;
  h.config_text = header.config_text;
  h.snapshot_ref = header.snapshot_ref;
  h.snapshot_hash = header.snapshot_hash;
  encode(h, buf_);
  lcm::LogEvent ev{};
  ev.eventnum = event_num_++;
  ev.timestamp = header.utime_us;
  ev.channel = kChanRecHeader;
  ev.datalen = static_cast<std::int32_t>(buf_.size());
  ev.data = buf_.data();
  if (log_->writeEvent(&ev) != 0) throw std::runtime_error("recorder: cannot write header to '" + path + "'");
  flush();  // the header is on disk before the first input is
  buf_.reserve(1024);
}

Recorder::~Recorder() { close(); }

void Recorder::write_input(const DeviceInput& in) {
  encode(to_lcm(in), buf_);
  lcm::LogEvent ev{};
  ev.eventnum = event_num_++;
  ev.timestamp = in.host_time_us + wall_minus_mono_us_;
  ev.channel = kChanRecInput;
  ev.datalen = static_cast<std::int32_t>(buf_.size());
  ev.data = buf_.data();
  if (log_->writeEvent(&ev) != 0) throw std::runtime_error("recorder: write failed on '" + path_ + "'");
  ++written_;
}

void Recorder::flush() {
  if (std::fflush(log_->getFilePtr()) != 0) throw std::runtime_error("recorder: flush failed on '" + path_ + "'");
  ++flushes_;
}

void Recorder::fail(const char* what) noexcept {
  if (!failed_) spdlog::error("{} — recording stopped, the session goes on", what);
  failed_ = true;
  log_.reset();  // closes the file: what was written so far stays readable
}

void Recorder::discard_queued() noexcept {
  DeviceInput in;
  while (ring_.try_pop(in)) ++lost_;
}

std::size_t Recorder::pump(std::int64_t now_ns) noexcept {
  if (!log_) {
    discard_queued();
    return 0;
  }
  std::size_t n = 0;
  try {
    DeviceInput in;
    while (ring_.try_pop(in)) {
      write_input(in);
      ++n;
    }
    if (last_flush_ns_ == INT64_MIN || now_ns - last_flush_ns_ >= config_.flush_interval_ns) {
      flush();
      last_flush_ns_ = now_ns;
    }
  } catch (const std::exception& e) {
    ++lost_;  // the input being written
    fail(e.what());
    discard_queued();
  }
  return n;
}

void Recorder::close() noexcept {
  if (!log_) return;
  try {
    DeviceInput in;
    while (ring_.try_pop(in)) write_input(in);
    flush();
    fdatasync(fileno(log_->getFilePtr()));
    log_.reset();
  } catch (const std::exception& e) {
    fail(e.what());
    discard_queued();
  }
}

Recording read_recording(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("recording: cannot open '" + path + "'");
  Recording rec;
  bool have_header = false;
  long good_end = 0;
  const lcm::LogEvent* ev = nullptr;
  while ((ev = log.readNextEvent()) != nullptr) {
    if (!have_header) {
      vitreo_lcm::recording_header_t h;
      if (ev->channel != kChanRecHeader || ev->datalen < 0 ||
          decode_message(ev->data, static_cast<std::size_t>(ev->datalen), h) != DecodeError::None)
        throw std::runtime_error("recording: '" + path + "' does not start with a " + kChanRecHeader + " event");
      if (h.format_version < 1 || h.format_version > vitreo_lcm::recording_header_t::FORMAT_VERSION)
        throw std::runtime_error("recording: '" + path + "' has format version " + std::to_string(h.format_version) +
                                 ", this build reads 1.." +
                                 std::to_string(vitreo_lcm::recording_header_t::FORMAT_VERSION));
      rec.header = RecordingHeader{h.utime_us,     h.format_version, h.software_version, h.case_id, h.step_period_us,
                                   h.config_name,  h.config_text,    h.snapshot_ref,     h.snapshot_hash};
      have_header = true;
    } else if (ev->channel == kChanRecInput) {
      vitreo_lcm::device_input_t m;
      DeviceInput in;
      if (ev->datalen < 0 || decode_message(ev->data, static_cast<std::size_t>(ev->datalen), m) != DecodeError::None ||
          !from_lcm(m, in))
        throw std::runtime_error("recording: undecodable input event " + std::to_string(ev->eventnum) + " in '" + path + "'");
      rec.inputs.push_back(in);
    } else {
      ++rec.other_events;
    }
    good_end = std::ftell(log.getFilePtr());
  }
  if (!have_header) throw std::runtime_error("recording: '" + path + "' is empty or has no header");
  struct stat st{};
  if (::stat(path.c_str(), &st) == 0) rec.truncated = st.st_size != good_end;
  return rec;
}

std::size_t replay(const Recording& rec, runtime::Clock& clock, ReplayOptions options,
                   const std::function<void(const DeviceInput&)>& fn) {
  if (rec.inputs.empty()) return 0;
  const std::int64_t t0_ns = clock.now_ns();
  const std::int64_t first_us = rec.inputs.front().host_time_us;
  std::size_t n = 0;
  for (const DeviceInput& in : rec.inputs) {
    if (options.speed > 0) {
      const double offset_ns = static_cast<double>(in.host_time_us - first_us) * 1000.0 / options.speed;
      clock.sleep_until_ns(t0_ns + static_cast<std::int64_t>(std::llround(offset_ns)));
    }
    fn(in);
    ++n;
  }
  return n;
}

}  // namespace vitreo::telemetry
