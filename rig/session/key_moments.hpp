#pragma once
// The moments of a session an instructor wants to see, not only read about (issue 17: "a few
// frames at the key events"): the first time each kind of iatrogenic event happened — the kinds
// the score card counts as such (core SessionTotals::iatrogenic_events: excessive retina force,
// unintended tear, laser on detached retina, light too close, light toxicity, instrument
// collision, lens touch, globe wall contact) — and the end of the case (every criterion met, or its
// time ran out). Physics asks each step whether the step holds a new one; the session captures the
// picture of that very step and the render thread writes it as
//   <frames>/moment_<step, 9 digits>_<slug>_{left,right,stereo,instructor}.png
// (slug: the kind's name with '-' for spaces, or "case-end"), which the debrief shows in order.
// A kind whose picture could not be taken (the previous one was still being rendered) stays
// unseen, so its next occurrence is pictured instead.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/instruments/instrument_events.hpp"

namespace vitreo::rig {

struct KeyMoment {
  // An iatrogenic event kind, or nothing for the end of the case.
  std::optional<core::InstrumentEventKind> kind;
  std::string slug() const;  // "unintended-tear", "case-end"
};

class KeyMoments {
 public:
  // The first key moment of this step not pictured yet, if any: `events` the step's instrument
  // events, `case_ended` true at the step the case ended.
  std::optional<KeyMoment> pending(const std::vector<core::InstrumentEvent>& events, bool case_ended) const;
  // The moment's picture was taken: it is not offered again (until reset()).
  void pictured(const KeyMoment& m);
  // A new case (or the same again) begins: every moment may be pictured again.
  void reset() { seen_ = {}; end_seen_ = false; }
  static bool is_key(core::InstrumentEventKind k);
  // The file prefix of a moment's picture: "<dir>/moment_<step>_<slug>".
  static std::string file_prefix(const std::string& dir, std::uint64_t step, const KeyMoment& m);

 private:
  std::array<bool, 32> seen_{};
  bool end_seen_ = false;
};

}  // namespace vitreo::rig
