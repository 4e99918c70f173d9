// Helper process for the udpm test (udpm_netns_test.sh), which runs it only inside a private network
// namespace. Modes:
//   publish <url> <n>           publish n event_t through TelemetryPublisher, ~1 kHz
//   subscribe <url> <n> <s>     count event_t until n arrived or s seconds passed; exit 0 iff n
//   count <log> <n>             count decodable event_t in an LCM log; exit 0 iff exactly n
//   respond <url> <n> <s>       stand-in rig: a CommandServer (case 1 of 3, running, zoom 1..25)
//                               answering until n commands were handled or s seconds passed
// A udpm URL ("" = the default) is refused unless VITREO_IN_PRIVATE_NETNS=1: this program must
// never send multicast on the host network.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "rig/telemetry/publisher.hpp"
#include "vitreo_lcm/event_t.hpp"

using namespace vitreo::telemetry;

namespace {
std::string resolve(const std::string& url) { return url.empty() ? std::string(kDefaultLcmUrl) : url; }

bool allowed(const std::string& url) {
  const char* ns = std::getenv("VITREO_IN_PRIVATE_NETNS");
  if (url.rfind("udpm://", 0) == 0 && !(ns && std::string(ns) == "1")) {
    std::fprintf(stderr, "lcm_probe: refusing %s outside a private network namespace\n", url.c_str());
    return false;
  }
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  try {
    if (mode == "publish" && argc == 4) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      const long n = std::atol(argv[3]);
      TelemetryPublisher pub(PublisherConfig{url, 4096});
      TelemetrySource& src = pub.add_source("probe");
      for (long i = 0; i < n; ++i) {
        Event e;
        e.step = i;
        e.kind = EventKind::Cut;
        e.magnitude = 0.5 * static_cast<double>(i);
        src.push(e);
        if (i % 10 == 9) {
          pub.pump();
          std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
      }
      pub.pump();
      std::printf("lcm_probe: published %llu events on %s (errors %llu, dropped %llu)\n",
                  static_cast<unsigned long long>(pub.published()), url.c_str(),
                  static_cast<unsigned long long>(pub.publish_errors()), static_cast<unsigned long long>(pub.dropped()));
      return pub.published() == static_cast<unsigned long long>(n) ? 0 : 1;
    }
    if (mode == "subscribe" && argc == 5) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      const long n = std::atol(argv[3]);
      lcm::LCM lc(url);
      if (!lc.good()) {
        std::fprintf(stderr, "lcm_probe: cannot open %s\n", url.c_str());
        return 2;
      }
      struct Counter {
        long n = 0, in_order = 0;
        void operator()(const vitreo_lcm::event_t& e) {
          if (e.step == n) ++in_order;
          ++n;
        }
      } c;
      // LCM keeps only 30 undelivered messages per subscription by default; under load this
      // process may not run for longer than that takes to arrive, so keep them all.
      subscribe_to<vitreo_lcm::event_t>(lc, kChanEvent, &c)->setQueueCapacity(static_cast<int>(n) + 16);
      std::printf("lcm_probe: subscribed\n");
      std::fflush(stdout);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(std::atol(argv[4]));
      while (c.n < n && std::chrono::steady_clock::now() < deadline) lc.handleTimeout(50);
      std::printf("lcm_probe: received %ld/%ld (%ld in order)\n", c.n, n, c.in_order);
      return c.n == n && c.in_order == n ? 0 : 1;
    }
    if (mode == "respond" && argc == 5) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      TelemetryPublisher pub(PublisherConfig{url, 16});
      CommandServer server(pub.lcm());
      CommandContext ctx;
      ctx.case_index = 0;
      ctx.case_count = 3;
      server.context().write(ctx);
      std::printf("lcm_probe: responding\n");
      std::fflush(stdout);
      const std::uint64_t n = static_cast<std::uint64_t>(std::atol(argv[3]));
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(std::atol(argv[4]));
      while (server.accepted() + server.refused() < n && std::chrono::steady_clock::now() < deadline)
        pub.lcm().handleTimeout(50);
      std::printf("lcm_probe: %llu accepted, %llu refused\n", static_cast<unsigned long long>(server.accepted()),
                  static_cast<unsigned long long>(server.refused()));
      return 0;
    }
    if (mode == "count" && argc == 4) {
      lcm::LogFile log(argv[2], "r");
      if (!log.good()) return 2;
      long n = 0;
      for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
        vitreo_lcm::event_t e;
        if (ev->channel == kChanEvent && e.decode(ev->data, 0, ev->datalen) >= 0 && e.step == n) ++n;
      }
      std::printf("lcm_probe: log %s holds %ld event_t in order\n", argv[2], n);
      return n == std::atol(argv[3]) ? 0 : 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lcm_probe: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr, "usage: lcm_probe publish <url> <n> | subscribe <url> <n> <s> | count <log> <n>\n");
  return 64;
}
