#include "rig/telemetry/lcm_subscribe.hpp"

#include <time.h>

#include <stdexcept>

#include <spdlog/spdlog.h>

namespace vitreo::telemetry {

namespace {
std::int64_t steady_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
}  // namespace

std::string ChannelCounters::last_error() const {
  std::lock_guard lock(mu_);
  return last_error_;
}

void ChannelCounters::on_rejected(const char* why, std::size_t bytes) noexcept {
  rejected_.fetch_add(1, std::memory_order_relaxed);
  note("packet refused", why, bytes);
}

void ChannelCounters::on_handler_error(const char* what) noexcept {
  handler_errors_.fetch_add(1, std::memory_order_relaxed);
  note("handling failed", what, 0);
}

void ChannelCounters::note(const char* kind, const char* what, std::size_t bytes) noexcept {
  try {
    {
      std::lock_guard lock(mu_);
      last_error_ = std::string(kind) + ": " + what;
    }
    // The first one is logged at once; after that at most one line a second, with the count, so a
    // flood of bad packets cannot flood the log or slow the thread that handles the bus.
    const std::int64_t now = steady_ns();
    if (!logged_once_ || now - last_log_ns_ >= 1'000'000'000) {
      if (unlogged_ > 0) {
        spdlog::warn("LCM {}: {} ({} bytes; {} more since the last report)", channel_, last_error_, bytes, unlogged_);
      } else {
        spdlog::warn("LCM {}: {} ({} bytes) — dropped, the process goes on", channel_, std::string(kind) + ": " + what,
                     bytes);
      }
      logged_once_ = true;
      last_log_ns_ = now;
      unlogged_ = 0;
    } else {
      ++unlogged_;
    }
  } catch (...) {
    // Out of memory while noting it: the counter above still says it happened.
  }
}

ChannelCounters& ReceiveStats::channel(std::string_view name) {
  std::lock_guard lock(mu_);
  for (auto& c : channels_) {
    if (c.channel() == name) return c;
  }
  return channels_.emplace_back(std::string(name));
}

std::vector<ReceiveStats::Row> ReceiveStats::snapshot() const {
  std::lock_guard lock(mu_);
  std::vector<Row> rows;
  rows.reserve(channels_.size());
  for (const auto& c : channels_) {
    rows.push_back(Row{c.channel(), c.received(), c.rejected(), c.handler_errors(), c.last_error()});
  }
  return rows;
}

CheckedSubscription& CheckedSubscription::operator=(CheckedSubscription&& o) noexcept {
  if (this != &o) {
    reset();
    lcm_ = o.lcm_;
    sub_ = o.sub_;
    ctx_ = std::move(o.ctx_);  // the C side holds ctx_.get(), which does not move
    o.lcm_ = nullptr;
    o.sub_ = nullptr;
  }
  return *this;
}

void CheckedSubscription::reset() noexcept {
  if (sub_ && lcm_) lcm_unsubscribe(lcm_, sub_);
  sub_ = nullptr;
  lcm_ = nullptr;
  ctx_.reset();
}

int CheckedSubscription::set_queue_capacity(int messages) noexcept {
  return sub_ ? lcm_subscription_set_queue_capacity(sub_, messages) : -1;
}

void CheckedSubscription::on_packet(const lcm_recv_buf_t* rbuf, const char*, void* user) noexcept {
  auto* ctx = static_cast<Context*>(user);
  ctx->counters->on_received();
  if (rbuf->data_size > ctx->max_bytes) {
    ctx->counters->on_rejected(to_string(DecodeError::Oversized), rbuf->data_size);
    return;
  }
  ctx->deliver(rbuf->data, rbuf->data_size);
}

CheckedSubscription CheckedSubscription::attach(lcm::LCM& lc, const std::string& channel, std::unique_ptr<Context> ctx,
                                                ChannelCounters* counters) {
  lcm_t* raw = lc.getUnderlyingLCM();
  if (raw == nullptr) throw std::runtime_error("LCM: cannot subscribe to " + channel + ": the LCM object is not usable");
  if (counters == nullptr) {
    ctx->own = std::make_unique<ChannelCounters>(channel);
    counters = ctx->own.get();
  }
  ctx->counters = counters;
  // liblcm treats the name as a regular expression: escape nothing, the names are [A-Z_] only.
  for (char c : channel) {
    const bool plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
    if (!plain) throw std::invalid_argument("LCM: channel name '" + channel + "' is not a plain name");
  }
  CheckedSubscription s;
  s.sub_ = lcm_subscribe(raw, channel.c_str(), &CheckedSubscription::on_packet, ctx.get());
  if (s.sub_ == nullptr) throw std::runtime_error("LCM: cannot subscribe to " + channel);
  s.lcm_ = raw;
  s.ctx_ = std::move(ctx);
  return s;
}

}  // namespace vitreo::telemetry
