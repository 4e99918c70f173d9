#include "rig/files/read_text_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace vitreo::files {

namespace {
std::string size_text(std::size_t bytes) {
  if (bytes % (1u << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  if (bytes % (1u << 10) == 0) return std::to_string(bytes >> 10) + " KiB";
  return std::to_string(bytes) + " bytes";
}
}  // namespace

TextFile read_text_file(const std::string& path, std::size_t max_bytes) {
  TextFile out;
  struct stat st{};
  if (::stat(path.c_str(), &st) != 0) {
    out.error = "'" + path + "': " + (errno == ENOENT ? std::string("no such file") : std::strerror(errno));
    return out;
  }
  if (S_ISDIR(st.st_mode)) {
    out.error = "'" + path + "' is a directory, not a file";
    return out;
  }
  if (!S_ISREG(st.st_mode)) {
    out.error = "'" + path + "' is not a regular file (a device, a FIFO or a socket)";
    return out;
  }
  if (static_cast<std::size_t>(st.st_size) > max_bytes) {
    out.error = "'" + path + "' is larger than " + size_text(max_bytes);
    return out;
  }
  // O_NONBLOCK: if the path was swapped for a FIFO since stat(), open must not wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    out.error = "cannot read '" + path + "': " + std::strerror(errno);
    return out;
  }
  struct stat fst{};
  if (::fstat(fd, &fst) != 0 || !S_ISREG(fst.st_mode)) {
    ::close(fd);
    out.error = "'" + path + "' is not a regular file";
    return out;
  }
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      out.error = "cannot read '" + path + "': " + std::strerror(errno);
      ::close(fd);
      return out;
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) {  // it grew while we read it
      ::close(fd);
      out.error = "'" + path + "' is larger than " + size_text(max_bytes);
      return out;
    }
  }
  ::close(fd);
  out.text = std::move(text);
  return out;
}

}  // namespace vitreo::files
