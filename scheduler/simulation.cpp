#include "scheduler/simulation.hpp"

#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "distance/toi_bound.hpp"
#include "impulse/microcollision.hpp"
#include "scheduler/pair_set.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

// The loop's state, with one owner: the world (bodies and their committed states), the queue, the
// pairs and the statistics. The contact model (scheduler/contact.hpp) sees values only.
struct Simulation::Impl {
  World world;
  SimulationOptions options;
  SimulationStats stats;
  double now = 0.0;
  EventQueue queue;
  PairSet pairs;
  std::uint64_t next_sample = 0;

  Impl(World w, SimulationOptions o)
      : world(std::move(w)), options(o), queue(o.queue), pairs(world, queue, stats) {}

  const Settings& settings() const { return world.settings; }
  Body& body(BodyId id) { return world.bodies[id.index]; }
  const Body& body(BodyId id) const { return world.bodies[id.index]; }

  BodyState extrapolate(BodyId id, double t) const {
    const Body& b = body(id);
    if (t <= b.state.t) return b.state;
    return advance(b, b.state, t, world.gravity_W, settings());
  }
  void commit(BodyId id, double t) {
    Body& b = body(id);
    if (t > b.state.t) b.state = advance(b, b.state, t, world.gravity_W, settings());
  }
  ContactSide side(BodyId id, const BodyState& s) const {
    return ContactSide{id, body(id), pairs.geometry(id), s};
  }

  // ---------------------------------------------------------------- pairs and bounds

  void refresh_broad_phase(BodyId id, double t) { pairs.refresh(id, extrapolate(id, t), t); }

  // After a collision: the boxes and pairs of every dynamic body it moved (the pair's and the
  // riders it carried), then every pair of those bodies re-bounded once. A fixed body's box never
  // changes, and every dynamic body overlapping it was paired with it at that body's own last
  // refresh, so refreshing a fixed body would change nothing - but cost a scan of every dynamic
  // body for a halfspace, whose box is infinite: it is skipped. So for a kinematic body, whose
  // box follows only time (its horizon event keeps it current).
  void refresh_after_collision(const CollisionRecord& r, double t) {
    std::vector<BodyId> moved{r.a, r.b};
    moved.insert(moved.end(), r.carried.begin(), r.carried.end());
    for (BodyId id : moved) {
      if (body(id).is_dynamic()) refresh_broad_phase(id, t);
    }
    for (std::uint32_t index : pairs.collect_rebounds(moved)) rebound(index, t);
  }

