// Persistent contact (Simulation::Impl, scheduler/simulation_impl.hpp): a contact that persists is
// held (scheduler/island.hpp); islands of held bodies are joined, split, planned and their events
// handled here.
#include "scheduler/simulation_impl.hpp"

#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "impulse/microcollision.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace palpable {

void Simulation::Impl::report(const char* kind, BodyId a, BodyId b, const Vec3& p_W, double t) {
  if (observer) observer->on_mode_change(ModeChange{t, kind, a, b, p_W});
}

std::optional<CollisionRecord> Simulation::Impl::collide_or_hold(std::uint32_t index, Contact& c,
                                                                 const DistanceResult& dr,
                                                                 double t) {
  PairSet::Pair& p = pairs.pair(index);
  const BodyId a = p.a, b = p.b;
  const double approach = -initial_normal_velocity(c);
  // A pair colliding again at the same instant is one whose bodies' other contacts (held, and
  // resolved after it, not with it) keep sending it back: a train of rebounds shrinking by the
  // restitution. Its limit is the plastic collision, taken at once from the third round; from
  // the fifth, a hold that keeps letting go at once gives way to a microcollision, whose
  // rebound floor moves the pair on in time.
  if (p.landed && approach <= settle_speed(p)) {
    p.quiet_landings = static_cast<std::uint8_t>(std::min(p.quiet_landings + 1, 255));
  } else {
    p.quiet_landings = 0;
  }
  p.landed = false;
  // The end of a rocking train. A body held on a support that tips and lands back on it, each
  // landing slower than a fall from the plane's resolution, rocks as a block does (Housner): by
  // a factor at each landing, ever faster, to rest in finite time. From its fourth such landing
  // it is at that limit: struck plastically, it is held at rest on its fixed support, if it moves
  // no faster than the hand-over speed anywhere within its reach (what that takes out is below
  // the energy the microcollision floor lends); on a dynamic body, both are stopped if both are
  // that slow (a hull rocking on a hull on the floor, struck by a microcollision at its fourth
  // quiet landing, took 1.1e-5 J and rocked again, for 9 s). (A microcollision instead, as at a
  // quick round below, rebounded at the hand-over speed: a lone hull rocking on a narrow face
  // took 9.8e-5 J at every fourth quiet landing, every 0.16 s, and never came to rest.) Landings
  // that go on after it - a body that tips again from rest - give way to that microcollision from
  // the eighth.
  const std::vector<BodyId> zeno = zeno_end_bodies(p, t);
  const int round = !zeno.empty() ? 0 : hold_round(p, t);
  const std::optional<HeldLink> link = round >= 4 ? std::optional<HeldLink>() : link_of(index, dr);
  // Two bodies in free flight share gravity: nothing presses their contact, so a collision
  // between them is resolved with the scene's restitution and held only if it leaves them at
  // rest to rounding (below). (Handed over at the upper body's weight, a hull struck at
  // 0.1 m/s was held, let go at once by its plan, and left receding from a gap of 2e-13 m at
  // 1e-8 m/s: its pair was then checked every 1e-12 s, 1.7 million times, while rotation
  // slowly drew the hulls apart.)
  const bool held_pair = !(in_free_flight(a) && in_free_flight(b));
  const double v_hold = held_pair ? hand_over_speed(c) : 0.0;
  // The least speed a held pair is resolved at (below): the hand-over speed, at least the
  // settling speed - a fall from the plane's resolution, the least the model resolves.
  const double v_least = std::max(v_hold, held_pair ? settle_speed(p) : 0.0);
  const bool gentle = approach <= v_hold * (1.0 + settings().microcollision_speed_slack);
  // A touch slower than a hundredth of the hand-over speed into a body that other contacts hold
  // is held without an impulse of its own: the island's plan takes out its approach together
  // with every held contact's (its velocity projection, which gives up kinetic energy), not a
  // pairwise impulse that knows nothing of the struck body's supports. (Struck pairwise, a ball
  // wedged on three balls of a pile set the support it pushed sliding, and the next plan let its
  // other side go: struck, held and let go on alternate sides 1,231 times in 0.6 s. Seven balls
  // cut from that pile took 8,115 events for 0.2 s, 2,230 now.) A pair held again and again at
  // one instant goes on through the rounds below. (Up to the hand-over speed itself, most piles
  // were cheaper still, but one of 16 ball piles and one of 24 hull piles broke down: their
  // islands grew, their motions were rejected step after step, cut off at 120 s of CPU.)
  if (approach <= 1e-2 * v_hold && link && zeno.empty() && round < 2 && (island(a) || island(b))) {
    hold(index, *link, dr, t, /*struck=*/false);
    return std::nullopt;
  }
  ResolveOptions options;
  options.microcollisions = !link;
  // The microcollision that replaces the hold rebounds at least at the hand-over speed. (The
  // contact's own v_micro is zero where the islands on both sides hold their bodies still along
  // n: a hull leaning on a hull at rest beside it, both held, was struck 100 times at one
  // instant at 1e-43 m/s, each rebound sent back by its island's plan, until the retry limit.)
  // Where nothing presses it along its normal by weight (a hull held on the floor, pushed against
  // a vertical wall by its island), the hand-over speed is zero too, and so was that rebound: the
  // hull was struck 101 times at one instant, from 1e-33 m/s down to 1e-62 m/s, each rebound sent
  // back by its island's plan, until the retry limit (100 hulls, seed 3). It rebounds at least at
  // the settling speed, a fall from the plane's resolution, the least the model resolves - also
  // where the hand-over speed is above zero but below it: a hull pressed against a vertical wall
  // by its island only by rounding (hand-over speed ~1e-25 m/s) was struck 101 times at one
  // instant, six times in 0.4 s (100 hulls, seed 6; the drift-free impulse then lies on the
  // friction cone's boundary, and reached that rebound and no more).
  if (!link) c.v_micro = std::max(c.v_micro, v_least);
  if ((gentle || round >= 2) && link) options.restitution = 0.0;
  CollisionRecord record = collide(p, c, t, options);
  if (!zeno.empty() && link) {
    const auto slow = [&](BodyId id) {
      const Body& m = body(id);
      return m.state.v_W.norm() + m.state.w_W.norm() * pairs.geometry(id).reach() <= v_hold;
    };
    if (std::all_of(zeno.begin(), zeno.end(), slow)) {
      for (BodyId id : zeno) {
        Body& m = body(id);
        record.energy_change -= kinetic_energy(m, m.state);
        m.state.v_W.setZero();
        m.state.w_W.setZero();
      }
      ++stats.rocking_ends;
    }
  }
  if (observer) observer->on_collision(record);
  const Vec3 u_after =
      point_velocity_W(body(a).state, record.p_W) - point_velocity_W(body(b).state, record.p_W);
  // Held if it leaves slower than the hand-over speed - or, where that is zero (nothing presses
  // the pair along its normal: a ball pushed against a vertical wall by its neighbours), at rest
  // to the rounding of its speeds. (Not held, a ball at rest in a pile, squeezed against a wall,
  // approached it again at 0.8 of each last approach from 4e-21 m/s down, 100 collisions at one
  // instant, until the retry limit.) A held pair is held too where it leaves slower than the
  // settling speed, the least the model resolves: a hull on the floor pushed against a wall by
  // its sliding neighbours rebounded at 4e-8 m/s, was stopped by the floor's friction 5e-9 s
  // later and carried into the wall again, a collision every 5e-9 s (100 hulls, seed 8, from
  // 0.3863 s; the run stalled there).
  if (link && u_after.dot(record.n_W) < std::max(v_least, rounding_speed(c))) {
    hold(index, *link, dr, t, /*struck=*/!gentle);
  } else {
    after_collision(record, t);
  }
  return record;
}

