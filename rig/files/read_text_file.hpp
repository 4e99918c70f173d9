#pragma once
// Reading a file a user names (a case, a materials library, a pedal mapping, an emulator script):
// only a regular file, only up to a size the caller states, and with a one-line reason otherwise.
// Reading "whatever the path gives" let `[materials] library = "/dev/zero"` grow a process to
// gigabytes, and a FIFO or a terminal would block it for ever.
#include <cstddef>
#include <optional>
#include <string>

namespace vitreo::files {

inline constexpr std::size_t kMaxConfigFileBytes = std::size_t{1} << 20;  // 1 MiB: cases, libraries, configs, scripts

struct TextFile {
  std::optional<std::string> text;  // the contents, or nothing
  std::string error;                // why not: "'x' is a directory, not a file", "'x' is larger than 1 MiB", ...
};

// Never blocks on a special file and never reads more than max_bytes + 1 bytes.
TextFile read_text_file(const std::string& path, std::size_t max_bytes = kMaxConfigFileBytes);

}  // namespace vitreo::files
