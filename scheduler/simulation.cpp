#include "scheduler/simulation.hpp"
#include "scheduler/simulation_impl.hpp"

#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "scheduler/island.hpp"
#include "scheduler/pair_set.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace palpable {

// ---------------------------------------------------------------- pairs and the broad phase
// (queries and bounds: simulation_bounds.cpp)

void Simulation::Impl::refresh_broad_phase(BodyId id, double t) {
  if (const Island* is = planned_island(id)) {
    const Island::MotionBound b = is->bound(static_cast<std::size_t>(is->index_of(id)));
    const HeldMotion held{b.a_W, b.a_slack};
    pairs.refresh(id, extrapolate(id, t), t, &held);
    return;
  }
  pairs.refresh(id, extrapolate(id, t), t);
}

void Simulation::Impl::refresh_moved(const std::vector<BodyId>& moved, double t) {
  for (BodyId id : moved) {
    if (body(id).is_dynamic()) refresh_broad_phase(id, t);
  }
  for (std::uint32_t index : pairs.collect_rebounds(moved)) rebound(index, t);
}

void Simulation::Impl::refresh_after_collision(const CollisionRecord& r, double t) {
  std::vector<BodyId> moved{r.a, r.b};
  moved.insert(moved.end(), r.carried.begin(), r.carried.end());
  refresh_moved(moved, t);
}

void Simulation::Impl::schedule_pair(std::uint32_t index, double t_next) {
  PairSet::Pair& p = pairs.pair(index);
  const double horizon = std::min(pairs.body(p.a).horizon, pairs.body(p.b).horizon);
  // A bound at or past a horizon needs no event: the horizon's refresh re-bounds the pair.
  if (!(t_next < horizon) || !std::isfinite(t_next)) {
    if (p.event != EventQueue::kNoEvent) {
      queue.erase(p.event);
      p.event = EventQueue::kNoEvent;
      ++stats.rescheduled;
    }
    return;
  }
  Event e;
  e.t = t_next;
  e.kind = EventKind::kPairCheck;
  e.a = p.a;
  e.b = p.b;
  e.owner = index;
  if (p.event == EventQueue::kNoEvent) {
    p.event = queue.push(e);
  } else {
    queue.update(p.event, e);
    ++stats.rescheduled;
  }
}

// ---------------------------------------------------------------- the loop

void Simulation::Impl::schedule_sample() {
  const double interval = options.output_interval;
  if (!(interval > 0.0)) return;
  Event e;
  e.t = static_cast<double>(next_sample) * interval;
  e.kind = EventKind::kSample;
  queue.push(e);
}

void Simulation::Impl::sample(double t, SimulationObserver* observer) {
  std::vector<BodyState> states(world.bodies.size());
  for (std::uint32_t i = 0; i < states.size(); ++i) {
    states[i] = extrapolate(BodyId{i}, t);
    states[i].t = t;
  }
  ++stats.samples;
  if (observer) observer->on_sample(t, states);
  ++next_sample;
  schedule_sample();
}

void Simulation::Impl::validate_start() {
  for (std::size_t i = 0; i < world.bodies.size(); ++i) {
    Body& b = world.bodies[i];
    if (!b.state.x_W.allFinite() || !b.state.v_W.allFinite() || !b.state.w_W.allFinite() ||
        !b.state.q_WM.coeffs().allFinite()) {
      throw InputError("/bodies/" + std::to_string(i), "non-finite initial state");
    }
    b.state.t = 0.0;
    if (b.motion == MotionKind::kKinematic) {
      // The state of a kinematic body at t = 0 follows from its prescribed motion.
      b.state.w_W = b.kinematic.angular_velocity_W;
      b.state.v_W = b.kinematic.velocity_W +
                    b.kinematic.angular_velocity_W.cross(b.state.x_W - b.kinematic.point_W);
    }
  }
  const auto n = static_cast<std::uint32_t>(world.bodies.size());
  for (std::uint32_t i = 0; i < n; ++i) pairs.set_box(BodyId{i}, body(BodyId{i}).state, 0.0);
  // Pairs in order (i, j), i < j, as the broad phase finds them.
  std::vector<std::uint32_t> overlapping;
  for (std::uint32_t i = 0; i < n; ++i) {
    pairs.find_overlaps(BodyId{i}, overlapping);
    for (std::uint32_t j : overlapping) {
      if (j < i) continue;
      PairCache cache;
      const Body& a = world.bodies[i];
      const Body& b = world.bodies[j];
      const DistanceResult dr = closest_features(
          pairs.geometry(BodyId{i}), Pose{a.state.x_W, a.state.q_WM}, pairs.geometry(BodyId{j}),
          Pose{b.state.x_W, b.state.q_WM}, cache, settings().distance_max_steps);
      if (dr.status == ContactStatus::kPenetrating) {
        throw InputError("/bodies/" + std::to_string(j),
                         "body \"" + b.name + "\" overlaps body \"" + a.name + "\" (/bodies/" +
                             std::to_string(i) +
                             ") at the start; bodies may touch but not interpenetrate");
      }
    }
  }
}