std::vector<BodyId> Simulation::Impl::zeno_end_bodies(const PairSet::Pair& p, double t) const {
  if (p.quiet_landings < 4 || p.quiet_landings >= 8 || collision_round(p, t) >= 4 ||
      p.quick_releases >= 4) {
    return {};
  }
  const Body& ba = body(p.a);
  const Body& bb = body(p.b);
  if (ba.is_dynamic() && bb.motion == MotionKind::kFixed) return {p.a};
  if (bb.is_dynamic() && ba.motion == MotionKind::kFixed) return {p.b};
  if (ba.is_dynamic() && bb.is_dynamic()) return {p.a, p.b};
  return {};
}

double Simulation::Impl::dynamic_reach(const PairSet::Pair& p) const {
  double reach = 0.0;
  for (BodyId id : {p.a, p.b}) {
    if (body(id).is_dynamic()) reach = std::max(reach, pairs.geometry(id).reach());
  }
  return reach;
}

double Simulation::Impl::settle_speed(const PairSet::Pair& p) const {
  return std::sqrt(2.0 * world.gravity_W.norm() * kPlaneResolution * dynamic_reach(p));
}

std::optional<HeldLink> Simulation::Impl::link_of(std::uint32_t index,
                                                  const DistanceResult& dr) const {
  const PairSet::Pair& p = pairs.pair(index);
  const Body& ba = body(p.a);
  const Body& bb = body(p.b);
  const ContactGeometry g =
      contact_geometry(pairs.geometry(p.a), Pose{ba.state.x_W, ba.state.q_WM}, pairs.geometry(p.b),
                       Pose{bb.state.x_W, bb.state.q_WM}, dr, settings().envelope_m);
  return make_held_link(index, p.a, p.b, LinkSide{ba, pairs.geometry(p.a), ba.state},
                        LinkSide{bb, pairs.geometry(p.b), bb.state}, dr, g, settings().envelope_m);
}

