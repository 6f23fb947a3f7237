#pragma once
// The event queue of the scheduler (DESIGN.md §5): a 4-ary heap ordered strictly and
// deterministically by (time, kind, body ids, sequence number). Events are addressed by a small
// integer id so that the owner of an event (a pair, a body's horizon) can reschedule or erase it
// in O(log n).
//
// Three implementations give the identical event sequence (tested):
// - kIndexed (the default): an indexed 4-ary heap written here, its entries stored in the heap's
//   own array, with an id -> position table. DESIGN.md §5 names it as the upgrade path from
//   Boost.Heap when the queue shows in profiles: Boost's mutable d_ary_heap keeps its values in a
//   std::list and the heap as iterators into it, so every comparison of a sift reads a list node
//   somewhere in memory. With 10^5 events queued (a 10,000-sphere gas) that is a cache miss per
//   comparison.
// - kBoost: Boost.Heap's d_ary_heap<arity<4>, mutable_<true>>, kept as a second implementation.
// - kReference: a linear scan of a vector, slow and obviously correct.
#include "core/types.hpp"

#include <boost/heap/d_ary_heap.hpp>

#include <cstdint>
#include <vector>

namespace palpable {

// Ordered: at equal times a kind listed earlier is processed first.
enum class EventKind : std::uint8_t {
  kPairCheck = 0,  // a pair's conservative bound (or exact time of impact) expires
  kIsland = 1,     // the motion of bodies held in contact changes mode (scheduler/island.hpp)
  kHorizon = 2,    // a body's broad-phase horizon expires: refresh its swept box and pairs
  kSample = 3,     // write an output sample (extrapolated, commits nothing)
};

struct Event {
  double t = 0.0;
  EventKind kind = EventKind::kPairCheck;
  BodyId a;                    // for pair events a < b
  BodyId b;                    // invalid for single-body and global events
  std::uint32_t owner = 0;     // what the event is for (a pair's slot); not part of the order
  std::uint64_t sequence = 0;  // assigned by the queue on push/update
};

// Strict weak order: true when x must be processed before y.
inline bool event_before(const Event& x, const Event& y) {
  if (x.t != y.t) return x.t < y.t;
  if (x.kind != y.kind) return x.kind < y.kind;
  if (x.a.index != y.a.index) return x.a.index < y.a.index;
  if (x.b.index != y.b.index) return x.b.index < y.b.index;
  return x.sequence < y.sequence;
}

enum class QueueImpl { kIndexed, kBoost, kReference };

class EventQueue {
 public:
  using EventId = std::uint32_t;
  static constexpr EventId kNoEvent = 0xffffffffu;

  explicit EventQueue(QueueImpl impl = QueueImpl::kIndexed) : impl_(impl) {}

  EventId push(Event event);
  // Reschedules an event that is in the queue (its sequence number is renewed).
  void update(EventId id, Event event);
  void erase(EventId id);
  bool contains(EventId id) const { return id < slots_.size() && slots_[id].live; }

  bool empty() const { return size_ == 0; }
  std::size_t size() const { return size_; }
  const Event& top() const;
  // Removes the earliest event and returns it together with its id (now free).
  Event pop(EventId* id = nullptr);

 private:
  struct Entry {
    Event event;
    EventId id;
  };
  // Boost.Heap is a max-heap: the comparator answers "a pops after b".
  struct PopsAfter {
    bool operator()(const Entry& x, const Entry& y) const { return event_before(y.event, x.event); }
  };
  using Heap = boost::heap::d_ary_heap<Entry, boost::heap::arity<4>, boost::heap::mutable_<true>,
                                       boost::heap::compare<PopsAfter>>;
  struct Slot {
    std::uint32_t index = 0;  // position in indexed_ or reference_
    bool live = false;
  };

  EventId allocate();
  std::size_t reference_min() const;
  // The indexed heap: moves the entry at position i up or down to its place.
  void sift_up(std::size_t i);
  void sift_down(std::size_t i);
  // Puts `entry` at position i in place of the entry there, then moves it up or down to its place.
  void replace_at(std::size_t i, const Entry& entry);
  void place(std::size_t i, const Entry& entry) {
    indexed_[i] = entry;
    slots_[entry.id].index = static_cast<std::uint32_t>(i);
  }

  QueueImpl impl_;
  std::vector<Entry> indexed_;  // a 4-ary heap: the children of i are 4 i + 1 ... 4 i + 4
  Heap heap_;
  std::vector<Heap::handle_type> boost_handles_;  // kBoost: per id
  std::vector<Entry> reference_;                  // unsorted; pop scans for the minimum
  std::vector<Slot> slots_;
  std::vector<EventId> free_ids_;
  std::uint64_t next_sequence_ = 0;
  std::size_t size_ = 0;
};

}  // namespace palpable
