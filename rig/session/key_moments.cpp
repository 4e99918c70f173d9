#include "rig/session/key_moments.hpp"

#include <cstdio>

#include "core/instruments/instrument_system.hpp"

namespace vitreo::rig {

std::string KeyMoment::slug() const {
  if (!kind) return "case-end";
  std::string s = core::to_string(*kind);
  for (char& c : s) {
    if (c == ' ') c = '-';
  }
  return s;
}

bool KeyMoments::is_key(core::InstrumentEventKind k) {
  using K = core::InstrumentEventKind;
  switch (k) {
    case K::kExcessiveRetinaForce:
    case K::kUnintendedTear:
    case K::kLaserOnDetachedRetina:
    case K::kLightTooClose:
    case K::kLightToxicity:
    case K::kInstrumentCollision:
    case K::kLensTouch:
    case K::kWallContact: return true;
    default: return false;
  }
}

std::optional<KeyMoment> KeyMoments::pending(const std::vector<core::InstrumentEvent>& events, bool case_ended) const {
  for (const core::InstrumentEvent& e : events) {
    const auto i = static_cast<std::size_t>(e.kind);
    if (is_key(e.kind) && i < seen_.size() && !seen_[i]) return KeyMoment{e.kind};
  }
  if (case_ended && !end_seen_) return KeyMoment{};
  return std::nullopt;
}

void KeyMoments::pictured(const KeyMoment& m) {
  if (!m.kind) {
    end_seen_ = true;
    return;
  }
  const auto i = static_cast<std::size_t>(*m.kind);
  if (i < seen_.size()) seen_[i] = true;
}

std::string KeyMoments::file_prefix(const std::string& dir, std::uint64_t step, const KeyMoment& m) {
  char name[48];
  std::snprintf(name, sizeof name, "/moment_%09llu_", static_cast<unsigned long long>(step));
  return dir + name + m.slug();
}

}  // namespace vitreo::rig
