// libFuzzer target: a recording file (rig/telemetry/RECORDING.md) read by read_recording, whose input
// codec range-checks every record. The bytes are a memfd, a regular file like any recording.
// Invariants on whatever it returns: inputs in step order, none after the step it is trusted through,
// each one the codec takes back unchanged; a complete recording has its end and nothing corrupt; a
// bad byte lies inside the file.
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <string>

#include "rig/telemetry/input_codec.hpp"
#include "rig/telemetry/recording.hpp"

using namespace vitreo;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const int fd = ::memfd_create("fuzz-recording", 0);
  if (fd < 0) std::abort();
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) std::abort();
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  try {
    const telemetry::Recording rec = telemetry::read_recording(path);
    std::int64_t last = -1;
    for (const auto& in : rec.inputs) {
      if (in.step < last || in.step > rec.trusted_through_step) std::abort();
      telemetry::RecordedInput again;
      if (telemetry::from_lcm(telemetry::to_lcm(in), again) != nullptr || !(again == in)) std::abort();
      last = in.step;
    }
    if (rec.verdict == telemetry::RecordingVerdict::Complete && (!rec.end || rec.end->steps != rec.trusted_through_step + 1))
      std::abort();
    if (rec.verdict == telemetry::RecordingVerdict::Corrupted && rec.bad_byte > size) std::abort();
    if (rec.describe().empty()) std::abort();
  } catch (const telemetry::RecordingError&) {
    // not a recording at all: said with a reason, which is the point
  }
  return 0;
}