void Simulation::Impl::after_collision(const CollisionRecord& record, double t) {
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

void Simulation::Impl::hold(std::uint32_t index, HeldLink link, const DistanceResult& dr, double t,
                            bool struck) {
  PairSet::Pair& p = pairs.pair(index);
  // A body in free flight held from the gap it was struck at (a few ulps).
  if (struck && !island(link.mover)) link.gap = raise_to_resolution(link, link.gap);
  std::vector<BodyId> dynamic;
  for (BodyId id : {p.a, p.b}) {
    if (body(id).is_dynamic()) dynamic.push_back(id);
    // Every body of an island joined here is brought to t by its island's plan, while that plan
    // still stands: until the island is planned again they are states at t (plan_pending).
    if (const Island* is = island(id)) {
      for (BodyId other : is->bodies) commit(other, t);
    }
  }
  const std::uint32_t i = join(dynamic, t);
  islands[i].links.push_back(link);
  if (p.cache.piece_results().empty()) {
    p.held = true;
    schedule_pair(index, kInfinity);
  }
  ++stats.holds;
  report("hold", p.a, p.b, dr.p2_W, t);
  defer_plan(i, t);
  // The other pairs of the bodies just held, with a body in free flight (or held at this
  // instant too), are checked at this instant, before the plan: a body stopped now is met now by
  // what it carries and by its neighbours (a box riding on it, touching and falling with it
  // until now, whose pair had no event), and the island is planned with all of them, not with a
  // part that is no equilibrium (a box held on one of its two supports tips; contacts let go
  // there came back at once, round after round). Pairs with a body already planned keep their
  // bounds: re-checking those too made a pile of 50 hulls 7.6x slower (195.8 s against 25.6 s).
  for (BodyId id : dynamic) {
    for (std::uint32_t q : pairs.body(id).pairs) {
      const PairSet::Pair& other_pair = pairs.pair(q);
      if (q == index || other_pair.held) continue;
      const Island* other = island(other_pair.a == id ? other_pair.b : other_pair.a);
      if (!other || other->plan_pending) schedule_pair(q, t);
    }
  }
}

double Simulation::Impl::raise_to_resolution(const HeldLink& link, double gap) {
  // A polyhedron struck at the instant its gap closes (a few ulps) would be held there, and the
  // held motion's integration error (1e-12 of its size over a motion) carries it into the
  // support: a bowling pin lying on the lane was found 2e-12 m into it when it lifted off; a
  // 32-gon prism's pivot, held for 0.17 s, was 1.4e-11 m into the slope when its next face landed
  // (found overlapping, the pair could not be held again, and a microcollision there pushed the
  // pivot off at v_micro, 5.8e-4 J gained, and yawed the prism). A body on a fixed or kinematic
  // support is placed at the plane's resolution above it (kPlaneResolution of its reach, a few
  // 1e-10 m): no deeper than its landing events resolve the plane, and far above the
  // integration's drift. Deeper than that below the plane is an overlap, and left as one.
  Body& mover = body(link.mover);
  const Body& support = body(link.support);
  if (!mover.is_dynamic() || support.is_dynamic() || link.sphere_radius > 0.0 ||
      link.curved_shape || link.point_pair) {
    return gap;
  }
  const double floor = kPlaneResolution * pairs.geometry(link.mover).reach();
  if (!(gap < floor && gap > -floor)) return gap;
  mover.state.x_W += (floor - gap) * (support.state.q_WM * link.normal_S);
  return floor;
}

void Simulation::Impl::part_released(std::uint32_t index, double t) {
  // A held contact's gap drifts with the integration of its motion (~1e-11 m over 0.2 s for a
  // ball rolling off a ball, held at a gap of zero): let go 5e-12 to 6e-11 m into the other
  // body, the pair was found overlapping at every check (51 and 114 times at the progress floor)
  // until the bodies had parted. Overlapping by less than that drift's scale (below) where the
  // depth is known (spheres, halfspaces, and polyhedra within closest_features' separating-axis
  // search, whose normal is then the axis of least overlap), the body the release set free is
  // moved out along the normal (both, by their inverse masses, if both are free; neither if
  // neither is: a body still held is where its own links hold it).
  const PairSet::Pair& q = pairs.pair(index);
  Body& a = body(q.a);
  Body& b = body(q.b);
  // The island's bodies are committed at t; a kinematic partner is advanced only when asked.
  const BodyState sa = extrapolate(q.a, t), sb = extrapolate(q.b, t);
  PairCache cache;  // fresh: the pair's own cache stays as its schedule left it
  const DistanceResult dr =
      closest_features(pairs.geometry(q.a), Pose{sa.x_W, sa.q_WM}, pairs.geometry(q.b),
                       Pose{sb.x_W, sb.q_WM}, cache, settings().distance_max_steps);
  if (dr.status != ContactStatus::kPenetrating || !(dr.penetration_depth > 0.0)) return;
  // The drift's scale: the integration's absolute tolerance [m] per step, summed over a motion.
  // Never more than a hundredth of the envelope, whatever the tolerance.
  const double drift = std::min(
      std::max(kPlaneResolution * dynamic_reach(q), 100.0 * settings().integration_tolerance),
      0.01 * settings().envelope_m);
  if (!(dr.penetration_depth <= drift)) return;
  const double wa = in_free_flight(q.a) && a.state.t == t ? a.mass.inv_mass : 0.0;
  const double wb = in_free_flight(q.b) && b.state.t == t ? b.mass.inv_mass : 0.0;
  if (!(wa + wb > 0.0)) return;
  a.state.x_W += dr.penetration_depth * wa / (wa + wb) * dr.n_W;  // n_W: from b to a
  b.state.x_W -= dr.penetration_depth * wb / (wa + wb) * dr.n_W;
}

void Simulation::Impl::defer_plan(std::uint32_t i, double t) {
  islands[i].plan_pending = true;
  put_island_event(i, t);
}

void Simulation::Impl::put_island_event(std::uint32_t i, double t) {
  const Island& is = islands[i];
  Event e;
  e.t = t;
  e.kind = EventKind::kIsland;
  e.a = *std::min_element(is.bodies.begin(), is.bodies.end());
  e.owner = i;
  if (island_events[i] == EventQueue::kNoEvent) {
    island_events[i] = queue.push(e);
  } else {
    queue.update(island_events[i], e);
  }
}

std::uint32_t Simulation::Impl::join(const std::vector<BodyId>& ids, double t) {
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
      to.plan_pending = to.plan_pending || from.plan_pending;
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

std::uint32_t Simulation::Impl::new_slot() {
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

void Simulation::Impl::release_slot(std::uint32_t i) {
  if (island_events[i] != EventQueue::kNoEvent) queue.erase(island_events[i]);
  island_events[i] = EventQueue::kNoEvent;
  islands[i] = Island{};
  island_live[i] = false;
  free_islands.push_back(i);
}

void Simulation::Impl::replan(std::uint32_t i, double t) {
  std::vector<BodyId> touched = islands[i].bodies;
  for (BodyId id : touched) commit(id, t);
  std::vector<std::uint32_t> todo{i};
  std::vector<std::uint32_t> let_go;  // pairs released, parted below
  // Components of the links among dynamic bodies; every body reached by a link stays held.
  while (!todo.empty()) {
    const std::uint32_t k = todo.back();
    todo.pop_back();
    Island& is = islands[k];
    is.plan_pending = false;
    const Island::PlanResult r = is.plan(world, geometries, t);
    ++stats.island_plans;
    if (r.inconsistent) ++stats.held_inconsistent;
    count_integration(is);
    for (std::uint32_t pair : r.released) {
      note_release(pair, t);
      let_go.push_back(pair);
    }
    bool changed = false;
    for (std::uint32_t extra : split(k, t, changed)) todo.push_back(extra);
    if (changed) {
      todo.push_back(k);  // its motion was planned with bodies it no longer has
      continue;
    }
    schedule_island(k, t);
  }
  for (std::uint32_t pair : let_go) part_released(pair, t);
  refresh_moved(touched, t);
}

void Simulation::Impl::note_release(std::uint32_t index, double t) {
  PairSet::Pair& q = pairs.pair(index);
  q.held = false;
  q.lifted = true;
  // Let go at the instant of its own collision, it keeps its count there: a hold that lets go at
  // once and collides again moves through the rounds of collide_or_hold (and at last the retry
  // limit) instead of looping at one instant; and it counts as a quick release (hold_round),
  // which a hold that lasts resets. A hold let go within the progress floor of its collision
  // counts as quick too: a hull held against a hull's side, its centre of pressure on its
  // patch's edge, tipped 1.6e-10 s after each hold, was let go, struck again at 2e-11 m/s and
  // held, 17,500 times in 3 ms of simulated time (112 s of CPU).
  const bool quick = t - q.last_collision_t <= progress_floor(t);
  q.quick_releases = quick ? static_cast<std::uint8_t>(std::min(q.quick_releases + 1, 255)) : 0;
  if (q.last_collision_t != t) {
    q.last_collision_t = t;
    q.collisions_at_t = 0;
  }
  report("release", q.a, q.b, body(q.a).state.x_W, t);
}

void Simulation::Impl::count_integration(const Island& is) {
  stats.island_steps += is.integration.steps;
  stats.island_rejected_steps += is.integration.rejected;
  if (is.integration.failed) ++stats.island_failed_motions;
}

std::vector<std::uint32_t> Simulation::Impl::split(std::uint32_t k, double t, bool& changed) {
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

void Simulation::Impl::schedule_island(std::uint32_t i, double t) {
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
  put_island_event(i, std::max(is.t_end, t));
}

void Simulation::Impl::island_event(std::uint32_t i, double t) {
  island_events[i] = EventQueue::kNoEvent;
  Island& is = islands[i];
  for (BodyId id : is.bodies) commit(id, t);
  if (is.plan_pending) {  // contacts held at this instant, all in now
    replan(i, t);
    return;
  }
  if (is.event.kind == IslandEvent::Kind::kChunkEnd) {
    // Its integration goes on from here, with the same links and modes; what its motion now
    // bounds is bounded again (as after a plan).
    is.extend(world, geometries, t);
    ++stats.island_chunks;
    count_integration(is);
    schedule_island(i, t);
    refresh_moved(is.bodies, t);
    return;
  }
  ++stats.mode_changes;
  // Motions that keep ending within 1e-2 of the progress floor of their start make no progress
  // at the scheduler's resolution: after 50 in a row, the contacts whose events ended them let go
  // (all of the island's, where no link's event did), as a plan lets go, and their pairs' checks
  // meet them again; a pair let go quickly again and again gives way to microcollisions
  // (hold_round). (Ending at the same clock tick only, 1e-12 of t, was not caught: a hull tipping
  // over its floor edge, whose end touched a resting hull at the floor, had the floor contacts of
  // both stop slipping in turn every 7e-10 s, 43,640 times in 3.4e-5 s - 100 hulls, seed 2, at
  // 0.7616 s. A ball's rolling on a ball that could neither hold nor start in any direction
  // stopped at once, 50 times at one instant; letting the whole island of 13 balls go struck all
  // of them again there, and so again, the clock creeping by 1e-9 s. Within 1e-3 of the floor
  // only, 100 balls, seed 3, stuck: at 0.746 s, a ball's rolling stopped on its two contacts in
  // turn, every 1.9e-9 s; at 0.989 s, once held rollings no longer leaked, a ball's rolling on a
  // ball, started by a resistance that barely failed to hold, was judged reversed by the
  // integration's noise 8e-9 s after each plan.)
  const bool no_progress = t - is.last_event_t <= 1e-2 * progress_floor(t);
  is.last_event_t = t;
  if (!no_progress) {
    is.stalls = 0;
    is.stall_pairs.clear();
  }
  const IslandEvent ev = is.event;
  is.trigger = ev;
  if (ev.link >= 0 && ev.link < static_cast<int>(is.links.size())) {
    const HeldLink& link = is.links[static_cast<std::size_t>(ev.link)];
    const auto& stalled = is.stall_pairs;
    if (no_progress && std::find(stalled.begin(), stalled.end(), link.pair) == stalled.end()) {
      is.stall_pairs.push_back(link.pair);
    }
    if (ev.kind != IslandEvent::Kind::kSegmentEnd) {
      report(to_string(ev.kind), std::min(link.mover, link.support),
             std::max(link.mover, link.support), body(link.mover).state.x_W, t);
    }
    if (ev.kind == IslandEvent::Kind::kLanding) {
      // Another part of the body reaches the plane: a collision, which the pair's check finds.
      pairs.pair(link.pair).held = false;
      pairs.pair(link.pair).landed = true;
      // Let go of its only contact, the body flies on from where the held motion left it.
      if (is.links.size() == 1) {
        raise_to_resolution(
            link, held_feature_height(link, body(link.mover).state, body(link.support).state));
      }
      is.links.erase(is.links.begin() + ev.link);
    }
  }
  std::vector<std::uint32_t> let_go;
  if (no_progress && ++is.stalls > 50) {
    ++stats.stalled_islands;
    const auto& stalled = is.stall_pairs;
    for (std::size_t k = is.links.size(); k-- > 0;) {
      const std::uint32_t pair = is.links[k].pair;
      if (stalled.empty() || std::find(stalled.begin(), stalled.end(), pair) != stalled.end()) {
        note_release(pair, t);
        let_go.push_back(pair);
        is.links.erase(is.links.begin() + static_cast<std::ptrdiff_t>(k));
      }
    }
    is.stalls = 0;
    is.stall_pairs.clear();
  }
  replan(i, t);
  for (std::uint32_t pair : let_go) part_released(pair, t);
}

}  // namespace palpable
