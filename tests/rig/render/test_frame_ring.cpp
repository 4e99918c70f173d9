// The shared-memory frame ring, read from another process as an external viewer would.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstring>
#include <string>

#include "vitreo/render/frame_ring.hpp"

namespace vr = vitreo::render;

namespace {
std::string unique_name(const char* what) { return std::string("/vitreo-test-") + what + "-" + std::to_string(getpid()); }

std::uint8_t pattern(std::uint64_t seq) { return static_cast<std::uint8_t>(seq * 7 + 3); }
}  // namespace

TEST(FrameRing, HeaderMatchesTheDocumentedLayout) {
  EXPECT_EQ(offsetof(vr::FrameRingHeader, version), 8u);
  EXPECT_EQ(offsetof(vr::FrameRingHeader, width), 16u);
  EXPECT_EQ(offsetof(vr::FrameRingHeader, format), 28u);
  EXPECT_EQ(offsetof(vr::FrameRingHeader, slot_count), 32u);
  EXPECT_EQ(offsetof(vr::FrameRingHeader, slot_stride), 40u);
  EXPECT_EQ(offsetof(vr::FrameRingHeader, latest_sequence), 56u);
  EXPECT_EQ(offsetof(vr::FrameRingHeader, writer_pid), 64u);
  EXPECT_EQ(offsetof(vr::FrameSlotHeader, sequence), 8u);
  EXPECT_EQ(offsetof(vr::FrameSlotHeader, sim_time_s), 16u);
  EXPECT_EQ(offsetof(vr::FrameSlotHeader, step_index), 24u);

  const std::string name = unique_name("hdr");
  vr::FrameRingWriter writer(name, 40, 30, 4);
  vr::FrameRingReader reader(name);
  const vr::FrameRingHeader& h = reader.header();
  char magic[8];
  std::memcpy(magic, &h.magic, 8);
  EXPECT_EQ(std::string(magic, 8), "VTRFRAME");
  EXPECT_EQ(h.version, 1u);
  EXPECT_EQ(h.width, 80u);
  EXPECT_EQ(h.eye_width, 40u);
  EXPECT_EQ(h.height, 30u);
  EXPECT_EQ(h.format, vr::kFrameFormatRgba8);
  EXPECT_EQ(h.slot_count, 4u);
  EXPECT_EQ(h.frame_bytes, 80u * 30u * 4u);
  EXPECT_EQ(h.slot_stride % 64, 0u);
  EXPECT_EQ(h.writer_pid, static_cast<std::uint64_t>(getpid()));
  vr::RingFrame f;
  EXPECT_FALSE(reader.read_latest(f));  // nothing written yet
}

TEST(FrameRing, ReaderInAnotherProcessSeesWholeFramesWithTimeAndStep) {
  const std::string name = unique_name("xproc");
  constexpr int kEyeW = 64, kH = 32;
  constexpr std::uint64_t kFrames = 400;
  vr::FrameRingWriter writer(name, kEyeW, kH, 3);
  int progress[2];  // child → parent: the sequence numbers it has read (paces the test, not the writer)
  ASSERT_EQ(pipe(progress), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(progress[0]);
    // Reader process: checks every frame it manages to read, until it has seen the last one.
    int code = 0;
    try {
      vr::FrameRingReader reader(name);
      vr::RingFrame f;
      std::uint64_t last = 0, distinct = 0;
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (last < kFrames && std::chrono::steady_clock::now() < deadline) {
        if (!reader.read_latest(f, last)) continue;
        if (f.sequence <= last) code = 10;
        if (f.step_index != f.sequence * 10 || f.sim_time_s != static_cast<double>(f.sequence) * 0.001) code = 11;
        for (std::uint8_t b : f.rgba)
          if (b != pattern(f.sequence)) code = 12;  // torn or mixed frame
        if (f.width != 2 * kEyeW || f.height != kH) code = 13;
        last = f.sequence;
        ++distinct;
        if (write(progress[1], &last, sizeof last) != sizeof last) code = 17;
      }
      if (last != kFrames) code = 14;
      if (distinct < 2) code = 15;
    } catch (...) {
      code = 16;
    }
    _exit(code);
  }
  close(progress[1]);
  // Every 100 frames the test waits until the reader has caught up, so it reads frames along the
  // way and not only the last one; in between, the writer runs flat out, overwriting slots the
  // reader may be copying (the seqlock must catch those).
  auto wait_for_reader = [&](std::uint64_t seq) {
    std::uint64_t seen = 0;
    while (seen < seq) {
      if (read(progress[0], &seen, sizeof seen) != sizeof seen) return false;
    }
    return true;
  };
  std::vector<std::uint8_t> px(static_cast<std::size_t>(2 * kEyeW) * kH * 4);
  for (std::uint64_t seq = 1; seq <= kFrames; ++seq) {
    std::memset(px.data(), pattern(seq), px.size());
    writer.write(px.data(), static_cast<double>(seq) * 0.001, seq * 10, seq);
    if (seq % 100 == 0 && seq < kFrames) {
      ASSERT_TRUE(wait_for_reader(seq)) << "reader process died";
    }
  }
  for (std::uint64_t drain = 0; read(progress[0], &drain, sizeof drain) > 0;) {
  }  // until the reader exits (it stops at the last frame, or after 20 s)
  close(progress[0]);
  EXPECT_EQ(writer.frames_written(), kFrames);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "reader process failed with code " << WEXITSTATUS(status)
                                    << " (10 order, 11 time/step, 12 torn pixels, 13 size, 14 missed last, 15 too few, 16 open, 17 pipe)";
}

TEST(FrameRing, ReaderRejectsSomethingElse) {
  const std::string name = unique_name("bad");
  const int fd = shm_open(name.c_str(), O_CREAT | O_RDWR, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, 4096), 0);
  close(fd);
  try {
    vr::FrameRingReader reader(name);
    ADD_FAILURE() << "a zeroed object was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad magic"), std::string::npos) << e.what();
  }
  shm_unlink(name.c_str());
  EXPECT_THROW(vr::FrameRingReader("/vitreo-test-does-not-exist"), std::runtime_error);
}

TEST(FrameRing, WriterRejectsAFrameOfTheWrongSize) {
  vr::FrameRingWriter writer(unique_name("size"), 16, 8, 2);
  vr::StereoFrame f;
  f.eye_width = 16;
  f.eye_height = 9;
  f.rgba.resize(32u * 9u * 4u);
  EXPECT_THROW(writer.write(f), std::invalid_argument);
}
