// Pair queries and the bounds that schedule each pair's next check (DESIGN.md §3): the closest
// features of a pair, the contact they make, and when the pair can next touch - in free flight,
// with a held body (its island's motion bound), or for two bodies flying together.
#include "scheduler/simulation_impl.hpp"

#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "distance/impact_instant.hpp"
#include "distance/toi_bound.hpp"
#include "impulse/microcollision.hpp"
#include "scheduler/island.hpp"
#include "scheduler/pair_set.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace palpable {

DistanceResult Simulation::Impl::query(PairSet::Pair& p, const BodyState& s1, const BodyState& s2) {
  DistanceResult dr =
      closest_features(pairs.geometry(p.a), Pose{s1.x_W, s1.q_WM}, pairs.geometry(p.b),
                       Pose{s2.x_W, s2.q_WM}, p.cache, settings().distance_max_steps);
  stats.feature_steps += static_cast<std::uint64_t>(dr.steps);
  if (dr.status == ContactStatus::kFailed && !p.cache.compound) {
    // The walk cycled from the cached features (degenerate, exactly parallel features at a gap
    // of a few ulps can): once more from a cold start before it counts as a failure.
    p.cache.single = FeaturePair{};
    dr = closest_features(pairs.geometry(p.a), Pose{s1.x_W, s1.q_WM}, pairs.geometry(p.b),
                          Pose{s2.x_W, s2.q_WM}, p.cache, settings().distance_max_steps);
    stats.feature_steps += static_cast<std::uint64_t>(dr.steps);
  }
  if (dr.status == ContactStatus::kPenetrating) {
    ++stats.penetrations;
    // NaN (unknown: polyhedra beyond the rounding check's budget) leaves it as it is.
    if (dr.penetration_depth > stats.deepest_penetration_m) {
      stats.deepest_penetration_m = dr.penetration_depth;
    }
  }
  // DESIGN.md §5 step 6: no penetration deeper than the envelope (where a polyhedron pair's
  // depth is unknown - beyond the separating-axis search's budget - any overlap of one fails).
  PALPABLE_DCHECK(
      dr.status != ContactStatus::kPenetrating || dr.penetration_depth <= settings().envelope_m,
      "bodies " + body(p.a).name + " and " + body(p.b).name +
          " overlap at t = " + std::to_string(now));
  return dr;
}

