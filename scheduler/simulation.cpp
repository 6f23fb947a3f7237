#include "scheduler/simulation.hpp"

#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "distance/toi_bound.hpp"
#include "impulse/microcollision.hpp"
#include "scheduler/island.hpp"
#include "scheduler/pair_set.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>

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
  SimulationObserver* observer = nullptr;  // of the step being processed

  // Persistent contact (scheduler/island.hpp): islands of held bodies, in slots.
  std::vector<Island> islands;
  std::vector<EventQueue::EventId> island_events;  // per slot
  std::vector<bool> island_live;                   // per slot
  std::vector<std::uint32_t> free_islands;
  std::vector<int> island_of;                    // per body: its island slot, or -1
  std::vector<const ShapeGeometry*> geometries;  // per body

  Impl(World w, SimulationOptions o)
      : world(std::move(w)), options(o), queue(o.queue), pairs(world, queue, stats) {}

  const Settings& settings() const { return world.settings; }
  Body& body(BodyId id) { return world.bodies[id.index]; }
  const Body& body(BodyId id) const { return world.bodies[id.index]; }

  bool persistent() const { return settings().contact_model == ContactModel::kPersistent; }
  const Island* island(BodyId id) const {
    const int i = island_of.empty() ? -1 : island_of[id.index];
    return i >= 0 ? &islands[static_cast<std::size_t>(i)] : nullptr;
  }

  BodyState extrapolate(BodyId id, double t) const {
    const Body& b = body(id);
    if (t <= b.state.t) return b.state;
    if (const Island* is = island(id)) {
      return is->state_at(static_cast<std::size_t>(is->index_of(id)), t);
    }
    return advance(b, b.state, t, world.gravity_W, settings());
  }
  void commit(BodyId id, double t) {
    Body& b = body(id);
    if (t > b.state.t) b.state = extrapolate(id, t);
  }
  // A held body's acceleration (its island's), or null for free flight.
  const Vec3* held_acceleration(BodyId id) const {
    const Island* is = island(id);
    return is ? &is->acceleration(static_cast<std::size_t>(is->index_of(id))) : nullptr;
  }
  ContactSide side(BodyId id, const BodyState& s) const {
    return ContactSide{id, body(id), pairs.geometry(id), s, held_acceleration(id)};
  }

  // ---------------------------------------------------------------- pairs and bounds

  void refresh_broad_phase(BodyId id, double t) {
    if (const Island* is = island(id)) {
      const Island::MotionBound b = is->bound(static_cast<std::size_t>(is->index_of(id)));
      const HeldMotion held{b.a_W, b.a_slack};
      pairs.refresh(id, extrapolate(id, t), t, &held);
      return;
    }
    pairs.refresh(id, extrapolate(id, t), t);
  }

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

  // The least step a pair's next check may take at time t [s] (core/settings.hpp).
  double progress_floor(double t) const { return derived_progress_floor(settings(), t); }

  DistanceResult query(PairSet::Pair& p, const BodyState& s1, const BodyState& s2) {
    DistanceResult dr =
        closest_features(pairs.geometry(p.a), Pose{s1.x_W, s1.q_WM}, pairs.geometry(p.b),
                         Pose{s2.x_W, s2.q_WM}, p.cache, settings().distance_max_steps);
    stats.feature_steps += static_cast<std::uint64_t>(dr.steps);
    if (dr.status == ContactStatus::kPenetrating) ++stats.penetrations;
    // DESIGN.md §5 step 6: no penetration deeper than the envelope (a polyhedron pair's depth is
    // unknown here: any overlap of one fails).
    PALPABLE_DCHECK(
        dr.status != ContactStatus::kPenetrating || dr.penetration_depth <= settings().envelope_m,
        "bodies " + body(p.a).name + " and " + body(p.b).name +
            " overlap at t = " + std::to_string(now));
    return dr;
  }

  // Is piece result r of pair p held (a compound's piece on which a link of p rests)? A pair
  // with a compound keeps its events for its other pieces (a ball held on the floor of a table
  // still meets its cushions); a plain held pair has none.
  bool held_piece(const PairSet::Pair& p, const DistanceResult& r) const {
    for (BodyId id : {p.a, p.b}) {
      const Island* is = island(id);
      if (!is) continue;
      for (const HeldLink& link : is->links) {
        if (!(std::min(link.mover, link.support) == p.a &&
              std::max(link.mover, link.support) == p.b)) {
          continue;
        }
        const int piece = link.support == p.a ? r.piece1 : r.piece2;
        if (piece == link.support_piece) return true;
      }
    }
    return false;
  }

  // The piece-pair result a collision would be resolved at: `dr` itself, or, for a pair with a
  // compound, the piece within the envelope approaching fastest (a ball in a crease touches two
  // pieces; the closest may be the one it is leaving), else the closest piece; held pieces
  // never.
  const DistanceResult& contact_result(const PairSet::Pair& p, const BodyState& s1,
                                       const BodyState& s2, const DistanceResult& dr) const {
    const DistanceResult* best = &dr;
    const DistanceResult* nearest = nullptr;
    double best_u_n = kInfinity;
    const bool any_held = p.held || island(p.a) || island(p.b);
    for (const DistanceResult& r : p.cache.piece_results()) {
      if (any_held && held_piece(p, r)) continue;
      if (r.status != ContactStatus::kFailed &&
          (!nearest || r.distance < nearest->distance || r.status == ContactStatus::kPenetrating)) {
        nearest = &r;
      }
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
    if (best == &dr && nearest && any_held && held_piece(p, dr)) return *nearest;
    return *best;
  }

  // A pair whose held contact let go at this very instant, not truly approaching (its contact
  // is only pressed by the gravity that no longer holds it: a ball leaving a table's edge).
  static bool lifting(const PairSet::Pair& p, const Contact& c, double t) {
    if (!(p.lifted && p.last_collision_t == t)) return false;
    const double scale =
        contact_point_velocity_W(c.body1).norm() + contact_point_velocity_W(c.body2).norm();
    return !(c.u_n < -kVelocityRounding * scale);
  }

  // How a body moves over the coming interval, for a bound: free flight, or its island's motion.
  ToiMotion motion_for(BodyId id, const BodyState& s, const BodyState& other,
                       BodyId other_id) const {
    if (const Island* is = island(id)) {
      const Island::MotionBound b = is->bound(static_cast<std::size_t>(is->index_of(id)));
      ToiMotion m;
      m.v_W = s.v_W;
      m.a_W = b.a_W;
      m.accel_slack = b.a_slack;
      m.omega_bound = b.w_bound;
      m.rotation_radius = pairs.geometry(id).rotation_radius();
      return m;
    }
    return toi_motion(body(id), s, pairs.geometry(id), world.gravity_W, other.x_W,
                      pairs.geometry(other_id).reach(), settings());
  }

  // The conservative bound of a pair with a held body (never exact: no closed form follows a held
  // body's motion).
  ToiBound held_time_of_impact(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                               const DistanceResult& dr) const {
    const ToiMotion m1 = motion_for(p.a, s1, s2, p.b);
    const ToiMotion m2 = motion_for(p.b, s2, s1, p.a);
    const double d_target = derived_target_gap(settings());
    if (p.cache.piece_results().empty()) return toi_bound(m1, m2, dr, d_target, settings());
    ToiBound best;
    for (const DistanceResult& piece : p.cache.piece_results()) {
      if (held_piece(p, piece)) continue;
      const ToiBound b = toi_bound(m1, m2, piece, d_target, settings());
      if (b.dt < best.dt) best = b;
    }
    return best;
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
        if (approaching(c) && !lifting(p, c, t)) return t;
        if (contact.status == ContactStatus::kPenetrating) return t + floor;
        resting = c.g_n == 0.0;
      }
    }
    ToiBound bound =
        island(p.a) || island(p.b)
            ? held_time_of_impact(p, s1, s2, dr)
            : time_of_impact(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2, pairs.geometry(p.b),
                             dr, p.cache, world.gravity_W, settings());
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
    if (p.held) {
      schedule_pair(index, kInfinity);  // its island watches it
      return;
    }
    const BodyState s1 = extrapolate(p.a, t);
    const BodyState s2 = extrapolate(p.b, t);
    ++stats.bound_queries;
    DistanceResult dr = query(p, s1, s2);
    schedule_pair(index, next_check_time(p, s1, s2, dr, t));
  }

  // ---------------------------------------------------------------- collisions

  // The dynamic bodies riding on body `id` at time t: resting on it (within two envelopes, a
  // microcollision bounces a body up to 1.5; the normal within 60 degrees of the vertical;
  // at rest on it along the normal or settling onto it slower than the microcollision speed),
  // and those riding on them, up to kMaxRiderDepth levels. Appended to `riders` (no repeats).
  void collect_riders(BodyId id, double t, int depth, std::vector<BodyId>& riders) {
    if (depth > kMaxRiderDepth || world.gravity_W.squaredNorm() == 0.0) return;
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
      if (dr.distance > derived_rider_distance(settings())) continue;
      const Vec3 n = q.a == other ? dr.n_W : Vec3(-dr.n_W);  // from `id` up to `other`
      if (n.dot(up) <= kSupportCosine) continue;
      const BodyState& s_other = q.a == other ? s1 : s2;
      const BodyState& s_id = q.a == other ? s2 : s1;
      const double v_micro = microcollision_speed(settings(), std::abs(world.gravity_W.dot(n)));
      // Resting on it or settling onto it, not flying off it.
      const double u_rel = n.dot(s_other.v_W - s_id.v_W);
      if (u_rel > kRestingApproachSlack * v_micro ||
          u_rel < -v_micro * (1.0 + settings().microcollision_speed_slack)) {
        continue;
      }
      riders.push_back(other);
      collect_riders(other, t, depth + 1, riders);
    }
  }

  // Resolves the collision of contact `c` (of pair `p`, states committed at t), commits the new
  // velocities and returns the record.
  CollisionRecord collide(const PairSet::Pair& p, Contact& c, double t,
                          const ResolveOptions& options = ResolveOptions{}) {
    std::vector<BodyId> rider_ids;
    if (options.microcollisions && carries_riders(c, settings(), world.gravity_W)) {
      collect_riders(c.dynamic1() ? p.a : p.b, t, 0, rider_ids);
      for (BodyId r : rider_ids) commit(r, t);
    }
    std::vector<Rider> riders;
    for (BodyId r : rider_ids) riders.push_back(Rider{r, body(r), body(r).state});
    Resolution out = resolve(c, side(p.a, body(p.a).state), side(p.b, body(p.b).state),
                             world.material(p.a, p.b), settings(), riders, t, options);
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
    // Under the persistent model a face whose corner lands is a collision even while its centre
    // of pressure does not approach (the hold, not a microcollision train, must catch it).
    const bool lands = approaching(c) || (persistent() && patch_approaching(c, s1, s2));
    if (!lands || lifting(p, c, t)) {
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
    if (persistent()) return collide_or_hold(index, c, DistanceResult(contact), t);
    CollisionRecord record = collide(p, c, t);
    if (observer) observer->on_collision(record);
    refresh_after_collision(record, t);  // `p` may move when pairs are created there
    return record;
  }

  // ---------------------------------------------------------------- persistent contact

  void report(const char* kind, BodyId a, BodyId b, const Vec3& p_W, double t) {
    if (observer) observer->on_mode_change(ModeChange{t, kind, a, b, p_W});
  }

  // Under the persistent contact model (DESIGN.md §8.1): the collision is integrated with the
  // material's restitution and no rebound floor (plastic if it arrives slower than the
  // microcollision speed: what would have started a microcollision train); if the contact then
  // separates slower than the microcollision speed, it is held. A contact whose features offer no
  // plane (two spheres, a sphere on an edge) cannot be held: it stays a microcollision train, as
  // under Mirtich's model.
  CollisionRecord collide_or_hold(std::uint32_t index, Contact& c, const DistanceResult& dr,
                                  double t) {
    PairSet::Pair& p = pairs.pair(index);
    const BodyId a = p.a, b = p.b;
    // A pair colliding again at the same instant is one whose bodies' other contacts (held, and
    // resolved after it, not with it) keep sending it back: a train of rebounds shrinking by the
    // restitution. Its limit is the plastic collision, taken at once from the third round; from
    // the fifth, a hold that keeps letting go at once gives way to a microcollision, whose
    // rebound floor moves the pair on in time.
    const int round = t == p.last_collision_t ? p.collisions_at_t : 0;
    const std::optional<HeldLink> link =
        round >= 4 ? std::optional<HeldLink>() : link_of(index, dr);
    // The hand-over speed: the microcollision speed of the bodies' weight along the normal (a
    // held body's acceleration may be zero, its weight is not).
    const double v_hold =
        std::max(c.v_micro, microcollision_speed(settings(), std::abs(world.gravity_W.dot(c.n_W))));
    const bool gentle =
        -initial_normal_velocity(c) <= v_hold * (1.0 + settings().microcollision_speed_slack);
    ResolveOptions options;
    options.microcollisions = !link;
    if ((gentle || round >= 2) && link) options.restitution = 0.0;
    CollisionRecord record = collide(p, c, t, options);
    if (observer) observer->on_collision(record);
    const Vec3 u_after =
        point_velocity_W(body(a).state, record.p_W) - point_velocity_W(body(b).state, record.p_W);
    if (link && u_after.dot(record.n_W) < v_hold) {
      hold(index, *link, dr, t);
    } else {
      after_collision(record, t);
    }
    return record;
  }

  // The link that would hold pair `index`'s contact (closest features `dr`, states at t).
  std::optional<HeldLink> link_of(std::uint32_t index, const DistanceResult& dr) const {
    const PairSet::Pair& p = pairs.pair(index);
    const Body& ba = body(p.a);
    const Body& bb = body(p.b);
    const ContactGeometry g = contact_geometry(
        pairs.geometry(p.a), Pose{ba.state.x_W, ba.state.q_WM}, pairs.geometry(p.b),
        Pose{bb.state.x_W, bb.state.q_WM}, dr, settings().envelope_m);
    return make_held_link(index, p.a, p.b, LinkSide{ba, pairs.geometry(p.a), ba.state},
                          LinkSide{bb, pairs.geometry(p.b), bb.state}, dr, g);
  }

  // A collision changed the velocities of these bodies: islands re-plan, free bodies re-bound.
  void after_collision(const CollisionRecord& record, double t) {
    CollisionRecord free_part = record;
    free_part.carried.clear();
    std::vector<int> replanned;
    for (BodyId id : {record.a, record.b}) {
      const int i = island_of[id.index];
      if (i >= 0 && std::find(replanned.begin(), replanned.end(), i) == replanned.end()) {
        replanned.push_back(i);
        replan(static_cast<std::uint32_t>(i), t);
      }
    }
    refresh_after_collision(free_part, t);
  }

  // Holds the contact of pair `index` (states committed at t): its link joins the island of its
  // dynamic bodies.
  void hold(std::uint32_t index, const HeldLink& link, const DistanceResult& dr, double t) {
    PairSet::Pair& p = pairs.pair(index);
    std::vector<BodyId> dynamic;
    for (BodyId id : {p.a, p.b}) {
      if (body(id).is_dynamic()) dynamic.push_back(id);
    }
    const std::uint32_t i = join(dynamic, t);
    islands[i].links.push_back(link);
    if (p.cache.piece_results().empty()) {
      p.held = true;
      schedule_pair(index, kInfinity);
    }
    ++stats.holds;
    report("hold", p.a, p.b, dr.p2_W, t);
    replan(i, t);
  }

  // The island holding all of `ids` (dynamic bodies): theirs merged, or a new one.
  std::uint32_t join(const std::vector<BodyId>& ids, double t) {
    int target = -1;
    for (BodyId id : ids) {
      const int i = island_of[id.index];
      if (i < 0) continue;
      if (target < 0) {
        target = i;
      } else if (i != target) {
        Island& from = islands[static_cast<std::size_t>(i)];
        Island& to = islands[static_cast<std::size_t>(target)];
        for (BodyId b : from.bodies) {
          commit(b, t);
          to.bodies.push_back(b);
          island_of[b.index] = target;
        }
        to.links.insert(to.links.end(), from.links.begin(), from.links.end());
        release_slot(static_cast<std::uint32_t>(i));
      }
    }
    if (target < 0) target = static_cast<int>(new_slot());
    Island& is = islands[static_cast<std::size_t>(target)];
    for (BodyId id : ids) {
      if (island_of[id.index] == target) continue;
      commit(id, t);
      is.bodies.push_back(id);
      island_of[id.index] = target;
    }
    return static_cast<std::uint32_t>(target);
  }

  std::uint32_t new_slot() {
    std::uint32_t i;
    if (!free_islands.empty()) {
      i = free_islands.back();
      free_islands.pop_back();
    } else {
      i = static_cast<std::uint32_t>(islands.size());
      islands.emplace_back();
      island_events.push_back(EventQueue::kNoEvent);
      island_live.push_back(false);
    }
    islands[i] = Island{};
    island_live[i] = true;
    return i;
  }

  void release_slot(std::uint32_t i) {
    if (island_events[i] != EventQueue::kNoEvent) queue.erase(island_events[i]);
    island_events[i] = EventQueue::kNoEvent;
    islands[i] = Island{};
    island_live[i] = false;
    free_islands.push_back(i);
  }

  // Plans island i's motion from time t (after a collision, a hold or one of its events), then
  // splits it where its links no longer connect it, frees bodies held by nothing, queues its next
  // event and refreshes its bodies' boxes and bounds.
  void replan(std::uint32_t i, double t) {
    std::vector<BodyId> touched = islands[i].bodies;
    for (BodyId id : touched) commit(id, t);
    std::vector<std::uint32_t> todo{i};
    // Components of the links among dynamic bodies; every body reached by a link stays held.
    while (!todo.empty()) {
      const std::uint32_t k = todo.back();
      todo.pop_back();
      Island& is = islands[k];
      const Island::PlanResult r = is.plan(world, geometries, t);
      ++stats.island_plans;
      if (r.inconsistent) ++stats.held_inconsistent;
      for (std::uint32_t pair : r.released) {
        PairSet::Pair& q = pairs.pair(pair);
        q.held = false;
        q.lifted = true;
        q.last_collision_t = t;
        q.collisions_at_t = 0;
        report("release", q.a, q.b, body(q.a).state.x_W, t);
      }
      bool changed = false;
      for (std::uint32_t extra : split(k, t, changed)) todo.push_back(extra);
      if (changed) {
        todo.push_back(k);  // its motion was planned with bodies it no longer has
        continue;
      }
      schedule_island(k, t);
    }
    for (BodyId id : touched) {
      if (body(id).is_dynamic()) refresh_broad_phase(id, t);
    }
    for (std::uint32_t index : pairs.collect_rebounds(touched)) rebound(index, t);
  }

  // Splits island k into the components its links connect; bodies no link holds leave it (free
  // flight from their state at t). Returns the new islands (to be planned); island k keeps the
  // component of its first link.
  std::vector<std::uint32_t> split(std::uint32_t k, double t, bool& changed) {
    std::vector<std::uint32_t> made;
    changed = false;
    Island& is = islands[k];
    if (is.links.empty()) {
      for (BodyId id : is.bodies) island_of[id.index] = -1;
      release_slot(k);
      return made;
    }
    // Union-find over the island's bodies.
    std::vector<int> parent(is.bodies.size());
    for (std::size_t n = 0; n < parent.size(); ++n) parent[n] = static_cast<int>(n);
    auto find = [&](int x) {
      while (parent[static_cast<std::size_t>(x)] != x) x = parent[static_cast<std::size_t>(x)];
      return x;
    };
    std::vector<bool> linked(is.bodies.size(), false);
    for (const HeldLink& link : is.links) {
      const int m = is.index_of(link.mover), s = is.index_of(link.support);
      if (m >= 0) linked[static_cast<std::size_t>(m)] = true;
      if (s >= 0) linked[static_cast<std::size_t>(s)] = true;
      if (m >= 0 && s >= 0) parent[static_cast<std::size_t>(find(m))] = find(s);
    }
    const int root = [&] {
      const HeldLink& first = is.links.front();
      const int m = is.index_of(first.mover);
      return find(m >= 0 ? m : is.index_of(first.support));
    }();
    std::vector<BodyId> keep;
    std::vector<std::pair<int, BodyId>> others;
    for (std::size_t n = 0; n < is.bodies.size(); ++n) {
      const BodyId id = is.bodies[n];
      if (!linked[n]) {
        island_of[id.index] = -1;
        body(id).state = is.state_at(n, t);
      } else if (find(static_cast<int>(n)) == root) {
        keep.push_back(id);
      } else {
        others.emplace_back(find(static_cast<int>(n)), id);
      }
    }
    if (others.empty() && keep.size() == is.bodies.size()) return made;
    changed = true;
    std::sort(others.begin(), others.end(), [](const auto& x, const auto& y) {
      return x.first < y.first || (x.first == y.first && x.second < y.second);
    });
    std::vector<HeldLink> links = std::move(is.links);
    for (BodyId id : is.bodies) commit(id, t);
    is.bodies = keep;
    is.links.clear();
    std::map<int, std::uint32_t> slot_of;
    for (const auto& [component, id] : others) {
      auto it = slot_of.find(component);
      if (it == slot_of.end()) {
        const std::uint32_t slot = new_slot();
        it = slot_of.emplace(component, slot).first;
        made.push_back(slot);
      }
      islands[it->second].bodies.push_back(id);
      island_of[id.index] = static_cast<int>(it->second);
    }
    Island& kept = islands[k];  // (new_slot may have moved the vector)
    for (const HeldLink& link : links) {
      const BodyId d = body(link.mover).is_dynamic() ? link.mover : link.support;
      const int slot = island_of[d.index];
      islands[static_cast<std::size_t>(slot)].links.push_back(link);
    }
    (void)kept;
    return made;
  }

  void schedule_island(std::uint32_t i, double t) {
    if (!island_live[i]) return;
    Island& is = islands[i];
    if (is.motion == Island::Motion::kRest && !is.links.empty()) {
      ++stats.rests;
      const HeldLink& link = is.links.front();
      report("rest", std::min(link.mover, link.support), std::max(link.mover, link.support),
             body(is.bodies.front()).state.x_W, t);
    }
    if (!std::isfinite(is.t_end)) {
      if (island_events[i] != EventQueue::kNoEvent) queue.erase(island_events[i]);
      island_events[i] = EventQueue::kNoEvent;
      return;
    }
    Event e;
    e.t = std::max(is.t_end, t);
    e.kind = EventKind::kIsland;
    e.a = *std::min_element(is.bodies.begin(), is.bodies.end());
    e.owner = i;
    if (island_events[i] == EventQueue::kNoEvent) {
      island_events[i] = queue.push(e);
    } else {
      queue.update(island_events[i], e);
    }
  }

  // Island i's motion reached its next event at time t: a mode change.
  void island_event(std::uint32_t i, double t) {
    island_events[i] = EventQueue::kNoEvent;
    Island& is = islands[i];
    for (BodyId id : is.bodies) commit(id, t);
    ++stats.mode_changes;
    const IslandEvent ev = is.event;
    is.trigger = ev;
    if (ev.link >= 0 && ev.link < static_cast<int>(is.links.size())) {
      const HeldLink& link = is.links[static_cast<std::size_t>(ev.link)];
      if (ev.kind != IslandEvent::Kind::kSegmentEnd) {
        report(to_string(ev.kind), std::min(link.mover, link.support),
               std::max(link.mover, link.support), body(link.mover).state.x_W, t);
      }
      if (ev.kind == IslandEvent::Kind::kLanding) {
        // Another part of the body reaches the plane: a collision, which the pair's check finds.
        pairs.pair(link.pair).held = false;
        is.links.erase(is.links.begin() + ev.link);
      }
    }
    // A motion that keeps ending where it began makes no progress: let its contacts go.
    if (t <= is.last_event_t) {
      if (++is.stalls > 50) {
        ++stats.stalled_islands;
        for (const HeldLink& link : is.links) pairs.pair(link.pair).held = false;
        is.links.clear();
      }
    } else {
      is.stalls = 0;
    }
    is.last_event_t = t;
    replan(i, t);
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
    island_of.assign(n, -1);
    for (std::uint32_t i = 0; i < n; ++i) geometries.push_back(&pairs.geometry(BodyId{i}));
    for (std::uint32_t i = 0; i < n; ++i) refresh_broad_phase(BodyId{i}, 0.0);
    for (std::uint32_t index = 0; index < pairs.slots(); ++index) {
      if (pairs.pair(index).live) rebound(index, 0.0);  // each pair once
    }
    schedule_sample();
  }

  StepResult step(double t_end, SimulationObserver* step_observer) {
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
