#include "rig/runtime/clock.hpp"

#include <cerrno>
#include <ctime>

namespace vitreo::runtime {
namespace {
constexpr std::int64_t kNsPerS = 1'000'000'000;
}

std::int64_t SteadyClock::now_ns() const noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

void SteadyClock::sleep_until_ns(std::int64_t t_ns) noexcept {
  const std::int64_t sleep_to = t_ns - spin_margin_ns_;
  if (sleep_to > now_ns()) {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(sleep_to / kNsPerS);
    ts.tv_nsec = static_cast<long>(sleep_to % kNsPerS);
    // Absolute deadline: an interrupted sleep just resumes towards the same instant.
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
  while (now_ns() < t_ns) {
  }
}

}  // namespace vitreo::runtime
