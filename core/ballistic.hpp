#pragma once
// Exact ballistic (free-flight) motion of a body between events (DESIGN.md §2).
//
// Frames and units: states are of the modelling frame M (BodyState::q_WM, origin at the centre of
// mass); rotation is computed in the principal frame B (R_WB = R_WM R_MB, I_B = diag(I1, I2, I3)
// ascending). SI units throughout; angular velocities in the world frame.
//
// What is closed form and what "10,000 small advances agree with one large advance" means:
//  - Translation of dynamic bodies: x = x0 + v0 dt + g dt^2 / 2, v = v0 + g dt. Closed form; the
//    chunked and single advances differ by rounding only (a few ulp of the coordinates, growing
//    like the number of chunks).
//  - Spherical inertia (I3 - I1 <= tol I3): omega_W constant, R(t) = exp([w dt]x) R0. Closed form.
//  - Axisymmetric inertia (two moments equal within tol, the symmetric axis may be the smallest or
//    the largest moment): regular precession, R(t) = exp([L_W dt / I_t]x) R0 exp([e_s w_s (1 -
//    I_s/I_t) dt]x) (e.g. Landau & Lifshitz, Mechanics §33). Closed form.
//  - General inertia: omega_B(t) from Jacobi elliptic functions (Landau & Lifshitz §37) and the
//    orientation as R_WB(t) = R_WB(t0) G(L_B(t0)) Rz(dpsi) G(L_B(t))^T, where G(L_B) is the ZXZ
//    Euler-angle frame that carries the pole-axis z to the body angular momentum L_B (pole = the
//    principal axis that L_B does NOT circulate around, so G is never singular) and dpsi, the
//    precession angle about the constant world L, is the integral of
//      psi' = |L| (Ia wa^2 + Ib wb^2) / (Ia^2 wa^2 + Ib^2 wb^2)    (a, b the non-pole axes),
//    evaluated in closed form with the incomplete elliptic integral of the third kind (Carlson's
//    R_F and R_J, computed from k'^2 directly so that the separatrix neighbourhood keeps full
//    precision); this is the construction of Celledoni, Fassò, Säfström & Zanna (2008), "The exact
//    computation of the free rigid body motion and its use in splitting methods", SIAM J. Sci.
//    Comput. 30(4), written with elliptic integrals instead of their theta-function series.
//    No quadrature, no step size: the result is exact up to the rounding of the special
//    functions (~1e-15 relative); the phase error grows like eps * (number of turns), as for any
//    evaluation of a periodic motion whose period is itself only known to eps. On the separatrix
//    (L^2 = 2 T I2 to the last bit) the k -> 1 limit (tanh, sech) is used; the unstable equilibrium
//    (pure rotation about the intermediate axis) stays a steady rotation.
//    Chunked advances re-derive T, L and the elliptic phase from each intermediate state, so they
//    agree with one large advance to rounding accumulated over the chunks (~1e-13 after 10,000).
//  - Fixed bodies never move (only the clock advances). Kinematic bodies follow KinematicMotion
//    exactly (rotation about a moving axis plus translation).
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"

namespace palpable {

// The symmetry of a principal inertia I_B (ascending), decided with a relative tolerance.
enum class InertiaSymmetry {
  kSpherical,     // I3 - I1 <= tol * I3
  kAxisymmetric,  // I2 - I1 <= tol * I3 (symmetric axis e3, oblate) or I3 - I2 <= tol * I3 (e1)
  kAsymmetric,    // all three moments distinct
};

InertiaSymmetry classify_inertia(const Vec3& I_B, double relative_tolerance);

// Torque-free rotation of a rigid body with principal moments I_B (ascending, positive): the
// orientation of its principal frame and its world angular velocity after a duration dt >= 0.
struct FreeRotation {
  Quat q_WB = Quat::Identity();
  Vec3 w_W = Vec3::Zero();  // [rad/s]
};
FreeRotation advance_free_rotation(const Vec3& I_B, const Quat& q_WB, const Vec3& w_W, double dt,
                                   double symmetry_tolerance);

// The exact state of `body` at absolute time t >= from.t, starting from `from` (which need not be
// body.state). Gravity [m/s^2] acts on dynamic bodies only. Settings: inertia_symmetry_tolerance.
BodyState advance(const Body& body, const BodyState& from, double t, const Vec3& gravity_W,
                  const Settings& settings = Settings{});

// A bound on |omega| over all future ballistic motion from `state` [rad/s]: the exact constant
// |omega| for spherical and axisymmetric inertia, min(|L| / I1, sqrt(2 T / I1)) for a general
// body (DESIGN.md §2), |Omega| for a kinematic body, 0 for a fixed body.
double angular_speed_bound(const Body& body, const BodyState& state,
                           const Settings& settings = Settings{});

// Principal-frame orientation R_WB = R_WM R_MB.
Quat principal_orientation_W(const MassProperties& mass, const Quat& q_WM);

// World-frame inverse inertia R_WB diag(1/I) R_WB^T [1/(kg m^2)]; zero for infinite mass.
Mat3 inverse_inertia_W(const Body& body, const Quat& q_WM);

// Velocity of the material point at p_W [m/s]: v + w x (p - x).
Vec3 point_velocity_W(const BodyState& state, const Vec3& p_W);

// Rotational kinetic energy T = w.I w / 2 [J] and world angular momentum L_W [kg m^2/s] of a
// dynamic body in `state`.
double rotational_energy(const MassProperties& mass, const BodyState& state);
Vec3 angular_momentum_W(const MassProperties& mass, const BodyState& state);

// Period of omega_B(t) of a torque-free asymmetric body [s]: 4 K(k) / lambda (Landau & Lifshitz
// §37), from the principal moments I_B (ascending, distinct) and the body-frame angular velocity.
// +inf on the separatrix and for omega = 0. For the intermediate-axis flip this is the time
// between two flips in the same direction.
double polhode_period(const Vec3& I_B, const Vec3& w_B);

}  // namespace palpable
