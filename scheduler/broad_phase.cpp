#include "scheduler/broad_phase.hpp"

#include "core/check.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

namespace {

// Cell indices are kept within +-2^60: a clamped query range still meets exactly the cells of
// stored boxes, whose indices are below 2^51 in magnitude (see level_of).
constexpr double kIndexLimit = 1152921504606846976.0;  // 2^60

bool finite_box(const Aabb& box) {
  return box.min_W.allFinite() && box.max_W.allFinite();
}

// The level of a finite box: the smallest L with 2^L >= its largest extent, raised so that its
// coordinates stay below 2^51 cells (a tiny box far out goes to a coarser level).
int level_of(const Aabb& box) {
  const double extent = (box.max_W - box.min_W).maxCoeff();
  const double far = std::max(box.min_W.cwiseAbs().maxCoeff(), box.max_W.cwiseAbs().maxCoeff());
  int level = -1074;
  if (extent > 0.0) {
    int e;
    const double m = std::frexp(extent, &e);  // extent = m 2^e, m in [0.5, 1)
    level = m == 0.5 ? e - 1 : e;
  }
  if (far > 0.0) {
    int e;
    std::frexp(far, &e);  // far < 2^e
    level = std::max(level, e - 51);
  }
  return level;
}

// The block (8 x 8 x 8 cells) of a cell index, rounding down.
std::int64_t block_of(std::int64_t i) {
  return i >= 0 ? i / 8 : -((-i + 7) / 8);
}

double cell_index(double x, int level) {
  return std::clamp(std::floor(std::ldexp(x, -level)), -kIndexLimit, kIndexLimit);
}

}  // namespace

std::uint64_t BroadPhase::hash(const CellKey& c) {
  std::uint64_t h = static_cast<std::uint64_t>(c.i) * 0x9E3779B97F4A7C15ull;
  h = h * 0xC2B2AE3D27D4EB4Full ^ static_cast<std::uint64_t>(c.j);
  h = h * 0x165667B19E3779F9ull ^ static_cast<std::uint64_t>(c.k);
  // The SplitMix64 finalizer: the low bits the table uses depend on every bit of the key, so
  // the cells of a row do not fill neighbouring slots (long probe runs).
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

template <class Value>
const Value* BroadPhase::CellTable<Value>::find(const CellKey& key) const {
  if (slots_.empty()) return nullptr;
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t i = hash(key) & mask;; i = (i + 1) & mask) {
    const Slot& slot = slots_[i];
    if (!slot.used) return nullptr;
    if (slot.key == key) return &slot.value;
  }
}

template <class Value>
template <class IsEmpty>
Value& BroadPhase::CellTable<Value>::get(const CellKey& key, IsEmpty is_empty) {
  if (Value* value = find(key)) return *value;
  if (2 * (used_ + 1) > slots_.size()) rebuild(is_empty);
  Slot& slot = free_slot(key);
  slot.key = key;
  slot.used = true;
  ++used_;
  return slot.value;
}

template <class Value>
typename BroadPhase::CellTable<Value>::Slot& BroadPhase::CellTable<Value>::free_slot(
    const CellKey& key) {
  const std::size_t mask = slots_.size() - 1;
  std::size_t i = hash(key) & mask;
  while (slots_[i].used) i = (i + 1) & mask;
  return slots_[i];
}

template <class Value>
template <class IsEmpty>
void BroadPhase::CellTable<Value>::rebuild(IsEmpty is_empty) {
  std::vector<Slot> old;
  old.swap(slots_);
  std::size_t live = 0;
  for (const Slot& slot : old) live += slot.used && !is_empty(slot.value);
  // At most a quarter full after the rebuild: at least as many insertions again before the next.
  std::size_t size = 16;
  while (size < 4 * (live + 1)) size *= 2;
  slots_.resize(size);
  used_ = 0;
  for (Slot& slot : old) {
    if (!slot.used || is_empty(slot.value)) continue;
    free_slot(slot.key) = std::move(slot);
    ++used_;
  }
}

void BroadPhase::set(std::uint32_t id, const Aabb& box) {
  if (id >= items_.size()) {
    items_.resize(id + 1);
    visited_.resize(id + 1, 0);
  }
  if (items_[id].present) {
    const Aabb& old = items_[id].box;
    if (old.min_W == box.min_W && old.max_W == box.max_W) return;  // a resting body: no change
    remove(id);
  }
  Item& item = items_[id];
  item.box = box;
  item.present = true;
  ++size_;
  if (!finite_box(box)) {
    item.unbounded = true;
    item.list_position = unbounded_.size();
    unbounded_.push_back(id);
    return;
  }
  item.unbounded = false;
  item.level = level_of(box);
  for (int a = 0; a < 3; ++a) {
    item.lo[a] = static_cast<std::int64_t>(cell_index(box.min_W[a], item.level));
    item.hi[a] = static_cast<std::int64_t>(cell_index(box.max_W[a], item.level));
  }
  Level& level = levels_[item.level];
  item.list_position = level.items.size();
  level.items.push_back(id);
  level.bounds.extend(box);
  insert_cells(id);
}

void BroadPhase::remove(std::uint32_t id) {
  PALPABLE_CHECK(contains(id), "removing an item the broad phase does not hold");
  Item& item = items_[id];
  std::vector<std::uint32_t>* list = &unbounded_;
  if (!item.unbounded) {
    erase_cells(id);
    list = &levels_.at(item.level).items;
  }
  // Swap-remove from its list, keeping the moved item's position current.
  const std::uint32_t last = list->back();
  (*list)[item.list_position] = last;
  items_[last].list_position = item.list_position;
  list->pop_back();
  item.present = false;
  --size_;
}

