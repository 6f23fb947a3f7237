#include "impulse/contact_torque.hpp"

#include "core/check.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

AngularImpulse resisting_angular_impulse(const Vec3& axis_W, const ContactBody& body1,
                                         const ContactBody& body2, double budget) {
  AngularImpulse result;
  const double k = axis_W.dot((body1.inv_inertia_W + body2.inv_inertia_W) * axis_W);
  const double s = axis_W.dot(body1.w_W - body2.w_W);
  if (!(k > 0.0) || s == 0.0 || !(budget > 0.0)) return result;
  const double stop = std::abs(s) / k;
  const double tau = std::min(budget, stop);
  result.stopped = budget >= stop;
  result.L_W = -std::copysign(tau, s) * axis_W;
  result.energy_change = -tau * std::abs(s) + 0.5 * tau * tau * k;
  return result;
}

void apply_angular_impulse(const Vec3& L_W, ContactBody& body1, ContactBody& body2) {
  body1.w_W += body1.inv_inertia_W * L_W;
  body2.w_W -= body2.inv_inertia_W * L_W;
}

namespace {

// Integral of |x - p| over the triangle (p, a, b) in polar coordinates about p: with h the
// distance from p to the line ab and s the signed position along it from the foot of p,
// integral of rho^3 / 3 d theta = [h s d + h^3 asinh(s / h)] / 6 between s_a and s_b,
// d = sqrt(h^2 + s^2). Returns that integral and the triangle's area.
std::pair<double, double> fan_triangle(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double length = ab.norm();
  if (!(length > 0.0)) return {0.0, 0.0};
  const Vec3 e = ab / length;
  const Vec3 foot = a + e * e.dot(p - a);
  const double h = (p - foot).norm();
  if (!(h > 0.0)) return {0.0, 0.0};
  const double sa = e.dot(a - foot), sb = e.dot(b - foot);
  auto F = [h](double s) { return h * s * std::hypot(h, s) + h * h * h * std::asinh(s / h); };
  return {(F(sb) - F(sa)) / 6.0, 0.5 * h * length};
}

}  // namespace

double mean_distance_over_patch(const std::vector<Vec3>& patch_W, const Vec3& n_W,
                                const Vec3& p_W) {
  PALPABLE_CHECK(!patch_W.empty(), "mean distance over an empty patch");
  // The point in the patch's plane.
  const Vec3 p = p_W - n_W * n_W.dot(p_W - patch_W[0]);
  if (patch_W.size() == 1) return (patch_W[0] - p).norm();
  if (patch_W.size() == 2) {
    // Uniform over the segment: the mean of |s - s_p| for s in [0, L].
    const Vec3 ab = patch_W[1] - patch_W[0];
    const double length = ab.norm();
    if (!(length > 0.0)) return (patch_W[0] - p).norm();
    const double s = std::clamp((p - patch_W[0]).dot(ab) / length, 0.0, length);
    return (s * s + (length - s) * (length - s)) / (2.0 * length);
  }
  double integral = 0.0, area = 0.0;
  for (std::size_t i = 0; i < patch_W.size(); ++i) {
    const auto [moment, a] = fan_triangle(p, patch_W[i], patch_W[(i + 1) % patch_W.size()]);
    integral += moment;
    area += a;
  }
  return area > 0.0 ? integral / area : 0.0;
}

}  // namespace palpable
