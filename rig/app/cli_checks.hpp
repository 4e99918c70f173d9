#pragma once
// Command-line checks CLI11 lacks. CLI::Range compares with < and >, and every comparison with NaN
// is false, so `--duration nan` passed it and ran 2^63 steps; these refuse NaN and infinities.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <CLI/CLI.hpp>

namespace vitreo::app {

inline std::string number_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// A finite number in [lo, hi].
inline CLI::Validator finite_range(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);  // HUGE_VAL for 1e999: refused as not finite
        if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v) || v < lo || v > hi) {
          return "'" + text + "' is not a number in [" + number_text(lo) + ", " + number_text(hi) + "]";
        }
        return {};
      },
      "FINITE in [" + number_text(lo) + " - " + number_text(hi) + "]");
}

// Empty when `path` is a serial port (a terminal device: tcgetattr works on it), else why not —
// `--serial tracker=/dev/null` used to run with a device that could never connect.
inline std::string serial_port_problem(const std::string& path) {
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0)
    return "cannot open '" + path + "': " + (errno == ENOENT ? "no such device" : std::strerror(errno));
  if (!S_ISCHR(st.st_mode)) return "'" + path + "' is not a serial port (not a character device)";
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return "cannot open '" + path + "': " + std::strerror(errno);
  termios t{};
  const bool tty = ::tcgetattr(fd, &t) == 0;
  ::close(fd);
  return tty ? std::string() : "'" + path + "' is not a serial port (" + std::strerror(ENOTTY) + ")";
}

}  // namespace vitreo::app
