// Tests of the collision matrix and the world-frame side of a collision
// (impulse/collision_matrix.hpp): DESIGN.md §4's closed forms (sphere, leaning rod), symmetry and
// positive definiteness, conservation of momentum and angular momentum by apply_impulse,
// infinite-mass (fixed, kinematic) bodies and the contact frame.
#include "impulse/collision_matrix.hpp"
#include "impulse_test_support.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <random>

namespace palpable {
namespace {

using palpable::test::params_for;

TEST_CASE("solid sphere on fixed ground: K_c = diag(7/2, 7/2, 1)", "[impulse][matrix]") {
  const double m = 1.0, R = 0.1;
  ContactBody sphere, ground;
  sphere.inv_mass = 1.0 / m;
  sphere.inv_inertia_W = Mat3::Identity() / (0.4 * m * R * R);
  sphere.r_W = Vec3(0.0, 0.0, -R);
  const Mat3 K = collision_matrix_W(sphere, ground);
  const Mat3 expected = Vec3(3.5, 3.5, 1.0).asDiagonal();
  CHECK((K - expected).cwiseAbs().maxCoeff() <= 1e-13);
}

TEST_CASE("thin rod leaning at 45 degrees: the DESIGN.md K_c", "[impulse][matrix]") {
  // m = 1, L = 1, transverse moments 1/12 and any positive axial moment; the axis points from the
  // lower end (r = (-sqrt2/4, 0, -sqrt2/4) from the centre of mass) to the upper one.
  for (double axial : {1e-4, 1e-2, 1.0}) {
    const Vec3 axis = Vec3(1.0, 0.0, 1.0).normalized();
    Mat3 Q;
    Q.col(0) = Vec3::UnitY();
    Q.col(1) = axis.cross(Vec3::UnitY());
    Q.col(2) = axis;
    ContactBody rod, ground;
    rod.inv_mass = 1.0;
    rod.inv_inertia_W = Q * Vec3(12.0, 12.0, 1.0 / axial).asDiagonal() * Q.transpose();
    rod.r_W = -0.5 * axis;
    Mat3 expected;
    expected << 2.5, 0.0, -1.5, 0.0, 4.0, 0.0, -1.5, 0.0, 2.5;
    CAPTURE(axial);
    CHECK((collision_matrix_W(rod, ground) - expected).cwiseAbs().maxCoeff() <= 1e-12);
  }
}

TEST_CASE("K is symmetric positive definite for random bodies, any frame", "[impulse][matrix]") {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 1000; ++i) {
    ContactBody b1, b2;
    for (ContactBody* b : {&b1, &b2}) {
      const Mat3 A = Mat3::NullaryExpr([&](Eigen::Index, Eigen::Index) { return unit(rng); });
      b->inv_mass = 0.1 + std::abs(unit(rng));
      b->inv_inertia_W = A * A.transpose() + 0.01 * Mat3::Identity();
      b->r_W = Vec3(unit(rng), unit(rng), unit(rng));
    }
    if (i % 3 == 0) {  // body 2 fixed
      b2.inv_mass = 0.0;
      b2.inv_inertia_W.setZero();
    }
    const Mat3 K = collision_matrix_W(b1, b2);
    CAPTURE(i);
    CHECK(K == K.transpose());
    CHECK(Eigen::SelfAdjointEigenSolver<Mat3>(K).eigenvalues().minCoeff() > 0.0);
    // du = K dp, checked against applying a unit impulse.
    const Vec3 p(unit(rng), unit(rng), unit(rng));
    ContactBody c1 = b1, c2 = b2;
    apply_impulse(p, c1, c2);
    const Vec3 du = (contact_point_velocity_W(c1) - contact_point_velocity_W(c2)) -
                    (contact_point_velocity_W(b1) - contact_point_velocity_W(b2));
    CHECK((du - K * p).norm() <= 1e-13 * (1.0 + K.norm()));
  }
}

TEST_CASE("apply_impulse: body 2 receives -p, momentum and angular momentum are conserved",
          "[impulse][apply]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Vec3 c(unit(rng), unit(rng), unit(rng));  // contact point
    const Vec3 x1(unit(rng), unit(rng), unit(rng)), x2(unit(rng), unit(rng), unit(rng));
    const double m1 = 0.5 + std::abs(unit(rng)), m2 = 0.5 + std::abs(unit(rng));
    const Mat3 A = Mat3::NullaryExpr([&](Eigen::Index, Eigen::Index) { return unit(rng); });
    const Mat3 I1 = A * A.transpose() + 0.1 * Mat3::Identity();
    const Mat3 I2 = A.transpose() * A + 0.2 * Mat3::Identity();
    ContactBody b1, b2;
    b1.inv_mass = 1.0 / m1;
    b2.inv_mass = 1.0 / m2;
    b1.inv_inertia_W = I1.inverse();
    b2.inv_inertia_W = I2.inverse();
    b1.r_W = c - x1;
    b2.r_W = c - x2;
    const Vec3 p(unit(rng), unit(rng), unit(rng));
    apply_impulse(p, b1, b2);
    // From rest, body 2's velocity change is exactly -p/m2 (the same operations as body 1's).
    CHECK(b2.v_W == -(b2.inv_mass * p));
    CHECK(b1.v_W == b1.inv_mass * p);
    const Vec3 momentum = m1 * b1.v_W + m2 * b2.v_W;
    const Vec3 angular = x1.cross(m1 * b1.v_W) + I1 * b1.w_W + x2.cross(m2 * b2.v_W) + I2 * b2.w_W;
    CAPTURE(i);
    CHECK(momentum.norm() <= 1e-14 * p.norm());
    CHECK(angular.norm() <= 1e-12 * p.norm());
  }
}

