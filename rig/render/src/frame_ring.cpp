#include "vitreo/render/frame_ring.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace vitreo::render {
namespace {

static_assert(std::atomic_ref<std::uint64_t>::is_always_lock_free,
              "the ring's atomics must be lock-free to be shared between processes");

std::atomic_ref<std::uint64_t> atomic_u64(std::uint64_t& v) { return std::atomic_ref<std::uint64_t>(v); }

FrameSlotHeader& slot_at(std::uint8_t* base, const FrameRingHeader& h, std::uint64_t k) {
  return *reinterpret_cast<FrameSlotHeader*>(base + h.header_bytes + k * h.slot_stride);
}

std::string errno_text() { return std::strerror(errno); }

// ThreadSanitizer does not model standalone fences (GCC rejects them under -fsanitize=thread), so
// there the reader's closing check uses a seq_cst load instead. TSan cannot see the other process
// of a shared-memory ring anyway; the fence is what is correct for the real build.
std::uint64_t reload_after_copy(std::atomic_ref<std::uint64_t> lock) {
#if defined(__SANITIZE_THREAD__)
  return lock.load(std::memory_order_seq_cst);
#else
  std::atomic_thread_fence(std::memory_order_acquire);  // the copy happens before the re-check
  return lock.load(std::memory_order_relaxed);
#endif
}

}  // namespace

FrameRingWriter::FrameRingWriter(std::string name, int eye_width, int height, int slot_count, int eyes)
    : name_(std::move(name)) {
  if (eye_width <= 0 || height <= 0 || slot_count < 2 || (eyes != 1 && eyes != 2))
    throw std::invalid_argument("frame ring: need positive size, at least 2 slots and 1 or 2 eyes");
  const std::uint64_t frame_bytes = std::uint64_t(eyes * eye_width) * std::uint64_t(height) * 4;
  const std::uint64_t stride = (sizeof(FrameSlotHeader) + frame_bytes + 63) / 64 * 64;
  bytes_ = sizeof(FrameRingHeader) + stride * std::uint64_t(slot_count);
  shm_unlink(name_.c_str());  // a stale ring from a crashed run
  const int fd = shm_open(name_.c_str(), O_CREAT | O_EXCL | O_RDWR, 0644);
  if (fd < 0) throw std::runtime_error("frame ring: shm_open(" + name_ + ") failed: " + errno_text());
  if (ftruncate(fd, static_cast<off_t>(bytes_)) != 0) {
    const std::string why = errno_text();
    close(fd);
    shm_unlink(name_.c_str());
    throw std::runtime_error("frame ring: ftruncate failed: " + why);
  }
  void* p = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  close(fd);
  if (p == MAP_FAILED) {
    shm_unlink(name_.c_str());
    throw std::runtime_error("frame ring: mmap failed: " + errno_text());
  }
  base_ = static_cast<std::uint8_t*>(p);
  std::memset(base_, 0, bytes_);
  auto& h = *reinterpret_cast<FrameRingHeader*>(base_);
  h.version = kFrameRingVersion;
  h.header_bytes = sizeof(FrameRingHeader);
  h.width = static_cast<std::uint32_t>(eyes * eye_width);
  h.height = static_cast<std::uint32_t>(height);
  h.eye_width = static_cast<std::uint32_t>(eye_width);
  h.format = kFrameFormatRgba8;
  h.slot_count = static_cast<std::uint32_t>(slot_count);
  h.slot_header_bytes = sizeof(FrameSlotHeader);
  h.slot_stride = stride;
  h.frame_bytes = frame_bytes;
  h.writer_pid = static_cast<std::uint64_t>(getpid());
  // The magic goes last (release), so a reader that sees it also sees a complete header.
  atomic_u64(h.magic).store(kFrameRingMagic, std::memory_order_release);
}

FrameRingWriter::~FrameRingWriter() {
  if (base_ != nullptr) munmap(base_, bytes_);
  shm_unlink(name_.c_str());
}

void FrameRingWriter::write(const Image& image, double sim_time_s, std::uint64_t step_index, std::uint64_t frame_index) {
  const auto& h = *reinterpret_cast<const FrameRingHeader*>(base_);
  if (static_cast<std::uint32_t>(image.width) != h.width || static_cast<std::uint32_t>(image.height) != h.height ||
      image.rgba.size() != h.frame_bytes)
    throw std::invalid_argument("frame ring: image size differs from the ring's");
  write(image.rgba.data(), sim_time_s, step_index, frame_index);
}

void FrameRingWriter::write(const StereoFrame& frame) {
  const auto& h = *reinterpret_cast<const FrameRingHeader*>(base_);
  if (static_cast<std::uint32_t>(frame.width()) != h.width || static_cast<std::uint32_t>(frame.eye_height) != h.height ||
      frame.rgba.size() != h.frame_bytes)
    throw std::invalid_argument("frame ring: frame size differs from the ring's");
  write(frame.rgba.data(), frame.sim_time_s, frame.step_index, frame.frame_index);
}

