#include "impulse/microcollision.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace palpable {

namespace {

// The result of applying a given impulse p_c (no integration).
CollisionResult direct_impulse(const Mat3& K_c, const Vec3& u0_c, const Vec3& p_c, PhaseKind kind) {
  CollisionResult result;
  result.u0_c = u0_c;
  result.p_c = p_c;
  result.u_final_c = u0_c + K_c * p_c;
  result.energy_change = 0.5 * (u0_c + result.u_final_c).dot(p_c);
  // u is linear in p along a straight impulse path, so W_z is the trapezoid.
  result.work_normal = 0.5 * (u0_c.z() + result.u_final_c.z()) * p_c.z();
  // For the record: u_z is linear in p_z along the path too, so compression ends where it is 0.
  const double du_z = result.u_final_c.z() - u0_c.z();
  result.p_z_compression =
      du_z > 0.0 ? p_c.z() * std::clamp(-u0_c.z() / du_z, 0.0, 1.0) : p_c.z();
  result.add_phase(kind, 0.0);
  return result;
}

}  // namespace

double microcollision_speed(const Settings& settings, double g_n) {
  return derived_microcollision_speed(settings, g_n);
}

bool is_microcollision(double u_z0, double v_micro, const Settings& settings) {
  return -u_z0 <= v_micro * (1.0 + settings.microcollision_speed_slack);
}

CollisionResult resolve_microcollision(const Mat3& K_c, const Vec3& u0_c,
                                       const CollisionParameters& params, MicrocollisionRule rule,
                                       const MicrocollisionContext& context, double v_micro) {
  CollisionParameters floored = params;
  floored.min_rebound_speed = std::max(v_micro, 0.0);
  if (!K_c.allFinite() || !u0_c.allFinite() || !context.a_t_c.allFinite() ||
      !std::isfinite(context.g_n) || !std::isfinite(v_micro)) {
    CollisionResult failed;
    failed.u0_c = u0_c;
    failed.u_final_c = u0_c;
    failed.status = CollisionStatus::kFailedNonFinite;
    return failed;
  }
  Vec3 target;
  PhaseKind kind;
  if (rule == MicrocollisionRule::kReversal) {
    // Mirtich & Canny 1995 §4: reverse the relative velocity, with the rebound floor.
    target = Vec3(-u0_c.x(), -u0_c.y(), std::max(-u0_c.z(), floored.min_rebound_speed));
    kind = PhaseKind::kReversed;
  } else {
    // Drift-free: the slip that averages to zero over the next flight of duration tau.
    const double u_z = std::max(-params.restitution * u0_c.z(), floored.min_rebound_speed);
    const double tau = context.g_n > 0.0 ? 2.0 * u_z / context.g_n : 0.0;
    // In the surface's frame, turning at Omega about n, the displacement over the flight is the
    // integral of (1 - [Omega n]x t) (u_t' + a_t t): zero, to second order in Omega tau, for
    // u_t' = -a_t tau / 2 + (Omega n x a_t) tau^2 / 12.
    const Vec2 spun(-context.a_t_c.y(), context.a_t_c.x());  // n x a_t in the contact frame
    const Vec2 u_t = -0.5 * tau * context.a_t_c + context.surface_spin * tau * tau / 12.0 * spun;
    target = Vec3(u_t.x(), u_t.y(), u_z);
    kind = PhaseKind::kDriftFreeTarget;
  }
  const Vec3 p_c = K_c.ldlt().solve(target - u0_c);
  if (p_c.allFinite() && in_friction_cone(p_c, params.friction, 1e-12)) {
    return direct_impulse(K_c, u0_c, p_c, kind);
  }
  if (rule == MicrocollisionRule::kDriftFree) {
    // Outside the cone: the impulse on the cone boundary, friction toward the tangential target
    // (the direction of the unconstrained impulse's tangential part), that reaches the normal
    // target through the full K (DESIGN.md §4). This is what lets a block that slid to a stop
    // reach the drift-free two-bounce cycle within a few bounces: the ordinary integration
    // would stop its slip at 0 on every bounce, and it would creep a_t tau / 2 like the
    // reversal rule.
    const Vec2 p_t = p_c.head<2>();
    const double p_t_norm = p_t.norm();
    if (p_t_norm > 0.0) {
      const Vec2 d = params.friction * p_t / p_t_norm;
      const Vec3 zeta(d.x(), d.y(), 1.0);
      const double rate = K_c.row(2).dot(zeta);  // du_z per unit normal impulse
      const double p_n = rate > 0.0 ? (target.z() - u0_c.z()) / rate : -1.0;
      if (p_n >= 0.0 && std::isfinite(p_n)) {
        return direct_impulse(K_c, u0_c, p_n * zeta, PhaseKind::kDriftFreeConeBoundary);
      }
    }
  }
  CollisionResult result = integrate_collision(K_c, u0_c, floored);
  // Record the fallback first: shift the integrator's phases by one.
  CollisionResult out = result;
  out.phase_count = 0;
  out.add_phase(PhaseKind::kMicroFallback, 0.0);
  for (int i = 0; i < result.phase_count; ++i) {
    out.add_phase(result.phases[i].kind, result.phases[i].p_z_begin, result.phases[i].direction);
  }
  return out;
}

}  // namespace palpable
