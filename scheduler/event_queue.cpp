#include "scheduler/event_queue.hpp"

#include "core/check.hpp"

namespace palpable {

EventQueue::EventId EventQueue::allocate() {
  if (!free_ids_.empty()) {
    EventId id = free_ids_.back();
    free_ids_.pop_back();
    return id;
  }
  slots_.emplace_back();
  return static_cast<EventId>(slots_.size() - 1);
}

EventQueue::EventId EventQueue::push(Event event) {
  event.sequence = next_sequence_++;
  EventId id = allocate();
  Slot& slot = slots_[id];
  slot.live = true;
  if (impl_ == QueueImpl::kHeap) {
    slot.handle = heap_.push(Entry{event, id});
  } else {
    slot.reference_index = reference_.size();
    reference_.push_back(Entry{event, id});
  }
  ++size_;
  return id;
}

void EventQueue::update(EventId id, Event event) {
  PALPABLE_CHECK(contains(id), "update of an event that is not queued");
  event.sequence = next_sequence_++;
  Slot& slot = slots_[id];
  if (impl_ == QueueImpl::kHeap) {
    heap_.update(slot.handle, Entry{event, id});
  } else {
    reference_[slot.reference_index].event = event;
  }
}

void EventQueue::erase(EventId id) {
  PALPABLE_CHECK(contains(id), "erase of an event that is not queued");
  Slot& slot = slots_[id];
  if (impl_ == QueueImpl::kHeap) {
    heap_.erase(slot.handle);
  } else {
    // Swap-remove, keeping the moved entry's slot index right.
    std::size_t i = slot.reference_index;
    reference_[i] = reference_.back();
    slots_[reference_[i].id].reference_index = i;
    reference_.pop_back();
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
  if (impl_ == QueueImpl::kHeap) return heap_.top().event;
  return reference_[reference_min()].event;
}

Event EventQueue::pop(EventId* id_out) {
  PALPABLE_CHECK(!empty(), "pop of an empty event queue");
  Entry entry = impl_ == QueueImpl::kHeap ? heap_.top() : reference_[reference_min()];
  erase(entry.id);
  if (id_out != nullptr) *id_out = entry.id;
  return entry.event;
}

}  // namespace palpable
