#include "scheduler/event_queue.hpp"

#include "core/check.hpp"

#include <algorithm>

namespace palpable {

EventQueue::EventId EventQueue::allocate() {
  if (!free_ids_.empty()) {
    EventId id = free_ids_.back();
    free_ids_.pop_back();
    return id;
  }
  PALPABLE_CHECK(slots_.size() < kNoEvent, "more events queued than ids");
  slots_.emplace_back();
  if (impl_ == QueueImpl::kBoost) boost_handles_.emplace_back();
  return static_cast<EventId>(slots_.size() - 1);
}

void EventQueue::sift_up(std::size_t i) {
  const Entry entry = indexed_[i];
  while (i > 0) {
    const std::size_t parent = (i - 1) / 4;
    if (!event_before(entry.event, indexed_[parent].event)) break;
    place(i, indexed_[parent]);
    i = parent;
  }
  place(i, entry);
}

void EventQueue::sift_down(std::size_t i) {
  const Entry entry = indexed_[i];
  const std::size_t n = indexed_.size();
  for (;;) {
    const std::size_t first = 4 * i + 1;
    if (first >= n) break;
    std::size_t best = first;
    const std::size_t last = std::min(first + 4, n);
    for (std::size_t c = first + 1; c < last; ++c) {
      if (event_before(indexed_[c].event, indexed_[best].event)) best = c;
    }
    if (!event_before(indexed_[best].event, entry.event)) break;
    place(i, indexed_[best]);
    i = best;
  }
  place(i, entry);
}

void EventQueue::replace_at(std::size_t i, const Entry& entry) {
  const bool earlier = event_before(entry.event, indexed_[i].event);
  place(i, entry);
  if (earlier) {
    sift_up(i);
  } else {
    sift_down(i);
  }
}

EventQueue::EventId EventQueue::push(Event event) {
  event.sequence = next_sequence_++;
  EventId id = allocate();
  Slot& slot = slots_[id];
  slot.live = true;
  switch (impl_) {
    case QueueImpl::kIndexed:
      indexed_.push_back(Entry{event, id});
      sift_up(indexed_.size() - 1);
      break;
    case QueueImpl::kBoost: boost_handles_[id] = heap_.push(Entry{event, id}); break;
    case QueueImpl::kReference:
      slot.index = static_cast<std::uint32_t>(reference_.size());
      reference_.push_back(Entry{event, id});
      break;
  }
  ++size_;
  return id;
}

void EventQueue::update(EventId id, Event event) {
  PALPABLE_CHECK(contains(id), "update of an event that is not queued");
  event.sequence = next_sequence_++;
  Slot& slot = slots_[id];
  switch (impl_) {
    case QueueImpl::kIndexed: replace_at(slot.index, Entry{event, id}); break;
    case QueueImpl::kBoost: heap_.update(boost_handles_[id], Entry{event, id}); break;
    case QueueImpl::kReference: reference_[slot.index].event = event; break;
  }
}

void EventQueue::erase(EventId id) {
  PALPABLE_CHECK(contains(id), "erase of an event that is not queued");
  Slot& slot = slots_[id];
  switch (impl_) {
    case QueueImpl::kIndexed: {
      // The last entry fills the hole and moves up or down from there.
      const std::size_t i = slot.index;
      const Entry last = indexed_.back();
      indexed_.pop_back();
      if (i < indexed_.size()) replace_at(i, last);
      break;
    }
    case QueueImpl::kBoost: heap_.erase(boost_handles_[id]); break;
    case QueueImpl::kReference: {
      // Swap-remove, keeping the moved entry's slot index right.
      const std::size_t i = slot.index;
      reference_[i] = reference_.back();
      slots_[reference_[i].id].index = static_cast<std::uint32_t>(i);
      reference_.pop_back();
      break;
    }
  }
  slot.live = false;
  free_ids_.push_back(id);
  --size_;
}

std::size_t EventQueue::reference_min() const {
  std::size_t best = 0;
  for (std::size_t i = 1; i < reference_.size(); ++i) {
    if (event_before(reference_[i].event, reference_[best].event)) best = i;
  }
  return best;
}

const Event& EventQueue::top() const {
  PALPABLE_CHECK(!empty(), "top of an empty event queue");
  switch (impl_) {
    case QueueImpl::kIndexed: return indexed_.front().event;
    case QueueImpl::kBoost: return heap_.top().event;
    case QueueImpl::kReference: break;
  }
  return reference_[reference_min()].event;
}

Event EventQueue::pop(EventId* id_out) {
  PALPABLE_CHECK(!empty(), "pop of an empty event queue");
  const Entry entry = impl_ == QueueImpl::kIndexed ? indexed_.front()
                      : impl_ == QueueImpl::kBoost ? heap_.top()
                                                   : reference_[reference_min()];
  erase(entry.id);
  if (id_out != nullptr) *id_out = entry.id;
  return entry.event;
}

}  // namespace palpable
