#pragma once
// Resisting angular impulses at a contact: the two couples a point impulse cannot carry.
//
//  - Torsional friction. Over a contact patch (a face or an edge resting on a face), the pressure
//    spread over the patch resists relative spin about the normal n. With Coulomb friction mu and
//    the pressure uniform over the patch, a normal impulse P_n can take out at most
//    mu P_n r_eff of angular momentum about n, where r_eff is the mean distance of the patch from
//    the centre of pressure (a disc of radius R about its centre: 2R/3). A coin spinning flat on a
//    table then slows at the constant rate mu m g r_eff / I_n, the continuous-contact result.
//  - Rolling resistance. A rolling body's contact deforms and its pressure moves ahead of the
//    contact point by a length d (the material's rolling_resistance [m]), a couple d N against
//    the relative rolling. Per collision: at most d P_n about the in-plane relative rotation. A
//    solid sphere rolling on a plane then decelerates at 5 d g / (7 r).
//
// Both are the same operation: an angular impulse Delta L = -tau a about a unit axis a on body 1
// (and -Delta L on body 2), tau = min(budget, |s| / k) with s = a . (w1 - w2) the relative spin
// about a and k = a . (I1^-1 + I2^-1) a. The cap |s| / k is what stops the spin exactly: never
// reversed, and the kinetic energy change -tau |s| + tau^2 k / 2 is never positive.
#include "core/types.hpp"
#include "impulse/collision_matrix.hpp"

#include <vector>

namespace palpable {

struct AngularImpulse {
  Vec3 L_W = Vec3::Zero();  // angular impulse on body 1 [N m s] (body 2 receives -L_W)
  // Kinetic energy change [J], <= 0: of both bodies if both are dynamic, of body 1 relative to
  // body 2 otherwise (exact in the lab frame when body 2 does not turn).
  double energy_change = 0.0;
  bool stopped = false;  // the relative spin about the axis was taken out entirely
};

// The resisting angular impulse about the unit axis `axis_W` with at most `budget` [N m s].
// Bodies with inv_inertia_W = 0 (fixed, kinematic) do not turn. Zero if nothing can turn or
// nothing spins.
AngularImpulse resisting_angular_impulse(const Vec3& axis_W, const ContactBody& body1,
                                         const ContactBody& body2, double budget);

// Applies L_W to body 1 and -L_W to body 2: w1 += I1^-1 L, w2 -= I2^-1 L.
void apply_angular_impulse(const Vec3& L_W, ContactBody& body1, ContactBody& body2);

// Mean distance of a convex polygon (vertices in order, in the plane normal to n_W) from a point
// p_W of its plane inside it, under uniform pressure: the integral of |x - p| over the area,
// divided by the area [m]. A segment (two vertices) gives the mean over its length. Exact
// (closed-form integral over the fan of triangles from p).
double mean_distance_over_patch(const std::vector<Vec3>& patch_W, const Vec3& n_W, const Vec3& p_W);

}  // namespace palpable
