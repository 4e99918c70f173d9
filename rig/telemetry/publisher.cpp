#include "rig/telemetry/publisher.hpp"

#include <algorithm>
#include <stdexcept>
#include <type_traits>

#include <cmath>

#include "rig/telemetry/telemetry_mapping.hpp"
#include "vitreo_lcm/receive_status_t.hpp"

namespace vitreo::telemetry {

namespace {
// Each item's channel (CHANNELS.md).
template <class T>
const char* channel_of() {
  if constexpr (std::is_same_v<T, InstrumentState>) return kChanInstrumentState;
  else if constexpr (std::is_same_v<T, Event>) return kChanEvent;
  else if constexpr (std::is_same_v<T, PhysicsTiming>) return kChanPhysicsTiming;
  else if constexpr (std::is_same_v<T, DeviceStatus>) return kChanDeviceStatus;
  else if constexpr (std::is_same_v<T, Score>) return kChanScore;
  else if constexpr (std::is_same_v<T, Criteria>) return kChanCriteria;
  else if constexpr (std::is_same_v<T, Totals>) return kChanTotals;
  else {
    static_assert(std::is_same_v<T, Controls>, "every item has its channel");
    return kChanControls;
  }
}
}  // namespace

std::uint32_t TimingReporter::steps_for_rate(std::int64_t period_ns, double hz) {
  const double steps = 1e9 / (hz * static_cast<double>(period_ns));
  return steps < 1.0 ? 1u : static_cast<std::uint32_t>(std::llround(steps));
}

void TimingReporter::on_step(std::uint64_t step, bool paused) {
  if ((step + 1) % every_ != 0) return;
  out_.push(timing_item(loop_.window_stats(), step, loop_.config().period_ns, paused));
  loop_.start_window();
}

TelemetryPublisher::TelemetryPublisher(PublisherConfig config) : config_(std::move(config)), lcm_(config_.url) {
  if (!lcm_.good()) throw std::runtime_error("telemetry: cannot open LCM URL '" + config_.url + "'");
}

TelemetrySource& TelemetryPublisher::add_source(std::string name, std::size_t capacity) {
  return sources_.emplace_back(std::move(name), capacity ? capacity : config_.default_capacity);
}

std::uint64_t TelemetryPublisher::dropped() const noexcept {
  std::uint64_t n = 0;
  for (const auto& s : sources_) n += s.dropped();
  return n;
}

int TelemetryPublisher::handle_incoming(int max_messages) {
  int n = 0;
  while (n < max_messages && lcm_.handleTimeout(0) > 0) ++n;
  return n;
}

void TelemetryPublisher::publish_receive_status(const std::string& process) {
  const std::vector<ReceiveStats::Row> rows = receive_stats_.snapshot();
  if (rows.empty()) return;
  vitreo_lcm::receive_status_t m;
  m.utime_us = wall_time_us();
  m.process = process;
  m.n = static_cast<std::int16_t>(std::min<std::size_t>(rows.size(), 256));
  for (std::size_t i = 0; i < static_cast<std::size_t>(m.n); ++i) {
    m.channel.push_back(rows[i].channel);
    m.received.push_back(static_cast<std::int64_t>(rows[i].received));
    m.rejected.push_back(static_cast<std::int64_t>(rows[i].rejected));
    m.handler_errors.push_back(static_cast<std::int64_t>(rows[i].handler_errors));
    m.last_error.push_back(rows[i].last_error);
  }
  if (lcm_.publish(kChanReceiveStatus, &m) == 0) {
    ++published_;
  } else {
    ++publish_errors_;
  }
}

std::size_t TelemetryPublisher::pump() {
  std::size_t n = 0;
  TelemetryItem item;
  for (auto& s : sources_) {
    // Bounded per call so one busy source cannot starve the others or the command channel.
    std::size_t budget = s.ring_.capacity();
    while (budget-- > 0 && s.ring_.try_pop(item)) {
      publish_item(item);
      ++n;
    }
  }
  return n;
}

void TelemetryPublisher::publish_item(const TelemetryItem& item) {
  const std::int64_t now = wall_time_us();
  int rc = 0;
  // telemetry_mapping.cpp fills every field; the publisher adds only what it alone knows.
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        auto m = to_lcm(v, now);
        if constexpr (std::is_same_v<T, PhysicsTiming>) m.telemetry_dropped = static_cast<std::int64_t>(dropped());
        rc = lcm_.publish(channel_of<T>(), &m);
      },
      item);
  if (rc == 0) {
    ++published_;
  } else {
    ++publish_errors_;
  }
}

}  // namespace vitreo::telemetry
