#pragma once
// The solver's springs grouped by sleep block, so a sweep skips whole groups whose springs touch
// only sleeping tissue.
//
// Group g holds the springs whose lower vertex lies in block g, in ascending slot order (the
// sweep order: mesh order within a group, groups in block order), and knows the other blocks its
// springs reach; it is active when block g or one of those is awake.
//
// A blade stroke changes a few hundred of the tens of thousands of springs, and rereading them
// all after each topology change cost the next step about 0.3 ms on the 20k-vertex retina (and
// flushed the caches the next stroke needed). So the groups follow the surface's spring log
// (Surface::spring_log_end): each group lives in a region of group_edges with room to spare, and
// a logged spring moves from its old group's region to its new one, in order. A full rebuild from
// every spring — the only way before 2026-11-25 — happens when the log was lost (the first
// update, a restored snapshot, more changes than the log holds) or a region is full, and gives
// every region fresh room. Either way the groups, and so the sweep, are the same: check() compares
// them with a rebuild.
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/status.hpp"
#include "core/tissue/surface.hpp"

namespace vitreo::core {

class SpringGroups {
 public:
  // Sized once to the surface's capacity (its block count and spring capacity).
  void reserve(const Surface& s);
  // Brings the groups up to date with the surface's springs, and marks which are active.
  void update(const Surface& s);

  // Calls f(spring) for every spring of an active group, in sweep order.
  template <class F>
  void for_each_active(F&& f) const {
    for (std::uint32_t g = 0; g < blocks_; ++g) {
      if (!active_[g]) continue;
      const std::uint32_t* e = group_edges_.data() + base_[g];
      for (std::uint32_t i = 0; i < size_[g]; ++i) f(e[i]);
    }
  }

  // Ok when every group holds exactly the live springs whose lower vertex lies in its block, in
  // ascending order, with the other blocks they reach among its partners; otherwise the first
  // difference. For tests: this is what a full rebuild gives.
  Status check(const Surface& s) const;
  // Full rebuilds so far (tests and benchmarks: a stroke should not need one).
  std::uint64_t rebuilds() const { return rebuilds_; }

 private:
  // Other blocks a group's springs reach, kept per group up to this many; a group reaching more is
  // marked and scanned spring by spring when its activity is decided.
  static constexpr std::uint32_t kPartners = 15;
  static constexpr std::uint8_t kScanGroup = 0xff;

  void rebuild(const Surface& s);
  // Moves logged spring e to the group its current vertices give (or out, if it was removed);
  // false when that group's region is full.
  bool follow(const Surface& s, std::uint32_t e);
  void find_partners(const Surface& s, std::uint32_t g);
  void mark_changed(std::uint32_t g) {
    if (changed_[g]) return;
    changed_[g] = 1;
    changed_list_.push_back(g);
  }
  static std::uint32_t group_of_spring(const Surface& s, std::uint32_t e);

  std::uint32_t blocks_ = 0;
  // Group g's springs: group_edges_[base_[g] .. base_[g] + size_[g]), room_[g] slots reserved.
  std::vector<std::uint32_t> base_, size_, room_, group_edges_;
  std::vector<std::uint32_t> group_of_;  // per spring slot: its group, or kNone
  std::vector<std::uint32_t> partners_;  // kPartners per group
  std::vector<std::uint8_t> partner_count_, active_, changed_;
  std::vector<std::uint32_t> changed_list_;
  std::uint64_t log_read_ = 0;  // the surface's spring log, read up to here
  bool built_ = false;
  std::uint64_t rebuilds_ = 0;
};

}  // namespace vitreo::core
