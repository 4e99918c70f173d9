#pragma once
// A strict reader of LCM log files (the format lcm-logger writes and lcm::LogFile reads), for
// recordings, which must say exactly where they stop being trustworthy.
//
// Each event is: sync word 0xEDA1DA01, event number (int64), timestamp (int64, µs), channel length
// (int32), data length (int32) — all big-endian — then the channel name and the data. liblcm's own
// reader skips forward to the next sync word when one is missing, silently dropping whatever lay
// between; this one stops there and reports the byte offset, and it also refuses event numbers that
// do not count up by one from 0, channel names that are not 1..63 printable characters and events
// larger than the caller allows. It reads the file through a buffer, never all at once.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace vitreo::telemetry {

struct LcmLogEvent {
  std::uint64_t offset = 0;  // byte offset of its sync word in the file
  std::uint64_t end = 0;     // byte offset just past its data
  std::int64_t eventnum = 0;
  std::int64_t timestamp = 0;
  std::string channel;
  std::vector<std::uint8_t> data;
};

class LcmLogReader {
 public:
  enum class Status {
    Event,      // `out` holds the next event
    End,        // the file ended exactly after the previous event
    Truncated,  // the file ended inside an event (at offset(): the event's start)
    Corrupt,    // the bytes at offset() are not the event they should be (problem() says why)
  };

  // Opens `path`; false with a reason in problem() when it cannot be read or is not a regular file
  // (a FIFO or a device could block or never end).
  bool open(const std::string& path);
  ~LcmLogReader();

  // The next event, whose data may hold at most max_data_bytes.
  Status next(LcmLogEvent& out, std::uint32_t max_data_bytes);

  // The next event may be number 0 again (to look at what follows the end of one log in a file).
  void restart_numbering() noexcept { next_eventnum_ = 0; }

  std::uint64_t offset() const noexcept { return offset_; }  // where the next (or failing) event starts
  std::uint64_t file_size() const noexcept { return size_; }
  const std::string& problem() const noexcept { return problem_; }

 private:
  bool read_exact(void* dst, std::size_t n);
  bool sync_word_follows();

  std::FILE* f_ = nullptr;
  std::uint64_t size_ = 0;
  std::uint64_t offset_ = 0;
  std::int64_t next_eventnum_ = 0;
  std::string problem_;
};

}  // namespace vitreo::telemetry
