#pragma once
// What happened to the instruments during a step, for telemetry, metrics and the debriefing: one
// list per step, written by the stages that notice things (grasps, laser, contacts, light) in the
// order the step runs them. Fixed capacity: nothing allocates during a step; a step with more events
// than fit keeps the first ones.
#include <cstdint>
#include <vector>

#include "core/common/types.hpp"

namespace vitreo::core {

enum class InstrumentEventKind : std::uint8_t {
  kExcessiveRetinaForce,  // magnitude: contact force on the retina (µN)
  kUnintendedTear,        // a tear in the retina; magnitude: strain
  kLaserOnDetachedRetina, // burn without adhesion; magnitude: clearance from the choroid (mm)
  kLightTooClose,         // the light pipe within the safe distance of the macula; magnitude: distance
  kLightToxicity,         // the macular light dose passed the limit; magnitude: dose (J/cm²)
  kInstrumentCollision,   // two instruments touch; `other` is the second; magnitude: depth (mm)
  kLensTouch,             // magnitude: depth (mm)
  kWallContact,           // the tip pressed into the globe wall; magnitude: depth (mm)
  kGrasp,                 // forceps closed on tissue; magnitude: distance to the grasp point (mm)
  kGraspLost,             // the grasped tissue pulled out of the jaws / tore away; magnitude: force
  kRelease,
  kAttachmentBroken,      // passed on from the tissue; magnitude: force (µN)
  kLaserBurn,             // magnitude: burn diameter (mm)
};
const char* to_string(InstrumentEventKind k);

struct InstrumentEvent {
  InstrumentEventKind kind;
  std::uint32_t instrument;  // kNone when not tied to one
  std::uint32_t other;       // second instrument, surface, … (kNone when unused)
  Vec3 position_mm;
  double magnitude;
};

class InstrumentEvents {
 public:
  static constexpr std::size_t kCapacity = 256;
  InstrumentEvents() { events_.reserve(kCapacity); }
  void clear() { events_.clear(); }
  void emit(InstrumentEventKind kind, std::uint32_t instrument, std::uint32_t other, const Vec3& p, double magnitude) {
    if (events_.size() < events_.capacity()) events_.push_back({kind, instrument, other, p, magnitude});
  }
  const std::vector<InstrumentEvent>& all() const { return events_; }

 private:
  std::vector<InstrumentEvent> events_;
};

}  // namespace vitreo::core
