// Simultaneous impact (Simulation::Impl, scheduler/simulation_impl.hpp): the contacts that meet
// a collision at its instant gathered into one group and resolved together
// (impulse/group_impulse.hpp).
#include "scheduler/simulation_impl.hpp"

#include "core/ballistic.hpp"
#include "distance/toi_bound.hpp"
#include "impulse/collision_matrix.hpp"
#include "impulse/group_impulse.hpp"
#include "impulse/microcollision.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

std::optional<CollisionRecord> Simulation::Impl::collide_group(std::uint32_t index,
                                                               const Contact& first,
                                                               const DistanceResult& first_dr,
                                                               double t) {
  const PairSet::Pair& p0 = pairs.pair(index);
  // Under the persistent model a group may strike held bodies (a ball landing on two balls
  // resting on a floor): their held contacts on fixed supports take part plastically, the
  // others are projected when their islands are planned again after it (as after a lone
  // collision, collide_or_hold). Under the microcollision model held bodies are only those
  // placed touching.
  if (!persistent() && (island(p0.a) || island(p0.b))) return std::nullopt;

  struct Member {
    std::uint32_t pair;
    BodyId a, b;
    Vec3 point_W, n_W;
    double approach;
    double floor;       // a microcollision's rebound floor v_micro (0: an impact)
    DistanceResult dr;  // the pair's contact query (a held link is made from it)
    double v_hold;      // the persistent model's hand-over speed (collide_or_hold)
    bool face;          // a face-on-face patch
    bool held = false;  // a held contact on a fixed or kinematic support, taken in plastically
  };
  std::vector<Member> members;
  // An impact: an approach faster than the microcollision speed under the scene's full gravity,
  // whatever the normal (two balls touching side by side in a row approach at rounding speeds).
  const double impact_speed = microcollision_speed(settings(), world.gravity_W.norm()) *
                              (1.0 + settings().microcollision_speed_slack);
  // Nothing is committed or cached until a group forms: a lone contact leaves the run exactly as
  // it was (states extrapolated here, closest features from a copy of each pair's cache).
  auto state_at = [&](BodyId id) {
    return body(id).state.t < t ? extrapolate(id, t) : body(id).state;
  };
  auto normal_velocity = [](const Contact& c, const BodyState& s1, const BodyState& s2) {
    return (point_velocity_W(s1, c.point_W) - point_velocity_W(s2, c.point_W)).dot(c.n_W);
  };
  // Impacts group with impacts. Microcollisions group too (a ball resting in a V-groove bounces
  // off both walls at once), not under the persistent model, which holds resting contact: one
  // gathers the contacts that gravity presses together (v_micro > 0) approaching at most at an
  // impact's speed, or as near to approaching as itself (an e = 0 impact leaves both walls of a
  // groove at u_n = 0 to rounding), each with its own rebound floor. Two balls rolling side by
  // side touch at u_n = 0 too, without v_micro: taken plastically into a cloth's microcollision,
  // their contact broke the pool break's mirror symmetry (0.13 m by 0.2 s). Between two dynamic
  // bodies too: a ball resting on two balls that roll apart bounces off both at once (one at a
  // time pushed it 2.5 cm sideways in 1 s). A face landing on a dynamic face (its patch's
  // corners as one group) is not grouped yet: resolved symmetrically, two boxes turning alike
  // sent the closest-feature walk of their exactly parallel faces into a cycle (issue 15's
  // note).
  const double first_u_n = normal_velocity(first, body(p0.a).state, body(p0.b).state);
  const bool gentle = first_u_n >= -impact_speed && first.v_micro > 0.0 && first.patch.size() < 2;
  const bool micro = gentle && !persistent();
  // Under the persistent model a gentle group is one plastic collision whose contacts are then
  // held, and only a fresh landing: a pair let go or struck already at this instant goes on
  // through collide_or_hold's rounds (a ball on the seam of two cubes, held by a group, tipped
  // off the edge and was held again, 8,675 times an ulp apart).
  if (gentle && persistent() && p0.collisions_at_t > 0) return std::nullopt;
  const double micro_join = std::max(first_u_n, 0.0) + 1e-12 * impact_speed;
  auto add_contact = [&](std::uint32_t pair, const Contact& c, const DistanceResult& dr,
                         const BodyState& s1, const BodyState& s2) {
    const double u_n = normal_velocity(c, s1, s2);
    const double v_hold = hand_over_speed(c);
    if (gentle && u_n <= micro_join && u_n >= -impact_speed && c.v_micro > 0.0) {
      // From its fourth quick round on (hold_round) a contact is no longer held after the group
      // (below): it is a microcollision, whose rebound floor lifts it clear, as on the lone path
      // (collide_or_hold). Plastic instead, a cluster whose held problem came out inconsistent
      // (three balls in a row on a floor) was struck by a group every 1e-11 s, gravity's
      // approach over a clock tick, 30,000 times and more.
      const bool floor = micro || hold_round(pairs.pair(pair), t) >= 4;
      members.push_back(Member{pair, c.a, c.b, c.point_W, c.n_W, -u_n, floor ? c.v_micro : 0.0, dr,
                               v_hold, c.patch.size() >= 2});
    } else if (!gentle && u_n < -impact_speed) {
      members.push_back(
          Member{pair, c.a, c.b, c.point_W, c.n_W, -u_n, 0.0, dr, v_hold, c.patch.size() >= 2});
    }
  };
  add_contact(index, first, first_dr, body(p0.a).state, body(p0.b).state);
  if (members.empty()) return std::nullopt;
  // Every pair within the envelope at t that reaches the collision through members' dynamic
  // bodies: the group is closed under shared bodies (one hop from the first pair only, a ball
  // dropped onto two balls resting on a floor met the floor under one of them in a group and under
  // the other alone, 2.3 cm apart in 1 s).
  // The bodies reached, in the order they are expanded; [level_begin, level_end) is this level.
  // A pair is gathered once: from the first level that holds one of its bodies.
  std::vector<BodyId> reached;
  for (BodyId id : {p0.a, p0.b}) {
    if (body(id).is_dynamic()) reached.push_back(id);
  }
  auto position = [&](BodyId id) {
    return static_cast<std::size_t>(std::find(reached.begin(), reached.end(), id) -
                                    reached.begin());
  };
  for (std::size_t level_begin = 0; level_begin < reached.size();) {
    const std::size_t level_end = reached.size();
    std::vector<std::uint32_t> others;
    for (std::size_t i = level_begin; i < level_end; ++i) {
      for (std::uint32_t q : pairs.body(reached[i]).pairs) {
        const PairSet::Pair& pq = pairs.pair(q);
        if (q != index && position(pq.a == reached[i] ? pq.b : pq.a) >= level_begin) {
          others.push_back(q);
        }
      }
    }
    std::sort(others.begin(), others.end());
    others.erase(std::unique(others.begin(), others.end()), others.end());
    level_begin = level_end;
    for (std::uint32_t q_index : others) {
      const PairSet::Pair& q = pairs.pair(q_index);
      if (!persistent() && (island(q.a) || island(q.b))) return std::nullopt;
      // A held contact is not held again (taken in at u_n = 0 by a gentle group, it was, and
      // piles of hulls stormed). On a fixed support it is a plastic member, at each point of its
      // patch: the ground takes its part of the impulse at once (struck on their free masses
      // and projected after, two cubes hit on their seam turned and knocked each other apart).
      // Between two dynamic bodies the island's plan projects it after the group.
      const bool already_held = persistent() && held_link(q_index);
      if (already_held && body(q.a).is_dynamic() && body(q.b).is_dynamic()) continue;
      const BodyState s1 = state_at(q.a), s2 = state_at(q.b);
      PairCache cache;  // fresh: the pair's own cache stays as its schedule left it
      ++stats.bound_queries;
      const DistanceResult dr =
          closest_features(pairs.geometry(q.a), Pose{s1.x_W, s1.q_WM}, pairs.geometry(q.b),
                           Pose{s2.x_W, s2.q_WM}, cache, settings().distance_max_steps);
      const DistanceResult& contact = contact_result(q, s1, s2, dr);
      if (contact.status == ContactStatus::kFailed ||
          contact.status == ContactStatus::kPenetrating ||
          contact.distance > settings().envelope_m) {
        continue;
      }
      // Sequential where the physics is: a contact whose instant of touching is still ahead
      // collides then, on its own (exact for spheres and planes, followed along the trajectories
      // otherwise). Not a pair with a held body: it collides at the envelope's instant
      // (time_to_contact), as the first did (a ball landing on two held balls struck one 6.8e-5 m
      // from touching, found the other at that gap "ahead", and left them 1.9 cm asymmetric).
      if (!gentle && contact.distance > touching_gap(q) && !island(q.a) && !island(q.b)) {
        const ToiBound ahead =
            time_to_touch(body(q.a), s1, pairs.geometry(q.a), body(q.b), s2, pairs.geometry(q.b),
                          contact, cache, world.gravity_W, settings());
        if (ahead.exact && ahead.dt > 0.0) continue;
        if (!ahead.exact && !persistent()) {
          const ImpactInstant in = refine_instant(q, s1, s2, dr, cache);
          if (in.status != InstantStatus::kNotApplicable && in.dt > 0.0) continue;
        }
      }
      const Contact c = make_contact(side(q.a, s1), side(q.b, s2), contact, settings(),
                                     world.gravity_W, /*with_patch=*/true);
      if (already_held) {
        std::vector<Vec3> points = c.patch.size() >= 2 ? c.patch : std::vector<Vec3>{c.point_W};
        if (points.size() > 4) {
          // A many-sided patch (a coin's face) by its extreme points along the plane's two axes:
          // they span the pressure the patch can take, and 32 redundant members left the group's
          // solve unconverged.
          const Vec3 t1 = c.n_W.unitOrthogonal(), t2 = c.n_W.cross(t1);
          std::vector<Vec3> extreme;
          for (const Vec3& axis : {t1, Vec3(-t1), t2, Vec3(-t2)}) {
            const Vec3* best = &points.front();
            for (const Vec3& q : points) {
              if (q.dot(axis) > best->dot(axis)) best = &q;
            }
            if (std::find(extreme.begin(), extreme.end(), *best) == extreme.end()) {
              extreme.push_back(*best);
            }
          }
          points = extreme;
        }
        for (const Vec3& point : points) {
          Member m{q_index, c.a, c.b, point, c.n_W, 0.0, 0.0, contact, 0.0, false};
          m.held = true;
          members.push_back(m);
        }
        continue;
      }
      const std::size_t before = members.size();
      add_contact(q_index, c, contact, s1, s2);
      if (members.size() == before) continue;
      for (BodyId id : {q.a, q.b}) {
        if (body(id).is_dynamic() && position(id) == reached.size()) reached.push_back(id);
      }
    }
  }
  const auto impacts =
      std::count_if(members.begin(), members.end(), [](const Member& m) { return !m.held; });
  const bool strikes_held =
      persistent() && !gentle && impacts == 1 &&
      std::any_of(members.begin(), members.end(), [](const Member& m) { return m.held; });
  if (impacts < 2 && !strikes_held) return std::nullopt;
  bool face_points = false;  // the landing spread over a face's points (below)
  if (strikes_held && first.patch.size() >= 2) {
    // A face landing on a held body: at each point of its patch, as the held face under it, so
    // the impulse spreads as the landing needs (at the patch's centre alone it turned a cube
    // landing off-centre on a resting cube).
    const auto lone = std::find_if(members.begin(), members.end(),
                                   [&](const Member& m) { return !m.held && m.pair == index; });
    if (lone != members.end()) {
      const Member landing = *lone;
      members.erase(lone);
      const BodyState& s1 = body(p0.a).state;
      const BodyState& s2 = body(p0.b).state;
      for (const Vec3& q : first.patch) {
        Member m = landing;
        m.point_W = q;
        m.approach = -(point_velocity_W(s1, q) - point_velocity_W(s2, q)).dot(first.n_W);
        members.push_back(m);
      }
      face_points = true;
    }
  }
  // A face striking a held body keeps the lone collision's path, which holds the relative
  // rotation of two dynamic faces (mark_held_rotations): as corners of a group a pyramid's boxes
  // landing on held rows turned, and its runs of 1 s did not end in 120 s.
  if (persistent()) {
    bool held = false, face = false;
    for (const Member& m : members) {
      held = held || island(m.a) || island(m.b);
      face = face || m.face;
    }
    if (held && face && !strikes_held) return std::nullopt;
  }

  // The group's bodies, once each.
  std::vector<BodyId> ids;
  auto index_of = [&](BodyId id) {
    auto it = std::find(ids.begin(), ids.end(), id);
    if (it != ids.end()) return static_cast<int>(it - ids.begin());
    ids.push_back(id);
    return static_cast<int>(ids.size() - 1);
  };
  std::vector<GroupContact> contacts;
  for (const Member& m : members) {
    const Material& material = world.material(m.a, m.b);
    contacts.push_back(
        GroupContact{index_of(m.a), index_of(m.b), m.point_W, m.n_W, material.friction,
                     gentle || (m.held && !strikes_held) ? 0.0 : material.restitution, m.floor});
  }
  std::vector<GroupBody> bodies;
  for (BodyId id : ids) {
    const Body& b = body(id);
    const BodyState s = state_at(id);
    GroupBody g;
    g.inv_mass = b.is_dynamic() ? b.mass.inv_mass : 0.0;
    g.inv_inertia_W = b.is_dynamic() ? inverse_inertia_W(b, s.q_WM) : Mat3::Zero();
    g.x_W = s.x_W;
    g.v_W = s.v_W;
    g.w_W = s.w_W;
    bodies.push_back(g);
  }
  GroupOptions options;
  // The scene's law. Newton's kinematic law is not offered to groups (it can create energy at a
  // lone contact already): a group under it is resolved by Poisson's.
  // A face's points share its impulse in no one way (they are redundant): Stronge's per-point
  // works then depend on the share, and a cube landing off-centre on a resting cube turned at
  // 0.31 rad/s under them. Such a group is resolved by Poisson's law, whose expansion is the
  // compression's own share scaled by e (the top leaves at e u, exactly).
  options.law = settings().restitution_law == RestitutionLaw::kStronge && !face_points
                    ? RestitutionLaw::kStronge
                    : RestitutionLaw::kPoisson;
  const GroupResult r = resolve_group(bodies, contacts, options);
  if (strikes_held) {
    // A solve that broke down leaves the lone path to it. (Not one merely short of its
    // tolerance: a face held at four coplanar points makes the floor's share singular, and the
    // solver reports that as unconverged with the answer exact to 1e-9.)
    bool finite = true;
    for (std::size_t j = 0; j < ids.size(); ++j) {
      finite = finite && r.v_W[j].allFinite() && r.w_W[j].allFinite();
    }
    if (!finite) return std::nullopt;
  }
  std::vector<double> kinetic_before;
  for (BodyId id : ids) {
    commit(id, t);
    kinetic_before.push_back(body(id).is_dynamic() ? kinetic_energy(body(id), body(id).state)
                                                   : 0.0);
  }
  for (std::size_t j = 0; j < ids.size(); ++j) {
    Body& b = body(ids[j]);
    if (!b.is_dynamic()) continue;
    b.state.v_W = r.v_W[j];
    b.state.w_W = r.w_W[j];
  }
  ++stats.groups;
  stats.group_contacts += members.size();
  if (!r.converged) ++stats.group_unconverged;

  // Each pair's round at this instant (collide_or_hold), before the records below stamp it.
  std::vector<int> rounds;
  for (const Member& m : members) rounds.push_back(hold_round(pairs.pair(m.pair), t));
  std::vector<CollisionRecord> records;
  std::vector<bool> counted(ids.size(), false);
  for (std::size_t i = 0; i < members.size(); ++i) {
    CollisionRecord record;
    record.t = t;
    record.a = members[i].a;
    record.b = members[i].b;
    record.p_W = members[i].point_W;
    record.n_W = members[i].n_W;
    record.impulse_W = r.impulse_W[i];
    record.approach_speed = members[i].approach;
    record.group = true;
    // The group's energy change, each body's once: on the first record that names it.
    for (BodyId id : {members[i].a, members[i].b}) {
      const std::size_t j = static_cast<std::size_t>(index_of(id));
      if (counted[j] || !body(id).is_dynamic()) continue;
      counted[j] = true;
      record.energy_change += kinetic_energy(body(id), body(id).state) - kinetic_before[j];
    }
    pairs.pair(members[i].pair).last_collision_t = t;
    record.kind = micro ? CollisionKind::kMicrocollision : CollisionKind::kCollision;
    ++(micro ? stats.microcollisions : stats.collisions);
    if (observer) observer->on_collision(record);
    records.push_back(record);
  }
  // Bodies and pairs refreshed once the whole group is committed (`p0` may move here).
  if (persistent()) {
    // As after a lone collision (collide_or_hold): a contact leaving slower than its hand-over
    // speed is held, first, every one; then the islands of the others are planned again.
    std::vector<bool> held(members.size(), false);
    for (std::size_t i = 0; i < members.size(); ++i) {
      const Member& m = members[i];
      held[i] = m.held;  // held already: its island is planned again through the others
      if (m.held || rounds[i] >= 4) continue;
      if (held_link(m.pair)) {  // held already through another point of its patch
        held[i] = true;
        continue;
      }
      const Vec3 u = point_velocity_W(body(m.a).state, m.point_W) -
                     point_velocity_W(body(m.b).state, m.point_W);
      if (!(u.dot(m.n_W) < m.v_hold)) continue;
      if (const std::optional<HeldLink> link = link_of(m.pair, m.dr)) {
        hold(m.pair, *link, m.dr, t,
             m.approach > m.v_hold * (1.0 + settings().microcollision_speed_slack));
        held[i] = true;
      }
    }
    for (std::size_t i = 0; i < members.size(); ++i) {
      if (!held[i]) after_collision(records[i], t);
    }
  } else {
    for (const CollisionRecord& record : records) refresh_after_collision(record, t);
  }
  return records.front();
}

}  // namespace palpable
