#pragma once
// Loading the next case without stalling physics.
//
// Physics asks for a case (request(), an atomic store) and, at each step boundary, takes whatever
// the loader has finished (take(), an atomic exchange) — it never waits for a load. The loader
// runs on its own service thread: it parses, builds and settles the case (or restores the settled
// start from the cache folder), builds its instruments and, for a rendering session, its look
// (static meshes, textures: once per case, kept for the whole session so the render thread can hold
// a plain pointer) and view-snapshot buffers. Cases physics is done with come back through a ring
// and are freed here, so physics never frees a case's memory either.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "rig/runtime/spsc_ring.hpp"
#include "rig/session/case_runtime.hpp"
#include "rig/session/frame_source.hpp"

namespace vitreo::rig {

class CaseSwitcher {
 public:
  CaseSwitcher(std::vector<scene_io::CaseText> cases, scene_io::CaseLoadOptions options, bool visuals);
  ~CaseSwitcher();
  CaseSwitcher(const CaseSwitcher&) = delete;
  CaseSwitcher& operator=(const CaseSwitcher&) = delete;

  // Any thread, before the session starts: loads a case synchronously (the first one).
  std::unique_ptr<PreparedCase> load_now(int index);

  // ---- physics thread (wait-free) ----
  // Asks for case `index` (a later request replaces an earlier one not yet started).
  void request(int index) noexcept { request_.store(index, std::memory_order_release); }
  // The case index requested and not yet handed over (-1: none).
  int pending() const noexcept;
  // A finished case, or nullptr.
  std::unique_ptr<PreparedCase> take() noexcept;
  // Hands back a case physics no longer uses; false when the ring is full (try again next step).
  bool retire(std::unique_ptr<PreparedCase>& c) noexcept;

  // ---- loader service thread ----
  // Frees retired cases and loads a requested one. Never throws (a failed load is logged and
  // counted; the session stays on its case).
  // `load`: false once the session is ending (only frees).
  void service(bool load = true) noexcept;
  std::uint64_t failures() const noexcept { return failures_.load(std::memory_order_relaxed); }
  std::string last_error() const;

 private:
  std::unique_ptr<PreparedCase> load(int index);

  std::vector<scene_io::CaseText> cases_;
  scene_io::CaseLoadOptions options_;
  bool visuals_;
  std::vector<std::unique_ptr<CaseVisuals>> looks_;  // per case index, kept for the session
  std::uint64_t serial_ = 0;
  std::atomic<int> request_{-1};
  std::atomic<int> loading_{-1};
  std::atomic<PreparedCase*> ready_{nullptr};
  runtime::SpscRing<PreparedCase*> retired_{16};
  std::atomic<std::uint64_t> failures_{0};
  mutable std::mutex error_mutex_;  // loader thread and summary only, never physics
  std::string last_error_;
};

}  // namespace vitreo::rig
