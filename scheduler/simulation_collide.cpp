// Collisions (Simulation::Impl, scheduler/simulation_impl.hpp): a pair's check event, the
// riders a microcollision carries, and the contact model's resolution committed to the bodies.
#include "scheduler/simulation_impl.hpp"

#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "impulse/microcollision.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace palpable {

namespace {

// The least part of gravity's magnitude pressing a touching pair along its normal at which it
// loads the pair (join_pending_plan); below it the part is rounding's (a ball beside a wall,
// turned about the vertical: ~1e-17).
constexpr double kLeastPressOfGravity = 1e-9;

}  // namespace

void Simulation::Impl::collect_riders(BodyId id, double t, int depth, std::vector<BodyId>& riders,
                                      std::vector<BodyId>& supports) {
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
    supports.push_back(id);
    collect_riders(other, t, depth + 1, riders, supports);
  }
}

bool Simulation::Impl::seated(BodyId id, BodyId above, double t, int depth) {
  if (depth > kMaxRiderDepth || world.gravity_W.squaredNorm() == 0.0) return false;
  const Vec3 up = -world.gravity_W.normalized();
  for (std::uint32_t index : pairs.body(id).pairs) {
    PairSet::Pair& q = pairs.pair(index);
    const BodyId other = q.a == id ? q.b : q.a;
    if (other == above) continue;
    const BodyState s1 = extrapolate(q.a, t), s2 = extrapolate(q.b, t);
    ++stats.bound_queries;
    const DistanceResult dr = query(q, s1, s2);  // warms the pair's cache only
    const DistanceResult& contact = contact_result(q, s1, s2, dr);
    if (contact.status != ContactStatus::kSeparated && contact.status != ContactStatus::kTouching) {
      continue;
    }
    if (contact.distance > derived_rider_distance(settings())) continue;
    const Vec3 n_up = q.a == id ? contact.n_W : Vec3(-contact.n_W);  // from `other` up to `id`
    if (n_up.dot(up) <= kSupportCosine) continue;
    const Contact c = make_contact(side(q.a, s1), side(q.b, s2), contact, settings(),
                                   world.gravity_W, /*with_patch=*/true);
    if (c.placement != Placement::kFace) continue;
    if (!body(other).is_dynamic() || seated(other, id, t, depth + 1)) return true;
  }
  return false;
}

void Simulation::Impl::mark_held_rotations(const PairSet::Pair& p, Contact& c, double t) {
  if (c.placement != Placement::kFace || c.dynamic != DynamicSide::kBoth) return;
  c.rotation_held1 = seated(p.a, p.b, t, 0);
  c.rotation_held2 = seated(p.b, p.a, t, 0);
}

