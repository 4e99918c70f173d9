#pragma once
// Stable snake_case names of the simulation's instrument events, as telemetry carries them
// (event_t.what, session_totals_t.event_kind) and the session report reads them. core's to_string()
// is prose for people ("light pipe too close to the macula"); these are keys a program can match.
#include "core/instruments/instrument_events.hpp"

namespace vitreo::telemetry {

constexpr const char* event_key(core::InstrumentEventKind k) {
  using K = core::InstrumentEventKind;
  switch (k) {
    case K::kExcessiveRetinaForce: return "excessive_retina_force";
    case K::kUnintendedTear: return "unintended_tear";
    case K::kLaserOnDetachedRetina: return "laser_on_detached_retina";
    case K::kLightTooClose: return "light_too_close";
    case K::kLightToxicity: return "light_toxicity";
    case K::kInstrumentCollision: return "instrument_collision";
    case K::kLensTouch: return "lens_touch";
    case K::kWallContact: return "wall_contact";
    case K::kGrasp: return "grasp";
    case K::kGraspLost: return "grasp_lost";
    case K::kRelease: return "release";
    case K::kAttachmentBroken: return "attachment_broken";
    case K::kLaserBurn: return "laser_burn";
  }
  return "unknown";
}

}  // namespace vitreo::telemetry
