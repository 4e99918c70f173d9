// Stage: find what the instruments may touch. The collision scene (FCL broad phase over tissue
// patches, core/collision) lists the triangles near each swept capsule; whatever an instrument may
// touch this step must be simulated, so those triangles' vertices are woken.
#include "core/instruments/instrument_system.hpp"

namespace vitreo::core {

void InstrumentSystem::find_contacts() {
  collision_->update(world_, colliders_, candidates_);
  for (const auto& c : candidates_) {
    Surface& s = world_.surface(c.surface);
    for (auto v : s.triangle_vertices(c.triangle)) {
      if (!s.vertex_awake(v)) s.wake_vertex(v);
    }
  }
}

}  // namespace vitreo::core
