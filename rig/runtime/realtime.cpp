#include "rig/runtime/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>

#include <cerrno>
#include <cstring>

#include <spdlog/spdlog.h>

namespace vitreo::runtime {

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
      out.memory_locked = true;
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