void Simulation::Impl::start() {
  validate_start();
  const auto n = static_cast<std::uint32_t>(world.bodies.size());
  island_of.assign(n, -1);
  for (std::uint32_t i = 0; i < n; ++i) geometries.push_back(&pairs.geometry(BodyId{i}));
  for (std::uint32_t i = 0; i < n; ++i) refresh_broad_phase(BodyId{i}, 0.0);
  for (std::uint32_t index = 0; index < pairs.slots(); ++index) {
    if (pairs.pair(index).live) rebound(index, 0.0);  // each pair once
  }
  schedule_sample();
}

void Simulation::Impl::report_stall(const Event& e) const {
  std::string what;
  if (e.b.valid()) {
    what = "bodies \"" + world.bodies[e.a.index].name + "\" and \"" + world.bodies[e.b.index].name +
           "\"";
  } else if (e.a.valid()) {
    what = "body \"" + world.bodies[e.a.index].name + "\"";
  } else {
    what = "the run";
  }
  std::ostringstream t;
  t.precision(17);
  t << e.t;
  throw InputError("t = " + t.str() + " s",
                   "the clock stopped advancing: " + std::to_string(stall_events) +
                       " events within " + std::to_string(kStallResolution) +
                       " of the time, the last for " + what +
                       " (a Zeno sequence, or a time step that rounds away)");
}

StepResult Simulation::Impl::step(double t_end, SimulationObserver* step_observer) {
  observer = step_observer;
  StepResult result;
  if (queue.empty() || !(queue.top().t <= t_end)) {
    result.done = true;
    return result;
  }
  EventQueue::EventId id;
  const Event e = queue.pop(&id);
  PALPABLE_CHECK(e.t >= now, "time ran backwards in the event queue");
  now = e.t;
  ++stats.events;
  if (e.t > stall_until) {
    stall_until = e.t + kStallResolution * std::max(1.0, std::abs(e.t));
    stall_events = 0;
  } else if (++stall_events > kStallEvents + kStallEventsPerBody * world.bodies.size()) {
    report_stall(e);
  }
  result.t = e.t;
  result.kind = e.kind;
  result.a = e.a;
  result.b = e.b;
  switch (e.kind) {
    case EventKind::kPairCheck: {
      PALPABLE_CHECK(e.owner < pairs.slots() && pairs.pair(e.owner).event == id &&
                         pairs.pair(e.owner).a == e.a && pairs.pair(e.owner).b == e.b,
                     "pair event without its pair");
      result.collision = check_pair(e.owner, e.t);
      break;
    }
    case EventKind::kIsland:
      PALPABLE_CHECK(
          e.owner < islands.size() && island_live[e.owner] && island_events[e.owner] == id,
          "island event without its island");
      island_event(e.owner, e.t);
      break;
    case EventKind::kHorizon:
      pairs.body(e.a).horizon_event = EventQueue::kNoEvent;
      commit(e.a, e.t);
      ++stats.horizon_refreshes;
      refresh_broad_phase(e.a, e.t);
      for (std::uint32_t index : pairs.body(e.a).pairs) rebound(index, e.t);
      break;
    case EventKind::kSample: sample(e.t, observer); break;
  }
  return result;
}

Simulation::Simulation(World world, SimulationOptions options)
    : impl_(std::make_unique<Impl>(std::move(world), options)) {
  impl_->start();
}

Simulation::~Simulation() = default;

const World& Simulation::world() const {
  return impl_->world;
}
const SimulationStats& Simulation::stats() const {
  return impl_->stats;
}
double Simulation::time() const {
  return impl_->now;
}

BodyState Simulation::state_at(BodyId id, double t) const {
  return impl_->extrapolate(id, t);
}

StepResult Simulation::step(double t_end, SimulationObserver* observer) {
  return impl_->step(t_end, observer);
}

void Simulation::run_until(double t_end, SimulationObserver* observer,
                           const std::function<bool(double)>& progress) {
  // Every 64 events, and after any event that ends 0.1 s of wall time after the last call: at
  // every 4096 events a pile's reports lagged its time by minutes (a pile of 100 balls reported
  // 0.533 s for minutes while it ran at 0.624 s), and at every 64 alone a pile of 200 balls ran
  // 156 s past a CPU limit of 900 s, its large islands' events taking that long between two
  // calls.
  constexpr std::uint64_t kEvery = 64;
  constexpr auto kInterval = std::chrono::milliseconds(100);
  std::uint64_t since_progress = 0;
  auto last_progress = std::chrono::steady_clock::now();
  while (!impl_->step(t_end, observer).done) {
    if (!progress) continue;
    const auto now = std::chrono::steady_clock::now();
    if (++since_progress < kEvery && now - last_progress < kInterval) continue;
    since_progress = 0;
    last_progress = now;
    if (!progress(impl_->now)) return;
  }
  impl_->now = std::max(impl_->now, t_end);
}

}  // namespace palpable
