#pragma once
// The pairs the scheduler tracks (DESIGN.md §5, broad phase): per body its shape's Voronoi
// structure, its swept box over a horizon and the pairs it is in; per pair its closest-feature
// cache, its pending event and its retry count. Only pairs whose swept boxes overlap exist, and
// never a pair of two fixed or kinematic bodies.
//
// Invariants: a body's box covers its motion from the time it was computed until its horizon (a
// horizon event is queued for every finite horizon); a pair exists exactly when the boxes of its
// bodies overlapped at the last refresh of either; pairs are created and dropped in ascending order
// of the other body, so the pair order (and with it the event sequence) does not depend on how the
// broad phase found the overlaps.
//
// The set owns this runtime data; the world owns the bodies' states, the simulation owns the queue
// and the statistics (the set queues horizon events there and counts its work there).
#include "core/body.hpp"
#include "distance/closest_features.hpp"
#include "scheduler/broad_phase.hpp"
#include "scheduler/event_queue.hpp"
#include "scheduler/world.hpp"

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace palpable {

struct SimulationStats;

// How a dynamic body moves over its coming horizon when it is held in contact rather than in free
// flight (scheduler/island.hpp): its acceleration and how far the true one may be from it.
struct HeldMotion {
  Vec3 a_W = Vec3::Zero();  // [m/s^2]
  double a_slack = 0.0;     // [m/s^2]
};

class PairSet {
 public:
  struct BodyRuntime {
    std::shared_ptr<const ShapeGeometry> geometry;
    Aabb box;                    // swept box over [time computed, horizon]
    double horizon = kInfinity;  // absolute time the box stops being valid
    EventQueue::EventId horizon_event = EventQueue::kNoEvent;
    std::vector<std::uint32_t> pairs;
  };
  // 64 bytes, one cache line (a 10,000-sphere gas holds some 76,000 pairs, read in no useful
  // order); members ordered to leave no padding.
  struct Pair {
    BodyId a, b;
    EventQueue::EventId event = EventQueue::kNoEvent;
    int collisions_at_t = 0;
    double last_collision_t = -kInfinity;
    std::uint64_t rebound_round = 0;  // the last collect_rebounds that listed it
    PairCache cache;
    bool live = false;
    bool held = false;  // its contact is held (scheduler/island.hpp): no pair events
    // Its held contact let go at last_collision_t (lift-off, separation): at that instant it is
    // not a collision unless it truly approaches (gravity pressing it is what just failed).
    bool lifted = false;
    // Checks of an impact's approach to the instant of contact so far (Simulation,
    // time_to_contact).
    std::uint8_t approach_steps = 0;
    // How many of its collisions in a row followed a landing of its held contact (an island's
    // event) and came down slower than a fall from the plane's resolution, without the pair
    // separating beyond the envelope in between: a body held on a face that keeps tipping and
    // landing back on it (Simulation, collide_or_hold's rounds).
    std::uint8_t quiet_landings = 0;
    bool landed = false;  // its held contact just landed: its next collision is that landing's
    // How many of its holds in a row let go at the instant they were made, without the pair
    // separating beyond the envelope in between (Simulation, collide_or_hold's rounds).
    std::uint8_t quick_releases = 0;
  };

  // One geometry per distinct shape (shapes are shared between bodies). Throws InputError
  // "/bodies/<i>/shape" for a body without a shape.
  PairSet(const World& world, EventQueue& queue, SimulationStats& stats);

  BodyRuntime& body(BodyId id) { return bodies_[id.index]; }
  const BodyRuntime& body(BodyId id) const { return bodies_[id.index]; }
  const ShapeGeometry& geometry(BodyId id) const { return *bodies_[id.index].geometry; }
  Pair& pair(std::uint32_t index) { return pairs_[index]; }
  const Pair& pair(std::uint32_t index) const { return pairs_[index]; }
  std::uint32_t slots() const { return static_cast<std::uint32_t>(pairs_.size()); }

  // Stores the swept box of `id` from state `s` (at time t) without touching its pairs.
  void set_box(BodyId id, const BodyState& s, double t);
  // Every body whose swept box overlaps that of `id` and that may pair with it (at least one of
  // the two dynamic), ascending, into `out`. Returns how many of them are dynamic.
  std::size_t find_overlaps(BodyId id, std::vector<std::uint32_t>& out);
  // Recomputes the swept box of `id` from state `s` at time t, queues its horizon event, and
  // brings its pairs up to date (creates and drops pairs; does not bound them).
  //
  // A dynamic body among other moving bodies looks ahead no further than it travels, at its
  // present speed, in Settings::broad_phase_max_sweep times its reach: a longer box would pair
  // it with bodies it cannot reach before its next collision, each pair re-bounded at every one
  // of its collisions (it halves the cost per collision of a 10,000-sphere gas). A body with no
  // moving body near even its short box - a projectile in empty space, a ball bouncing alone on
  // a floor - keeps the whole horizon: shortening it would only add refreshes.
  void refresh(BodyId id, const BodyState& s, double t, const HeldMotion* held = nullptr);
  // The pairs of the dynamic bodies among `moved`, each listed once (a pair of two moved bodies
  // too), in order: what a collision that changed those bodies' motion must re-bound. A fixed
  // or kinematic body's motion never changes in a collision, so its other pairs' bounds stay
  // valid (a table or wall with a pair for each of n bodies cost O(n^(2/3)) re-bounds per
  // collision in a gas).
  const std::vector<std::uint32_t>& collect_rebounds(const std::vector<BodyId>& moved);

 private:
  // Computes the swept box; with `limit_sweep` a dynamic body's horizon is cut to the sweep
  // limit; returns whether that cut it.
  bool compute_box(BodyId id, const BodyState& s, double t, bool limit_sweep,
                   const HeldMotion* held);
  bool refresh_box(BodyId id, const BodyState& s, double t, bool limit_sweep,
                   const HeldMotion* held = nullptr);
  void schedule_horizon(BodyId id);
  std::uint32_t create_pair(BodyId a, BodyId b);
  void remove_pair(std::uint32_t index);

  const World& world_;
  EventQueue& queue_;
  SimulationStats& stats_;
  std::vector<BodyRuntime> bodies_;
  std::vector<Pair> pairs_;
  std::vector<std::uint32_t> free_pairs_;
  std::size_t live_pairs_ = 0;
  // The swept boxes, dynamic bodies apart from fixed and kinematic ones: a non-dynamic body
  // looks only among the dynamic ones, so two non-dynamic bodies are never even compared.
  BroadPhase dynamic_boxes_, static_boxes_;
  std::vector<std::uint32_t> overlapping_;  // scratch of refresh
  // Scratch of refresh: (the other body, the pair) for each pair of a body.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> partners_;
  std::vector<std::uint32_t> rebounds_;  // scratch of collect_rebounds
  std::uint64_t rebound_round_ = 0;      // collect_rebounds calls so far
};

}  // namespace palpable
