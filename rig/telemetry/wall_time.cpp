#include "rig/telemetry/wall_time.hpp"

#include <ctime>

namespace vitreo::telemetry {

std::int64_t wall_time_us() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

}  // namespace vitreo::telemetry
