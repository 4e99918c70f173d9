#include "rig/runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>

#include <spdlog/spdlog.h>

namespace vitreo::runtime {

namespace {
// Locked memory of this process in kB from /proc/self/status (-1 if unknown). mlockall's return
// value alone is not trusted: sanitizer runtimes intercept it and return success without locking.
long locked_kb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmLck:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}
}  // namespace

RealtimeOutcome apply_realtime(const RealtimeConfig& config) {
  RealtimeOutcome out;
  auto refuse = [&](const std::string& what, int err) {
    std::string line = what + ": " + std::strerror(err) + " — continuing without it";
    spdlog::warn("realtime: {}", line);
    out.warnings.push_back(std::move(line));
  };

  if (config.low_timer_slack) {
    // Default slack (50 µs) would blur a 1 ms schedule; 1 ns asks for exact wake-ups.
    if (prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) == 0) {
      out.timer_slack = true;
    } else {
      refuse("PR_SET_TIMERSLACK 1 ns", errno);
    }
  }
  if (config.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      if (locked_kb() == 0) {
        refuse("mlockall succeeded but VmLck is 0 (intercepted, e.g. by a sanitizer)", ENOTSUP);
      } else {
        out.memory_locked = true;
      }
    } else {
      refuse("mlockall", errno);
    }
  }
  if (config.cpu >= 0) {
    if (config.cpu >= CPU_SETSIZE) {
      refuse("pin to CPU " + std::to_string(config.cpu), EINVAL);
    } else {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(config.cpu, &set);
      const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
      if (rc == 0) {
        out.affinity = true;
      } else {
        refuse("pin to CPU " + std::to_string(config.cpu), rc);
      }
    }
  }
  if (config.sched_fifo) {
    sched_param sp{};
    sp.sched_priority = config.fifo_priority;
    const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (rc == 0) {
      out.fifo = true;
    } else {
      refuse("SCHED_FIFO priority " + std::to_string(config.fifo_priority), rc);
    }
  }
  if (out.warnings.empty()) {
    spdlog::info("realtime: all requested settings applied");
  }
  return out;
}

}  // namespace vitreo::runtime
