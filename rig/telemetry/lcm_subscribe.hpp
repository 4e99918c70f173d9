#pragma once
// Checked LCM subscriptions: the only way vitreo (and its tools) listen to a channel.
//
//   struct OnAck { void operator()(const vitreo_lcm::command_ack_t& a) { ... } } on_ack;
//   CheckedSubscription sub = subscribe_to<vitreo_lcm::command_ack_t>(lcm, kChanCommandAck, &on_ack);
//
// Every packet is counted, decoded through decode_message() (lcm_decode.hpp) and handed to the
// handler only when it decodes exactly; a malformed or oversized packet is dropped, counted and
// logged (the first one per channel, then at most once a second). Nothing can cross liblcm's C
// dispatch: the callback registered with lcm_subscribe() is noexcept and catches whatever the
// decoder or the handler throws (a handler failure is counted apart). An exception that crossed it
// would leave the lcm_t inside lcm_handle(), and the next message would abort the process.
//
// Why the C API rather than lcm::LCM::subscribeFunction: its typed path decodes with the unchecked
// generated decoder outside any try, its untyped path builds a std::string for the channel before
// our code runs, and its member-function path trips a UBSan false positive on GCC 12.
#include <lcm/lcm.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rig/telemetry/lcm_decode.hpp"

namespace vitreo::telemetry {

// Receive accounting of one channel. Counters are written on the thread that handles the LCM
// object and may be read from any thread.
class ChannelCounters {
 public:
  explicit ChannelCounters(std::string channel) : channel_(std::move(channel)) {}
  const std::string& channel() const noexcept { return channel_; }
  std::uint64_t received() const noexcept { return received_.load(std::memory_order_relaxed); }
  std::uint64_t rejected() const noexcept { return rejected_.load(std::memory_order_relaxed); }
  std::uint64_t handler_errors() const noexcept { return handler_errors_.load(std::memory_order_relaxed); }
  std::string last_error() const;

  // LCM thread.
  void on_received() noexcept { received_.fetch_add(1, std::memory_order_relaxed); }
  void on_rejected(const char* why, std::size_t bytes) noexcept;
  void on_handler_error(const char* what) noexcept;

 private:
  void note(const char* kind, const char* what, std::size_t bytes) noexcept;

  std::string channel_;
  std::atomic<std::uint64_t> received_{0}, rejected_{0}, handler_errors_{0};
  mutable std::mutex mu_;  // last_error_
  std::string last_error_;
  std::int64_t last_log_ns_ = 0;  // LCM thread only: rate limit of the log lines
  std::uint64_t unlogged_ = 0;
  bool logged_once_ = false;
};

// The channels one process listens to, for its summary and VITREO_RECEIVE_STATUS.
class ReceiveStats {
 public:
  // The counters of `channel`, created on first use (the reference stays valid).
  ChannelCounters& channel(std::string_view channel);
  struct Row {
    std::string channel;
    std::uint64_t received = 0, rejected = 0, handler_errors = 0;
    std::string last_error;
  };
  std::vector<Row> snapshot() const;

 private:
  mutable std::mutex mu_;
  std::deque<ChannelCounters> channels_;
};

// A subscription that unsubscribes when destroyed (destroy it before its lcm::LCM).
class [[nodiscard]] CheckedSubscription {
 public:
  CheckedSubscription() = default;
  CheckedSubscription(CheckedSubscription&& o) noexcept { *this = std::move(o); }
  CheckedSubscription& operator=(CheckedSubscription&& o) noexcept;
  CheckedSubscription(const CheckedSubscription&) = delete;
  CheckedSubscription& operator=(const CheckedSubscription&) = delete;
  ~CheckedSubscription() { reset(); }

  void reset() noexcept;
  bool active() const noexcept { return sub_ != nullptr; }
  // How many packets LCM queues for this subscription before it drops (LCM's own default: 30).
  int set_queue_capacity(int messages) noexcept;
  const ChannelCounters& counters() const noexcept { return *ctx_->counters; }

  struct Context {
    virtual ~Context() = default;
    virtual void deliver(const void* data, std::size_t size) noexcept = 0;
    ChannelCounters* counters = nullptr;
    std::unique_ptr<ChannelCounters> own;  // when the caller keeps no ReceiveStats
    std::size_t max_bytes = 0;
  };
  // Registers `ctx` on `channel` (exact name, not a regex: the channel names here are literal).
  static CheckedSubscription attach(lcm::LCM& lc, const std::string& channel, std::unique_ptr<Context> ctx,
                                    ChannelCounters* counters);

 private:
  static void on_packet(const lcm_recv_buf_t* rbuf, const char* channel, void* user) noexcept;

  lcm_t* lcm_ = nullptr;
  lcm_subscription_t* sub_ = nullptr;
  std::unique_ptr<Context> ctx_;
};

// Packets larger than this are refused unread unless a subscription says otherwise: every vitreo
// message that crosses the bus is a few hundred bytes.
inline constexpr std::size_t kDefaultMaxMessageBytes = 64 * 1024;

// `handler` (any callable `void(const Msg&)`) must outlive the subscription. `counters`: where to
// count (e.g. a ReceiveStats' channel); nullptr keeps them in the subscription.
template <class Msg, class Handler>
CheckedSubscription subscribe_to(lcm::LCM& lc, const std::string& channel, Handler* handler,
                                 ChannelCounters* counters = nullptr,
                                 std::size_t max_bytes = kDefaultMaxMessageBytes) {
  struct Typed final : CheckedSubscription::Context {
    Handler* handler = nullptr;
    void deliver(const void* data, std::size_t size) noexcept override {
      Msg msg;
      const DecodeError e = decode_message(data, size, msg, max_bytes);
      if (e != DecodeError::None) {
        counters->on_rejected(to_string(e), size);
        return;
      }
      try {
        (*handler)(msg);
      } catch (const std::exception& ex) {
        counters->on_handler_error(ex.what());
      } catch (...) {
        counters->on_handler_error("unknown exception");
      }
    }
  };
  auto ctx = std::make_unique<Typed>();
  ctx->handler = handler;
  ctx->max_bytes = max_bytes;
  return CheckedSubscription::attach(lc, channel, std::move(ctx), counters);
}

}  // namespace vitreo::telemetry
