#pragma once
// Conservative time-of-impact bounds and exact times of impact (DESIGN.md §3).
//
// The slab argument: with d the current distance and d̂ the unit direction from body 1's closest
// point to body 2's (d̂ = -n), the two bodies cannot touch before the slab between them, normal to
// d̂, has closed. Each body's support along d̂ moves at most at its centre's velocity along d̂ plus
// a rotational term, so the gap obeys d(t) >= d - b t - 1/2 a t^2 with
//   b = (v1 - v2) . d̂ + rot1 + rot2   (closing speed)      a = (g1 - g2) . d̂   (closing accel.)
// The bound aims at a target gap d_target inside the envelope (default envelope / 2), so an exact
// bound lands at d ~ d_target rather than at d = 0 where the normal is ill-conditioned. With
// Δ = d - d_target it solves 1/2 a t^2 + b t - Δ = 0 by branch:
//   b > 0:           t = 2Δ / (b + sqrt(b^2 + 2 a Δ))      (no cancellation; valid for any a)
//   b <= 0, a > 0:   t = (-b + sqrt(b^2 + 2 a Δ)) / a
//   otherwise, or a negative discriminant: no contact within this ballistic phase (+inf).
// (2Δ / (b + sqrt(...)) alone is wrong for b < 0: it cancels, is NaN at Δ = 0 and overshoots for
// tiny Δ.)
//
// Rotational terms (an upper bound on the speed, along d̂, of a surface point relative to the
// body's reference point, over the whole coming interval):
//   dynamic sphere: 0 (its shape is invariant under rotation about its centre);
//   dynamic polyhedron or compound: min(ω̄, |ω_fixed x d̂| + ω_free) ρ (ω̄ from DESIGN.md §2,
//   ρ the maximum radius; see ToiMotion: spin about d̂ itself does not count);
//   fixed body: 0;
//   kinematic body spinning at Ω about an axis: |Ω x d̂| r_axis, r_axis the largest distance from
//   the axis of the relevant surface points — exactly 0 when Ω is parallel to d̂ (a platter or
//   halfspace spinning about its own normal), tested before multiplying, so never 0 x inf.
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"
#include "distance/closest_features.hpp"

