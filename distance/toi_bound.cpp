#include "distance/toi_bound.hpp"

#include <cmath>

namespace palpable {

double rotational_term(const ToiMotion& motion, const Vec3& d_hat) {
  if (motion.kinematic) {
    const double s = motion.spin_W.cross(d_hat).norm();
    if (s == 0.0 || motion.rotation_radius == 0.0) return 0.0;
    return s * motion.rotation_radius;
  }
  if (motion.omega_bound == 0.0 || motion.rotation_radius == 0.0) return 0.0;
  return motion.omega_bound * motion.rotation_radius;
}

double solve_gap_closing(double a, double b, double delta) {
  if (!(delta > 0.0)) return 0.0;
  const double disc = b * b + 2.0 * a * delta;
  if (disc < 0.0) return kInfinity;
  if (b > 0.0) return 2.0 * delta / (b + std::sqrt(disc));
  if (a > 0.0) return (-b + std::sqrt(disc)) / a;
  return kInfinity;
}

ToiBound toi_bound(const ToiMotion& motion1, const ToiMotion& motion2,
                   const DistanceResult& closest, double d_target, const Settings& settings) {
  ToiBound bound;
  if (closest.status != ContactStatus::kSeparated && closest.status != ContactStatus::kTouching) {
    bound.dt = 0.0;
    return bound;
  }
  const Vec3 d_hat = -closest.n_W;
  bound.closing_speed = (motion1.v_W - motion2.v_W).dot(d_hat) + rotational_term(motion1, d_hat) +
                        rotational_term(motion2, d_hat);
  bound.closing_accel = (motion1.a_W - motion2.a_W).dot(d_hat);
  const double delta = closest.distance - d_target;
  bound.dt = solve_gap_closing(bound.closing_accel, bound.closing_speed, delta);
  if (bound.dt < settings.toi_min_progress_s) {
    bound.dt = settings.toi_min_progress_s;
    bound.floored = true;
  }
  return bound;
}

ToiBound exact_toi_sphere_sphere(const Vec3& c1_W, const Vec3& v1_W, double r1, const Vec3& c2_W,
                                 const Vec3& v2_W, double r2, double d_target) {
  ToiBound bound;
  bound.exact = true;
  const Vec3 r = c1_W - c2_W;
  const Vec3 w = v1_W - v2_W;
  const double reach = r1 + r2 + d_target;
  // |r + w t|^2 = reach^2:  A t^2 + 2 B t + C = 0.
  const double A = w.squaredNorm();
  const double B = r.dot(w);
  const double C = r.squaredNorm() - reach * reach;
  bound.closing_speed = r.norm() > 0.0 ? -B / r.norm() : 0.0;
  if (C <= 0.0) {
    bound.dt = 0.0;
    return bound;
  }
  if (B >= 0.0 || A == 0.0) return bound;  // receding or at rest relative to each other
  const double disc = B * B - A * C;
  if (disc < 0.0) return bound;  // passes by
  // Smaller root without cancellation: t = C / (-B + sqrt(B^2 - A C)).
  bound.dt = C / (-B + std::sqrt(disc));
  return bound;
}

ToiBound exact_toi_sphere_plane(const Vec3& c_W, const Vec3& v_W, const Vec3& g_W, double radius,
                                const Vec3& n_W, double offset_W, const Vec3& plane_velocity_W,
                                double d_target) {
  ToiBound bound;
  bound.exact = true;
  // Gap h(t) = delta - b t - 1/2 a t^2 exactly, with b = -(v - u) . n and a = -g . n.
  const double delta = n_W.dot(c_W) - offset_W - radius - d_target;
  bound.closing_speed = -(v_W - plane_velocity_W).dot(n_W);
  bound.closing_accel = -g_W.dot(n_W);
  bound.dt = solve_gap_closing(bound.closing_accel, bound.closing_speed, delta);
  return bound;
}

}  // namespace palpable