TEST_CASE("fixed and kinematic bodies: infinite mass, but their velocity field counts",
          "[impulse][kinematic]") {
  // A resting sphere on a kinematic conveyor moving at +x: the conveyor's velocity makes the
  // contact slide, friction drags the sphere along +x, and the conveyor is not changed.
  const double m = 1.0, R = 0.1;
  ContactBody sphere, conveyor;
  sphere.inv_mass = 1.0 / m;
  sphere.inv_inertia_W = Mat3::Identity() / (0.4 * m * R * R);
  sphere.r_W = Vec3(0.0, 0.0, -R);
  sphere.v_W = Vec3(0.0, 0.0, -1.0);
  conveyor.v_W = Vec3(1.0, 0.0, 0.0);
  conveyor.w_W = Vec3(0.0, 0.0, 0.5);
  conveyor.r_W = Vec3(2.0, 0.0, 0.0);  // contact 2 m from the conveyor's reference point
  const CollisionResult r = resolve_collision(sphere, conveyor, Mat3::Identity(),
                                              params_for(0.3, 0.5, RestitutionLaw::kStronge));
  REQUIRE(r.status == CollisionStatus::kOk);
  // Surface velocity of the conveyor at the contact: v + w x r = (1, 1, 0).
  CHECK((r.u0_c - Vec3(-1.0, -1.0, -1.0)).norm() <= 1e-15);
  ContactBody s = sphere, c = conveyor;
  apply_impulse(r.p_W, s, c);
  CHECK(c.v_W == conveyor.v_W);
  CHECK(c.w_W == conveyor.w_W);
  CHECK(s.v_W.x() > 0.0);
  CHECK(s.v_W.y() > 0.0);
  CHECK(s.v_W.z() == Approx(0.5).epsilon(1e-12));
  const Vec3 u_after = contact_point_velocity_W(s) - contact_point_velocity_W(c);
  CHECK((u_after - r.u_final_c).norm() <= 1e-13);
}

TEST_CASE("contact frame: orthonormal, right-handed, normal third", "[impulse][frame]") {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  std::vector<Vec3> normals = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ(),
                               Vec3(1, 1, 0).normalized()};
  for (int i = 0; i < 100; ++i) normals.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
  for (const Vec3& n : normals) {
    const Mat3 R = contact_frame_W(n);
    CAPTURE(n.transpose());
    CHECK((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-15);
    CHECK(R.determinant() == Approx(1.0).epsilon(1e-15));
    CHECK((R.col(2) - n).norm() <= 1e-15);
  }
}

TEST_CASE("resolve_collision: world impulse and frame-independent outcome", "[impulse][frame]") {
  // The same sphere-on-ground collision described in a rotated world gives the rotated impulse.
  const double m = 1.0, R = 0.1;
  const Mat3 Q = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  ContactBody sphere, ground;
  sphere.inv_mass = 1.0 / m;
  sphere.inv_inertia_W = Mat3::Identity() / (0.4 * m * R * R);
  sphere.r_W = Q * Vec3(0.0, 0.0, -R);
  sphere.v_W = Q * Vec3(3.0, 0.0, -2.0);
  const Mat3 R_WC = contact_frame_W(Q * Vec3::UnitZ());
  const CollisionResult r =
      resolve_collision(sphere, ground, R_WC, params_for(0.1, 0.6, RestitutionLaw::kStronge));
  REQUIRE(r.status == CollisionStatus::kOk);
  CHECK((r.p_W - R_WC * r.p_c).norm() <= 1e-15);
  ContactBody s = sphere, g = ground;
  apply_impulse(r.p_W, s, g);
  const Vec3 v_body = Q.transpose() * s.v_W;
  CHECK(v_body.z() == Approx(1.2).epsilon(1e-12));
  // Slip 3 - 7/2 * 0.1 * 3.2 = 1.88 at the contact; centre velocity 3 - 0.1 * 3.2 = 2.68.
  CHECK(v_body.x() == Approx(2.68).epsilon(1e-12));
  CHECK(std::abs(v_body.y()) <= 1e-12);
}

}  // namespace
}  // namespace palpable
