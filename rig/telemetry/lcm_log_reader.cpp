#include "rig/telemetry/lcm_log_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace vitreo::telemetry {

namespace {
constexpr std::uint32_t kSync = 0xEDA1DA01u;
constexpr std::size_t kEventHeaderBytes = 4 + 8 + 8 + 4 + 4;
constexpr std::int32_t kMaxChannelLength = 63;  // LCM's own limit (LCM_MAX_CHANNEL_NAME_LENGTH)

std::uint64_t be(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}
}  // namespace

LcmLogReader::~LcmLogReader() {
  if (f_) std::fclose(f_);
}

bool LcmLogReader::open(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    problem_ = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  struct stat st{};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    problem_ = "'" + path + "' is not a regular file";
    ::close(fd);
    return false;
  }
  f_ = ::fdopen(fd, "rb");
  if (!f_) {
    problem_ = "cannot read '" + path + "': " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  size_ = static_cast<std::uint64_t>(st.st_size);
  return true;
}

bool LcmLogReader::read_exact(void* dst, std::size_t n) { return n == 0 || std::fread(dst, 1, n, f_) == n; }

bool LcmLogReader::sync_word_follows() {
  // From just after this event's header to the end of the file as it was when opened (a file still
  // being written grows meanwhile); the position is not needed again.
  std::uint32_t window = 0;
  std::uint64_t left = size_ - offset_ - kEventHeaderBytes;
  for (int c; left-- > 0 && (c = std::fgetc(f_)) != EOF;) {
    window = (window << 8) | static_cast<std::uint32_t>(c);
    if (window == kSync) return true;
  }
  return false;
}

LcmLogReader::Status LcmLogReader::next(LcmLogEvent& out, std::uint32_t max_data_bytes) {
  if (!f_) {
    problem_ = "not open";
    return Status::Corrupt;
  }
  if (offset_ == size_) return Status::End;
  if (size_ - offset_ < kEventHeaderBytes) {
    problem_ = "the file ends inside an event header";
    return Status::Truncated;
  }
  std::uint8_t h[kEventHeaderBytes];
  if (!read_exact(h, sizeof h)) {
    problem_ = "read error";
    return Status::Truncated;
  }
  const auto sync = static_cast<std::uint32_t>(be(h, 4));
  const auto eventnum = static_cast<std::int64_t>(be(h + 4, 8));
  const auto timestamp = static_cast<std::int64_t>(be(h + 12, 8));
  const auto channel_len = static_cast<std::int32_t>(be(h + 20, 4));
  const auto data_len = static_cast<std::int32_t>(be(h + 24, 4));
  if (sync != kSync) {
    problem_ = "not an LCM log event (no sync word)";
    return Status::Corrupt;
  }
  if (eventnum != next_eventnum_) {
    problem_ = "event number " + std::to_string(eventnum) + " where " + std::to_string(next_eventnum_) + " was due";
    return Status::Corrupt;
  }
  if (channel_len < 1 || channel_len > kMaxChannelLength) {
    problem_ = "channel name length " + std::to_string(channel_len) + " (1.." + std::to_string(kMaxChannelLength) + ")";
    return Status::Corrupt;
  }
  if (data_len < 0 || static_cast<std::uint32_t>(data_len) > max_data_bytes) {
    problem_ = "event of " + std::to_string(data_len) + " bytes (at most " + std::to_string(max_data_bytes) + " here)";
    return Status::Corrupt;
  }
  const std::uint64_t total = kEventHeaderBytes + static_cast<std::uint64_t>(channel_len) + static_cast<std::uint64_t>(data_len);
  if (size_ - offset_ < total) {
    // A file cut inside its last event, or a damaged length field in the middle of one: if another
    // event's sync word follows, the bytes did not run out — a length lies.
    if (sync_word_follows()) {
      problem_ = "event " + std::to_string(eventnum) + " claims to run past the end of the file, but more events follow";
      return Status::Corrupt;
    }
    problem_ = "the file ends inside event " + std::to_string(eventnum);
    return Status::Truncated;
  }
  out.channel.resize(static_cast<std::size_t>(channel_len));
  out.data.resize(static_cast<std::size_t>(data_len));
  if (!read_exact(out.channel.data(), out.channel.size()) || !read_exact(out.data.data(), out.data.size())) {
    problem_ = "read error";
    return Status::Truncated;
  }
  for (char c : out.channel) {
    if (c < 0x21 || c > 0x7e) {
      problem_ = "channel name with a byte that is not printable";
      return Status::Corrupt;
    }
  }
  out.offset = offset_;
  out.end = offset_ + total;
  out.eventnum = eventnum;
  out.timestamp = timestamp;
  offset_ = out.end;
  ++next_eventnum_;
  return Status::Event;
}

}  // namespace vitreo::telemetry