void FrameRingWriter::write(const std::uint8_t* rgba, double sim_time_s, std::uint64_t step_index,
                            std::uint64_t frame_index) {
  auto& h = *reinterpret_cast<FrameRingHeader*>(base_);
  const std::uint64_t seq = ++sequence_;
  FrameSlotHeader& s = slot_at(base_, h, seq % h.slot_count);
  auto lock = atomic_u64(s.lock);
  // Odd: writing. A read-modify-write with acquire keeps the stores below from moving above it
  // (the fence-free form of the seqlock writer, Boehm 2012).
  const std::uint64_t l = lock.fetch_add(1, std::memory_order_acq_rel);
  s.sequence = seq;
  s.sim_time_s = sim_time_s;
  s.step_index = step_index;
  s.frame_index = frame_index;
  std::memcpy(reinterpret_cast<std::uint8_t*>(&s) + sizeof(FrameSlotHeader), rgba, h.frame_bytes);
  lock.store(l + 2, std::memory_order_release);  // even: complete
  atomic_u64(h.latest_sequence).store(seq, std::memory_order_release);
}

FrameRingReader::FrameRingReader(const std::string& name) {
  const int fd = shm_open(name.c_str(), O_RDONLY, 0);
  if (fd < 0) throw std::runtime_error("frame ring: cannot open " + name + ": " + errno_text());
  struct stat st {};
  if (fstat(fd, &st) != 0 || st.st_size < static_cast<off_t>(sizeof(FrameRingHeader))) {
    close(fd);
    throw std::runtime_error("frame ring: " + name + " is too small to hold a header");
  }
  bytes_ = static_cast<std::size_t>(st.st_size);
  void* p = mmap(nullptr, bytes_, PROT_READ, MAP_SHARED, fd, 0);
  close(fd);
  if (p == MAP_FAILED) throw std::runtime_error("frame ring: mmap failed: " + errno_text());
  base_ = static_cast<std::uint8_t*>(p);
  auto& h = *reinterpret_cast<FrameRingHeader*>(base_);
  std::string why;
  if (atomic_u64(h.magic).load(std::memory_order_acquire) != kFrameRingMagic) why = "bad magic";
  else if (h.version != kFrameRingVersion) why = "unsupported version " + std::to_string(h.version);
  else if (h.header_bytes != sizeof(FrameRingHeader) || h.slot_header_bytes != sizeof(FrameSlotHeader)) why = "unexpected header sizes";
  else if (h.format != kFrameFormatRgba8) why = "unknown format " + std::to_string(h.format);
  else if (h.frame_bytes != std::uint64_t(h.width) * h.height * 4 || h.slot_count < 2 ||
           h.slot_stride < sizeof(FrameSlotHeader) + h.frame_bytes ||
           h.header_bytes + h.slot_stride * h.slot_count > bytes_)
    why = "inconsistent sizes";
  if (!why.empty()) {
    munmap(base_, bytes_);
    base_ = nullptr;
    throw std::runtime_error("frame ring: " + name + ": " + why);
  }
}

FrameRingReader::~FrameRingReader() {
  if (base_ != nullptr) munmap(base_, bytes_);
}

bool FrameRingReader::read_latest(RingFrame& out, std::uint64_t after_sequence) {
  auto& h = *reinterpret_cast<FrameRingHeader*>(base_);
  for (int attempt = 0; attempt < 4; ++attempt) {
    const std::uint64_t latest = atomic_u64(h.latest_sequence).load(std::memory_order_acquire);
    if (latest == 0 || latest <= after_sequence) return false;
    FrameSlotHeader& s = slot_at(base_, h, latest % h.slot_count);
    auto lock = atomic_u64(s.lock);
    const std::uint64_t l1 = lock.load(std::memory_order_acquire);
    if (l1 & 1u) {
      ++torn_;
      continue;
    }
    out.sequence = s.sequence;
    out.sim_time_s = s.sim_time_s;
    out.step_index = s.step_index;
    out.frame_index = s.frame_index;
    out.width = static_cast<int>(h.width);
    out.height = static_cast<int>(h.height);
    out.eye_width = static_cast<int>(h.eye_width);
    out.rgba.resize(h.frame_bytes);
    std::memcpy(out.rgba.data(), reinterpret_cast<const std::uint8_t*>(&s) + sizeof(FrameSlotHeader), h.frame_bytes);
    if (reload_after_copy(lock) != l1 || out.sequence <= after_sequence) {
      ++torn_;
      continue;
    }
    return true;
  }
  return false;
}

}  // namespace vitreo::render
