#include "rig/session/snapshot_writer.hpp"

#include <spdlog/spdlog.h>

#include <cstring>
#include <filesystem>

#include "core/scene/snapshot.hpp"

namespace vitreo::rig {

SnapshotWriter::SnapshotWriter(std::string folder, std::size_t reserve_bytes) : folder_(std::move(folder)) {
  for (Slot& s : slots_) s.bytes.reserve(reserve_bytes);
}

bool SnapshotWriter::capture(const core::TissueWorld& world, const std::string& case_name, const char* name,
                             std::uint64_t step) noexcept {
  for (Slot& s : slots_) {
    if (s.state.load(std::memory_order_acquire) != 0) continue;
    core::encode_snapshot(world, case_name, s.bytes);
    std::strncpy(s.name, name, sizeof s.name - 1);
    std::strncpy(s.case_name, case_name.c_str(), sizeof s.case_name - 1);
    s.step = step;
    s.state.store(1, std::memory_order_release);
    return true;
  }
  refused_.fetch_add(1, std::memory_order_relaxed);
  return false;
}

void SnapshotWriter::service() noexcept {
  for (Slot& s : slots_) {
    if (s.state.load(std::memory_order_acquire) != 1) continue;
    try {
      std::error_code ec;
      std::filesystem::create_directories(folder_, ec);
      const std::string path = path_for(s.name);
      const core::Status st = core::write_snapshot_file(s.bytes, path);
      std::string line = st ? path + " (" + s.case_name + ", step " + std::to_string(s.step) + ")"
                            : "FAILED " + st.message();
      if (st) {
        spdlog::info("snapshot written: {}", line);
      } else {
        spdlog::error("snapshot {}: {}", s.name, st.message());
      }
      std::lock_guard<std::mutex> lock(written_mutex_);
      written_.push_back(std::move(line));
    } catch (const std::exception& e) {
      spdlog::error("snapshot {}: {}", s.name, e.what());
    }
    s.state.store(0, std::memory_order_release);
  }
}

std::vector<std::string> SnapshotWriter::written() const {
  std::lock_guard<std::mutex> lock(written_mutex_);
  return written_;
}

}  // namespace vitreo::rig
