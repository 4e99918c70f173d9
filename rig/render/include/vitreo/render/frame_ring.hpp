#pragma once
// Shared-memory frame ring: the renderer publishes every stereo frame into a POSIX shared-memory
// object (shm_open name, e.g. "/vitreo-frames") for an external viewer or recorder. The writer
// never waits for readers; a reader that is too slow simply sees a newer frame.
//
// Layout (all integers little-endian as on the host, offsets in bytes; version 1):
//
//   offset 0: FrameRingHeader (128 bytes)
//     0  char[8]  magic            "VTRFRAME"
//     8  u32      version          1
//    12  u32      header_bytes     128
//    16  u32      width            full image width in pixels (both eyes side by side)
//    20  u32      height           pixels
//    24  u32      eye_width        width of one eye: width/2 for a stereo ring (the left eye is the left
//                                  half); = width for a one-picture ring (the instructor's view)
//    28  u32      format           1 = RGBA8, 4 bytes per pixel, rows top to bottom, no padding
//    32  u32      slot_count       number of slots (≥ 2)
//    36  u32      slot_header_bytes 64
//    40  u64      slot_stride      bytes from one slot to the next (header + pixels, 64-aligned)
//    48  u64      frame_bytes      width*height*4
//    56  u64      latest_sequence  (atomic) sequence number of the newest complete frame; 0 = none yet
//    64  u64      writer_pid
//    72  ...      reserved (zero)
//
//   offset 128 + k*slot_stride: slot k, FrameSlotHeader (64 bytes) then frame_bytes of pixels
//     0  u64  lock         (atomic) seqlock: odd while the writer is filling the slot
//     8  u64  sequence     1, 2, 3, … (frame n lives in slot n % slot_count)
//    16  f64  sim_time_s   simulation time the frame shows
//    24  u64  step_index   physics step the frame shows
//    32  u64  frame_index  renderer's frame counter
//    40  ...  reserved
//
// Reading a slot (seqlock): load `lock` (acquire); if odd, the slot is being written; copy the
// fields and pixels; fence (acquire); load `lock` again; if it changed, the copy is torn: discard it.
#include <cstdint>
#include <string>
#include <vector>

#include "vitreo/render/renderer.hpp"

namespace vitreo::render {

struct FrameRingHeader {
  std::uint64_t magic;  // the bytes "VTRFRAME" (kFrameRingMagic on a little-endian host); written last
  std::uint32_t version;
  std::uint32_t header_bytes;
  std::uint32_t width;
  std::uint32_t height;
  std::uint32_t eye_width;
  std::uint32_t format;
  std::uint32_t slot_count;
  std::uint32_t slot_header_bytes;
  std::uint64_t slot_stride;
  std::uint64_t frame_bytes;
  std::uint64_t latest_sequence;
  std::uint64_t writer_pid;
  std::uint8_t reserved[56];
};
static_assert(sizeof(FrameRingHeader) == 128);

struct FrameSlotHeader {
  std::uint64_t lock;
  std::uint64_t sequence;
  double sim_time_s;
  std::uint64_t step_index;
  std::uint64_t frame_index;
  std::uint8_t reserved[24];
};
static_assert(sizeof(FrameSlotHeader) == 64);

// "VTRFRAME" read as a little-endian u64.
inline constexpr std::uint64_t kFrameRingMagic = 0x454D415246525456ull;
inline constexpr std::uint32_t kFrameRingVersion = 1;
inline constexpr std::uint32_t kFrameFormatRgba8 = 1;

class FrameRingWriter {
 public:
  /// Creates (or replaces) the shared-memory object `name` ("/something") for frames of `eyes`
  /// (2: stereo side by side; 1: one picture) of eye_width×height. Throws std::runtime_error.
  FrameRingWriter(std::string name, int eye_width, int height, int slot_count = 3, int eyes = 2);
  ~FrameRingWriter();  // unmaps and unlinks the object
  FrameRingWriter(const FrameRingWriter&) = delete;
  FrameRingWriter& operator=(const FrameRingWriter&) = delete;

  /// Copies `frame` into the next slot. Never blocks. Throws std::invalid_argument on a size mismatch.
  void write(const StereoFrame& frame);
  /// A one-picture ring's frame (or a whole stereo image); `image` must match the ring's size.
  void write(const Image& image, double sim_time_s, std::uint64_t step_index, std::uint64_t frame_index);
  /// Lower-level form: `rgba` must hold width*height*4 bytes.
  void write(const std::uint8_t* rgba, double sim_time_s, std::uint64_t step_index, std::uint64_t frame_index);
  std::uint64_t frames_written() const { return sequence_; }
  const std::string& name() const { return name_; }

 private:
  std::string name_;
  std::uint8_t* base_ = nullptr;
  std::size_t bytes_ = 0;
  std::uint64_t sequence_ = 0;
};

struct RingFrame {
  std::uint64_t sequence = 0;
  double sim_time_s = 0;
  std::uint64_t step_index = 0;
  std::uint64_t frame_index = 0;
  int width = 0, height = 0, eye_width = 0;
  std::vector<std::uint8_t> rgba;
};

class FrameRingReader {
 public:
  /// Opens and validates an existing ring. Throws std::runtime_error with the reason.
  explicit FrameRingReader(const std::string& name);
  ~FrameRingReader();
  FrameRingReader(const FrameRingReader&) = delete;
  FrameRingReader& operator=(const FrameRingReader&) = delete;

  /// Copies the newest complete frame if its sequence is greater than `after_sequence`. Returns false
  /// when there is none, or when every attempt was overwritten mid-copy (bounded: never spins long).
  bool read_latest(RingFrame& out, std::uint64_t after_sequence = 0);
  const FrameRingHeader& header() const { return *reinterpret_cast<const FrameRingHeader*>(base_); }
  std::uint64_t torn_reads() const { return torn_; }

 private:
  std::uint8_t* base_ = nullptr;
  std::size_t bytes_ = 0;
  std::uint64_t torn_ = 0;
};

}  // namespace vitreo::render
