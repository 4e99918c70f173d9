#include "core/tissue/spring_groups.hpp"

#include <algorithm>
#include <cstring>

#include "core/common/prefault.hpp"

namespace vitreo::core {

namespace {
// Room a region gets at a rebuild: twice its springs (repeated cuts through one block add a few
// dozen each), and at least enough for a block filled with new vertices (a cut's splits and copies
// take fresh slots, and the springs among them go to those blocks' groups).
constexpr std::uint32_t kMinRoom = 16;
constexpr std::uint32_t kFreshBlockRoom = 4 * Surface::kSleepBlock;
}  // namespace

std::uint32_t SpringGroups::group_of_spring(const Surface& s, std::uint32_t e) {
  if (!s.edge_alive(e)) return kNone;
  const auto ev = s.edge_vertices(e);
  return std::min(ev[0], ev[1]) / Surface::kSleepBlock;
}

void SpringGroups::reserve(const Surface& s) {
  blocks_ = s.block_count();
  base_.assign(blocks_, 0);
  size_.assign(blocks_, 0);
  room_.assign(blocks_, 0);
  // Every rebuild's layout fits: twice the springs + the minimum or fresh room of every block.
  group_edges_.assign(2 * std::size_t{s.edge_capacity()} + std::size_t{kFreshBlockRoom + kMinRoom} * blocks_, 0);
  group_of_.assign(s.edge_capacity(), kNone);
  partners_.assign(std::size_t{kPartners} * blocks_, 0);
  partner_count_.assign(blocks_, 0);
  active_.assign(blocks_, 1);
  changed_.assign(blocks_, 0);
  reserve_touched(changed_list_, blocks_);
  built_ = false;
}

void SpringGroups::update(const Surface& s) {
  if (!built_ || s.spring_log_lost(log_read_)) {
    rebuild(s);
  } else {
    bool fits = true;
    for (std::uint64_t p = log_read_; p < s.spring_log_end() && fits; ++p) fits = follow(s, s.spring_log_at(p));
    if (fits) {
      for (const std::uint32_t g : changed_list_) find_partners(s, g);
    } else {
      rebuild(s);
    }
  }
  for (const std::uint32_t g : changed_list_) changed_[g] = 0;
  changed_list_.clear();
  log_read_ = s.spring_log_end();

  for (std::uint32_t g = 0; g < blocks_; ++g) {
    bool active = s.block_awake(g);
    if (!active && partner_count_[g] == kScanGroup) {
      const std::uint32_t* e = group_edges_.data() + base_[g];
      for (std::uint32_t i = 0; i < size_[g] && !active; ++i) {
        const auto ev = s.edge_vertices(e[i]);
        active = s.block_awake(std::max(ev[0], ev[1]) / Surface::kSleepBlock);
      }
    } else {
      const std::uint32_t* p = partners_.data() + std::size_t{kPartners} * g;
      for (std::uint32_t i = 0; i < partner_count_[g] && !active; ++i) active = s.block_awake(p[i]);
    }
    active_[g] = active ? 1 : 0;
  }
}

void SpringGroups::rebuild(const Surface& s) {
  std::fill(size_.begin(), size_.end(), 0u);
  std::fill(group_of_.begin(), group_of_.end(), kNone);
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    const std::uint32_t g = group_of_spring(s, e);
    if (g != kNone) ++size_[g];
  }
  const std::uint32_t first_fresh = s.vertex_slots() / Surface::kSleepBlock;  // the last, partly used block too
  std::size_t next = 0;
  for (std::uint32_t g = 0; g < blocks_; ++g) {
    room_[g] = 2 * size_[g] + kMinRoom;
    if (g >= first_fresh) room_[g] = std::max(room_[g], kFreshBlockRoom);
    base_[g] = static_cast<std::uint32_t>(next);
    next += room_[g];
    size_[g] = 0;
  }
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {  // ascending: each group in slot order
    const std::uint32_t g = group_of_spring(s, e);
    if (g == kNone) continue;
    group_edges_[base_[g] + size_[g]++] = e;
    group_of_[e] = g;
  }
  for (std::uint32_t g = 0; g < blocks_; ++g) find_partners(s, g);
  built_ = true;
  ++rebuilds_;
}

