#pragma once
// Operator commands typed on the rig's terminal (the thesis' keyboard table, ch. 2.6.1), one per
// line in parse_command_line's spelling (n, p, pause, resume, r, s NAME, w, l, z X). A reader thread
// reads lines from a file descriptor (stdin when it is a terminal, or a pipe), parses them, hands
// them to the CommandServer — which validates them on the telemetry thread exactly like commands
// from LCM, queues accepted ones to physics and publishes the ack — and prints the ack:
//   > next: accepted
//   > zoom: refused: zoom 99 outside the rig's range 1..25
// Syntax errors are printed at once and never reach the server. Each line waits for its ack before
// the next is sent, so acks come back in order; the last line counts even without its newline.
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <thread>

#include "rig/telemetry/commands.hpp"

namespace vitreo::telemetry {

class TerminalCommands {
 public:
  static constexpr std::size_t kMaxLine = 1024;  // longer lines are refused, not buffered
  // Does not take ownership of `fd`. `out`: where acks are printed (nullptr: nowhere; the commands
  // still run and are counted).
  TerminalCommands(int fd, CommandServer& server, std::FILE* out = stdout);
  ~TerminalCommands();
  TerminalCommands(const TerminalCommands&) = delete;
  TerminalCommands& operator=(const TerminalCommands&) = delete;

  void start();
  void stop();  // idempotent; returns within ~100 ms

  std::uint64_t lines() const noexcept { return lines_.load(); }
  std::uint64_t accepted() const noexcept { return accepted_.load(); }
  std::uint64_t refused() const noexcept { return refused_.load(); }  // by the server or by syntax

 private:
  void run();
  void handle_line(const std::string& line);
  void say(const char* format, ...) __attribute__((format(printf, 2, 3)));  // to out_, flushed; no-op without one

  int fd_;
  CommandServer& server_;
  std::FILE* out_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::int64_t seq_ = 0;
  std::atomic<std::uint64_t> lines_{0}, accepted_{0}, refused_{0};
};

}  // namespace vitreo::telemetry
