// vitreo-cmd: send operator commands to a running rig over LCM and print its acknowledgement.
//   vitreo-cmd zoom 12.5            one command; exit 0 accepted, 1 refused, 2 no answer / bad input
//   vitreo-cmd < script.txt         one command per line (terminal spelling, see --help)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/commands.hpp"
#include "rig/telemetry/lcm_subscribe.hpp"
#include "rig/telemetry/publisher.hpp"
#include "vitreo_lcm/command_ack_t.hpp"

using namespace vitreo::telemetry;

namespace {
struct AckWaiter {
  std::string source;
  std::int64_t seq = -1;
  bool got = false;
  vitreo_lcm::command_ack_t ack;
  void operator()(const vitreo_lcm::command_ack_t& a) {
    if (a.source == source && a.seq == seq) {
      ack = a;
      got = true;
    }
  }
};

// 0 accepted, 1 refused, 2 not sent or not answered.
int send(lcm::LCM& lc, AckWaiter& waiter, const std::string& line, int timeout_ms) {
  // Wall-clock µs as the sequence: strictly increasing across invocations of this tool.
  const std::int64_t seq = wall_time_us();
  const ParsedCommand p = parse_command_line(line, waiter.source, seq);
  if (!p.ok) {
    std::fprintf(stderr, "vitreo-cmd: %s\n", p.error.c_str());
    return 2;
  }
  waiter.seq = seq;
  waiter.got = false;
  if (lc.publish(kChanCommand, &p.command) != 0) {
    std::fprintf(stderr, "vitreo-cmd: publish failed\n");
    return 2;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!waiter.got && std::chrono::steady_clock::now() < deadline) lc.handleTimeout(20);
  if (!waiter.got) {
    std::fprintf(stderr, "vitreo-cmd: no acknowledgement for '%s' within %d ms (is the rig running on this URL?)\n",
                 line.c_str(), timeout_ms);
    return 2;
  }
  if (waiter.ack.accepted) {
    std::printf("%s: accepted%s%s\n", command_name(waiter.ack.command), waiter.ack.reason.empty() ? "" : " ",
                waiter.ack.reason.c_str());
    return 0;
  }
  std::printf("%s: refused: %s\n", command_name(waiter.ack.command), waiter.ack.reason.c_str());
  return 1;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Send operator commands to a running vitreo rig over LCM and print its acknowledgement.\n"
      "Commands: n|next, p|prev, pause (or a line with one space), resume, r|reset, s|save NAME,\n"
      "w|wireframe, l|labels, z|zoom X, pan X Y, focus F, flat, wide, invert, laser_power MW,\n"
      "laser_duration MS. Without a command, reads one command per line from stdin."};
  std::string url = kDefaultLcmUrl;
  std::string source = "vitreo-cmd";
  int timeout_ms = 1000;
  std::vector<std::string> words;
  app.add_option("--lcm-url", url, "LCM URL of the rig")->capture_default_str();
  app.add_option("--source", source, "name this sender is acknowledged as")->capture_default_str();
  app.add_option("--timeout-ms", timeout_ms, "how long to wait for each acknowledgement")
      ->capture_default_str()
      ->check(CLI::Range(1, 600000));
  app.add_option("command", words, "command and argument, e.g. 'zoom 12.5'");
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::warn);

  lcm::LCM lc(url);
  if (!lc.good()) {
    std::fprintf(stderr, "vitreo-cmd: cannot open LCM URL '%s'\n", url.c_str());
    return 2;
  }
  AckWaiter waiter;
  waiter.source = source;
  // Checked: a malformed acknowledgement on the bus is counted and ignored, never decoded blindly.
  const CheckedSubscription acks = subscribe_to<vitreo_lcm::command_ack_t>(lc, kChanCommandAck, &waiter);
  auto report_malformed = [&](int rc) {
    if (const auto bad = acks.counters().rejected(); bad > 0) {
      std::fprintf(stderr, "vitreo-cmd: ignored %llu malformed packet(s) on %s (%s)\n", static_cast<unsigned long long>(bad),
                   kChanCommandAck, acks.counters().last_error().c_str());
    }
    return rc;
  };

  if (!words.empty()) {
    std::string line;
    for (const auto& w : words) line += (line.empty() ? "" : " ") + w;
    return report_malformed(send(lc, waiter, line, timeout_ms));
  }
  int worst = 0;
  for (std::string line; std::getline(std::cin, line);) {  // the last line counts without its newline too
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const int rc = send(lc, waiter, line, timeout_ms);
    worst = std::max(worst, rc);
  }
  return report_malformed(worst);
}
