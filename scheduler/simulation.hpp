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
#include "scheduler/event_queue.hpp"
#include "scheduler/world.hpp"

#include <cstdint>
#include <functional>
#include <memory>
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
  std::uint64_t penetrations = 0;        // queries that found overlapping bodies
  std::uint64_t distance_failures = 0;   // closest-feature walks that hit their step limit
  std::uint64_t impulse_failures = 0;    // collisions whose integration failed
  std::uint64_t centre_of_pressure = 0;  // collisions resolved by the centre-of-pressure rule
  std::uint64_t riders_carried = 0;      // bodies carried along by a microcollision below them
  std::uint64_t feature_steps = 0;       // V-Clip feature steps, all queries
  std::uint64_t integration_steps = 0;   // Runge-Kutta steps, all collisions
  std::uint64_t pairs_created = 0;       // pairs entering the broad phase
  std::uint64_t max_pairs = 0;           // most pairs tracked at once
  std::uint64_t box_tests = 0;           // swept-box overlap tests made by the broad phase
};

enum class CollisionKind : std::uint8_t { kCollision, kMicrocollision };

// One resolved collision, in the world frame.
struct CollisionRecord {
  double t = 0.0;
  CollisionKind kind = CollisionKind::kCollision;
  BodyId a;                       // body 1 of the pair (the lower id)
  BodyId b;                       // body 2
  Vec3 p_W = Vec3::Zero();        // contact point [m]
  Vec3 n_W = Vec3::UnitZ();       // contact normal, from b to a
  Vec3 impulse_W = Vec3::Zero();  // impulse on a [N s] (b receives the opposite)
  double approach_speed = 0.0;    // -u_n before the collision [m/s]
  double energy_change = 0.0;     // kinetic energy of the two bodies after minus before [J]
  bool centre_of_pressure = false;
  // Bodies resting on the dynamic body of a microcollision with its support, carried along with
  // it (their velocity along n set to its); energy_change includes them. impulse_W is the
  // support's impulse on the whole stack; a rider settling onto the carrier also takes the
  // plastic impulse that matches its normal velocity to the carrier's, not recorded apart.
  std::vector<BodyId> carried;
};

// Receives what a run produces. Default implementations ignore everything.
class SimulationObserver {
 public:
  virtual ~SimulationObserver() = default;
  // Every body's state at t = k x interval (extrapolated; ids index the world's bodies).
  virtual void on_sample(double /*t*/, const std::vector<BodyState>& /*states*/) {}
  virtual void on_collision(const CollisionRecord& /*record*/) {}
};

struct SimulationOptions {
  double output_interval = 0.0;  // [s]; 0: no samples
  QueueImpl queue = QueueImpl::kIndexed;
};

class Simulation {
 public:
  // Validates the world (throws InputError "/bodies/<i>": ... for bodies that overlap at the
  // start, or non-finite states) and sets up the broad phase and the first bounds.
  Simulation(World world, SimulationOptions options);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // Runs every event up to and including t_end (samples at k x interval <= t_end).
  // `progress` (optional) is called now and then with the current time.
  void run_until(double t_end, SimulationObserver* observer,
                 const std::function<void(double)>& progress = {});

  const World& world() const { return world_; }
  const SimulationStats& stats() const { return stats_; }
  // Body `id` extrapolated to time t (>= its clock) without committing.
  BodyState state_at(BodyId id, double t) const;
  double time() const { return now_; }

 private:
  struct Impl;
  World world_;
  SimulationOptions options_;
  SimulationStats stats_;
  double now_ = 0.0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace palpable
