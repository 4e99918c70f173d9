#include "rig/telemetry/terminal_commands.hpp"

#include <poll.h>
#include <pthread.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>
#include <chrono>
#include <string>

#include "rig/telemetry/items.hpp"

namespace vitreo::telemetry {

TerminalCommands::TerminalCommands(int fd, CommandServer& server, std::FILE* out) : fd_(fd), server_(server), out_(out) {}

TerminalCommands::~TerminalCommands() { stop(); }

void TerminalCommands::say(const char* format, ...) {
  if (out_ == nullptr) return;  // a session with nowhere to print its acks still runs the commands
  va_list args;
  va_start(args, format);
  std::vfprintf(out_, format, args);
  va_end(args);
  std::fflush(out_);
}

void TerminalCommands::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] {
    pthread_setname_np(pthread_self(), "vitreo-terminal");
    run();
  });
}

void TerminalCommands::stop() {
  running_.store(false);
  if (thread_.joinable()) thread_.join();
}

void TerminalCommands::run() {
  std::string pending;
  bool overlong = false;  // inside a line longer than kMaxLine: dropped up to its newline
  char buf[512];
  auto take_line = [&](std::string line) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty()) handle_line(line);
  };
  while (running_.load()) {
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, 100);  // wakes up to notice stop()
    if (r < 0 && errno != EINTR) return;
    if (r <= 0) continue;
    const ssize_t n = ::read(fd_, buf, sizeof buf);
    if (n == 0) {
      // End of input: a last line without its newline is still a command.
      if (!overlong) take_line(std::move(pending));
      return;
    }
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return;
    }
    pending.append(buf, static_cast<std::size_t>(n));
    for (std::size_t nl; (nl = pending.find('\n')) != std::string::npos;) {
      std::string line = pending.substr(0, nl);
      pending.erase(0, nl + 1);
      if (overlong) {
        overlong = false;
        continue;
      }
      take_line(std::move(line));
    }
    if (pending.size() > kMaxLine) {  // no newline in sight: refuse it rather than grow without bound
      ++lines_;
      ++refused_;
      say("> line longer than %zu characters: ignored\n", kMaxLine);
      pending.clear();
      overlong = true;
    }
  }
}

void TerminalCommands::handle_line(const std::string& line) {
  ++lines_;
  const ParsedCommand parsed = parse_command_line(line, "terminal", ++seq_);
  if (!parsed.ok) {
    ++refused_;
    say("> %s\n", parsed.error.c_str());
    return;
  }
  LocalCommand cmd;
  cmd.command = parsed.command.command;
  cmd.value = parsed.command.value;
  copy_text(cmd.arg, parsed.command.arg);
  copy_text(cmd.source, "terminal");
  cmd.seq = parsed.command.seq;
  const char* name = command_name(cmd.command);
  if (!server_.submit(cmd)) {
    ++refused_;
    say("> %s: refused: too many commands waiting\n", name);
    return;
  }
  // The telemetry thread answers within a few milliseconds; give it two seconds (a loaded machine).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  LocalAck ack;
  bool got = false;
  while (running_.load() && std::chrono::steady_clock::now() < deadline) {
    while (server_.poll_ack(ack)) {
      if (ack.seq == cmd.seq) got = true;
    }
    if (got) break;
    ::usleep(2000);
  }
  if (!got) {
    ++refused_;
    say("> %s: no answer from the rig\n", name);
  } else if (ack.accepted) {
    ++accepted_;
    const std::string_view reason = text(ack.reason);
    say("> %s: accepted%s%.*s\n", name, reason.empty() ? "" : " ", static_cast<int>(reason.size()), reason.data());
  } else {
    ++refused_;
    const std::string_view reason = text(ack.reason);
    say("> %s: refused: %.*s\n", name, static_cast<int>(reason.size()), reason.data());
  }
}

}  // namespace vitreo::telemetry