namespace palpable {

// How one body moves over the coming interval, as far as the bound needs it.
struct ToiMotion {
  Vec3 v_W = Vec3::Zero();   // velocity of the reference point (centre of mass, or the
                             // kinematic axis point) [m/s]
  Vec3 a_W = Vec3::Zero();   // its constant acceleration: gravity for a dynamic body, 0
                             // for fixed and kinematic bodies [m/s^2]
  double accel_slack = 0.0;  // how far the true acceleration may be from a_W [m/s^2] (a body
                             // held in contact whose motion is integrated)
  // Dynamic body: the rotational term is omega_bound * rotation_radius (0 if either is 0).
  // Kinematic body: |spin_W x d̂| * rotation_radius (0 if the cross product is 0).
  bool kinematic = false;
  double omega_bound = 0.0;      // ω̄ [rad/s] (dynamic)
  // Dynamic: over the interval ω(t) = omega_fixed_W + a part of magnitude <= omega_free, so only
  // |omega_fixed_W x d̂| + omega_free can move a surface point along d̂ (spin about d̂ cannot
  // close the gap): a spherical body's ω is constant (omega_free 0); an axisymmetric body's
  // precesses about its angular momentum L (the part along L is fixed, the rest turns at a
  // constant magnitude); an asymmetric body's is bounded by ω̄ alone (omega_fixed 0). Left at
  // its default (infinite), only ω̄ counts: a motion that does not know its ω (a held body's).
  Vec3 omega_fixed_W = Vec3::Zero();
  double omega_free = kInfinity;
  Vec3 spin_W = Vec3::Zero();    // Ω [rad/s] (kinematic)
  double rotation_radius = 0.0;  // ρ or r_axis [m]; may be +inf (halfspace)
};

// Upper bound on the speed along `d_hat` of the body's surface relative to its reference point.
double rotational_term(const ToiMotion& motion, const Vec3& d_hat);

struct ToiBound {
  double dt = kInfinity;  // [s] from now: the gap stays >= d_target for at least this long
  bool exact = false;     // dt is the exact time the gap reaches d_target (closed form): the
                          // scheduler needs no recheck before it
  bool floored = false;   // the conservative value was below settings.toi_min_progress_s and was
                          // raised to it, or to the time the gap (or d_target, inside the
                          // target gap) can close, if that is sooner (count these)
  double closing_speed = 0.0;  // b [m/s]
  double closing_accel = 0.0;  // a [m/s^2]
};

// Smallest t >= 0 with 1/2 a t^2 + b t = delta (delta > 0), by the branches above; +inf if none.
double solve_gap_closing(double a, double b, double delta);
// Inside the target gap (delta <= 0) and receding (b < 0), the gap stays above the parabola
// d - b t - a t^2 / 2, which is at least its present value until it comes back down to it: the
// time it falls back to the target if it rises above it, else -2b/a back to the present gap;
// +inf without a closing acceleration (a <= 0).
double solve_return_to_gap(double a, double b, double delta);

// The single halfspace piece of a geometry, or nullptr.
const ShapeGeometry::Piece* halfspace(const ShapeGeometry& g);

// A polyhedral body (every piece a polyhedron) above the plane of `half`, a halfspace piece of a
// body at state `plane` that does not move: its gap is the least height of its vertices, and
// each vertex's height obeys
//   h(t) >= h - b t - A t^2 / 2,   b = -n . (v + ω x r)  (its closing speed now, exact),
//   A = -n . accel_W + accel_slack + |r| spin,
// r the vertex from the centre of mass, accel_W the centre of mass's acceleration (within
// accel_slack of it over the interval), `spin` a bound on ω^2 + |ω'| over the interval (ω̄^2 +
// ᾱ). Returns the least time over the vertices (the branches of toi_bound) at which one can
// come within d_target of the plane; -1 if a piece is not a polyhedron or a vertex lies below
// the plane (not this bound's case); 0 if a vertex can be there now.
double vertex_bound_above_plane(const BodyState& s, const ShapeGeometry& g, const BodyState& plane,
                                const ShapeGeometry::Piece& half, const Vec3& accel_W,
                                double accel_slack, double spin, double d_target);

// How a body may move over an interval, for vertex_bound_above_face: its centre of mass's
// acceleration within accel_slack of accel_W, |ω| <= w_bound and |ω'| <= alpha_bound throughout
// (all zero for a body that does not move).
struct VertexMotion {
  Vec3 accel_W = Vec3::Zero();
  double accel_slack = 0.0;
  double w_bound = 0.0;
  double alpha_bound = 0.0;
};

// A polyhedral body A (state sa, geometry ga, motion ma) above the plane of face `face` of
// `piece`, a polyhedral piece of a body B (state sb, motion mb) that moves too: B lies below that
// plane, so A cannot touch B before a vertex of A reaches it. With n the plane's normal and
// rho = q - x_B a vertex q of A from B's centre of mass, its height h = n . rho - d obeys
//   h'' = n'' . rho + 2 n' . rho' + n . rho'',   |n'| <= w_B, |n''| <= w_B^2 + alpha_B,
//   n . rho'' >= n0 . (a_A - a_B) - w_B t |a_A - a_B| - slacks - (w_A^2 + alpha_A) |r_A|,
// r_A the vertex from A's centre, |rho'| <= U = |v_A - v_B| + w_A |r_A| + (|a_A| + |a_B| +
// slacks) t and |rho| <= |rho0| + U t over [0, t]: h(t) >= h - b t - A t^2 / 2 with b its exact
// closing speed now. Bounded over horizons of 1e-5, 1e-4, 1e-3 and 1e-2 s (each bound, capped at
// its horizon, holds), the largest is returned: the least time at which a vertex can come within
// d_target of the plane, at most 1e-2 s. -1 if a piece of A is not a polyhedron or a vertex of A
// lies below the plane (not this bound's case); 0 if a vertex can be there now.
double vertex_bound_above_face(const BodyState& sa, const ShapeGeometry& ga, const VertexMotion& ma,
                               const BodyState& sb, const ShapeGeometry::Piece& piece, int face,
                               const VertexMotion& mb, double d_target);

// The conservative bound from the closest-feature result (status separated or touching; any other
// status gives dt = 0). d_target [m] < envelope. A pair already inside the target gap and
// receding (closing speed b < 0) gets the time its gap can be back at its present value,
// -2b/a (infinite without a closing acceleration a): no contact is possible before it.
ToiBound toi_bound(const ToiMotion& motion1, const ToiMotion& motion2,
                   const DistanceResult& closest, double d_target, const Settings& settings);

// Exact time for two spheres to come within d_target of each other when their relative motion is
// linear (both dynamic under the same gravity, or both unaccelerated): centres c1, c2, relative
// velocity v1 - v2, radii r1, r2. The earliest root of |c1 - c2 + (v1 - v2) t| = r1 + r2 +
// d_target.
ToiBound exact_toi_sphere_sphere(const Vec3& c1_W, const Vec3& v1_W, double r1, const Vec3& c2_W,
                                 const Vec3& v2_W, double r2, double d_target);

// Exact time for a sphere (centre c, velocity v, acceleration g) to come within d_target of a
// plane n . x = offset moving at velocity u_plane whose motion maps the plane onto itself (fixed,
// or spinning about n): a parabola in the height.
ToiBound exact_toi_sphere_plane(const Vec3& c_W, const Vec3& v_W, const Vec3& g_W, double radius,
                                const Vec3& n_W, double offset_W, const Vec3& plane_velocity_W,
                                double d_target);

// The ToiMotion of a body in `state` (DESIGN.md §3): dynamic bodies move at v under gravity with
// the rotational term ω̄ ρ (ω̄ = angular_speed_bound, ρ = ShapeGeometry::rotation_radius(), 0 for
// a sphere about its centre); fixed bodies do not move; kinematic bodies translate at their axis
// velocity and spin at Ω, with r_axis the distance from the axis to the body's centre plus ρ —
// or, for a halfspace, the distance from the axis to the other body's centre plus that body's
// reach `other_reach_m` (the part of the plane the other body can touch; valid while the other
// body stays within that reach of where it is now).
ToiMotion toi_motion(const Body& body, const BodyState& state, const ShapeGeometry& geometry,
                     const Vec3& gravity_W, const Vec3& other_center_W, double other_reach_m,
                     const Settings& settings);

// The time-of-impact bound of a pair of bodies in the given states (at the same time), from their
// closest-feature result, aimed at d_target = envelope / 2. Exact where a closed form exists (two
// dynamic spheres; a dynamic sphere against a fixed halfspace or a kinematic halfspace whose
// rotation is about its own normal), conservative otherwise (floored and counted by
// settings.toi_min_progress_s).
ToiBound time_of_impact(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                        const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                        const DistanceResult& closest, const Vec3& gravity_W,
                        const Settings& settings);

// The same for a pair whose last query filled `cache.piece_results` (a compound in the pair): the
// smallest bound over every piece pair, each from its own distance and direction; otherwise as
// above.
ToiBound time_of_impact(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                        const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                        const DistanceResult& closest, const PairCache& cache,
                        const Vec3& gravity_W, const Settings& settings);

// Of two dynamic bodies in free flight under the same gravity, each with the same inertia about
// every axis (a cube, a ball: its angular velocity stays what it is): a time before which their
// gap cannot close by `closing` [s], from their motion relative to each other, which a bound from
// each body's own rotation does not see (two cubes tumbling together, one on the other). Seen
// from body a's frame, rotating at w_a about its centre of mass, a point of b at R_b r moves at
// (dv - w_a x dx(t)) + (w_b - w_a) x R_b r with dx(t) = dx + dv t: no faster than
// |dv - w_a x dx| + |w_b - w_a| reach_b + |w_a| |dv| t. The longer of the two frames' times; 0
// where a body's inertia is not the same about every axis.
double co_flying_time(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                      const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                      double closing);

// The time until the pair touches (gap 0) [s], to place an impact at the instant of contact
// rather than where the bound stopped (half an envelope up): exact where time_of_impact is exact,
// otherwise the conservative bound aimed at gap 0 and never floored — a lower bound on the
// instant, which repeated checks approach (conservative advancement).
ToiBound time_to_touch(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                       const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                       const DistanceResult& closest, const PairCache& cache,
                       const Vec3& gravity_W, const Settings& settings);

}  // namespace palpable
