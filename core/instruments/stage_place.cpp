// Stage: place the instruments. Each tracked tip and shaft, given in the eye-fixture frame, is turned
// into the eye frame by the eye's rotation; the tip's geometry (jaws, blades, port) and its
// collision capsules follow. A capsule sweeps from where it was at the end of the last step to where
// it is now, so the tissue's substeps see it move through the step, not jump.
#include "core/instruments/instrument_system.hpp"

namespace vitreo::core {

void InstrumentSystem::place(const Quat& fixture_to_eye) {
  const Quat& rt = fixture_to_eye;
  colliders_.clear();
  collider_owner_.clear();
  for (std::uint32_t i = 0; i < state_.size(); ++i) {
    InstrumentState& st = state_[i];
    const Vec3 tip = rt * st.input.tip_fixture_mm;
    const Vec3 axis = rt * st.input.axis_fixture;
    st.frame = make_frame(tip, axis, st.input.twist_rad, options_.ports_mm[st.description.port]);
    st.inside = st.input.present && st.frame.inserted_mm > 0.0;
    st.tip = st.inside ? tip_geometry(st.description.kind, st.description.gauge, st.frame, st.input, st.description.dimensions)
                       : TipGeometry{};
    if (!st.inside) continue;
    const bool had = was_inside_[i] != 0;
    for (int k = 0; k < st.tip.count; ++k) {
      const Capsule& c = st.tip.parts[static_cast<std::size_t>(k)];
      if (!c.pushes_tissue || c.radius_mm <= 0.0) continue;
      ColliderCapsule cc;
      cc.a1 = c.a;
      cc.b1 = c.b;
      cc.radius_mm = c.radius_mm;
      const Capsule& prev = previous_tip_[i].parts[static_cast<std::size_t>(k)];
      const bool same = had && k < previous_tip_[i].count && prev.pushes_tissue;
      cc.a0 = same ? prev.a : c.a;
      cc.b0 = same ? prev.b : c.b;
      colliders_.push_back(cc);
      collider_owner_.push_back(i);
    }
  }
}

}  // namespace vitreo::core
