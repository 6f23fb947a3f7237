#pragma once
// Exact ballistic (free-flight) motion of a body between events (DESIGN.md §2).
//
// Frames and units: states are of the modelling frame M (BodyState::q_WM, origin at the centre of
// mass); rotation is computed in the principal frame B (R_WB = R_WM R_MB, I_B = diag(I1, I2, I3)
// ascending). SI units throughout; angular velocities in the world frame.
//
// What is closed form, and what "10,000 small advances agree with one large advance" means.
// Every motion below is closed form — no quadrature, no step size — so one call covers any
// interval. A chained advance re-derives everything from the stored (double) state, so chunking
// only adds the rounding of that state at each chunk boundary:
//  - Translation of dynamic bodies: x = x0 + v0 dt + g dt^2 / 2, v = v0 + g dt. Chunked and
//    single advances differ by a few ulp of the coordinates.
//  - Spherical inertia (I3 - I1 <= tol I3, Settings::inertia_symmetry_tolerance): omega_W
//    constant, R(t) = exp([w dt]x) R0.
//  - Axisymmetric inertia (two moments equal within tol; the symmetric axis may be the smallest or
//    the largest moment): regular precession, R(t) = exp([L_W dt / I_t]x) R0 exp([e_s w_s (1 -
//    I_s / I_t) dt]x), since w = L / I_t + w_s (1 - I_s / I_t) e_s (Landau & Lifshitz, Mechanics
//    §33).
//  - General inertia: omega_B(t) = (A_c cn, A_2 sn, A_d dn)(lambda t + u0) (Landau & Lifshitz §37;
//    cn on the axis L_B does not circulate around, dn on the one it does), with sn, cn, dn by
//    the AGM from k'^2 formed without cancellation, so the separatrix neighbourhood keeps full
//    precision. Orientation: R_WB(t) = R_WB(t0) G(L_B(t0)) Rz(dpsi) G(L_B(t))^T, where G(L_B) is
//    the ZXZ Euler frame carrying the pole axis to L_B (pole = the cn axis, which L_B never
//    reaches, so G is never singular) and dpsi, the precession about the constant world L, is the
//    integral of psi' = |L| (Ia wa^2 + Ib wb^2) / (Ia^2 wa^2 + Ib^2 wb^2) (a, b the non-pole axes)
//    = (|L| / I_p) (1 + C / (1 - n sn^2)), i.e. an incomplete elliptic integral of the third kind
//    (Carlson R_F, R_J). The same frame construction as Celledoni, Fassò, Säfström & Zanna (2008),
//    "The exact computation of the free rigid body motion and its use in splitting methods", SIAM
//    J. Sci. Comput. 30(4), with elliptic integrals instead of theta-function series. Rotations
//    and the reconstruction are done in extended precision (long double). On the separatrix
//    (L^2 = 2 T I2 to the last bit) the k -> 1 limit (tanh, sech) is used; the unstable
//    equilibrium (pure rotation about the intermediate axis) stays a steady rotation.
//    One advance is exact to ~1e-15; the phase error of a long advance grows like eps * phase.
//    Chunking: rounding the stored orientation turns the principal frame by ~1e-16 rad, which
//    changes the body-frame T and L^2 by up to ~(I3 / I1) 1e-16, and the elliptic phase rate
//    depends on them; the discrepancy is a random walk, ~eps sqrt(chunks) x phase x condition.
//    Measured (tests/core/ballistic_test.cpp) for 10,000 uneven chunks: ~1e-13 over one turn for
//    moderate inertia ratios, 1e-13..1e-12 over ~4 turns; ~1e-11 for I3 / I1 = 100 or a state
//    1e-3 from the separatrix (where the period itself is log-sensitive to T and L).
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
// Kinetic energy m v^2 / 2 + w.I w / 2 [J] of a dynamic body in `state`.
double kinetic_energy(const Body& body, const BodyState& state);
Vec3 angular_momentum_W(const MassProperties& mass, const BodyState& state);

// Period of omega_B(t) of a torque-free asymmetric body [s]: 4 K(k) / lambda (Landau & Lifshitz
// §37), from the principal moments I_B (ascending, distinct) and the body-frame angular velocity.
// +inf on the separatrix, for omega = 0 and for moments that are not distinct. For the
// intermediate-axis flip this is the time between two flips in the same direction.
double polhode_period(const Vec3& I_B, const Vec3& w_B);

}  // namespace palpable
