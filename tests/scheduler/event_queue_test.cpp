// The indexed and Boost.Heap event queues against the linear-scan reference queue, and the strict
// order.
#include "scheduler/event_queue.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <random>
#include <vector>

using palpable::BodyId;
using palpable::Event;
using palpable::EventKind;
using palpable::EventQueue;
using palpable::QueueImpl;

namespace {
Event make_event(double t, EventKind kind, std::uint32_t a, std::uint32_t b) {
  Event e;
  e.t = t;
  e.kind = kind;
  e.a = BodyId{a};
  e.b = BodyId{b};
  return e;
}
}  // namespace

TEST_CASE("events pop in (time, kind, ids, sequence) order", "[scheduler][queue]") {
  for (QueueImpl impl : {QueueImpl::kIndexed, QueueImpl::kBoost, QueueImpl::kReference}) {
    EventQueue q(impl);
    q.push(make_event(1.0, EventKind::kSample, 0, 1));
    q.push(make_event(1.0, EventKind::kPairCheck, 2, 3));
    q.push(make_event(1.0, EventKind::kPairCheck, 1, 5));
    q.push(make_event(0.5, EventKind::kSample, 9, 9));
    q.push(make_event(1.0, EventKind::kPairCheck, 1, 4));
    q.push(make_event(1.0, EventKind::kPairCheck, 1, 4));  // identical but later sequence
    std::vector<Event> popped;
    while (!q.empty()) popped.push_back(q.pop());
    REQUIRE(popped.size() == 6);
    CHECK(popped[0].t == 0.5);  // time first, whatever the kind
    CHECK((popped[1].a.index == 1 && popped[1].b.index == 4));
    CHECK((popped[2].a.index == 1 && popped[2].b.index == 4));
    CHECK(popped[1].sequence < popped[2].sequence);
    CHECK(popped[3].b.index == 5);
    CHECK(popped[4].a.index == 2);
    CHECK(popped[5].kind == EventKind::kSample);
  }
}

TEST_CASE("both heap queues give the identical event sequence as the reference queue",
          "[scheduler][queue]") {
  for (QueueImpl impl : {QueueImpl::kIndexed, QueueImpl::kBoost}) {
    CAPTURE(static_cast<int>(impl));
    const std::uint64_t seed = 20261121;
    CAPTURE(seed);
    std::mt19937_64 rng(seed);
    EventQueue heap(impl);
    EventQueue reference(QueueImpl::kReference);
    std::vector<EventQueue::EventId> live;
    std::uniform_int_distribution<int> op(0, 9);
    // Coarse times so that ties (resolved by kind, ids, sequence) are frequent.
    std::uniform_int_distribution<int> tick(0, 50);
    std::uniform_int_distribution<std::uint32_t> body(0, 6);
    std::uniform_int_distribution<int> kind(0, 2);
    double now = 0.0;
    std::size_t pops = 0;
    for (int step = 0; step < 100000; ++step) {
      int o = op(rng);
      Event e = make_event(now + 0.01 * tick(rng), static_cast<EventKind>(kind(rng)), body(rng),
                           body(rng));
      if (o < 4 || live.empty()) {
        auto id_heap = heap.push(e);
        auto id_ref = reference.push(e);
        REQUIRE(id_heap == id_ref);  // same id allocation: same free-list use
        live.push_back(id_heap);
      } else if (o < 6) {
        std::size_t k = std::uniform_int_distribution<std::size_t>(0, live.size() - 1)(rng);
        heap.update(live[k], e);
        reference.update(live[k], e);
      } else if (o < 7) {
        std::size_t k = std::uniform_int_distribution<std::size_t>(0, live.size() - 1)(rng);
        heap.erase(live[k]);
        reference.erase(live[k]);
        live[k] = live.back();
        live.pop_back();
      } else {
        EventQueue::EventId id_heap, id_ref;
        Event x = heap.pop(&id_heap);
        Event y = reference.pop(&id_ref);
        REQUIRE(id_heap == id_ref);
        REQUIRE(x.t == y.t);
        REQUIRE(x.kind == y.kind);
        REQUIRE(x.a == y.a);
        REQUIRE(x.b == y.b);
        REQUIRE(x.sequence == y.sequence);
        now = x.t;  // time never runs back, as in the event loop
        for (auto& id : live) {
          if (id == id_heap) {
            id = live.back();
            live.pop_back();
            break;
          }
        }
        ++pops;
      }
      REQUIRE(heap.size() == reference.size());
    }
    CHECK(pops > 10000);
  }
}

TEST_CASE("misuse of event ids is an invariant error", "[scheduler][queue]") {
  EventQueue q;
  auto id = q.push(make_event(1.0, EventKind::kPairCheck, 0, 1));
  q.erase(id);
  CHECK_FALSE(q.contains(id));
  CHECK_THROWS_AS(q.erase(id), palpable::InvariantError);
  CHECK_THROWS_AS(q.top(), palpable::InvariantError);
}
