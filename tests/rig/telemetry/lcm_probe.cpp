// Helper process for the udpm test (udpm_netns_test.sh), which runs it only inside a private network
// namespace. Modes:
//   publish <url> <n>           publish n event_t through TelemetryPublisher, ~1 kHz
//   subscribe <url> <n> <s>     count event_t until n arrived or s seconds passed; exit 0 iff n
//   count <log> <n>             count decodable event_t in an LCM log; exit 0 iff exactly n
//   respond[-noisy] <url> <n> <s>
//                               stand-in rig: a CommandServer (case 1 of 3, running, zoom 1..25)
//                               answering until n commands were handled or s seconds passed
//   wait <url> <channel> <s>    exit 0 once anything arrives on channel within s seconds
//   inject <url>                malformed packets on VITREO_COMMAND (malformed_packets.hpp; prints
//                               how many), garbage on every other vitreo channel and, on udpm, raw
//                               datagrams that are not LCM at all or lie in their fragment headers
//   expect-status <url> <channel> <n> <s>
//                               exit 0 once a VITREO_RECEIVE_STATUS counts >= n packets refused on
//                               channel (within s seconds); prints its row
// A udpm URL ("" = the default) is refused unless VITREO_IN_PRIVATE_NETNS=1: this program must
// never send multicast on the host network.
#include <arpa/inet.h>
#include <lcm/lcm.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "rig/telemetry/publisher.hpp"
#include "tests/rig/telemetry/malformed_packets.hpp"
#include "tests/rig/telemetry/physics_stand_in.hpp"
#include "vitreo_lcm/event_t.hpp"
#include "vitreo_lcm/receive_status_t.hpp"

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
// Datagrams straight to the LCM multicast group (the default URL's): LCM's own packet parsing in
// liblcm is what they exercise, before any decoder of ours runs.
int send_raw_datagrams() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return 0;
  unsigned char ttl = 0, loop = 1;
  setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
  setsockopt(fd, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(7667);
  inet_pton(AF_INET, "239.255.76.67", &to.sin_addr);
  std::mt19937 rng(20);
  auto be32 = [](std::vector<std::uint8_t>& v, std::uint32_t x) {
    for (int i = 3; i >= 0; --i) v.push_back(static_cast<std::uint8_t>(x >> (8 * i)));
  };
  auto be16 = [](std::vector<std::uint8_t>& v, std::uint16_t x) {
    v.push_back(static_cast<std::uint8_t>(x >> 8));
    v.push_back(static_cast<std::uint8_t>(x));
  };
  int sent = 0;
  auto send = [&](const std::vector<std::uint8_t>& d) {
    if (::sendto(fd, d.data(), d.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to) >= 0) ++sent;
  };
  for (int i = 0; i < 50; ++i) {  // random bytes
    std::vector<std::uint8_t> d(static_cast<std::size_t>(rng() % 1400));
    for (auto& b : d) b = static_cast<std::uint8_t>(rng());
    send(d);
  }
  for (int i = 0; i < 20; ++i) {  // a short-message header (LC02) whose channel never ends
    std::vector<std::uint8_t> d;
    be32(d, 0x4c433032);
    be32(d, static_cast<std::uint32_t>(i));
    d.insert(d.end(), 100, 'A');
    send(d);
  }
  // Fragment headers (LC03) that lie: message sizes of 0 and 256 MiB, fragment counts of 0 and
  // 65535, an offset past the message, the fragment of a message whose first never came.
  const std::uint32_t sizes[] = {0, 1, 1u << 28, 0xffffffffu};
  const std::uint16_t counts[] = {0, 1, 2, 65535};
  std::uint32_t seq = 1000;
  for (std::uint32_t size : sizes) {
    for (std::uint16_t n : counts) {
      for (std::uint16_t no : {std::uint16_t{0}, std::uint16_t{1}, std::uint16_t{65534}}) {
        std::vector<std::uint8_t> d;
        be32(d, 0x4c433033);
        be32(d, seq++);
        be32(d, size);
        be32(d, no == 0 ? 0u : 0xfffffff0u);  // fragment offset
        be16(d, no);
        be16(d, n);
        if (no == 0) {
          const char* ch = "VITREO_COMMAND";
          d.insert(d.end(), ch, ch + std::strlen(ch) + 1);
        }
        d.insert(d.end(), 64, 0x5a);
        send(d);
      }
    }
  }
  ::close(fd);
  return sent;
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
      auto sub = subscribe_to<vitreo_lcm::event_t>(lc, kChanEvent, &c);
      sub.set_queue_capacity(static_cast<int>(n) + 16);
      std::printf("lcm_probe: subscribed\n");
      std::fflush(stdout);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(std::atol(argv[4]));
      while (c.n < n && std::chrono::steady_clock::now() < deadline) lc.handleTimeout(50);
      std::printf("lcm_probe: received %ld/%ld (%ld in order)\n", c.n, n, c.in_order);
      return c.n == n && c.in_order == n ? 0 : 1;
    }
    if ((mode == "respond" || mode == "respond-noisy") && argc == 5) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      TelemetryPublisher pub(PublisherConfig{url, 16});
      // respond-noisy: every command is first answered with malformed acknowledgements (string
      // lengths INT_MIN and 0, the packets that crashed vitreo-cmd), then by the server. Subscribed
      // first, so liblcm calls it first.
      lcm_subscription_t* noise = nullptr;
      if (mode == "respond-noisy") {
        noise = lcm_subscribe(
            pub.lcm().getUnderlyingLCM(), kChanCommand,
            [](const lcm_recv_buf_t*, const char*, void* u) {
              for (const auto& p : vitreo::test::malformed_acks())
                lcm_publish(static_cast<lcm_t*>(u), kChanCommandAck, p.bytes.data(), static_cast<unsigned>(p.bytes.size()));
            },
            pub.lcm().getUnderlyingLCM());
      }
      CommandServer server(pub.lcm());
      vitreo::test::PhysicsStandIn physics;  // case 1 of 3, running
      physics.ctx.case_count = 3;
      std::printf("lcm_probe: responding\n");
      std::fflush(stdout);
      const std::uint64_t n = static_cast<std::uint64_t>(std::atol(argv[3]));
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(std::atol(argv[4]));
      while (server.accepted() + server.refused() < n && std::chrono::steady_clock::now() < deadline) {
        pub.lcm().handleTimeout(5);
        physics.step(server);
      }
      std::printf("lcm_probe: %llu accepted, %llu refused\n", static_cast<unsigned long long>(server.accepted()),
                  static_cast<unsigned long long>(server.refused()));
      if (noise) lcm_unsubscribe(pub.lcm().getUnderlyingLCM(), noise);
      return 0;
    }
    if (mode == "wait" && argc == 5) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      lcm::LCM lc(url);
      if (!lc.good()) return 2;
      bool got = false;
      lcm_subscription_t* sub = lcm_subscribe(
          lc.getUnderlyingLCM(), argv[3], [](const lcm_recv_buf_t*, const char*, void* u) { *static_cast<bool*>(u) = true; },
          &got);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(std::atol(argv[4]));
      while (!got && std::chrono::steady_clock::now() < deadline) lc.handleTimeout(50);
      lcm_unsubscribe(lc.getUnderlyingLCM(), sub);
      std::printf("lcm_probe: %s on %s\n", got ? "traffic" : "nothing", argv[3]);
      return got ? 0 : 1;
    }
    if (mode == "inject" && argc == 3) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      lcm::LCM lc(url);
      if (!lc.good()) return 2;
      int commands = 0;
      for (const auto& p : vitreo::test::malformed_commands()) {
        if (lcm_publish(lc.getUnderlyingLCM(), kChanCommand, p.bytes.data(), static_cast<unsigned>(p.bytes.size())) == 0)
          ++commands;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      std::mt19937 rng(7);
      int junk = 0;
      for (const char* ch : {kChanInstrumentState, kChanDeviceStatus, kChanPhysicsTiming, kChanEvent, kChanScore,
                             kChanCommandAck, kChanRecHeader, kChanRecInput, kChanReceiveStatus, "NOT_A_VITREO_CHANNEL"}) {
        for (int i = 0; i < 10; ++i) {
          std::vector<std::uint8_t> d(static_cast<std::size_t>(rng() % 300));
          for (auto& b : d) b = static_cast<std::uint8_t>(rng());
          if (lcm_publish(lc.getUnderlyingLCM(), ch, d.data(), static_cast<unsigned>(d.size())) == 0) ++junk;
        }
      }
      const int raw = url.rfind("udpm://", 0) == 0 ? send_raw_datagrams() : 0;
      std::printf("lcm_probe: injected %d malformed packets on %s, %d junk packets on other channels, %d raw datagrams\n",
                  commands, kChanCommand, junk, raw);
      return 0;
    }
    if (mode == "expect-status" && argc == 6) {
      const std::string url = resolve(argv[2]);
      if (!allowed(url)) return 3;
      lcm::LCM lc(url);
      if (!lc.good()) return 2;
      struct Watch {
        std::string channel;
        long want = 0;
        bool ok = false;
        void operator()(const vitreo_lcm::receive_status_t& s) {
          for (int i = 0; i < s.n; ++i) {
            if (s.channel[static_cast<std::size_t>(i)] != channel) continue;
            std::printf("lcm_probe: %s says %s: %lld received, %lld refused, %lld handler errors (last: %s)\n",
                        s.process.c_str(), channel.c_str(), static_cast<long long>(s.received[static_cast<std::size_t>(i)]),
                        static_cast<long long>(s.rejected[static_cast<std::size_t>(i)]),
                        static_cast<long long>(s.handler_errors[static_cast<std::size_t>(i)]),
                        s.last_error[static_cast<std::size_t>(i)].c_str());
            std::fflush(stdout);
            if (s.rejected[static_cast<std::size_t>(i)] >= want) ok = true;
          }
        }
      } w{argv[3], std::atol(argv[4])};
      auto sub = subscribe_to<vitreo_lcm::receive_status_t>(lc, kChanReceiveStatus, &w);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(std::atol(argv[5]));
      while (!w.ok && std::chrono::steady_clock::now() < deadline) lc.handleTimeout(50);
      return w.ok ? 0 : 1;
    }
    if (mode == "count" && argc == 4) {
      lcm::LogFile log(argv[2], "r");
      if (!log.good()) return 2;
      long n = 0;
      for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
        vitreo_lcm::event_t e;
        if (ev->channel == kChanEvent && decode_message(ev->data, static_cast<std::size_t>(ev->datalen), e) == DecodeError::None &&
            e.step == n)
          ++n;
      }
      std::printf("lcm_probe: log %s holds %ld event_t in order\n", argv[2], n);
      return n == std::atol(argv[3]) ? 0 : 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lcm_probe: %s\n", e.what());
    return 2;
  }
  std::fprintf(stderr,
               "usage: lcm_probe publish <url> <n> | subscribe <url> <n> <s> | count <log> <n> | respond <url> <n> <s> |\n"
               "       wait <url> <channel> <s> | inject <url> | expect-status <url> <channel> <n> <s>\n");
  return 64;
}
