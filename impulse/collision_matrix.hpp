#pragma once
// The collision matrix K and the world-frame side of a collision (DESIGN.md §4; Mirtich, PhD
// thesis 1996, §4.2): plain velocity data in, impulse and new velocities out. No shapes, no
// distance queries — the caller supplies the contact point offsets and the contact normal.
//
// Frames: everything here is world (_W) except the contact frame C = (t1, t2, n), n from body 2
// to body 1, with R_WC = [t1 t2 n]. Fixed and kinematic bodies have infinite mass: inv_mass = 0
// and inv_inertia_W = 0, while their velocity field (v_W, w_W) still enters u.
#include "core/settings.hpp"
#include "core/types.hpp"
#include "impulse/collision_integrator.hpp"

namespace palpable {

// One body's share of a contact, as plain data.
struct ContactBody {
  double inv_mass = 0.0;              // [1/kg]; 0 for fixed and kinematic bodies
  Mat3 inv_inertia_W = Mat3::Zero();  // world-frame inverse inertia [1/(kg m^2)]; 0 if infinite
  Vec3 v_W = Vec3::Zero();            // centre-of-mass velocity [m/s]
  Vec3 w_W = Vec3::Zero();            // angular velocity [rad/s]
  Vec3 r_W = Vec3::Zero();            // contact point minus centre of mass [m]
};

// K = (1/m1 + 1/m2) 1 - [r1]x I1^-1 [r1]x - [r2]x I2^-1 [r2]x, so that du = K dp (world frame).
Mat3 collision_matrix_W(const ContactBody& body1, const ContactBody& body2);

// Velocity of the material point of `body` at the contact, v + w x r [m/s].
Vec3 contact_point_velocity_W(const ContactBody& body);

// An orthonormal right-handed contact frame R_WC = [t1 t2 n] with the given unit normal n_W
// (t1 is the axis of n's smallest component crossed with n, normalised — deterministic).
Mat3 contact_frame_W(const Vec3& n_W);

// Applies p_W to body 1 and -p_W to body 2 (v1 += p/m1, w1 += I1^-1 (r1 x p); body 2 opposite).
void apply_impulse(const Vec3& p_W, ContactBody& body1, ContactBody& body2);

// Two dynamic bodies face to face over a patch that holds their relative rotation (DESIGN.md §4's
// centre-of-pressure rule for two dynamic bodies): an impulse p on body 1 and -p on body 2 at any
// point of the patch, with the couple the pressure carries so that the faces stay parallel, turns
// both bodies alike, dw1 = dw2 = W p with W = (I1 + I2)^-1 [d]x, d = x2 - x1, and changes the
// relative velocity at the patch by du = K p, K = (1/m1 + 1/m2) 1 - [d]x (I1 + I2)^-1 [d]x - the
// Schur complement of the rotation constraint, symmetric and positive definite, and the same for
// every point of the patch. (From I1 dw = r1 x p + L and I2 dw = -r2 x p - L, L the couple.) A
// body whose rotation something else holds (inverse inertia zero) holds the other's: W = 0.
struct HeldRotationResponse {
  Mat3 K_W = Mat3::Identity();
  Mat3 W = Mat3::Zero();
};
HeldRotationResponse held_rotation_response(const ContactBody& body1, const Vec3& x1_W,
                                            const ContactBody& body2, const Vec3& x2_W);

// The collision of two bodies as the integrator sees it, in the contact frame R_WC (third column
// the normal from body 2 to body 1): K_c = R^T K R and u0_c = R^T (u1 - u2).
struct FrameProblem {
  Mat3 K_c = Mat3::Identity();
  Vec3 u0_c = Vec3::Zero();
};
FrameProblem frame_problem(const ContactBody& body1, const ContactBody& body2, const Mat3& R_WC);

// Resolves the collision of two bodies in the contact frame R_WC (third column the normal from
// body 2 to body 1): integrates the frame_problem and fills result.p_W = R p_c. Does not change the
// bodies; apply result.p_W with apply_impulse.
CollisionResult resolve_collision(const ContactBody& body1, const ContactBody& body2,
                                  const Mat3& R_WC, const CollisionParameters& params);

}  // namespace palpable