  void schedule_pair(std::uint32_t index, double t_next) {
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

  // The least step a pair's next check may take at time t [s]: settings.toi_min_progress_s, and
  // never less than 1e-12 t, so that t + step > t however long the run.
  double progress_floor(double t) const {
    return std::max(settings().toi_min_progress_s, 1e-12 * std::max(1.0, t));
  }

  DistanceResult query(PairSet::Pair& p, const BodyState& s1, const BodyState& s2) {
    DistanceResult dr =
        closest_features(pairs.geometry(p.a), Pose{s1.x_W, s1.q_WM}, pairs.geometry(p.b),
                         Pose{s2.x_W, s2.q_WM}, p.cache, settings().distance_max_steps);
    stats.feature_steps += static_cast<std::uint64_t>(dr.steps);
    if (dr.status == ContactStatus::kPenetrating) ++stats.penetrations;
    // DESIGN.md §5 step 6: no penetration deeper than the envelope (a polyhedron pair's depth is
    // unknown here: any overlap of one fails).
    PALPABLE_DCHECK(dr.status != ContactStatus::kPenetrating ||
                        dr.penetration_depth <= settings().envelope_m,
                    "bodies " + body(p.a).name + " and " + body(p.b).name + " overlap at t = " +
                        std::to_string(now));
    return dr;
  }

  // The piece-pair result a collision would be resolved at: `dr` itself, or, for a pair with a
  // compound, the piece within the envelope approaching fastest (a ball in a crease touches two
  // pieces; the closest may be the one it is leaving).
  const DistanceResult& contact_result(const PairSet::Pair& p, const BodyState& s1,
                                       const BodyState& s2, const DistanceResult& dr) const {
    const DistanceResult* best = &dr;
    double best_u_n = kInfinity;
    for (const DistanceResult& r : p.cache.piece_results()) {
      if (r.status == ContactStatus::kFailed ||
          (r.status != ContactStatus::kPenetrating && r.distance > settings().envelope_m)) {
        continue;
      }
      const Contact c = make_contact(side(p.a, s1), side(p.b, s2), r, settings(), world.gravity_W,
                                     /*with_patch=*/false);
      if (approaching(c) && c.u_n < best_u_n) {
        best_u_n = c.u_n;
        best = &r;
      }
    }
    return *best;
  }

  // The next event time of a pair from its closest features at time t.
  // `known`: the contact check_pair already made of this very query and found not approaching
  // (saves making it again); null to make it here.
  double next_check_time(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                         const DistanceResult& dr, double t, const Contact* known = nullptr) {
    const double floor = progress_floor(t);
    if (dr.status == ContactStatus::kFailed) {
      ++stats.distance_failures;
      return t + floor;
    }
    bool resting = false;  // within the envelope, neither approaching nor accelerated together
    if (known) {
      if (dr.status == ContactStatus::kPenetrating) return t + floor;
      resting = known->g_n == 0.0;
    } else {
      const DistanceResult& contact = contact_result(p, s1, s2, dr);
      if (contact.status == ContactStatus::kPenetrating ||
          contact.distance <= settings().envelope_m) {
        const Contact c = make_contact(side(p.a, s1), side(p.b, s2), contact, settings(),
                                       world.gravity_W, /*with_patch=*/false);
        if (approaching(c)) return t;
        if (contact.status == ContactStatus::kPenetrating) return t + floor;
        resting = c.g_n == 0.0;
      }
    }
    ToiBound bound = time_of_impact(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2,
                                    pairs.geometry(p.b), dr, p.cache, world.gravity_W, settings());
    if (bound.floored) ++stats.floored_bounds;
    if (bound.exact) ++stats.exact_bounds;
    if (bound.exact && resting && bound.dt < floor) {
      // An exact time of impact of zero for a pair at rest in contact (an e = 0 collision without
      // gravity leaves them so, up to rounding): their relative motion is linear, so the gap
      // cannot close; only another collision (which re-bounds the pair) changes that.
      return kInfinity;
    }
    if (!(bound.dt >= 0.0)) return t + floor;  // NaN guard: never stall, never skip
    // The progress floor is applied (capped, so that it never carries a pair through contact)
    // by the bound itself; here only the resolution of the clock, so that t + dt > t.
    const double tick = 1e-12 * std::max(1.0, t);
    return t + std::max(bound.dt, bound.exact ? 0.0 : tick);
  }

  void rebound(std::uint32_t index, double t) {
    PairSet::Pair& p = pairs.pair(index);
    const BodyState s1 = extrapolate(p.a, t);
    const BodyState s2 = extrapolate(p.b, t);
    ++stats.bound_queries;
    DistanceResult dr = query(p, s1, s2);
    schedule_pair(index, next_check_time(p, s1, s2, dr, t));
  }

  // ---------------------------------------------------------------- collisions

  // How steep a contact normal must be to count as support, cos 60 degrees from the vertical.
  static constexpr double kSupportCosine = 0.5;

  // The dynamic bodies riding on body `id` at time t: resting on it (within two envelopes, a
  // microcollision bounces a body up to 1.5; the normal within 60 degrees of the vertical;
  // at rest on it along the normal or settling onto it slower than the microcollision speed),
  // and those riding on them, up to 8 levels. Appended to `riders` (no repeats).
  void collect_riders(BodyId id, double t, int depth, std::vector<BodyId>& riders) {
    if (depth > 8 || world.gravity_W.squaredNorm() == 0.0) return;
    const Vec3 up = -world.gravity_W.normalized();
    // query() only warms a pair's cache: the pair lists do not change here.
    for (std::uint32_t index : pairs.body(id).pairs) {
      PairSet::Pair& q = pairs.pair(index);
      const BodyId other = q.a == id ? q.b : q.a;
      if (!body(other).is_dynamic() ||
          std::find(riders.begin(), riders.end(), other) != riders.end()) {
        continue;
      }
      const BodyState s1 = extrapolate(q.a, t), s2 = extrapolate(q.b, t);
      ++stats.bound_queries;
      const DistanceResult dr = query(q, s1, s2);
      if (dr.status != ContactStatus::kSeparated && dr.status != ContactStatus::kTouching) continue;
      if (dr.distance > 2.0 * settings().envelope_m) continue;
      const Vec3 n = q.a == other ? dr.n_W : Vec3(-dr.n_W);  // from `id` up to `other`
      if (n.dot(up) <= kSupportCosine) continue;
      const BodyState& s_other = q.a == other ? s1 : s2;
      const BodyState& s_id = q.a == other ? s2 : s1;
      const double v_micro = microcollision_speed(settings(), std::abs(world.gravity_W.dot(n)));
      // Resting on it or settling onto it, not flying off it.
      const double u_rel = n.dot(s_other.v_W - s_id.v_W);
      if (u_rel > 1e-9 * v_micro || u_rel < -v_micro * (1.0 + 1e-6)) continue;
      riders.push_back(other);
      collect_riders(other, t, depth + 1, riders);
    }
  }

  // Resolves the collision of contact `c` (of pair `p`, states committed at t), commits the new
  // velocities and returns the record.
  CollisionRecord collide(const PairSet::Pair& p, Contact& c, double t) {
    std::vector<BodyId> rider_ids;
    if (carries_riders(c, settings(), world.gravity_W)) {
      collect_riders(c.dynamic1() ? p.a : p.b, t, 0, rider_ids);
      for (BodyId r : rider_ids) commit(r, t);
    }
    std::vector<Rider> riders;
    for (BodyId r : rider_ids) riders.push_back(Rider{r, body(r), body(r).state});
    Resolution out = resolve(c, side(p.a, body(p.a).state), side(p.b, body(p.b).state),
                             world.material(p.a, p.b), settings(), riders, t);
    stats.integration_steps += static_cast<std::uint64_t>(out.integration_steps);
    stats.impulse_failures += static_cast<std::uint64_t>(out.impulse_failures);
    auto store = [&](BodyId id, const Vec3& v, const Vec3& w) {
      Body& b = body(id);
      if (!b.is_dynamic()) return;
      b.state.v_W = v;
      b.state.w_W = w;
    };
    store(p.a, out.v1_W, out.w1_W);
    store(p.b, out.v2_W, out.w2_W);
    for (std::size_t i = 0; i < out.record.carried.size(); ++i) {
      body(out.record.carried[i]).state.v_W = out.rider_v_W[i];
    }
    if (out.record.kind == CollisionKind::kMicrocollision) {
      ++stats.microcollisions;
    } else {
      ++stats.collisions;
    }
    if (out.record.centre_of_pressure) ++stats.centre_of_pressure;
    stats.riders_carried += out.record.carried.size();
    return std::move(out.record);
  }

  // A pair's event: collide if within the envelope and approaching, else re-bound. Returns the
  // collision, if any.
  std::optional<CollisionRecord> check_pair(std::uint32_t index, double t) {
    PairSet::Pair& p = pairs.pair(index);
    p.event = EventQueue::kNoEvent;  // it was just popped
    commit(p.a, t);
    commit(p.b, t);
    const BodyState& s1 = body(p.a).state;
    const BodyState& s2 = body(p.b).state;
    ++stats.pair_checks;
    DistanceResult dr = query(p, s1, s2);
    const DistanceResult& contact = contact_result(p, s1, s2, dr);
    if (contact.status == ContactStatus::kFailed ||
        (contact.status != ContactStatus::kPenetrating &&
         contact.distance > settings().envelope_m)) {
      schedule_pair(index, next_check_time(p, s1, s2, dr, t));
      return std::nullopt;
    }
    Contact c = make_contact(side(p.a, s1), side(p.b, s2), contact, settings(), world.gravity_W,
                             /*with_patch=*/true);
    if (!approaching(c)) {
      schedule_pair(index, next_check_time(p, s1, s2, dr, t, &c));
      return std::nullopt;
    }
    if (t == p.last_collision_t) {
      ++p.collisions_at_t;
      ++stats.retries;
      if (p.collisions_at_t > settings().retry_limit) {
        // A rounding loop: report it and move on by the progress floor.
        ++stats.retry_limit_hits;
        schedule_pair(index, t + progress_floor(t));
        return std::nullopt;
      }
    } else {
      p.last_collision_t = t;
      p.collisions_at_t = 0;
    }
    CollisionRecord record = collide(p, c, t);
    refresh_after_collision(record, t);  // `p` may move when pairs are created there
    return record;
  }

  void schedule_sample() {
    const double interval = options.output_interval;
    if (!(interval > 0.0)) return;
    Event e;
    e.t = static_cast<double>(next_sample) * interval;
    e.kind = EventKind::kSample;
    queue.push(e);
  }

  void sample(double t, SimulationObserver* observer) {
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

  // Bodies may start touching (the racked pool balls sit inside each other's envelopes) but never
  // overlapping, and only with finite states.
  void validate_start() {
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

  void start() {
    validate_start();
    const auto n = static_cast<std::uint32_t>(world.bodies.size());
    for (std::uint32_t i = 0; i < n; ++i) refresh_broad_phase(BodyId{i}, 0.0);
    for (std::uint32_t index = 0; index < pairs.slots(); ++index) {
      if (pairs.pair(index).live) rebound(index, 0.0);  // each pair once
    }
    schedule_sample();
  }

  StepResult step(double t_end, SimulationObserver* observer) {
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
        if (result.collision && observer) observer->on_collision(*result.collision);
        break;
      }
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
};

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
                           const std::function<void(double)>& progress) {
  std::uint64_t since_progress = 0;
  while (!impl_->step(t_end, observer).done) {
    if (progress && ++since_progress >= 4096) {
      since_progress = 0;
      progress(impl_->now);
    }
  }
  impl_->now = std::max(impl_->now, t_end);
}

}  // namespace palpable
