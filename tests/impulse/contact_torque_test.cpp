// Resisting angular impulses (torsional friction, rolling resistance) and the mean distance of a
// contact patch, against closed forms, a brute-force quadrature and the energy bound.
#include "impulse/contact_torque.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

namespace palpable {
namespace {

const double kPi = std::acos(-1.0);

std::vector<Vec3> regular_polygon(int sides, double radius, const Vec3& centre) {
  std::vector<Vec3> points;
  for (int i = 0; i < sides; ++i) {
    const double angle = 2.0 * kPi * i / sides;
    points.push_back(centre + radius * Vec3(std::cos(angle), std::sin(angle), 0.0));
  }
  return points;
}

double kinetic_energy(const ContactBody& b) {
  double e = 0.0;
  if (b.inv_inertia_W.squaredNorm() > 0.0) e += 0.5 * b.w_W.dot(b.inv_inertia_W.inverse() * b.w_W);
  return e;
}

Mat3 random_inverse_inertia(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mat3 A;
  for (int i = 0; i < 9; ++i) A(i / 3, i % 3) = u(rng);
  return A * A.transpose() + 0.1 * Mat3::Identity();
}

}  // namespace

TEST_CASE("mean distance over a square from its centre and from a corner is the closed form",
          "[contact_torque]") {
  const double a = 0.3;
  const std::vector<Vec3> square = {Vec3(0, 0, 1), Vec3(a, 0, 1), Vec3(a, a, 1), Vec3(0, a, 1)};
  const double k = std::sqrt(2.0) + std::log(1.0 + std::sqrt(2.0));
  CHECK(mean_distance_over_patch(square, Vec3::UnitZ(), Vec3(a / 2, a / 2, 1)) ==
        Approx(a * k / 6.0).epsilon(1e-13));
  // A point off the plane is projected onto it.
  CHECK(mean_distance_over_patch(square, Vec3::UnitZ(), Vec3(0, 0, 5)) ==
        Approx(a * k / 3.0).epsilon(1e-13));
}

TEST_CASE("mean distance over a fine regular polygon tends to 2R/3 of a disc", "[contact_torque]") {
  const double R = 0.012;
  const int sides = 4096;
  const double m = mean_distance_over_patch(regular_polygon(sides, R, Vec3(1, 2, 0)), Vec3::UnitZ(),
                                            Vec3(1, 2, 0));
  // The inscribed polygon's apothem is R cos(pi/n): relative deficit of order (pi/n)^2.
  CHECK(m == Approx(2.0 * R / 3.0).epsilon(2.0 * std::pow(kPi / sides, 2)));
}

TEST_CASE("mean distance over a segment is (s^2 + (L - s)^2) / 2L", "[contact_torque]") {
  const std::vector<Vec3> segment = {Vec3(0, 0, 0), Vec3(2, 0, 0)};
  CHECK(mean_distance_over_patch(segment, Vec3::UnitZ(), Vec3(1, 0, 0)) == Approx(0.5));
  CHECK(mean_distance_over_patch(segment, Vec3::UnitZ(), Vec3(0.5, 0, 0)) == Approx(0.625));
}

TEST_CASE("mean distance over random convex polygons agrees with a grid quadrature",
          "[contact_torque]") {
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    CAPTURE(trial);
    // A convex polygon: sorted random angles on an ellipse.
    std::vector<double> angles;
    for (int i = 0; i < 7; ++i) angles.push_back(2.0 * kPi * u(rng));
    std::sort(angles.begin(), angles.end());
    std::vector<Vec3> polygon;
    for (double t : angles) polygon.emplace_back(2.0 * std::cos(t), std::sin(t), 0.0);
    Vec3 p = Vec3::Zero();
    for (const Vec3& q : polygon) p += q;
    p /= static_cast<double>(polygon.size());
    auto inside = [&](const Vec3& x) {
      for (std::size_t i = 0; i < polygon.size(); ++i) {
        const Vec3 e = polygon[(i + 1) % polygon.size()] - polygon[i];
        if (e.cross(x - polygon[i]).z() < 0.0) return false;
      }
      return true;
    };
    const int n = 1500;
    double sum = 0.0;
    long count = 0;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Vec3 x(-2.0 + 4.0 * (i + 0.5) / n, -1.0 + 2.0 * (j + 0.5) / n, 0.0);
        if (!inside(x)) continue;
        sum += (x - p).norm();
        ++count;
      }
    }
    CHECK(mean_distance_over_patch(polygon, Vec3::UnitZ(), p) ==
          Approx(sum / static_cast<double>(count)).epsilon(2e-3));
  }
}

