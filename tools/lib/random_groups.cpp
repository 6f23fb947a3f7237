#include "tools/lib/random_groups.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace palpable::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

double RandomGroups::uniform() {
  return U_(rng_);
}

Vec3 RandomGroups::uniform3() {
  const double x = uniform();
  const double y = uniform();
  const double z = uniform();
  return Vec3(x, y, z);
}

RandomGroup RandomGroups::next(int contacts) {
  RandomGroup g;
  const int nb = 1 + static_cast<int>(rng_() % 4);
  const int k = contacts > 0 ? contacts : 2 + static_cast<int>(rng_() % 7);
  g.with_fixed = rng_() % 2 == 0 || nb == 1;
  for (int j = 0; j < nb; ++j) {
    GroupBody b;
    b.inv_mass = 1.0 / std::pow(10.0, 2 * uniform());
    // A uniformly random rotation from three uniform draws (Shoemake, Graphics Gems III, 1992).
    const double u1 = 0.5 * (uniform() + 1), u2 = 0.5 * (uniform() + 1), u3 = 0.5 * (uniform() + 1);
    const Eigen::Quaterniond q(
        std::sqrt(u1) * std::cos(2 * kPi * u3), std::sqrt(1 - u1) * std::sin(2 * kPi * u2),
        std::sqrt(1 - u1) * std::cos(2 * kPi * u2), std::sqrt(u1) * std::sin(2 * kPi * u3));
    const Mat3 Q = q.normalized().toRotationMatrix();
    const Vec3 e = uniform3();
    const Vec3 d(std::pow(10.0, e.x()), std::pow(10.0, e.y()), std::pow(10.0, e.z()));
    b.inv_inertia_W = Q * d.asDiagonal() * Q.transpose() * b.inv_mass * 10.0;
    b.x_W = uniform3();
    b.v_W = uniform3() * 3.0;
    b.w_W = uniform3() * 5.0;
    g.bodies.push_back(b);
  }
  if (g.with_fixed) g.bodies.push_back(GroupBody{});
  const int all = static_cast<int>(g.bodies.size());
  for (int i = 0; i < k; ++i) {
    const int b1 = static_cast<int>(rng_() % nb);
    int b2 = static_cast<int>(rng_() % all);
    if (b2 == b1) b2 = (b1 + 1) % all;  // never b1: a lone body always has the fixed one
    GroupContact c;
    c.body1 = b1;
    c.body2 = b2;
    c.point_W = uniform3();
    c.n_W = uniform3().normalized();
    c.friction = 0.5 * (uniform() + 1) * 1.2;
    c.restitution = 0.5 * (uniform() + 1);
    g.contacts.push_back(c);
  }
  return g;
}

GroupFigures group_figures(const RandomGroup& group, const GroupResult& r) {
  const std::vector<GroupBody>& bodies = group.bodies;
  GroupFigures f;
  f.converged = r.converged;
  f.energy_ratio = r.energy_before > 0.0 ? r.energy_after / r.energy_before : 0.0;
  f.energy_excess = r.energy_after - r.energy_before * (1 + 1e-12);
  double speed = 0.0;
  for (const GroupBody& b : bodies) speed = std::max(speed, b.v_W.norm() + b.w_W.norm());
  double p_scale = 0.0;
  for (const Vec3& p : r.impulse_W) p_scale = std::max(p_scale, p.norm());
  const double p_div = p_scale > 0.0 ? p_scale : 1.0;
  f.cone_excess = f.negative_normal = f.normal_deficit = -kInfinity;
  for (std::size_t i = 0; i < group.contacts.size(); ++i) {
    const GroupContact& c = group.contacts[i];
    const double pn = r.impulse_W[i].dot(c.n_W);
    const double pt = (r.impulse_W[i] - c.n_W * pn).norm();
    f.cone_excess = std::max(f.cone_excess, (pt - c.friction * pn) / p_div);
    f.negative_normal = std::max(f.negative_normal, -pn / p_div);
    auto at = [&](int j) { return Vec3(r.v_W[j] + r.w_W[j].cross(c.point_W - bodies[j].x_W)); };
    const double u_n = (at(c.body1) - at(c.body2)).dot(c.n_W);
    f.normal_deficit = std::max(f.normal_deficit, (c.min_separation - u_n) / (1 + speed));
    f.normal_mismatch = std::max(f.normal_mismatch, std::abs(u_n - r.normal_velocity[i]));
  }
  if (!group.with_fixed) {
    std::vector<Vec3> v0;
    for (const GroupBody& b : bodies) v0.push_back(b.v_W);
    const Vec3 p0 = linear_momentum(bodies, v0);
    f.momentum_error = (linear_momentum(bodies, r.v_W) - p0).norm() / (1 + p0.norm() + p_scale);
  }
  return f;
}

bool violates(const GroupFigures& f, const GroupBounds& b) {
  return f.energy_excess > b.energy_excess || f.cone_excess > b.cone_excess ||
         f.negative_normal > b.negative_normal || f.normal_deficit > b.normal_deficit ||
         f.normal_mismatch > b.normal_mismatch || f.momentum_error > b.momentum_error;
}

}  // namespace palpable::tools
