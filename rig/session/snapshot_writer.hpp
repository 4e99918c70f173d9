#pragma once
// "Save snapshot NAME" without file I/O on the physics thread: physics encodes the world (an exact
// core/scene/snapshot) into one of two buffers reserved before the session, at a step boundary, and
// flags it; the writer service thread writes it atomically to <folder>/NAME.snapshot and frees the
// buffer. With both buffers still being written the request is refused (counted), never waited for.
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "core/tissue/tissue_world.hpp"

namespace vitreo::rig {

class SnapshotWriter {
 public:
  // `reserve_bytes`: capacity of each buffer (a state larger than that allocates once).
  SnapshotWriter(std::string folder, std::size_t reserve_bytes);

  // Physics thread: copies the state; false when no buffer is free.
  bool capture(const core::TissueWorld& world, const std::string& case_name, const char* name, std::uint64_t step) noexcept;
  // Writer thread: writes captured snapshots. Never throws (errors are logged and listed).
  void service() noexcept;

  const std::string& folder() const noexcept { return folder_; }
  std::string path_for(const std::string& name) const { return folder_ + "/" + name + ".snapshot"; }
  // After the session: "path (case, step)" per snapshot written, and failures.
  std::vector<std::string> written() const;
  std::uint64_t refused() const noexcept { return refused_.load(std::memory_order_relaxed); }

 private:
  struct Slot {
    std::atomic<int> state{0};  // 0 free, 1 captured (writer's turn)
    std::vector<std::uint8_t> bytes;
    char name[65] = {};
    char case_name[64] = {};
    std::uint64_t step = 0;
  };
  std::string folder_;
  Slot slots_[2];
  std::atomic<std::uint64_t> refused_{0};
  mutable std::mutex written_mutex_;  // writer thread and the summary, never physics
  std::vector<std::string> written_;
};

}  // namespace vitreo::rig
