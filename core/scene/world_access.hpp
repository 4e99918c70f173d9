#pragma once
// Privileged access to Surface and TissueWorld for the scene layer: complete binary serialisation of
// the physical state (snapshots) and the settings swap used while settling a case. Declared a friend
// of both classes; nothing else should need it.
#include <cstdint>
#include <vector>

#include "core/common/status.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

class WorldAccess {
 public:
  static void set_settings(TissueWorld& world, const SolverSettings& settings);
  // Sets time and step count (settling resets them to zero).
  static void set_clock(TissueWorld& world, std::uint64_t steps, double time_s);

  // Every bit of mutable state, in a fixed layout (little-endian host order).
  static void write_state(const TissueWorld& world, std::vector<std::uint8_t>& out);
  // Reads it back into a world built from the same scene (same surfaces, capacities, attachments
  // and forces); refuses anything that does not fit, leaving the world unchanged.
  static Status read_state(TissueWorld& world, const std::uint8_t* data, std::size_t size);
};

}  // namespace vitreo::core