CollisionRecord Simulation::Impl::collide(const PairSet::Pair& p, Contact& c, double t,
                                          const ResolveOptions& options) {
  std::vector<BodyId> rider_ids, rider_supports;
  if (options.microcollisions && carries_riders(c, settings(), world.gravity_W)) {
    collect_riders(c.dynamic1() ? p.a : p.b, t, 0, rider_ids, rider_supports);
    for (BodyId r : rider_ids) commit(r, t);
  }
  std::vector<Rider> riders;
  for (std::size_t k = 0; k < rider_ids.size(); ++k) {
    riders.push_back(Rider{rider_ids[k], body(rider_ids[k]), body(rider_ids[k]).state,
                           world.material(rider_ids[k], rider_supports[k]).friction});
  }
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

double Simulation::Impl::touching_gap(const PairSet::Pair& p) const {
  double scale = 0.0;  // the finite reaches (a halfspace's is infinite)
  for (BodyId id : {p.a, p.b}) {
    if (std::isfinite(pairs.geometry(id).reach())) scale += pairs.geometry(id).reach();
  }
  return kTouchingGap * scale;
}

ImpactInstant Simulation::Impl::refine_instant(const PairSet::Pair& p, const BodyState& s1,
                                               const BodyState& s2, const DistanceResult& dr,
                                               const PairCache& cache) {
  const ImpactInstant in =
      impact_instant(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2, pairs.geometry(p.b), dr,
                     cache, world.gravity_W, settings(), touching_gap(p), kMaxInstantIterations);
  if (in.status != InstantStatus::kNotApplicable) {
    ++stats.instant_refinements;
    stats.instant_iterations += static_cast<std::uint64_t>(in.iterations);
    if (in.status != InstantStatus::kFound) ++stats.instant_unfound;
  }
  return in;
}

double Simulation::Impl::time_to_contact(PairSet::Pair& p, const Contact& c,
                                         const DistanceResult& dr, const DistanceResult& contact,
                                         double t) {
  // Only impacts: a microcollision is resting contact (held under the persistent model), and
  // lands where the train puts it. Pairs with a held body keep the envelope's instant (their
  // bound follows the island's motion, not a closed form).
  if (contact.status == ContactStatus::kPenetrating || island(p.a) || island(p.b) ||
      p.approach_steps >= kMaxApproachSteps) {
    return 0.0;
  }
  if (!(contact.distance > touching_gap(p))) return 0.0;
  if (is_microcollision(initial_normal_velocity(c), c.v_micro, settings())) return 0.0;
  const BodyState& s1 = body(p.a).state;
  const BodyState& s2 = body(p.b).state;
  auto usable = [&](double dt) { return dt > 0.0 && std::isfinite(dt) && t + dt > t ? dt : 0.0; };
  const ToiBound b =
      time_to_touch(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2, pairs.geometry(p.b), contact,
                    p.cache, world.gravity_W, settings());
  // Spheres against spheres and planes: the closed form.
  if (b.exact) return usable(b.dt);
  // Otherwise (polyhedra, compounds) the gap is followed along the trajectories to where it
  // closes (DESIGN.md §8.5; distance/impact_instant.hpp): every step certified, so the instant
  // found is the first. Under the persistent model too: a contact struck there is held a little
  // above it (raise_to_resolution), and a hold that lets go at once, round after round, gives way
  // to a microcollision (hold_round's quick releases).
  const ImpactInstant in = refine_instant(p, s1, s2, dr, p.cache);
  switch (in.status) {
    case InstantStatus::kFound: return usable(in.dt);
    case InstantStatus::kStalled:
      // The clock cannot resolve the instant further: collide where the steps stopped.
      if (usable(in.dt) > 0.0) p.approach_steps = kMaxApproachSteps - 1;
      return usable(in.dt);
    case InstantStatus::kReceding:      // the gap opens again: checked there as any pair
    case InstantStatus::kNotConverged:  // checked again from where the steps got
      return usable(in.dt);
    case InstantStatus::kNotApplicable: return 0.0;
  }
  return 0.0;
}

bool Simulation::Impl::join_pending_plan(std::uint32_t index, const Contact& c,
                                         const DistanceResult& contact, double t) {
  // A pair touching a body held at this instant (its island's plan pending), neither
  // approaching nor parting, that gravity loads (one body above the other along its normal) is
  // held too, and planned with it: the plan decides what it carries. (Checked against the held
  // body's fall before that plan, both falling together, the pair had no event, and was met only
  // after the plan had stopped the body: a pyramid of 21 boxes placed touching was planned 48
  // times at its first instant, one row more each time, each part no equilibrium, its boxes
  // tipping and sliding from rest in turn - 76,000 solves of its contact problem, 103 s of CPU.)
  // A pair gravity does not load (a ball placed touching a wall, held on the floor beside it;
  // boxes side by side) is left to its checks: a contact that carries nothing, held, resists
  // through rounding (that ball's rolling stopped against the wall within 0.02 s).
  const PairSet::Pair& p = pairs.pair(index);
  const auto pending = [&](BodyId id) {
    const Island* is = island(id);
    return is && is->plan_pending;
  };
  if (!persistent() || !(pending(p.a) || pending(p.b)) || lifting(p, c, t) ||
      contact.status == ContactStatus::kPenetrating || !(contact.distance <= touching_gap(p)) ||
      !(c.u_n <= rounding_speed(c))) {
    return false;
  }
  // What presses the pair together along its normal: the contact's own g_n (a body held at this
  // instant counts as held still: ContactSide), and between two such bodies the upper one's
  // weight along n (DESIGN.md §4), as between two bodies in free flight.
  const double pressed =
      pending(p.a) && pending(p.b) ? std::abs(world.gravity_W.dot(c.n_W)) : c.g_n;
  if (!(pressed > kLeastPressOfGravity * world.gravity_W.norm())) return false;
  const std::optional<HeldLink> link = link_of(index, contact);
  if (!link) return false;
  hold(index, *link, contact, t, /*struck=*/false);
  return true;
}

std::optional<CollisionRecord> Simulation::Impl::part_free_pair(const PairSet::Pair& p,
                                                                const Contact& c,
                                                                const DistanceResult& contact,
                                                                double t) {
  // Free, or held by an island whose motion is planned (not one joined at this instant).
  const auto free_or_planned = [&](BodyId id) {
    return in_free_flight(id) || (body(id).is_dynamic() && planned_island(id));
  };
  if (!persistent() || !(in_free_flight(p.a) || in_free_flight(p.b)) || !free_or_planned(p.a) ||
      !free_or_planned(p.b) || contact.status == ContactStatus::kPenetrating ||
      !(contact.distance <= touching_gap(p))) {
    return std::nullopt;
  }
  // Against a held body the contact's own v_micro may be zero (its island holds it still along
  // n): the hand-over speed, as a collision into it that is not held (collide_or_hold).
  const bool held = !in_free_flight(p.a) || !in_free_flight(p.b);
  const double v_part = held ? hand_over_speed(c) : c.v_micro;
  if (!(v_part > 0.0) || !(c.u_n < v_part)) return std::nullopt;
  const double k = c.n_W.dot(collision_matrix_W(c.body1, c.body2) * c.n_W);
  if (!(k > 0.0)) return std::nullopt;
  const Vec3 impulse = (v_part - c.u_n) / k * c.n_W;  // on a; b takes the opposite
  ContactBody after1 = c.body1, after2 = c.body2;
  apply_impulse(impulse, after1, after2);
  Body& a = body(p.a);
  Body& b = body(p.b);
  const double before = kinetic_energy(a, a.state) + kinetic_energy(b, b.state);
  a.state.v_W = after1.v_W;
  a.state.w_W = after1.w_W;
  b.state.v_W = after2.v_W;
  b.state.w_W = after2.w_W;
  CollisionRecord record;
  record.t = t;
  record.kind = CollisionKind::kMicrocollision;
  record.a = p.a;
  record.b = p.b;
  record.p_W = c.point_W;
  record.n_W = c.n_W;
  record.impulse_W = impulse;
  record.approach_speed = -c.u_n;
  record.energy_change = kinetic_energy(a, a.state) + kinetic_energy(b, b.state) - before;
  ++stats.microcollisions;
  if (observer) observer->on_collision(record);
  if (held) {
    after_collision(record, t);  // the held body's island is planned again from its new velocity
  } else {
    refresh_after_collision(record, t);
  }
  return record;
}

std::optional<CollisionRecord> Simulation::Impl::check_pair(std::uint32_t index, double t) {
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
      (contact.status != ContactStatus::kPenetrating && contact.distance > settings().envelope_m)) {
    if (contact.status != ContactStatus::kFailed) {  // apart: the next contact is a fresh one
      p.quiet_landings = 0;
      p.quick_releases = 0;
      p.landed = false;
    }
    schedule_pair(index, next_check_time(p, s1, s2, dr, t));
    return std::nullopt;
  }
  Contact c = make_contact(side(p.a, s1), side(p.b, s2), contact, settings(), world.gravity_W,
                           /*with_patch=*/true);
  // Under the persistent model a face whose corner lands is a collision even while its centre
  // of pressure does not approach (the hold, not a microcollision train, must catch it). So at
  // the instant of contact (DESIGN.md §8.5), where no envelope is left to absorb a corner that
  // the last impulse did not stop: a face landing flat on a dynamic face is struck at its
  // corners one after another at that instant.
  const bool approaches = approaching(c);
  const bool lands = approaches || ((persistent() || contact.distance <= touching_gap(p)) &&
                                    patch_approaching(c, s1, s2));
  if (lands && !approaches) {
    // Only a corner lands: the collision acts there, not through the centre of pressure, which
    // recedes (integrated from a receding start, that impulse created energy: 6.5e-4 J for a
    // bowling pin, found by the checked build).
    Settings at_corner = settings();
    at_corner.centre_of_pressure = false;
    c = make_contact(side(p.a, s1), side(p.b, s2), contact, at_corner, world.gravity_W,
                     /*with_patch=*/true);
  }
  if (!lands || lifting(p, c, t)) {
    p.approach_steps = 0;
    if (!lands && join_pending_plan(index, c, contact, t)) return std::nullopt;
    if (auto parted = part_free_pair(p, c, contact, t)) return parted;
    double next = next_check_time(p, s1, s2, dr, t, &c);
    // An exact bound of zero means "collide now"; a contact found not approaching (a group impact
    // leaves a sliding contact at u_n = 0 to rounding, drawn together by gravity), or let go at
    // this instant and not approaching beyond rounding (lifting), is checked again a clock tick
    // later, when its approach (or its island's lift) has begun - not at this instant forever
    // (a sphere let go by the floor in a pile of 100 was checked 1.1 million times at one
    // instant, and the run stopped with "the clock stopped advancing").
    if (next == t) next = t + 1e-12 * std::max(1.0, t);
    if (next < t + settings().toi_min_progress_s && persistent() &&
        (planned_island(p.a) || planned_island(p.b)) && !(contact.distance > touching_gap(p))) {
      // A held body touching it, neither approaching nor landing (a ball placed touching a wall,
      // held on the floor beside it, resting against the wall at rounding): checked at each
      // tick of the clock it was 37 million times in 0.3 s. It is checked again when its
      // island's bound could have carried it the touching gap into it: where it comes back, it
      // is met then, approaching, and collides.
      DistanceResult into = contact;
      into.status = ContactStatus::kSeparated;
      into.distance = std::max(contact.distance, 0.0) + touching_gap(p);
      const ToiBound bound = toi_bound(motion_for(p.a, s1, s2, p.b), motion_for(p.b, s2, s1, p.a),
                                       into, 0.0, settings());
      if (bound.dt >= 0.0) next = std::max(next, t + bound.dt);
    }
    schedule_pair(index, next);
    return std::nullopt;
  }
  if (const double dt = time_to_contact(p, c, dr, contact, t); dt > 0.0) {
    // An impact lands where the gap closes, not where the bound stopped (half an envelope up).
    ++p.approach_steps;
    ++stats.approach_checks;
    schedule_pair(index, t + dt);
    return std::nullopt;
  }
  p.approach_steps = 0;
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
    // A pair whose quick holds gave way to microcollisions (hold_round) flies between them: once
    // it has flown half the flight of a rebound at the hand-over speed since its last collision,
    // those releases are forgotten and it may be held again. (Not forgotten, a hull on the floor
    // of a pile went on as a microcollision train at v_micro, one rebound every 9 ms, to the end
    // of its 10 s; a bowling pin's chatter, one every 2e-6 s, stays a train.)
    if (persistent() && p.quick_releases >= 4) {
      const double g_n = std::abs(world.gravity_W.dot(c.n_W));
      if (g_n > 0.0 && t - p.last_collision_t >= hand_over_speed(c) / g_n) p.quick_releases = 0;
    }
    p.last_collision_t = t;
    p.collisions_at_t = 0;
  }
  if (auto group = collide_group(index, c, contact, t)) return group;
  mark_held_rotations(p, c, t);
  if (persistent()) return collide_or_hold(index, c, DistanceResult(contact), t);
  CollisionRecord record = collide(p, c, t);
  if (observer) observer->on_collision(record);
  refresh_after_collision(record, t);  // `p` may move when pairs are created there
  return record;
}

}  // namespace palpable
