// Stage: what the instruments feel after the tissue step. The solver's contact multipliers become
// each instrument's contact force (and the retina's part of it), grips report their force, the
// tissue's events become the instruments' (a retinal tear is put down to the nearest tip, a grip
// that broke is a lost grasp), and the rigid contacts — lens, globe wall, another instrument — are
// reported on their first step. Then the step's cuts and removals go to core/topology, at the step
// boundary.
#include "core/instruments/instrument_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vitreo::core {

namespace {
CapsuleShape shape(const Capsule& c) { return {c.a, c.b, c.radius_mm}; }
}  // namespace

void InstrumentSystem::sense(const StepReport& report, InstrumentEvents& events) {
  const std::uint32_t retina = options_.retina_surface;
  for (auto& st : state_) {
    st.contact_force_un = Vec3::Zero();
    st.retina_force_un = 0.0;
  }
  for (std::uint32_t c = 0; c < colliders_.size(); ++c) {
    InstrumentState& st = state_[collider_owner_[c]];
    st.contact_force_un += world_.contact_force(c);
    if (retina != kNone) st.retina_force_un += world_.contact_force(c, retina).norm();
  }
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    const bool over = st.retina_force_un > options_.retina_force_limit_un;
    if (over && !retina_overloaded_[i]) events.emit(InstrumentEventKind::kExcessiveRetinaForce, i, retina, st.frame.tip, st.retina_force_un);
    retina_overloaded_[i] = over;
    if (st.grip != kNone) st.grip_force_un = world_.grip_force(st.grip);
  }
  if (report.ok) {
    for (const TissueEvent& e : world_.events()) {
      if (e.kind == TissueEventKind::kTear && e.surface == retina) {
        // Attributed to the nearest instrument tip.
        std::uint32_t who = kNone;
        double best = std::numeric_limits<double>::infinity();
        for (std::uint32_t i = 0; i < state_.size(); ++i) {
          if (!state_[i].inside) continue;
          const double d = (state_[i].frame.tip - e.position_mm).norm();
          if (d < best) {
            best = d;
            who = i;
          }
        }
        events.emit(InstrumentEventKind::kUnintendedTear, who, e.surface, e.position_mm, e.magnitude);
      } else if (e.kind == TissueEventKind::kGripBroken) {
        for (std::uint32_t i = 0; i < state_.size(); ++i) {
          if (state_[i].grip == e.item) {
            events.emit(InstrumentEventKind::kGraspLost, i, e.surface, e.position_mm, e.magnitude);
            state_[i].grip = kNone;
          }
        }
      } else if (e.kind == TissueEventKind::kAttachmentBroken) {
        events.emit(InstrumentEventKind::kAttachmentBroken, kNone, e.surface, e.position_mm, e.magnitude);
      }
    }
  }
  rigid_contacts(events);
}

namespace {
// How far inside the eye a trocar cannula and the pars plana around it reach (a 23/25G cannula's
// tube stands ~1 mm in; the entry's wall is within another half millimetre).
constexpr double kCannulaReachMm = 1.5;
}  // namespace

void InstrumentSystem::rigid_contacts(InstrumentEvents& events) {
  const std::uint32_t n = static_cast<std::uint32_t>(state_.size());
  for (std::uint32_t i = 0; i < n; ++i) {
    const InstrumentState& a = state_[i];
    // Lens and globe wall.
    double lens = std::numeric_limits<double>::infinity();
    if (a.inside && options_.anatomy.has_lens) {
      for (int k = 0; k < a.tip.count; ++k) lens = std::min(lens, collision_->lens_distance(shape(a.tip.parts[static_cast<std::size_t>(k)])));
    }
    const bool touching_lens = lens <= 0.0;
    if (touching_lens && !lens_touching_[i]) events.emit(InstrumentEventKind::kLensTouch, i, kNone, a.frame.tip, -lens);
    lens_touching_[i] = touching_lens;
    // Not within the cannula's reach of its own port: there the instrument goes through the wall
    // by design (every entry used to count as a wall contact).
    const bool in_cannula = (a.frame.tip - options_.ports_mm[a.description.port]).norm() < kCannulaReachMm;
    const double wall = a.inside && !in_cannula ? world_.wall().clearance(a.frame.tip) - shaft_radius_mm(a.description.gauge) +
                                                      options_.anatomy.retina_thickness_mm
                                                : std::numeric_limits<double>::infinity();
    if (wall < 0.0 && !wall_touching_[i]) events.emit(InstrumentEventKind::kWallContact, i, kNone, a.frame.tip, -wall);
    wall_touching_[i] = wall < 0.0;
    // Other instruments (FCL capsule–capsule).
    for (std::uint32_t j = i + 1; j < n; ++j) {
      const InstrumentState& b = state_[j];
      double best = std::numeric_limits<double>::infinity();
      Vec3 where = Vec3::Zero();
      if (a.inside && b.inside) {
        for (int k = 0; k < a.tip.count; ++k) {
          for (int l = 0; l < b.tip.count; ++l) {
            Vec3 w;
            const double d = collision_->capsule_distance(shape(a.tip.parts[static_cast<std::size_t>(k)]),
                                                          shape(b.tip.parts[static_cast<std::size_t>(l)]), &w);
            if (d < best) {
              best = d;
              where = w;
            }
          }
        }
      }
      std::uint8_t& touching = pair_touching_[i * n + j];
      if (best <= 0.0 && !touching) events.emit(InstrumentEventKind::kInstrumentCollision, i, j, where, -best);
      touching = best <= 0.0;
    }
  }
}

void InstrumentSystem::hand_over_topology(TopologyActions& topology) {
  for (const auto& p : poses_) topology.cut(world_, p);
  for (const auto& r : removals_) topology.remove(world_, r);
}

}  // namespace vitreo::core