template <class F>
void BroadPhase::for_each_block(const Item& item, F f) {
  for (std::int64_t i = block_of(item.lo[0]); i <= block_of(item.hi[0]); ++i) {
    for (std::int64_t j = block_of(item.lo[1]); j <= block_of(item.hi[1]); ++j) {
      for (std::int64_t k = block_of(item.lo[2]); k <= block_of(item.hi[2]); ++k) {
        f(CellKey{i, j, k});
      }
    }
  }
}

void BroadPhase::insert_cells(std::uint32_t id) {
  const auto no_entries = [](const std::vector<CellEntry>& cell) { return cell.empty(); };
  const auto zero_count = [](std::uint32_t count) { return count == 0; };
  const Item& item = items_[id];
  Level& level = levels_[item.level];
  for (std::int64_t i = item.lo[0]; i <= item.hi[0]; ++i) {
    for (std::int64_t j = item.lo[1]; j <= item.hi[1]; ++j) {
      for (std::int64_t k = item.lo[2]; k <= item.hi[2]; ++k) {
        level.cells.get(CellKey{i, j, k}, no_entries).push_back(CellEntry{item.box, id});
      }
    }
  }
  for_each_block(item, [&](const CellKey& block) { ++level.blocks.get(block, zero_count); });
}

void BroadPhase::erase_cells(std::uint32_t id) {
  const Item& item = items_[id];
  Level& level = levels_.at(item.level);
  for (std::int64_t i = item.lo[0]; i <= item.hi[0]; ++i) {
    for (std::int64_t j = item.lo[1]; j <= item.hi[1]; ++j) {
      for (std::int64_t k = item.lo[2]; k <= item.hi[2]; ++k) {
        // Swap-remove: the order of a cell's entries does not matter (a query sorts its answer).
        std::vector<CellEntry>& cell = *level.cells.find(CellKey{i, j, k});
        *std::find_if(cell.begin(), cell.end(), [id](const CellEntry& e) { return e.id == id; }) =
            cell.back();
        cell.pop_back();
      }
    }
  }
  for_each_block(item, [&](const CellKey& block) { --*level.blocks.find(block); });
}

void BroadPhase::visit_cells(const Level& level, const std::int64_t lo[3], const std::int64_t hi[3],
                             const Aabb& box, std::uint32_t self, std::vector<std::uint32_t>& out) {
  for (std::int64_t i = lo[0]; i <= hi[0]; ++i) {
    for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
      for (std::int64_t k = lo[2]; k <= hi[2]; ++k) {
        const std::vector<CellEntry>* cell = level.cells.find(CellKey{i, j, k});
        if (cell == nullptr) continue;
        for (const CellEntry& e : *cell) test(e.id, e.box, box, self, out);
      }
    }
  }
}

void BroadPhase::test(std::uint32_t id, const Aabb& stored, const Aabb& box, std::uint32_t self,
                      std::vector<std::uint32_t>& out) {
  if (visited_[id] == stamp_) return;
  visited_[id] = stamp_;
  if (id == self) return;
  ++box_tests_;
  if (stored.overlaps(box)) out.push_back(id);
}

void BroadPhase::query(const Aabb& box, std::uint32_t self, std::vector<std::uint32_t>& out) {
  if (++stamp_ == 0) {  // the stamp wrapped: forget every mark
    std::fill(visited_.begin(), visited_.end(), 0);
    stamp_ = 1;
  }
  const std::size_t first = out.size();
  const bool finite = finite_box(box);
  for (const auto& [level, contents] : levels_) {
    if (contents.items.empty() || !contents.bounds.overlaps(box)) continue;
    double lo[3], hi[3];
    double cells = 1.0;
    for (int a = 0; a < 3 && finite; ++a) {
      lo[a] = cell_index(box.min_W[a], level);
      hi[a] = cell_index(box.max_W[a], level);
      cells *= hi[a] - lo[a] + 1.0;
    }
    if (!finite || cells > static_cast<double>(contents.items.size())) {
      for (std::uint32_t id : contents.items) test(id, items_[id].box, box, self, out);
      continue;
    }
    std::int64_t lo_i[3], hi_i[3];
    for (int a = 0; a < 3; ++a) {
      lo_i[a] = static_cast<std::int64_t>(lo[a]);
      hi_i[a] = static_cast<std::int64_t>(hi[a]);
    }
    if (cells <= 8.0) {
      visit_cells(contents, lo_i, hi_i, box, self, out);
      continue;
    }
    // Many cells: only those of the occupied blocks.
    std::int64_t b_lo[3], b_hi[3];
    for (int a = 0; a < 3; ++a) {
      b_lo[a] = block_of(lo_i[a]);
      b_hi[a] = block_of(hi_i[a]);
    }
    for (std::int64_t bi = b_lo[0]; bi <= b_hi[0]; ++bi) {
      for (std::int64_t bj = b_lo[1]; bj <= b_hi[1]; ++bj) {
        for (std::int64_t bk = b_lo[2]; bk <= b_hi[2]; ++bk) {
          const std::uint32_t* count = contents.blocks.find(CellKey{bi, bj, bk});
          if (count == nullptr || *count == 0) continue;
          const std::int64_t block[3] = {bi, bj, bk};
          std::int64_t c_lo[3], c_hi[3];
          for (int a = 0; a < 3; ++a) {
            c_lo[a] = std::max(lo_i[a], 8 * block[a]);
            c_hi[a] = std::min(hi_i[a], 8 * block[a] + 7);
          }
          visit_cells(contents, c_lo, c_hi, box, self, out);
        }
      }
    }
  }
  for (std::uint32_t id : unbounded_) test(id, items_[id].box, box, self, out);
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
}

}  // namespace palpable
