#pragma once
// Session recording and replay as standard LCM logs (lcm-logger / lcm-logplayer / lcm::LogFile read
// them): a VITREO_REC_HEADER event (configuration, starting snapshot reference) followed by one
// VITREO_REC_INPUT event per raw device input sample, in the order physics consumed them.
//
// Recorder: the physics thread pushes samples into a wait-free SPSC ring (dropped and counted when
// full, never waited for); a recorder thread calls pump(), which appends them to the log and flushes
// the stdio buffer to the kernel at least every flush_interval (100 ms by default). A flushed event
// is in the page cache, so it survives the process being SIGKILLed (not a power cut: close() and
// sync_to_disk() fdatasync for that). A log cut mid-event is still readable up to the cut.
//
// Replay: read_recording() validates the header and decodes the inputs; replay() feeds them to a
// callback in order, paced by their host timestamps on a Clock — a SteadyClock for real time (or a
// multiple of it), a SimulatedClock or speed <= 0 for as fast as possible. InputCursor hands a
// fixed-step loop the inputs that belong to each step.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rig/runtime/clock.hpp"
#include "rig/runtime/spsc_ring.hpp"

namespace lcm {
class LogFile;
}

namespace vitreo::telemetry {

struct DeviceInput {
  static constexpr std::size_t kMaxValues = 16;
  static constexpr std::size_t kMaxRaw = 64;
  std::int64_t host_time_us = 0;    // monotonic host clock at receive
  std::int64_t device_time_us = 0;
  std::int64_t step = 0;            // physics step that consumed it
  std::int32_t device_id = 0;
  std::int8_t device_kind = 0;
  std::int32_t channel = 0;
  std::int64_t sequence = 0;
  std::uint8_t n_values = 0;
  double values[kMaxValues] = {};
  std::uint8_t n_raw = 0;
  std::uint8_t raw[kMaxRaw] = {};
};
bool operator==(const DeviceInput& a, const DeviceInput& b) noexcept;  // bitwise on the used parts

struct RecordingHeader {
  std::int64_t utime_us = 0;  // filled by the Recorder
  std::int32_t format_version = 1;
  std::string software_version;
  std::string case_id;
  std::int32_t step_period_us = 1000;
  std::string config_name;
  std::string config_text;
  std::string snapshot_ref;
  std::string snapshot_hash;
};

struct RecorderConfig {
  std::size_t ring_capacity = 16384;          // 16 s of a 1 kHz tracker
  std::int64_t flush_interval_ns = 100'000'000;
};

class Recorder {
 public:
  // Creates (truncates) the log and writes the header; throws std::runtime_error on failure.
  Recorder(const std::string& path, RecordingHeader header, RecorderConfig config = {});
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Producer (physics) thread: wait-free; false = dropped (counted).
  bool push(const DeviceInput& in) noexcept { return ring_.try_push(in); }

  // Recorder thread: writes queued inputs; flushes when flush_interval has passed since the last
  // flush (now_ns on any monotonic clock). Returns inputs written. Never throws: a write error (disk
  // full, device gone) is logged once, the log is closed with what it has, and later inputs are
  // drained and counted in lost() — a recording failure must not stop the session.
  std::size_t pump(std::int64_t now_ns) noexcept;
  // Recorder thread: drain, flush and fdatasync, close. Idempotent; the destructor calls it.
  void close() noexcept;
  bool failed() const noexcept { return failed_; }
  std::uint64_t lost() const noexcept { return lost_; }

  std::uint64_t written() const noexcept { return written_; }
  std::uint64_t dropped() const noexcept { return ring_.dropped(); }
  std::uint64_t flushes() const noexcept { return flushes_; }
  const std::string& path() const noexcept { return path_; }

 private:
  void write_input(const DeviceInput& in);
  void flush();
  void fail(const char* what) noexcept;
  void discard_queued() noexcept;

  std::string path_;
  RecorderConfig config_;
  std::unique_ptr<lcm::LogFile> log_;
  runtime::SpscRing<DeviceInput> ring_;
  std::vector<std::uint8_t> buf_;
  std::int64_t wall_minus_mono_us_ = 0;  // maps monotonic sample times to log (wall) timestamps
  std::int64_t event_num_ = 0;
  std::int64_t last_flush_ns_ = INT64_MIN;
  std::uint64_t written_ = 0;
  std::uint64_t flushes_ = 0;
  std::uint64_t lost_ = 0;
  bool failed_ = false;
};

struct Recording {
  RecordingHeader header;
  std::vector<DeviceInput> inputs;
  std::size_t other_events = 0;  // events on other channels (ignored)
  bool truncated = false;        // the file ended inside an event (e.g. the recorder was killed)
};

// Throws std::runtime_error if the file cannot be opened, has no header first, or a newer format.
Recording read_recording(const std::string& path);

struct ReplayOptions {
  double speed = 1.0;  // 1 = real time, 2 = twice as fast; <= 0 = as fast as possible
};

// Feeds every input, in recorded order, to fn; waits on clock between inputs to keep their recorded
// spacing / speed. Returns the number delivered.
std::size_t replay(const Recording& rec, runtime::Clock& clock, ReplayOptions options,
                   const std::function<void(const DeviceInput&)>& fn);

// Step-driven replay for a fixed-step loop: hands over, in order, the inputs recorded for steps up
// to and including `step`.
class InputCursor {
 public:
  explicit InputCursor(const Recording& rec) : inputs_(&rec.inputs) {}
  template <class Fn>
  std::size_t feed_through_step(std::int64_t step, Fn&& fn) {
    std::size_t n = 0;
    while (next_ < inputs_->size() && (*inputs_)[next_].step <= step) {
      fn((*inputs_)[next_++]);
      ++n;
    }
    return n;
  }
  bool done() const noexcept { return next_ >= inputs_->size(); }

 private:
  const std::vector<DeviceInput>* inputs_;
  std::size_t next_ = 0;
};

}  // namespace vitreo::telemetry
