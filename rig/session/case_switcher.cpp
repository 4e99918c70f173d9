#include "rig/session/case_switcher.hpp"

#include <spdlog/spdlog.h>

namespace vitreo::rig {

CaseSwitcher::CaseSwitcher(std::vector<scene_io::CaseText> cases, scene_io::CaseLoadOptions options, bool visuals)
    : cases_(std::move(cases)), options_(std::move(options)), visuals_(visuals), looks_(cases_.size()) {}

CaseSwitcher::~CaseSwitcher() {
  delete ready_.exchange(nullptr);
  PreparedCase* p = nullptr;
  while (retired_.try_pop(p)) delete p;
}

std::unique_ptr<PreparedCase> CaseSwitcher::load(int index) {
  scene_io::CaseLoadOptions o = options_;
  // Textures only to build the case's look once; physics never needs them.
  const bool need_look = visuals_ && index >= 0 && index < static_cast<int>(looks_.size()) && !looks_[static_cast<std::size_t>(index)];
  o.textures = need_look;
  std::unique_ptr<PreparedCase> c = prepare_case(cases_, index, o);
  c->serial = ++serial_;
  if (visuals_) {
    auto& look = looks_[static_cast<std::size_t>(index)];
    if (!look) look = build_case_visuals(*c);
    c->visuals = look.get();
    prepare_view_snapshots(*c);
  }
  return c;
}

std::unique_ptr<PreparedCase> CaseSwitcher::load_now(int index) { return load(index); }

int CaseSwitcher::pending() const noexcept {
  const int r = request_.load(std::memory_order_acquire);
  if (r >= 0) return r;
  const PreparedCase* ready = ready_.load(std::memory_order_acquire);
  if (ready) return ready->index;
  return loading_.load(std::memory_order_acquire);
}

std::unique_ptr<PreparedCase> CaseSwitcher::take() noexcept {
  return std::unique_ptr<PreparedCase>(ready_.exchange(nullptr, std::memory_order_acq_rel));
}

bool CaseSwitcher::retire(std::unique_ptr<PreparedCase>& c) noexcept {
  if (!c) return true;
  if (!retired_.try_push(c.get())) return false;
  (void)c.release();
  return true;
}

void CaseSwitcher::service(bool load_cases) noexcept {
  PreparedCase* old = nullptr;
  while (retired_.try_pop(old)) delete old;
  if (!load_cases) return;
  if (ready_.load(std::memory_order_acquire) != nullptr) return;  // physics has not taken the last one yet
  const int wanted = request_.load(std::memory_order_acquire);
  if (wanted < 0) return;
  loading_.store(wanted, std::memory_order_release);  // before the request clears: pending() never sees a gap
  const int index = request_.exchange(-1, std::memory_order_acq_rel);
  loading_.store(index, std::memory_order_release);
  try {
    std::unique_ptr<PreparedCase> c = load(index);
    spdlog::info("case {} ({}) loaded{}", index, c->scene->description.name, c->from_cache ? " from the cache" : "");
    ready_.store(c.release(), std::memory_order_release);
  } catch (const std::exception& e) {
    failures_.fetch_add(1, std::memory_order_relaxed);
    spdlog::error("case {} could not be loaded: {}", index, e.what());
    std::lock_guard<std::mutex> lock(error_mutex_);
    last_error_ = e.what();
  }
  loading_.store(-1, std::memory_order_release);
}

std::string CaseSwitcher::last_error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

}  // namespace vitreo::rig