TEST_CASE("a large budget stops the relative spin exactly and a small one takes out its budget",
          "[contact_torque]") {
  ContactBody coin, table;
  coin.inv_inertia_W = Vec3(50.0, 50.0, 25.0).asDiagonal();
  coin.w_W = Vec3(0.0, 0.0, 30.0);
  const Vec3 n = Vec3::UnitZ();

  const AngularImpulse stop = resisting_angular_impulse(n, coin, table, 10.0);
  CHECK(stop.stopped);
  ContactBody c1 = coin, t1 = table;
  apply_angular_impulse(stop.L_W, c1, t1);
  CHECK(std::abs(c1.w_W.z()) <= 1e-15 * 30.0);
  CHECK(t1.w_W == Vec3::Zero());
  CHECK(stop.energy_change == Approx(kinetic_energy(c1) - kinetic_energy(coin)));

  const double budget = 0.2;  // [N m s]: takes out 0.2 x 25 = 5 rad/s
  const AngularImpulse part = resisting_angular_impulse(n, coin, table, budget);
  CHECK_FALSE(part.stopped);
  ContactBody c2 = coin, t2 = table;
  apply_angular_impulse(part.L_W, c2, t2);
  CHECK(c2.w_W.z() == Approx(25.0));
  CHECK(part.L_W.norm() == Approx(budget));
  CHECK(part.energy_change == Approx(kinetic_energy(c2) - kinetic_energy(coin)));
  CHECK(part.energy_change < 0.0);

  // Nothing turns, nothing spins, or no budget: no impulse.
  CHECK(resisting_angular_impulse(n, table, table, 1.0).L_W == Vec3::Zero());
  ContactBody still = coin;
  still.w_W.setZero();
  CHECK(resisting_angular_impulse(n, still, table, 1.0).L_W == Vec3::Zero());
  CHECK(resisting_angular_impulse(n, coin, table, 0.0).L_W == Vec3::Zero());
}

TEST_CASE("a resisting angular impulse never reverses the spin and never creates energy",
          "[contact_torque]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    CAPTURE(trial);
    ContactBody b1, b2;
    b1.inv_inertia_W = random_inverse_inertia(rng);
    b2.inv_inertia_W = trial % 3 == 0 ? Mat3::Zero() : random_inverse_inertia(rng);
    b1.w_W = 10.0 * Vec3(u(rng), u(rng), u(rng));
    // A fixed body 2 does not turn (a spinning kinematic one may drive body 1: see the header).
    b2.w_W = trial % 3 == 0 ? Vec3::Zero() : Vec3(10.0 * Vec3(u(rng), u(rng), u(rng)));
    const Vec3 axis = Vec3(u(rng), u(rng), u(rng)).normalized();
    const double budget = std::abs(u(rng));
    const AngularImpulse r = resisting_angular_impulse(axis, b1, b2, budget);
    const double s0 = axis.dot(b1.w_W - b2.w_W);
    ContactBody a1 = b1, a2 = b2;
    apply_angular_impulse(r.L_W, a1, a2);
    const double s1 = axis.dot(a1.w_W - a2.w_W);
    CHECK(s0 * s1 >= -1e-12 * s0 * s0);
    CHECK(std::abs(s1) <= std::abs(s0));
    const double dE =
        kinetic_energy(a1) + kinetic_energy(a2) - kinetic_energy(b1) - kinetic_energy(b2);
    CHECK(dE == Approx(r.energy_change).margin(1e-9 * (1.0 + kinetic_energy(b1))));
    CHECK(r.energy_change <= 0.0);
  }
}

}  // namespace palpable
