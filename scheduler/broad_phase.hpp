#pragma once
// The broad phase of the scheduler (DESIGN.md §5): which stored swept boxes overlap a given box.
//
// A hierarchical uniform hash grid in the manner of Mirtich's thesis (after Overmars): level L has
// cubic cells of side 2^L m (L any integer), and a box lives at the smallest level whose cell side
// is at least its largest extent, so it occupies at most 2 x 2 x 2 cells of that level. A query
// visits, on every level that holds boxes, the cells its box covers there — or, where those cells
// outnumber the boxes of that level, that level's list — so its cost is the number of nearby boxes
// (plus the number of occupied levels, a handful: log2 of the ratio of largest to smallest box),
// not the number of boxes stored. Each level has its own cell table and a coarse table of
// 8 x 8 x 8-cell blocks: a query spanning many cells of a fine level looks up the blocks first, so
// a region where that level holds nothing costs a lookup per block, not per cell. Boxes with an
// infinite or non-finite coordinate (halfspaces, a halfspace that spins off its own normal) or too
// far out to index (|x| / 2^L > 2^52) are kept in a separate list that every query tests.
//
// Exactness: a query reports exactly the items whose stored box overlaps the query box by
// Aabb::overlaps — the same answer as testing every item — in ascending id order. Moving an
// item (set) costs O(1) cells; memory is O(items) (cells emptied by moves keep their slot until
// their level's table is rebuilt, which drops them).
#include "core/types.hpp"

#include <cstdint>
#include <map>
#include <vector>

namespace palpable {

class BroadPhase {
 public:
  // Stores `box` for item `id` (inserting it, or moving it if present). Ids are small integers.
  void set(std::uint32_t id, const Aabb& box);
  void remove(std::uint32_t id);
  bool contains(std::uint32_t id) const { return id < items_.size() && items_[id].present; }
  std::size_t size() const { return size_; }

  // Appends to `out`, in ascending order, every stored id other than `self` whose box overlaps
  // `box` (Aabb::overlaps). `self` may be any value (e.g. one not stored).
  void query(const Aabb& box, std::uint32_t self, std::vector<std::uint32_t>& out);

  // Box-overlap tests made by all queries so far (the broad phase's work).
  std::uint64_t box_tests() const { return box_tests_; }

 private:
  struct CellKey {
    std::int64_t i, j, k;
    bool operator==(const CellKey& o) const { return i == o.i && j == o.j && k == o.k; }
  };
  static std::uint64_t hash(const CellKey& c);
  // An open-addressing hash table (linear probing, power-of-two size, at most half full) from a
  // cell to a value, its slots in one array: a lookup reads one slot, not a bucket, a node and
  // then the node's value as std::unordered_map does. Slots are never erased one by one: a cell
  // that empties keeps its slot, and its buffer, so that a box moving to and fro allocates
  // nothing; the table is rebuilt without its empty cells when it would pass half full.
  template <class Value>
  class CellTable {
   public:
    const Value* find(const CellKey& key) const;
    Value* find(const CellKey& key) {
      return const_cast<Value*>(static_cast<const CellTable&>(*this).find(key));
    }
    // The value of `key`, inserted empty (Value{}) if absent. `is_empty(value)` tells which
    // cells a rebuild may drop. The reference is valid until the next call of get.
    template <class IsEmpty>
    Value& get(const CellKey& key, IsEmpty is_empty);

   private:
    struct Slot {
      CellKey key{0, 0, 0};
      bool used = false;
      Value value{};
    };
    template <class IsEmpty>
    void rebuild(IsEmpty is_empty);
    // The first unused slot on the probe sequence of `key` (the table is never full).
    Slot& free_slot(const CellKey& key);
    std::vector<Slot> slots_;
    std::size_t used_ = 0;
  };
  struct Item {
    Aabb box;
    bool present = false;
    bool unbounded = false;  // in unbounded_, not in the grid
    int level = 0;
    std::int64_t lo[3] = {0, 0, 0};  // cell range at `level`, inclusive
    std::int64_t hi[3] = {0, 0, 0};
    std::size_t list_position = 0;  // in unbounded_ or in its level's list
  };
  struct CellEntry {
    Aabb box;
    std::uint32_t id;
  };
  struct Level {
    std::vector<std::uint32_t> items;
    // Holds every box ever stored at the level (it only grows): a query far from all of them
    // skips the level without a lookup. 10,000 idle bodies far away on a level of their own so
    // cost a gas's queries nothing; without it each query looked up its cells in their table,
    // a cache miss each (bench idle, gas + fixed cubes: x1.07-1.19 -> x1.00-1.03).
    Aabb bounds;
    // Each cell holds copies of its items' boxes, so a query reads them in sequence.
    CellTable<std::vector<CellEntry>> cells;
    CellTable<std::uint32_t> blocks;  // items with a cell in the block (0: an emptied block)
  };

  // f(block) for every block (8 x 8 x 8 cells) holding a cell of the item: one or two per axis.
  template <class F>
  static void for_each_block(const Item& item, F f);
  void insert_cells(std::uint32_t id);
  void erase_cells(std::uint32_t id);
  // Tests item `id`, whose stored box is `stored`, against `box` (once per query).
  void test(std::uint32_t id, const Aabb& stored, const Aabb& box, std::uint32_t self,
            std::vector<std::uint32_t>& out);
  // Tests the items of the cells lo..hi (inclusive, per axis) of `level`.
  void visit_cells(const Level& level, const std::int64_t lo[3], const std::int64_t hi[3],
                   const Aabb& box, std::uint32_t self, std::vector<std::uint32_t>& out);

  std::vector<Item> items_;
  std::vector<std::uint32_t> unbounded_;
  std::map<int, Level> levels_;         // every level that ever held an item (kept: no table churn)
  std::vector<std::uint32_t> visited_;  // per id: the query stamp that last tested it
  std::uint32_t stamp_ = 0;
  std::size_t size_ = 0;
  std::uint64_t box_tests_ = 0;
};

}  // namespace palpable