bool SpringGroups::follow(const Surface& s, std::uint32_t e) {
  const std::uint32_t to = group_of_spring(s, e), from = group_of_[e];
  if (to == from) {  // same group; its vertices may have changed, and with them the blocks reached
    if (to != kNone) mark_changed(to);
    return true;
  }
  if (to != kNone && size_[to] == room_[to]) return false;
  if (from != kNone) {
    std::uint32_t* first = group_edges_.data() + base_[from];
    std::uint32_t* last = first + size_[from];
    std::uint32_t* at = std::lower_bound(first, last, e);
    if (at == last || *at != e) return false;  // not where the groups say: rebuild
    std::memmove(at, at + 1, static_cast<std::size_t>(last - at - 1) * sizeof(std::uint32_t));
    --size_[from];
    mark_changed(from);
  }
  if (to != kNone) {
    std::uint32_t* first = group_edges_.data() + base_[to];
    std::uint32_t* last = first + size_[to];
    std::uint32_t* at = std::lower_bound(first, last, e);
    std::memmove(at + 1, at, static_cast<std::size_t>(last - at) * sizeof(std::uint32_t));
    *at = e;
    ++size_[to];
    mark_changed(to);
  }
  group_of_[e] = to;
  return true;
}

void SpringGroups::find_partners(const Surface& s, std::uint32_t g) {
  std::uint32_t* p = partners_.data() + std::size_t{kPartners} * g;
  std::uint32_t n = 0;
  const std::uint32_t* e = group_edges_.data() + base_[g];
  for (std::uint32_t i = 0; i < size_[g]; ++i) {
    const auto ev = s.edge_vertices(e[i]);
    const std::uint32_t other = std::max(ev[0], ev[1]) / Surface::kSleepBlock;
    if (other == g || std::find(p, p + n, other) != p + n) continue;
    if (n == kPartners) {
      partner_count_[g] = kScanGroup;
      return;
    }
    p[n++] = other;
  }
  partner_count_[g] = static_cast<std::uint8_t>(n);
}

Status SpringGroups::check(const Surface& s) const {
  std::vector<std::vector<std::uint32_t>> expected(blocks_);
  for (std::uint32_t e = 0; e < s.edge_slots(); ++e) {
    const std::uint32_t g = group_of_spring(s, e);
    if (g != kNone) expected[g].push_back(e);
  }
  for (std::uint32_t g = 0; g < blocks_; ++g) {
    const std::string where = "spring group " + std::to_string(g);
    if (size_[g] != expected[g].size()) {
      return Status::error(where + " holds " + std::to_string(size_[g]) + " springs, the surface has " +
                           std::to_string(expected[g].size()));
    }
    if (!std::equal(expected[g].begin(), expected[g].end(), group_edges_.begin() + base_[g])) {
      return Status::error(where + ": springs differ from the surface's, or are out of order");
    }
    if (size_[g] > room_[g] || (g + 1 < blocks_ && base_[g] + room_[g] > base_[g + 1])) {
      return Status::error(where + ": region overflows");
    }
    const std::uint32_t* p = partners_.data() + std::size_t{kPartners} * g;
    std::vector<std::uint32_t> reached;
    for (const std::uint32_t e : expected[g]) {
      const auto ev = s.edge_vertices(e);
      const std::uint32_t other = std::max(ev[0], ev[1]) / Surface::kSleepBlock;
      if (other != g && std::find(reached.begin(), reached.end(), other) == reached.end()) reached.push_back(other);
    }
    if (partner_count_[g] == kScanGroup) {
      if (reached.size() <= kPartners) return Status::error(where + " is scanned but has few partners");
      continue;
    }
    if (reached.size() != partner_count_[g] ||
        !std::all_of(reached.begin(), reached.end(), [&](std::uint32_t b) { return std::find(p, p + partner_count_[g], b) != p + partner_count_[g]; })) {
      return Status::error(where + ": partner blocks differ from the blocks its springs reach");
    }
  }
  return Status::ok();
}

}  // namespace vitreo::core
