#pragma once
// Microcollisions: resting, sliding and rolling contact as trains of small collisions (DESIGN.md
// §4, "Continuous contact"; Mirtich & Canny 1995, §4). A collision whose approach speed is below
// v_micro = sqrt(2 g_n envelope) is a microcollision. Whatever the rule, it leaves the contact
// separating at no less than v_micro (the rebound floor), so a resting contact bounces about
// g_n / (2 v_micro) times per second instead of in a Zeno cascade.
//
// Two rules (Settings::microcollision_rule):
//  - drift-free (default): aim at u' = (-a_t tau / 2, max(-e u_z0, v_micro)), tau = 2 u_z'/g_n
//    the flight to the next bounce, so that the slip averages to zero over that flight (on a
//    surface turning at Omega about n, the displacement on it: u_t' = -a_t tau / 2 +
//    (Omega n x a_t) tau^2 / 12, since the slip integrates in the turning frame); apply
//    p = K^-1 (u' - u0) if it lies in the friction cone, else the impulse on the cone boundary
//    with friction toward the tangential target that reaches the normal target through the full
//    K. (DESIGN.md also allows the ordinary integration with the floor as the fallback; measured
//    here, that fallback makes a block that slid to a stop creep exactly like the reversal
//    rule, so it is used only if the boundary impulse cannot reach the normal target.)
//  - reversal (Mirtich): u' = (-u_t0, max(-u_z0, v_micro)), same cone check and fallback.
// The e-law rebound used in the drift-free target is -e u_z0: what all three laws give when the
// slip direction does not change. Below v_micro it is dominated by the floor whenever e < 1.
#include "core/settings.hpp"
#include "core/types.hpp"
#include "impulse/collision_integrator.hpp"

namespace palpable {

// What the caller (the scheduler) predicts about the flight after this microcollision.
struct MicrocollisionContext {
  // Rate of change of the slip at the contact location the next collision will use, in the
  // contact frame (t1, t2) [m/s^2]: against a fixed plane, gravity's tangential part.
  Vec2 a_t_c = Vec2::Zero();
  // Relative normal acceleration toward contact, g_n = -(a1 - a2) . n >= 0 [m/s^2].
  double g_n = 0.0;
  // Spin about n of the surface the slip is measured against [rad/s] (a kinematic platter: its
  // angular velocity . n; 0 for a fixed one). Zero mean slip over a flight is not zero
  // displacement on a turning surface: the drift-free target adds (Omega n x a_t) tau^2 / 12.
  double surface_spin = 0.0;
};

// v_micro [m/s]: derived_microcollision_speed (core/settings.hpp): the setting if given, else
// sqrt(2 g_n envelope);
// a negative g_n counts as 0 (never a negative value under the square root).
double microcollision_speed(const Settings& settings, double g_n);

// True if a collision approaching at normal velocity u_z0 (<= 0) is a microcollision: approach
// speed below v_micro, with the relative slack Settings::microcollision_speed_slack, since a
// resting body returns at exactly v_micro.
bool is_microcollision(double u_z0, double v_micro, const Settings& settings);

// Resolves a microcollision by `rule` with rebound floor v_micro (params.min_rebound_speed is
// overridden by v_micro). Never throws; the result's phases say which branch was taken.
CollisionResult resolve_microcollision(const Mat3& K_c, const Vec3& u0_c,
                                       const CollisionParameters& params, MicrocollisionRule rule,
                                       const MicrocollisionContext& context, double v_micro);

}  // namespace palpable
