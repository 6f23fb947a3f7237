#pragma once
// The event loop (DESIGN.md §5). Bodies fly ballistically on their own clocks; a priority queue
// holds, per nearby pair, a conservative bound on when the pair can next touch (or its exact time
// of impact), per body the expiry of its broad-phase horizon, and the output samples. One event:
//   1. pop the earliest event (ties broken by kind, body ids, sequence: deterministic);
//   2. advance only the bodies it names to its time (exact ballistic motion, committed);
//   3. query closest features, warm-started from the pair's feature cache;
//   4. within the envelope and approaching: resolve the collision through impulse/, apply it,
//      report it; otherwise push the pair's new bound and stop;
//   5. after a collision refresh both bodies' swept boxes and re-bound every pair of either body
//      (other bodies' states extrapolated, never committed).
// Samples extrapolate every body to k x interval without committing anything.
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"
#include "scheduler/contact.hpp"
#include "scheduler/event_queue.hpp"
#include "scheduler/world.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace palpable {

// Counters of one run. Numerical trouble is counted here, never silent.
struct SimulationStats {
  std::uint64_t events = 0;              // events popped
  std::uint64_t pair_checks = 0;         // closest-feature queries at a pair's event
  std::uint64_t bound_queries = 0;       // closest-feature queries to (re)bound a pair
  std::uint64_t horizon_refreshes = 0;   // broad-phase horizon events
  std::uint64_t samples = 0;             // output samples written
  std::uint64_t collisions = 0;          // ordinary collisions resolved
  std::uint64_t microcollisions = 0;     // collisions below the microcollision speed
  std::uint64_t rescheduled = 0;         // pair events replaced before they fired (erased by id)
  std::uint64_t retries = 0;             // a pair colliding again at the same instant
  std::uint64_t retry_limit_hits = 0;    // ... more than settings.retry_limit times (skipped)
  std::uint64_t floored_bounds = 0;      // bounds raised to settings.toi_min_progress_s
  std::uint64_t exact_bounds = 0;        // bounds that are exact times of impact
  std::uint64_t approach_checks = 0;     // checks of an impact moved on to its instant of contact
  std::uint64_t instant_refinements = 0;  // searches for the instant of contact (polyhedra)
  std::uint64_t instant_iterations = 0;   // ... their closest-feature queries
  std::uint64_t instant_unfound = 0;      // ... ended receding, stalled or at their query cap
  std::uint64_t penetrations = 0;        // queries that found overlapping bodies
  double deepest_penetration_m = 0.0;    // ... the deepest overlap among them of known depth [m]
  std::uint64_t distance_failures = 0;   // closest-feature walks that hit their step limit
  std::uint64_t impulse_failures = 0;    // collisions whose integration failed
  std::uint64_t centre_of_pressure = 0;  // collisions resolved by the centre-of-pressure rule
  std::uint64_t riders_carried = 0;      // bodies carried along by a microcollision below them
  std::uint64_t groups = 0;              // simultaneous impacts resolved as one group
  std::uint64_t group_contacts = 0;      // their contacts (counted in collisions too)
  std::uint64_t group_unconverged = 0;   // groups whose cone solver stopped at its iteration cap
  std::uint64_t feature_steps = 0;       // V-Clip feature steps, all queries
  std::uint64_t integration_steps = 0;   // Runge-Kutta steps, all collisions
  std::uint64_t pairs_created = 0;       // pairs entering the broad phase
  std::uint64_t max_pairs = 0;           // most pairs tracked at once
  std::uint64_t box_tests = 0;           // swept-box overlap tests made by the broad phase
  // Persistent contact (scheduler/island.hpp).
  std::uint64_t holds = 0;              // contacts handed over to the hold
  std::uint64_t mode_changes = 0;       // island events (stick, slip, lift-off, tip, ...)
  std::uint64_t island_plans = 0;       // contact problems solved to plan a motion
  std::uint64_t rests = 0;              // islands put at rest
  std::uint64_t rocking_ends = 0;       // bodies stopped at the end of a rocking train
  std::uint64_t held_inconsistent = 0;  // contact problems without a solution (let go)
  // Islands whose motions stopped making progress (the contacts ending them let go).
  std::uint64_t stalled_islands = 0;
  // Integrated island motions (Island::integration): Dormand-Prince steps accepted and rejected,
  // and motions whose contact problem broke down along the way (ended early, re-planned).
  std::uint64_t island_steps = 0;
  std::uint64_t island_rejected_steps = 0;
  std::uint64_t island_failed_motions = 0;
  std::uint64_t island_chunks = 0;  // integrated motions gone on at a chunk's end (Island::extend)
};

// A held contact changing how it behaves, at its exact instant (persistent contact model).
struct ModeChange {
  double t = 0.0;
  const char* kind = "";    // hold, stick, slip, lift_off, tip, landing, rest, release, ...
  BodyId a, b;              // the pair (a < b)
  Vec3 p_W = Vec3::Zero();  // where: the contact's reference point
};

// Receives what a run produces. Default implementations ignore everything.
class SimulationObserver {
 public:
  virtual ~SimulationObserver() = default;
  // Every body's state at t = k x interval (extrapolated; ids index the world's bodies).
  virtual void on_sample(double /*t*/, const std::vector<BodyState>& /*states*/) {}
  virtual void on_collision(const CollisionRecord& /*record*/) {}
  virtual void on_mode_change(const ModeChange& /*change*/) {}
};

struct SimulationOptions {
  double output_interval = 0.0;  // [s]; 0: no samples
  QueueImpl queue = QueueImpl::kIndexed;
};

// What one step did: the event it processed and, for a collision, its record.
struct StepResult {
  bool done = false;  // nothing left to do before the time asked for: no event was processed
  double t = 0.0;     // the event's time [s]
  EventKind kind = EventKind::kPairCheck;
  BodyId a, b;                               // the bodies it named (b invalid for one body)
  std::optional<CollisionRecord> collision;  // the collision it resolved, if any
};

class Simulation {
 public:
  // Validates the world (throws InputError "/bodies/<i>": ... for bodies that overlap at the
  // start, or non-finite states) and sets up the broad phase and the first bounds.
  Simulation(World world, SimulationOptions options);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // Processes the next event if it is due at or before t_end, and says what it did.
  StepResult step(double t_end, SimulationObserver* observer = nullptr);
  // Runs every event up to and including t_end (samples at k x interval <= t_end).
  // `progress` (optional) is called every 64 events with the current time; where it returns
  // false, the run stops there, between two events, and time() is that event's time.
  void run_until(double t_end, SimulationObserver* observer,
                 const std::function<bool(double)>& progress = {});

  const World& world() const;
  const SimulationStats& stats() const;
  // Body `id` extrapolated to time t (>= its clock) without committing.
  BodyState state_at(BodyId id, double t) const;
  double time() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace palpable