bool Simulation::Impl::held_piece(const PairSet::Pair& p, const DistanceResult& r) const {
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

const DistanceResult& Simulation::Impl::contact_result(const PairSet::Pair& p, const BodyState& s1,
                                                       const BodyState& s2,
                                                       const DistanceResult& dr) const {
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

bool Simulation::Impl::lifting(const PairSet::Pair& p, const Contact& c, double t) {
  if (!(p.lifted && p.last_collision_t == t)) return false;
  return !(c.u_n < -rounding_speed(c));
}

Island::MotionBound Simulation::Impl::held_bound(const Island& is, BodyId id,
                                                 const BodyState& s) const {
  Island::MotionBound b = is.bound(static_cast<std::size_t>(is.index_of(id)));
  if (!std::isfinite(b.w_bound)) {
    // A uniform motion that turns ever faster and has no end (a cylinder rolling down a
    // halfspace, or rolling on the level with an angular acceleration of rounding): its bound
    // over all time is infinite, and every pair of its body was checked at each tick of the
    // clock (a log resting on a log, 1.5 million checks in 0.7 ms). A check is never scheduled
    // past the body's broad-phase horizon, where the pair is bounded again: the bound to there.
    const double left = pairs.body(id).horizon - s.t;
    if (std::isfinite(left) && left >= 0.0) {
      b.w_bound = s.w_W.norm() + (b.alpha_W.norm() + b.alpha_slack) * left;
    }
  }
  return b;
}

ToiMotion Simulation::Impl::motion_for(BodyId id, const BodyState& s, const BodyState& other,
                                       BodyId other_id) const {
  if (const Island* is = planned_island(id)) {
    const Island::MotionBound b = held_bound(*is, id, s);
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

ToiBound Simulation::Impl::held_time_of_impact(const PairSet::Pair& p, const BodyState& s1,
                                               const BodyState& s2, const DistanceResult& dr,
                                               bool halve_gap) const {
  const ToiMotion m1 = motion_for(p.a, s1, s2, p.b);
  const ToiMotion m2 = motion_for(p.b, s2, s1, p.a);
  // A pair already inside the target gap and moving apart, or at rest against a fixed body (let
  // go within the envelope: a ball released from a wall it still nearly touches), is checked
  // again before it can close half of what is left, not at once: aimed at half an envelope, its
  // bound was zero, and such a pair was checked at every tick of the clock (8.7 million checks
  // in 0.3 s of a ball in a corner). Two dynamic bodies at rest within the envelope are still
  // checked at once: a box landing on two held boxes meets the second as it meets the first, in
  // one group (aimed at half its gap, the second was met 1.4 ms later, and the pyramid of four
  // rows that followed did not end).
  const double d_target = derived_target_gap(settings());
  auto target = [&](const DistanceResult& r) {
    return halve_gap && r.distance > 0.0 ? std::min(d_target, 0.5 * r.distance) : d_target;
  };
  if (p.cache.piece_results().empty()) {
    ToiBound bound = toi_bound(m1, m2, dr, target(dr), settings());
    if (bound.floored &&
        (dr.status == ContactStatus::kSeparated || dr.status == ContactStatus::kTouching)) {
      // A held body above a fixed plane, a corner a few nanometres over it while the body rocks
      // or slides on another: the rotational term (its angular-speed bound times its reach) made
      // the bound the time to close that gap at once, and the pair was checked every 3e-11 s
      // (the floor-p15 pair of a pile of 200 hulls, seed 1: 319,494 checks in 0.3 s, 92 % of the
      // pile's floored bounds were such pairs). Its vertices bound it, as a body's in free flight
      // (time_of_impact), by what each truly does: its speed along the normal now, and a bound on
      // its acceleration from the island's (the centre of mass's, and w^2 + |w'| times its
      // distance from the centre of mass). Both bounds are lower bounds on the same instant.
      double by_vertices = held_vertex_bound(p, s1, s2, target(dr));
      // And a vertex above a face of a body that moves too: two held hulls of a pile, in
      // islands of their own, a vertex of one resting 1e-11 to 1e-7 m over a face of the other
      // with nothing pressing them together, were checked at the floor 493,000 times in 0.3 s
      // (the p44-p197 pair of 200 hulls, seed 1, on the path the next commit's sliding rule takes).
      if (by_vertices < 0.0) by_vertices = held_face_bound(p, s1, s2, dr, target(dr));
      if (by_vertices > bound.dt) {
        bound.dt = by_vertices;
        bound.floored = false;
      }
    }
    return bound;
  }
  ToiBound best;
  for (const DistanceResult& piece : p.cache.piece_results()) {
    if (held_piece(p, piece)) continue;
    const ToiBound b = toi_bound(m1, m2, piece, target(piece), settings());
    if (b.dt < best.dt) best = b;
  }
  return best;
}

double Simulation::Impl::held_vertex_bound(const PairSet::Pair& p, const BodyState& s1,
                                           const BodyState& s2, double d_target) const {
  for (int side = 0; side < 2; ++side) {
    const BodyId id = side == 0 ? p.a : p.b, plane_id = side == 0 ? p.b : p.a;
    const BodyState& s = side == 0 ? s1 : s2;
    const BodyState& ps = side == 0 ? s2 : s1;
    const ShapeGeometry::Piece* half = halfspace(pairs.geometry(plane_id));
    if (body(plane_id).motion != MotionKind::kFixed || !half) continue;
    const Island* is = planned_island(id);
    if (!is) continue;
    const Island::MotionBound b = held_bound(*is, id, s);
    return vertex_bound_above_plane(s, pairs.geometry(id), ps, *half, b.a_W, b.a_slack,
                                    b.w_bound * b.w_bound + b.alpha_W.norm() + b.alpha_slack,
                                    d_target);
  }
  return -1.0;
}

double Simulation::Impl::held_face_bound(const PairSet::Pair& p, const BodyState& s1,
                                         const BodyState& s2, const DistanceResult& dr,
                                         double d_target) const {
  const bool face_on_a =
      dr.feature1.kind == FeatureKind::kFace && dr.feature2.kind == FeatureKind::kVertex;
  const bool face_on_b =
      dr.feature2.kind == FeatureKind::kFace && dr.feature1.kind == FeatureKind::kVertex;
  if (!face_on_a && !face_on_b) return -1.0;
  const BodyId face_id = face_on_a ? p.a : p.b, vertex_id = face_on_a ? p.b : p.a;
  const BodyState& sf = face_on_a ? s1 : s2;
  const BodyState& sv = face_on_a ? s2 : s1;
  // The face's body must be that one piece, all below the face's plane (a compound's other
  // pieces need not be).
  const std::vector<ShapeGeometry::Piece>& pieces = pairs.geometry(face_id).pieces();
  const int piece = face_on_a ? dr.piece1 : dr.piece2;
  if (pieces.size() != 1 || piece != 0) return -1.0;
  // Each body's motion over the coming interval: its island's bounds, free flight's (gravity,
  // its angular-speed bound, and the torque-free bound on its angular acceleration), or none.
  auto motion = [&](BodyId id, const BodyState& s, const BodyState& other,
                    BodyId other_id) -> std::optional<VertexMotion> {
    VertexMotion m;
    if (body(id).motion == MotionKind::kFixed) return m;
    if (const Island* is = planned_island(id)) {
      const Island::MotionBound b = held_bound(*is, id, s);
      m.accel_W = b.a_W;
      m.accel_slack = b.a_slack;
      m.w_bound = b.w_bound;
      m.alpha_bound = b.alpha_W.norm() + b.alpha_slack;
      return m;
    }
    if (!in_free_flight(id)) return std::nullopt;
    const Vec3& I = body(id).mass.principal_moments;
    m.accel_W = world.gravity_W;
    m.w_bound = motion_for(id, s, other, other_id).omega_bound;
    m.alpha_bound = I.minCoeff() > 0.0
                        ? m.w_bound * m.w_bound * (I.maxCoeff() - I.minCoeff()) / I.minCoeff()
                        : kInfinity;
    return m;
  };
  const std::optional<VertexMotion> mf = motion(face_id, sf, sv, vertex_id);
  const std::optional<VertexMotion> mv = motion(vertex_id, sv, sf, face_id);
  if (!mf || !mv) return -1.0;
  const int face = face_on_a ? dr.feature1.index : dr.feature2.index;
  return vertex_bound_above_face(sv, pairs.geometry(vertex_id), *mv, sf,
                                 pieces[static_cast<std::size_t>(piece)], face, *mf, d_target);
}

double Simulation::Impl::next_check_time(const PairSet::Pair& p, const BodyState& s1,
                                         const BodyState& s2, const DistanceResult& dr, double t,
                                         const Contact* known) {
  const double floor = progress_floor(t);
  if (dr.status == ContactStatus::kFailed) {
    ++stats.distance_failures;
    return t + floor;
  }
  // Of a contact within the envelope: neither approaching nor accelerated together (`resting`);
  // moving apart faster than the still speed, or resting against a fixed or kinematic body
  // (`halve_gap`, see held_time_of_impact).
  bool resting = false, halve_gap = false;
  const bool one_known = !body(p.a).is_dynamic() || !body(p.b).is_dynamic();
  auto within_envelope = [&](const Contact& c) {
    resting = c.g_n == 0.0;
    halve_gap = c.u_n > settings().still_speed_mps || (one_known && c.u_n >= 0.0 && resting);
  };
  if (known) {
    if (dr.status == ContactStatus::kPenetrating) return t + floor;
    within_envelope(*known);
  } else {
    const DistanceResult& contact = contact_result(p, s1, s2, dr);
    if (contact.status == ContactStatus::kPenetrating ||
        contact.distance <= settings().envelope_m) {
      const Contact c = make_contact(side(p.a, s1), side(p.b, s2), contact, settings(),
                                     world.gravity_W, /*with_patch=*/false);
      if (approaching(c) && !lifting(p, c, t)) return t;
      if (contact.distance <= touching_gap(p) && !lifting(p, c, t)) {
        // At the instant of contact a corner of the patch may still approach (see check_pair).
        const Contact with_patch = make_contact(side(p.a, s1), side(p.b, s2), contact, settings(),
                                                world.gravity_W, /*with_patch=*/true);
        if (patch_approaching(with_patch, s1, s2)) return t;
      }
      if (contact.status == ContactStatus::kPenetrating) return t + floor;
      within_envelope(c);
    }
  }
  ToiBound bound =
      island(p.a) || island(p.b)
          ? held_time_of_impact(p, s1, s2, dr, halve_gap)
          : time_of_impact(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2, pairs.geometry(p.b),
                           dr, p.cache, world.gravity_W, settings());
  // Under the persistent model, only where both bodies fly (see below).
  const bool ballistic = !persistent() || (in_free_flight(p.a) && in_free_flight(p.b));
  if (ballistic && !bound.exact && (bound.floored || bound.dt < floor) &&
      dr.status == ContactStatus::kSeparated) {
    // A floored bound (the rotational term) near contact: the certified vertex model
    // (distance/impact_instant.hpp) keeps the pair from closing even half of its gap for
    // longer, and grows with the gap as the contact lifts off. An impact applied at the instant
    // of contact (DESIGN.md §8.5) leaves a pair a few ulps apart, where the floor either carried
    // it into overlap (a box struck at one corner, its other corners still landing) or stormed.
    // (Free flight only, as the model: not under the persistent model, whose held bodies fly
    // otherwise, and whose pair resting within the envelope is held where it is: with the step,
    // a box started sliding half an envelope above a floor at mu 1e3 fell a quarter envelope
    // before its contact was found, and slid 2.2 mm where it stops within 0.15 mm.) Two dynamic
    // bodies that both fly are the model's case under either: nothing holds or presses them
    // together. (Left to the floor, two hulls of a pile of 50 (seed 3) falling side by side,
    // 1.9e-6 m apart and parting at 7e-7 m/s while turning, were checked every 1e-6 s, 9,400
    // times; a pile of 200 hulls counted a million floored bounds in 0.5 s.)
    const double certified =
        certified_step(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2, pairs.geometry(p.b), dr,
                       p.cache, world.gravity_W, settings(), 0.5 * dr.distance);
    if (certified > bound.dt) {
      bound.dt = certified;
      bound.floored = false;
    }
  }
  if (ballistic && !bound.exact && (bound.floored || bound.dt < floor) &&
      dr.status == ContactStatus::kSeparated && body(p.a).is_dynamic() && body(p.b).is_dynamic() &&
      in_free_flight(p.a) && in_free_flight(p.b)) {
    // Two cubes tumbling off a ramp's edge together, one on the other 5e-12 m apart, bounded by
    // each one's own rotation, were checked every 6e-12 s: 2.6 million checks.
    const double together = co_flying_time(body(p.a), s1, pairs.geometry(p.a), body(p.b), s2,
                                           pairs.geometry(p.b), 0.5 * dr.distance);
    if (together > bound.dt) {
      bound.dt = together;
      bound.floored = false;
    }
  }
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
  if (bound.floored && dr.status != ContactStatus::kPenetrating && in_free_flight(p.a) &&
      in_free_flight(p.b) && s1.w_W.isZero(0.0) && s2.w_W.isZero(0.0) &&
      world.gravity_W.squaredNorm() > 0.0 &&
      std::abs(dr.n_W.dot(world.gravity_W.normalized())) > kSupportCosine) {
    // Two dynamic bodies in free flight without rotation, one above the other (a box resting on
    // a box, carried by the microcollisions of the one below) share gravity, so they move uniformly
    // relative to each other: their distance shrinks no faster than their relative speed, and only
    // a collision of one of them (which re-bounds the pair) changes that. The bound's aim at half
    // an envelope is meaningless for a pair already closer (it re-checked such a pair at the
    // progress floor, a million times a second).
    // (Where that is sooner than the floor - touching to rounding while sliding - the floor.)
    const double speed = (s1.v_W - s2.v_W).norm();
    if (speed == 0.0) return kInfinity;
    if (dr.distance * (1.0 - 1e-9) > floor * speed) {
      return t + dr.distance * (1.0 - 1e-9) / speed;
    }
  }
  return t + std::max(bound.dt, bound.exact ? 0.0 : tick);
}

void Simulation::Impl::rebound(std::uint32_t index, double t) {
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

}  // namespace palpable
