// Reading a recording and deciding what of it can be trusted (RECORDING.md, "Verdicts").
#include <algorithm>
#include <cstdio>
#include <string>

#include "rig/telemetry/channels.hpp"
#include "rig/telemetry/input_codec.hpp"
#include "rig/telemetry/lcm_decode.hpp"
#include "rig/telemetry/lcm_log_reader.hpp"
#include "rig/telemetry/recording.hpp"
#include "rig/telemetry/recording_checksum.hpp"
#include "vitreo_lcm/recording_check_t.hpp"
#include "vitreo_lcm/recording_end_t.hpp"
#include "vitreo_lcm/recording_header_t.hpp"

namespace vitreo::telemetry {

namespace {

// The header carries the session's case texts (each case file and materials library <= 1 MiB, a
// few dozen cases at most); every other event is a few hundred bytes.
constexpr std::uint32_t kMaxHeaderBytes = 64u << 20;
constexpr std::uint32_t kMaxEventBytes = 64u << 10;

bool hex16(const std::string& s, std::uint64_t& out) {
  if (s.size() != 16) return false;
  out = 0;
  for (char c : s) {
    int d;
    if (c >= '0' && c <= '9') d = c - '0';
    else if (c >= 'a' && c <= 'f') d = c - 'a' + 10;
    else return false;
    out = (out << 4) | static_cast<std::uint64_t>(d);
  }
  return true;
}

RecordingHeader read_header(LcmLogReader& log, const std::string& path, std::uint32_t& crc) {
  LcmLogEvent ev;
  const auto st = log.next(ev, kMaxHeaderBytes);
  auto fail = [&](const std::string& why) { throw RecordingError("recording '" + path + "': " + why); };
  if (st == LcmLogReader::Status::End) fail("empty file");
  if (st != LcmLogReader::Status::Event) fail("not an LCM log (" + log.problem() + ")");
  vitreo_lcm::recording_header_t h;
  if (ev.channel != kChanRecHeader || decode_message(ev.data.data(), ev.data.size(), h) != DecodeError::None)
    fail(std::string("does not start with a ") + kChanRecHeader + " event");
  if (h.format_version != vitreo_lcm::recording_header_t::FORMAT_VERSION) {
    // Both versions named: a person can tell at once whether the file or the build is the newer one.
    fail("recording format version " + std::to_string(h.format_version) + ", this vitreo reads " +
         std::to_string(vitreo_lcm::recording_header_t::FORMAT_VERSION) +
         " (replay it with the vitreo that made it)");
  }
  if (h.step_period_us < 100 || h.step_period_us > 100'000)
    fail("step period of " + std::to_string(h.step_period_us) + " µs (0.1..100 ms)");
  std::uint64_t start_hash = 0;
  if (!hex16(h.snapshot_hash, start_hash))
    fail("start-state hash '" + h.snapshot_hash.substr(0, 40) + "' is not 16 hex digits: the start cannot be checked");
  crc = checksum_event(crc, ev.channel, ev.data.data(), ev.data.size());
  return RecordingHeader{h.utime_us,     h.format_version, h.software_version, h.case_id, h.step_period_us,
                         h.config_name,  h.config_text,    h.snapshot_ref,     h.snapshot_hash};
}

}  // namespace

Recording read_recording(const std::string& path) {
  LcmLogReader log;
  if (!log.open(path)) throw RecordingError("recording: " + log.problem());
  Recording rec;
  rec.file_bytes = log.file_size();
  std::uint32_t crc = 0;
  rec.header = read_header(log, path, crc);
  rec.events = 1;

  // Inputs read since the last verified checksum: they join rec.inputs when one vouches for them.
  std::vector<RecordedInput> pending;
  std::uint64_t block_start = 0;  // first byte the next checksum vouches for (the first covers the header)
  std::int64_t inputs_total = 0, last_step = -1, blocks = 0;
  auto stop = [&](RecordingVerdict v, std::uint64_t at, std::string why) {
    rec.verdict = v;
    rec.bad_byte = at;
    rec.problem = std::move(why);
    rec.unverified_inputs = pending.size();
  };

  LcmLogEvent ev;
  for (;;) {
    const std::uint64_t at = log.offset();
    const auto st = log.next(ev, kMaxEventBytes);
    if (st == LcmLogReader::Status::End) {
      stop(RecordingVerdict::Truncated, at, "the file ends before the recording's end event");
      break;
    }
    if (st == LcmLogReader::Status::Truncated) {
      stop(RecordingVerdict::Truncated, at, "the file ends inside an event (" + log.problem() + ")");
      break;
    }
    if (st == LcmLogReader::Status::Corrupt) {
      stop(RecordingVerdict::Corrupted, std::min(at, block_start), "event at byte " + std::to_string(at) + ": " + log.problem());
      break;
    }
    ++rec.events;
    if (ev.channel == kChanRecInput) {
      vitreo_lcm::device_input_t m;
      RecordedInput in;
      const DecodeError de = decode_message(ev.data.data(), ev.data.size(), m);
      const char* why = de != DecodeError::None ? to_string(de) : from_lcm(m, in);
      if (!why && in.step < last_step) why = "its step is before the previous input's";
      if (why) {
        stop(RecordingVerdict::Corrupted, block_start, "input at byte " + std::to_string(at) + ": " + why);
        break;
      }
      last_step = in.step;
      ++inputs_total;
      pending.push_back(in);
      crc = checksum_event(crc, ev.channel, ev.data.data(), ev.data.size());
    } else if (ev.channel == kChanRecCheck) {
      vitreo_lcm::recording_check_t c;
      const DecodeError de = decode_message(ev.data.data(), ev.data.size(), c);
      if (de != DecodeError::None || c.block != blocks || c.events != static_cast<std::int64_t>(rec.events) - 1 ||
          c.inputs != inputs_total || c.last_step != last_step || c.crc32 != static_cast<std::int64_t>(crc)) {
        stop(RecordingVerdict::Corrupted, block_start,
             "checksum block " + std::to_string(blocks) + " (bytes " + std::to_string(block_start) + ".." +
                 std::to_string(ev.end) + ") does not match its contents");
        break;
      }
      crc = checksum_event(crc, ev.channel, ev.data.data(), ev.data.size());
      ++blocks;
      rec.inputs.insert(rec.inputs.end(), pending.begin(), pending.end());
      pending.clear();
      block_start = ev.end;
    } else if (ev.channel == kChanRecEnd) {
      vitreo_lcm::recording_end_t e;
      std::uint64_t final_hash = 0;
      const DecodeError de = decode_message(ev.data.data(), ev.data.size(), e);
      if (de != DecodeError::None || e.events != static_cast<std::int64_t>(rec.events) - 1 || e.inputs != inputs_total ||
          e.crc32 != static_cast<std::int64_t>(crc) || !hex16(e.state_hash, final_hash) || e.steps < 0 ||
          e.steps > kMaxRecordedStep || e.steps <= last_step || e.stop_reason.size() > 200) {
        stop(RecordingVerdict::Corrupted, block_start,
             "the end event's checksum or counts do not match the bytes " + std::to_string(block_start) + ".." +
                 std::to_string(ev.end));
        break;
      }
      rec.inputs.insert(rec.inputs.end(), pending.begin(), pending.end());
      pending.clear();
      rec.end = RecordingEnd{e.steps, final_hash, e.stop_reason};
      rec.verdict = RecordingVerdict::Complete;
      rec.trusted_through_step = e.steps - 1;
      if (log.offset() != log.file_size()) {
        // A complete recording with more after it: a second recording appended, or garbage.
        std::string what = std::to_string(log.file_size() - log.offset()) + " bytes after the end of the recording";
        LcmLogEvent more;
        log.restart_numbering();
        if (log.next(more, kMaxHeaderBytes) == LcmLogReader::Status::Event && more.channel == kChanRecHeader)
          what = "another recording starts after the end of this one (concatenated files)";
        rec.verdict = RecordingVerdict::Corrupted;
        rec.bad_byte = ev.end;
        rec.problem = what;
      }
      break;
    } else {
      stop(RecordingVerdict::Corrupted, block_start, "event at byte " + std::to_string(at) + " on channel '" +
                                                         ev.channel.substr(0, 64) + "', which recordings do not use");
      break;
    }
  }
  rec.truncated = rec.verdict == RecordingVerdict::Truncated;
  if (!rec.end) {
    // The inputs of the last verified step may be incomplete (a checksum can fall between two inputs
    // of one step): trust the steps before it.
    const std::int64_t last = rec.inputs.empty() ? -1 : rec.inputs.back().step;
    rec.trusted_through_step = last - 1;
    while (!rec.inputs.empty() && rec.inputs.back().step > rec.trusted_through_step) {
      rec.inputs.pop_back();
      ++rec.unverified_inputs;
    }
    if (rec.verdict == RecordingVerdict::Truncated) rec.bad_byte = block_start;
  }
  return rec;
}

}  // namespace vitreo::telemetry
