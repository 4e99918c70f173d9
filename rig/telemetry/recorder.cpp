// The recorder: header, inputs, a checksum event at every flush, the end event (RECORDING.md).
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/input_codec.hpp"
#include "rig/telemetry/publisher.hpp"
#include "rig/telemetry/recording.hpp"
#include "rig/telemetry/recording_checksum.hpp"
#include "vitreo_lcm/recording_check_t.hpp"
#include "vitreo_lcm/recording_end_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"

namespace vitreo::telemetry {
namespace {

template <class Msg>
void encode(const Msg& m, std::vector<std::uint8_t>& buf) {
  buf.resize(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0) throw std::runtime_error("LCM encode failed");
}

std::string hex16(std::uint64_t v) {
  char b[17];
  std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
  return b;
}

}  // namespace

Recorder::Recorder(const std::string& path, RecordingHeader header, RecorderConfig config)
    : path_(path), config_(config), ring_(config.ring_capacity) {
  log_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!log_->good()) throw std::runtime_error("recorder: cannot create '" + path + "': " + std::strerror(errno));
  header.utime_us = wall_time_us();
  start_wall_us_ = last_log_us_ = header.utime_us;
  period_us_ = header.step_period_us > 0 ? header.step_period_us : 1000;
  vitreo_lcm::recording_header_t h;
  h.utime_us = header.utime_us;
  h.format_version = vitreo_lcm::recording_header_t::FORMAT_VERSION;
  h.software_version = header.software_version.empty() ? std::string("vitreo ") + VITREO_VERSION : header.software_version;
  h.case_id = header.case_id;
  h.step_period_us = header.step_period_us;
  h.config_name = header.config_name;
  h.config_text = header.config_text;
  h.snapshot_ref = header.snapshot_ref;
  h.snapshot_hash = header.snapshot_hash;
  encode(h, buf_);
  write_event(kChanRecHeader, header.utime_us);
  flush();  // the header is on disk before the first input is
  buf_.reserve(1024);
}

Recorder::~Recorder() { close(); }

std::int64_t Recorder::log_time_of_step(std::int64_t step) noexcept {
  last_log_us_ = std::max(last_log_us_, start_wall_us_ + step * period_us_);
  return last_log_us_;
}

void Recorder::write_event(const char* channel, std::int64_t timestamp_us) {
  lcm::LogEvent ev{};
  ev.eventnum = event_num_;
  ev.timestamp = timestamp_us;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(buf_.size());
  ev.data = buf_.data();
  if (log_->writeEvent(&ev) != 0) throw std::runtime_error("recorder: write failed on '" + path_ + "'");
  ++event_num_;
  crc_ = checksum_event(crc_, channel, buf_.data(), buf_.size());
}

void Recorder::write_input(const RecordedInput& in) {
  encode(to_lcm(in), buf_);
  write_event(kChanRecInput, log_time_of_step(in.step));
  ++inputs_in_file_;
  last_step_ = in.step;
  ++written_;
}

void Recorder::write_check() {
  if (event_num_ == events_at_check_) return;  // nothing new to vouch for
  vitreo_lcm::recording_check_t c;
  c.block = static_cast<std::int64_t>(checks_);
  c.events = event_num_;
  c.inputs = inputs_in_file_;
  c.last_step = last_step_;
  c.crc32 = crc_;
  encode(c, buf_);
  write_event(kChanRecCheck, last_log_us_);
  events_at_check_ = event_num_;
  ++checks_;
}

void Recorder::flush() {
  if (std::fflush(log_->getFilePtr()) != 0) throw std::runtime_error("recorder: flush failed on '" + path_ + "'");
  ++flushes_;
}

void Recorder::fail(const char* what) noexcept {
  if (!failed_) spdlog::error("{} — recording stopped, the session goes on", what);
  failed_ = true;
  log_.reset();  // closes the file: what was written and checksummed so far stays replayable
}

void Recorder::discard_queued() noexcept {
  RecordedInput in;
  while (ring_.try_pop(in)) ++lost_;
}

std::size_t Recorder::pump(std::int64_t now_ns) noexcept {
  if (!log_) {
    discard_queued();
    return 0;
  }
  std::size_t n = 0;
  try {
    RecordedInput in;
    auto checkpoint = [&] {
      write_check();
      flush();
      last_flush_ns_ = now_ns;
      unflushed_since_us_ = INT64_MIN;
    };
    while (ring_.try_pop(in)) {
      write_input(in);
      ++n;
      if (unflushed_since_us_ == INT64_MIN) unflushed_since_us_ = in.host_time_us;
      if (in.host_time_us - unflushed_since_us_ >= config_.flush_input_span_us) checkpoint();
    }
    if (last_flush_ns_ == INT64_MIN || now_ns - last_flush_ns_ >= config_.flush_interval_ns) checkpoint();
  } catch (const std::exception& e) {
    ++lost_;  // the input being written
    fail(e.what());
    discard_queued();
  }
  return n;
}

bool Recorder::finish(const RecordingEnd& end) noexcept {
  if (!log_) return false;
  try {
    RecordedInput in;
    while (ring_.try_pop(in)) write_input(in);
    vitreo_lcm::recording_end_t e;
    e.utime_us = wall_time_us();
    e.steps = end.steps;
    e.events = event_num_;
    e.inputs = inputs_in_file_;
    e.state_hash = hex16(end.state_hash);
    e.stop_reason = end.stop_reason;
    e.crc32 = crc_;
    encode(e, buf_);
    write_event(kChanRecEnd, log_time_of_step(end.steps));
    flush();
    fdatasync(fileno(log_->getFilePtr()));
    log_.reset();
    return true;
  } catch (const std::exception& e) {
    fail(e.what());
    discard_queued();
    return false;
  }
}

void Recorder::close() noexcept {
  if (!log_) return;
  try {
    RecordedInput in;
    while (ring_.try_pop(in)) write_input(in);
    write_check();
    flush();
    fdatasync(fileno(log_->getFilePtr()));
    log_.reset();
  } catch (const std::exception& e) {
    fail(e.what());
    discard_queued();
  }
}

}  // namespace vitreo::telemetry
