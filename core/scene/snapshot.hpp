#pragma once
// Exact snapshots of the physical state of a TissueWorld: every position, velocity, rest vector,
// pool, free list, generation, sleeping counter, attachment, force and solver scratch value, so a
// world loaded from a snapshot steps on in the same bits as the one that was saved.
//
// A snapshot is restored into a world built from the same scene (build_scene with settle = false is
// enough): the static parts (globe wall, pool capacities) come from the scene, the state from the
// file. Format (little-endian):
//   "VTRSNAP\0" | u32 version | u32 flags (0) | u64 payload bytes | u64 FNV-1a-64 of the payload | payload
// payload = scene name, state hash, then the world state (TissueWorld::write_state: the field lists in
// core/tissue/tissue_world_state.cpp and surface_state.cpp). Files are written to a
// temporary name and renamed, so a reader never sees half a snapshot.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/common/status.hpp"
#include "core/tissue/tissue_world.hpp"

namespace vitreo::core {

// Compatibility is by version, explicitly: a change to any state_io field list changes the payload,
// so it bumps this number; a snapshot of another version is refused with both numbers (and cached
// case starts, keyed on it, are settled again).
inline constexpr std::uint32_t kSnapshotVersion = 4;  // 2: the solver's wake lengths; 3: sleep groups are derived, not stored; 4: VBD (bending, start state; no multipliers)

struct SnapshotInfo {
  std::uint32_t version = 0;
  std::string scene_name;
  std::uint64_t state_hash = 0;
};

std::vector<std::uint8_t> encode_snapshot(const TissueWorld& world, const std::string& scene_name);
// The same into `out`, reusing its capacity: a real-time thread that reserved enough copies the
// state without allocating and hands the bytes to another thread to write.
void encode_snapshot(const TissueWorld& world, const std::string& scene_name, std::vector<std::uint8_t>& out);
// Validates magic, version, size and checksum, then that the state fits the world; on any error the
// world is unchanged. Afterwards world.state_hash() equals the hash recorded at save time.
Status decode_snapshot(TissueWorld& world, std::span<const std::uint8_t> bytes, SnapshotInfo* info = nullptr);

Status save_snapshot(const TissueWorld& world, const std::string& scene_name, const std::string& path);
Status load_snapshot(TissueWorld& world, const std::string& path, SnapshotInfo* info = nullptr);
// Writes encoded bytes atomically (temporary name, then rename).
Status write_snapshot_file(std::span<const std::uint8_t> bytes, const std::string& path);

}  // namespace vitreo::core
