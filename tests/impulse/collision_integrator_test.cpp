// Tests of the collision integrator (impulse/collision_integrator.hpp): closed forms (the rod
// table of DESIGN.md §4 derived exactly, the sphere on ground, the 1-D impact formula), energy
// and friction-cone invariants over random contacts, Kane's paradox for Newton's law, and an
// independent fixed-step RK4 integration of a 3-D contact whose slip direction curves.
#include "impulse/collision_integrator.hpp"
#include "impulse/collision_matrix.hpp"
#include "impulse_test_support.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <iostream>
#include <random>

namespace palpable {
namespace {

using palpable::test::params_for;

const RestitutionLaw kLaws[] = {RestitutionLaw::kNewton, RestitutionLaw::kPoisson,
                                RestitutionLaw::kStronge};

// The thin rod of DESIGN.md §4 (m = 1, L = 1, leaning 45 degrees, lower end on fixed ground).
Mat3 rod_K() {
  Mat3 K;
  K << 2.5, 0.0, -1.5, 0.0, 4.0, 0.0, -1.5, 0.0, 2.5;
  return K;
}
const Vec3 kRodU0(0.5, 0.0, -1.0);

struct RodRow {
  double mu;
  RestitutionLaw law;
  double u_x, u_z, p_x, p_z;  // as printed in DESIGN.md (5 decimals)
  double exact_u_x, exact_u_z, exact_p_x, exact_p_z;
};

// Exact values: with a 2-D K the slip direction is piecewise constant (+x, then reversed or
// stuck), so u, p are piecewise linear in p_z and W_z piecewise quadratic. Derived with exact
// rationals (Stronge brings a square root): slip stops at p1 = 0.5 / (2.5 mu + 1.5); for mu < 0.6
// = |K_xz| / K_xx the stick is unstable and sliding reverses (zeta = (mu, 0, 1)), for mu = 1 it is
// stable (zeta = (0.6, 0, 1)); maximum compression and the end of restitution follow.
const double s322 = std::sqrt(322.0), s298 = std::sqrt(298.0), s55 = std::sqrt(55.0);
const RodRow kRodTable[] = {
    {0.2, RestitutionLaw::kNewton, -0.36364, 0.5, 0.02273, 0.61364,  //
     -4.0 / 11.0, 0.5, 1.0 / 44.0, 27.0 / 44.0},
    {0.2, RestitutionLaw::kPoisson, -0.32955, 0.425, 0.01591, 0.57955,  //
     -29.0 / 88.0, 17.0 / 40.0, 7.0 / 440.0, 51.0 / 88.0},
    {0.2, RestitutionLaw::kStronge, -0.34028, 0.44861, 0.01806, 0.59028,  //
     -s322 / 88.0 - 3.0 / 22.0, s322 / 40.0, -1.0 / 44.0 + s322 / 440.0, s322 / 88.0 + 17.0 / 44.0},
    {0.5, RestitutionLaw::kNewton, -0.12987, 0.5, 0.16883, 0.70130,  //
     -10.0 / 77.0, 0.5, 13.0 / 77.0, 54.0 / 77.0},
    {0.5, RestitutionLaw::kPoisson, -0.11039, 0.36364, 0.12987, 0.62338,  //
     -17.0 / 154.0, 4.0 / 11.0, 10.0 / 77.0, 48.0 / 77.0},
    {0.5, RestitutionLaw::kStronge, -0.11449, 0.39233, 0.13807, 0.63978,  //
     -9.0 / 154.0 - s298 / 308.0, s298 / 44.0, 2.0 / 77.0 + s298 / 154.0,
     s298 / 77.0 + 32.0 / 77.0},
    {1.0, RestitutionLaw::kNewton, 0.0, 0.5, 0.25, 0.75,  //
     0.0, 0.5, 0.25, 0.75},
    {1.0, RestitutionLaw::kPoisson, 0.0, 0.35, 0.19375, 0.65625,  //
     0.0, 7.0 / 20.0, 31.0 / 160.0, 21.0 / 32.0},
    {1.0, RestitutionLaw::kStronge, 0.0, 0.37081, 0.20155, 0.66926,  //
     0.0, s55 / 20.0, 1.0 / 16.0 + 3.0 * s55 / 160.0, s55 / 32.0 + 7.0 / 16.0},
};

std::string phase_list(const CollisionResult& r) {
  std::string out;
  for (int i = 0; i < r.phase_count; ++i) out += (i ? "; " : "") + describe(r.phases[i]);
  return out;
}

TEST_CASE("rod on ground: the DESIGN.md table, to the printed digits and exactly",
          "[impulse][rod]") {
  for (const RodRow& row : kRodTable) {
    CAPTURE(row.mu, to_string(row.law));
    const CollisionResult r =
        integrate_collision(rod_K(), kRodU0, params_for(row.mu, 0.5, row.law));
    CAPTURE(phase_list(r));
    REQUIRE(r.status == CollisionStatus::kOk);
    // The printed table, to its precision.
    CHECK(std::abs(r.u_final_c.x() - row.u_x) <= 6e-6);
    CHECK(std::abs(r.u_final_c.z() - row.u_z) <= 6e-6);
    CHECK(std::abs(r.p_c.x() - row.p_x) <= 6e-6);
    CHECK(std::abs(r.p_c.z() - row.p_z) <= 6e-6);
    // The exact closed forms, at the default tolerance.
    CHECK(std::abs(r.u_final_c.x() - row.exact_u_x) <= 1e-9);
    CHECK(std::abs(r.u_final_c.z() - row.exact_u_z) <= 1e-9);
    CHECK(std::abs(r.p_c.x() - row.exact_p_x) <= 1e-9);
    CHECK(std::abs(r.p_c.z() - row.exact_p_z) <= 1e-9);
    CHECK(r.u_final_c.y() == 0.0);
    CHECK(r.p_c.y() == 0.0);
    // What happened: slid, then reversed (unstable stick, mu < 0.6) or stuck stably (mu = 1).
    REQUIRE(r.phase_count >= 2);
    CHECK(r.phases[0].kind == PhaseKind::kSlid);
    if (row.mu < 0.6) {
      CHECK(r.phases[1].kind == PhaseKind::kResumedSliding);
      CHECK(r.phases[1].direction.x() == Approx(-1.0).margin(1e-15));
      CHECK(describe(r.phases[1]) == "resumed sliding in direction (-1, 0)");
    } else {
      CHECK(r.phases[1].kind == PhaseKind::kStuckStably);
    }
    CHECK(r.phases[1].p_z_begin == Approx(0.5 / (2.5 * row.mu + 1.5)).epsilon(1e-12));
    // Consistency of the reported quantities.
    CHECK((r.u_final_c - (kRodU0 + rod_K() * r.p_c)).norm() <= 1e-15);
    CHECK(r.energy_change == Approx(0.5 * (kRodU0 + r.u_final_c).dot(r.p_c)).epsilon(1e-14));
    CHECK(r.work_compression < 0.0);
    if (row.law == RestitutionLaw::kStronge) {
      CHECK(r.work_normal == Approx(0.75 * r.work_compression).epsilon(1e-9));
    }
    if (row.law == RestitutionLaw::kPoisson) {
      CHECK(r.p_c.z() == Approx(1.5 * r.p_z_compression).epsilon(1e-12));
    }
  }
}

TEST_CASE("rod on ground: convergence with the integration tolerance", "[impulse][rod]") {
  for (const RodRow& row : kRodTable) {
    CAPTURE(row.mu, to_string(row.law));
    const Vec3 reference =
        integrate_collision(rod_K(), kRodU0, params_for(row.mu, 0.5, row.law, 1e-13)).p_c;
    const Vec3 exact(row.exact_p_x, 0.0, row.exact_p_z);
    CHECK((reference - exact).norm() <= 1e-12);
    const Vec3 p_default =
        integrate_collision(rod_K(), kRodU0, params_for(row.mu, 0.5, row.law, 1e-9)).p_c;
    const Vec3 p_tight =
        integrate_collision(rod_K(), kRodU0, params_for(row.mu, 0.5, row.law, 1e-11)).p_c;
    CHECK((p_default - reference).norm() <= 1e-6);
    CHECK((p_tight - reference).norm() <= 1e-9);
  }
}

TEST_CASE("sphere on ground: u_z' = 1.2, p_z = 3.2 under all laws, slip decays by 7/2 mu p_z",
          "[impulse][sphere]") {
  const Mat3 K = Vec3(3.5, 3.5, 1.0).asDiagonal();
  const double slips[] = {0.0, 0.5, 3.0, 11.2, 25.0};
  const double mus[] = {0.0, 0.1, 0.5, 1.0};
  for (RestitutionLaw law : kLaws) {
    for (double mu : mus) {
      for (double slip : slips) {
        const Vec2 dir = Vec2(0.6, -0.8);
        const Vec3 u0(slip * dir.x(), slip * dir.y(), -2.0);
        CAPTURE(to_string(law), mu, slip);
        const CollisionResult r = integrate_collision(K, u0, params_for(mu, 0.6, law));
        CAPTURE(phase_list(r));
        REQUIRE(r.status == CollisionStatus::kOk);
        CHECK(r.u_final_c.z() == Approx(1.2).epsilon(1e-12));
        CHECK(r.p_c.z() == Approx(3.2).epsilon(1e-12));
        const double expected = std::max(0.0, slip - 3.5 * mu * 3.2);
        const Vec2 u_t = r.u_final_c.head<2>();
        CHECK(std::abs(u_t.norm() - expected) <= 1e-9);
        if (expected > 0.0) CHECK((u_t / u_t.norm() - dir).norm() <= 1e-12);
      }
    }
  }
}

TEST_CASE("two bodies head on: v1' = [m1 v1 + m2 v2 + m2 e (v2 - v1)] / (m1 + m2)",
          "[impulse][one_dimensional]") {
  const double ratios[] = {1e-6, 1e-4, 1e-2, 0.3, 1.0, 3.0, 1e2, 1e4, 1e6};
  const double restitutions[] = {0.0, 0.25, 0.5, 0.9, 1.0};
  for (RestitutionLaw law : kLaws) {
    for (double ratio : ratios) {
      for (double e : restitutions) {
        for (double mu : {0.0, 0.7}) {
          const double m1 = 1.0, m2 = ratio;
          const double v1 = -1.5, v2 = 0.5;  // along the normal n (body 2 -> body 1)
          ContactBody b1, b2;
          b1.inv_mass = 1.0 / m1;
          b2.inv_mass = 1.0 / m2;
          b1.v_W = Vec3(0, 0, v1);
          b2.v_W = Vec3(0, 0, v2);
          CAPTURE(to_string(law), ratio, e, mu);
          const CollisionResult r =
              resolve_collision(b1, b2, Mat3::Identity(), params_for(mu, e, law));
          REQUIRE(r.status == CollisionStatus::kOk);
          apply_impulse(r.p_W, b1, b2);
          const double v1_expected = (m1 * v1 + m2 * v2 + m2 * e * (v2 - v1)) / (m1 + m2);
          const double v2_expected = (m1 * v1 + m2 * v2 + m1 * e * (v1 - v2)) / (m1 + m2);
          CHECK(b1.v_W.z() == Approx(v1_expected).epsilon(1e-12).margin(1e-12));
          CHECK(b2.v_W.z() == Approx(v2_expected).epsilon(1e-12).margin(1e-12));
          CHECK(b1.v_W.head<2>().norm() == 0.0);
        }
      }
    }
  }
}

TEST_CASE("frictionless contacts are closed form, with no integration steps",
          "[impulse][frictionless]") {
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    Mat3 A = Mat3::NullaryExpr([&](Eigen::Index, Eigen::Index) { return unit(rng); });
    const Mat3 K = A * A.transpose() + 0.1 * Mat3::Identity();
    const Vec3 u0(unit(rng), unit(rng), -0.1 - std::abs(unit(rng)));
    const double e = 0.5 * (1.0 + unit(rng));
    for (RestitutionLaw law : kLaws) {
      CAPTURE(i, to_string(law));
      const CollisionResult r = integrate_collision(K, u0, params_for(0.0, e, law));
      REQUIRE(r.status == CollisionStatus::kOk);
      CHECK(r.steps == 0);
      CHECK(r.rhs_evaluations == 0);
      CHECK(r.p_c.head<2>().norm() == 0.0);
      CHECK(r.p_c.z() == Approx(-(1.0 + e) * u0.z() / K(2, 2)).epsilon(1e-13));
      CHECK(r.u_final_c.z() == Approx(-e * u0.z()).epsilon(1e-13));
      REQUIRE(r.phase_count == 1);
      CHECK(r.phases[0].kind == PhaseKind::kFrictionless);
    }
  }
}

TEST_CASE("e = 0 ends at maximum compression under every law", "[impulse][plastic]") {
  for (RestitutionLaw law : kLaws) {
    for (double mu : {0.0, 0.2, 0.5, 1.0}) {
      CAPTURE(to_string(law), mu);
      const CollisionResult r = integrate_collision(rod_K(), kRodU0, params_for(mu, 0.0, law));
      REQUIRE(r.status == CollisionStatus::kOk);
      CHECK(std::abs(r.u_final_c.z()) <= 1e-15);
      CHECK(r.p_c.z() == r.p_z_compression);
      CHECK(r.work_normal == r.work_compression);
    }
  }
}

TEST_CASE("a collision can stick from the start (u_t0 = 0)", "[impulse][stick]") {
  // Rod dropped vertically: no slip at p_z = 0. mu = 1 >= 0.6 sticks stably; mu = 0.2 slides at
  // once in the direction that makes (K zeta)_t parallel to it: -x here.
  const Vec3 u0(0.0, 0.0, -1.0);
  const CollisionResult stable =
      integrate_collision(rod_K(), u0, params_for(1.0, 0.5, RestitutionLaw::kPoisson));
  REQUIRE(stable.status == CollisionStatus::kOk);
  REQUIRE(stable.phase_count == 1);
  CHECK(stable.phases[0].kind == PhaseKind::kStuckStably);
  CHECK(std::abs(stable.u_final_c.x()) <= 1e-15);
  // Stable sticking: du_z/dp_z = 1 / (K^-1)_33 = 2.5 - 1.5 * 0.6 = 1.6.
  CHECK(stable.p_z_compression == Approx(1.0 / 1.6).epsilon(1e-14));
  const CollisionResult unstable =
      integrate_collision(rod_K(), u0, params_for(0.2, 0.5, RestitutionLaw::kPoisson));
  REQUIRE(unstable.status == CollisionStatus::kOk);
  REQUIRE(unstable.phase_count == 1);
  CHECK(unstable.phases[0].kind == PhaseKind::kResumedSliding);
  CHECK(unstable.phases[0].direction.x() == Approx(-1.0));
  CHECK(unstable.p_c.x() == Approx(0.2 * unstable.p_c.z()).epsilon(1e-14));
}

TEST_CASE("unstable sticking resumes in the direction where (K zeta)_t is parallel to it",
          "[impulse][stick]") {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int unstable_count = 0;
  for (int i = 0; i < 2000; ++i) {
    Mat3 A = Mat3::NullaryExpr([&](Eigen::Index, Eigen::Index) { return unit(rng); });
    const Mat3 K = A * A.transpose() + 0.05 * Mat3::Identity();
    const double mu = std::abs(unit(rng));
    Vec2 t;
    const Vec2 stick_t = K.topLeftCorner<2, 2>().inverse() * Vec2(K(0, 2), K(1, 2));
    CAPTURE(i, mu);
    const bool unstable = unstable_stick_direction(K, mu, t);
    CHECK(unstable == (stick_t.norm() > mu));
    if (!unstable) continue;
    ++unstable_count;
    CHECK(t.norm() == Approx(1.0).epsilon(1e-14));
    const Vec3 d = K * Vec3(-mu * t.x(), -mu * t.y(), 1.0);
    const Vec2 d_t = d.head<2>();
    CHECK(d_t.dot(t) > 0.0);
    CHECK(std::abs(d_t.x() * t.y() - d_t.y() * t.x()) <= 1e-12 * d_t.norm());
  }
  CHECK(unstable_count > 100);
}

// Random bodies and offsets: the collision matrix of a random contact.
struct RandomContact {
  ContactBody b1, b2;
  Mat3 R_WC;
  double m1 = 0.0, m2 = 0.0;  // 0: infinite
};

Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

ContactBody random_body(std::mt19937_64& rng, bool infinite, double& mass) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  ContactBody b;
  b.v_W = Vec3(unit(rng), unit(rng), unit(rng));
  b.w_W = Vec3(unit(rng), unit(rng), unit(rng));
  b.r_W = Vec3(unit(rng), unit(rng), unit(rng));
  if (infinite) {
    mass = 0.0;
    return b;
  }
  mass = std::pow(10.0, 1.5 * unit(rng));
  const Mat3 Q = random_rotation(rng);
  const Vec3 moments = mass * Vec3(0.05 + 0.5 * (1 + unit(rng)), 0.05 + 0.5 * (1 + unit(rng)),
                                   0.05 + 0.5 * (1 + unit(rng)));
  b.inv_mass = 1.0 / mass;
  b.inv_inertia_W = Q * moments.cwiseInverse().asDiagonal() * Q.transpose();
  return b;
}

TEST_CASE("100000 random contacts: energy, friction cone, momentum - Newton's law creates energy",
          "[impulse][random]") {
  std::mt19937_64 rng(0x9a4f7052);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> zero_one(0.0, 1.0);
  int newton_gains = 0;
  double max_gain[3] = {-1.0, -1.0, -1.0};
  double max_cone_excess = 0.0;
  int sticks = 0, reversals = 0;
  long steps = 0;
  int stalls = 0, max_steps = 0;
  double max_deviation = 0.0;
  const int kContacts = 100000;
  for (int i = 0; i < kContacts; ++i) {
    RandomContact c;
    c.b1 = random_body(rng, false, c.m1);
    c.b2 = random_body(rng, zero_one(rng) < 0.3, c.m2);
    const Mat3 R = random_rotation(rng);
    // Make the contact approaching: flip body 1's velocity field if needed.
    const Vec3 u_W = contact_point_velocity_W(c.b1) - contact_point_velocity_W(c.b2);
    if (u_W.dot(R.col(2)) >= 0.0) {
      c.b1.v_W -= 2.0 * u_W.dot(R.col(2)) * R.col(2) + 0.01 * R.col(2);
    }
    const double mu = 2.0 * zero_one(rng);
    const double e = zero_one(rng);
    for (int l = 0; l < 3; ++l) {
      const RestitutionLaw law = kLaws[l];
      INFO("contact " << i << " law " << to_string(law) << " mu " << mu << " e " << e);
      const CollisionResult r = resolve_collision(c.b1, c.b2, R, params_for(mu, e, law));
      if (r.status != CollisionStatus::kOk) {
        const Mat3 K_c = R.transpose() * collision_matrix_W(c.b1, c.b2) * R;
        std::cout.precision(17);
        std::cout << "failed: " << to_string(r.status) << "\nK_c\n"
                  << K_c << "\nu0_c " << r.u0_c.transpose() << "\n";
      }
      REQUIRE(r.status == CollisionStatus::kOk);
      steps += r.steps;
      stalls += r.stalled_slip_landings;
      max_steps = std::max(max_steps, r.steps + r.rejected_steps);
      for (int k = 0; k < r.phase_count; ++k) {
        sticks += r.phases[k].kind == PhaseKind::kStuckStably;
        reversals += r.phases[k].kind == PhaseKind::kResumedSliding;
      }
      // Kinetic energy of the relative motion available at the contact: 1/2 u0^T K^-1 u0.
      const Mat3 K_c = R.transpose() * collision_matrix_W(c.b1, c.b2) * R;
      const double available = 0.5 * r.u0_c.dot(K_c.ldlt().solve(r.u0_c));
      const double gain = r.energy_change / available;
      max_gain[l] = std::max(max_gain[l], gain);
      if (law == RestitutionLaw::kNewton) {
        if (gain > 1e-9) ++newton_gains;
      } else {
        REQUIRE(gain <= 1e-12);
      }
      // Every 20th contact: the default tolerance agrees with a 1e-13 solution to 1e-6.
      if (i % 20 == 0) {
        const CollisionResult tight =
            resolve_collision(c.b1, c.b2, R, params_for(mu, e, law, 1e-13));
        const double deviation = (r.p_c - tight.p_c).norm() / tight.p_c.norm();
        max_deviation = std::max(max_deviation, deviation);
        REQUIRE(deviation <= 1e-6);
      }
      // The accumulated impulse lies in the friction cone (to the integration tolerance).
      const double excess = std::hypot(r.p_c.x(), r.p_c.y()) - mu * r.p_c.z();
      max_cone_excess = std::max(max_cone_excess, excess / r.p_c.z());
      REQUIRE(excess <= 1e-8 * r.p_c.z());
      REQUIRE(r.p_c.z() > 0.0);
      // Body 2 receives exactly -p; linear momentum is conserved; u' = u0 + K p at the contact.
      ContactBody b1 = c.b1, b2 = c.b2;
      apply_impulse(r.p_W, b1, b2);
      if (c.m2 > 0.0) {
        const Vec3 momentum_before = c.m1 * c.b1.v_W + c.m2 * c.b2.v_W;
        const Vec3 momentum_after = c.m1 * b1.v_W + c.m2 * b2.v_W;
        REQUIRE((momentum_after - momentum_before).norm() <=
                1e-13 * (c.m1 * c.b1.v_W.norm() + c.m2 * c.b2.v_W.norm() + r.p_W.norm()));
        // Body 2's change of momentum is -p (to the rounding of v2 + dv2).
        REQUIRE(((b2.v_W - c.b2.v_W) * c.m2 + r.p_W).norm() <=
                4e-16 * (c.m2 * c.b2.v_W.norm() + r.p_W.norm()));
      } else {
        REQUIRE(b2.v_W == c.b2.v_W);
        REQUIRE(b2.w_W == c.b2.w_W);
      }
      const Vec3 u_after =
          R.transpose() * (contact_point_velocity_W(b1) - contact_point_velocity_W(b2));
      REQUIRE((u_after - r.u_final_c).norm() <= 1e-11 * (1.0 + r.u0_c.norm()));
    }
  }
  std::cout << "random contacts: " << kContacts << " x 3 laws; Newton created energy in "
            << newton_gains << "; max relative energy gain Newton " << max_gain[0] << " Poisson "
            << max_gain[1] << " Stronge " << max_gain[2] << "; max cone excess " << max_cone_excess
            << "; stable sticks " << sticks << ", resumed slides " << reversals
            << "; mean RK steps " << double(steps) / (3.0 * kContacts) << ", max steps "
            << max_steps << "; stalled slip zeros landed implicitly " << stalls
            << "; max relative deviation from the 1e-13 solution " << max_deviation << "\n";
  // Kane's paradox: Newton's law creates energy in some contacts; the other two never do.
  CHECK(newton_gains > 0);
  CHECK(max_gain[0] > 1e-3);
}

// An independent oracle: classical RK4 at a fixed, fine step in p_z, with linear interpolation
// of the event functions between steps (error O(h^2)).
struct Rk4Result {
  Vec3 p = Vec3::Zero();
  double W = 0.0;
};

Rk4Result rk4_stronge(const Mat3& K, const Vec3& u0, double mu, double e, double h) {
  auto f = [&](double p_z, const Vec3& y) {
    const Vec3 u = u0 + K * Vec3(y(0), y(1), p_z);
    const Vec2 t = u.head<2>().normalized();
    return Vec3(-mu * t.x(), -mu * t.y(), u.z());
  };
  Vec3 y = Vec3::Zero();
  double p_z = 0.0;
  bool compressing = true;
  double W_end = 0.0;
  for (;;) {
    const Vec3 k1 = f(p_z, y);
    const Vec3 k2 = f(p_z + 0.5 * h, y + 0.5 * h * k1);
    const Vec3 k3 = f(p_z + 0.5 * h, y + 0.5 * h * k2);
    const Vec3 k4 = f(p_z + h, y + h * k3);
    const Vec3 y1 = y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    const double g0 = compressing ? (u0 + K * Vec3(y(0), y(1), p_z)).z() : y(2) - W_end;
    const double g1 = compressing ? (u0 + K * Vec3(y1(0), y1(1), p_z + h)).z() : y1(2) - W_end;
    if (g0 < 0.0 && g1 >= 0.0) {
      const double s = g0 / (g0 - g1);
      const Vec3 ys = y + s * (y1 - y);
      if (compressing) {
        compressing = false;
        W_end = (1.0 - e * e) * ys(2);
        y = ys;
        p_z += s * h;
        continue;
      }
      return {Vec3(ys(0), ys(1), p_z + s * h), ys(2)};
    }
    y = y1;
    p_z += h;
  }
}

TEST_CASE("3-D contact with a curving slip direction against a fixed-step RK4",
          "[impulse][curving]") {
  // A body touching at an offset off every principal axis: K couples all three directions, so
  // the slip direction turns continuously; mu and u0 chosen so that it slides throughout.
  ContactBody b1, b2;
  b1.inv_mass = 1.0;
  b1.inv_inertia_W = Vec3(12.0, 6.0, 3.0).asDiagonal();
  b1.r_W = Vec3(-0.3, 0.2, -0.35);
  const Mat3 K = collision_matrix_W(b1, b2);
  const Vec3 u0(1.0, 1.5, -1.0);
  const double mu = 0.3, e = 0.7;
  const CollisionResult r = integrate_collision(K, u0, params_for(mu, e, RestitutionLaw::kStronge));
  CAPTURE(phase_list(r));
  REQUIRE(r.status == CollisionStatus::kOk);
  REQUIRE(r.phase_count == 1);
  REQUIRE(r.phases[0].kind == PhaseKind::kSlid);
  // The slip direction really turns.
  const Vec2 t0 = u0.head<2>().normalized(), t1 = r.u_final_c.head<2>().normalized();
  CHECK(std::acos(t0.dot(t1)) > 0.3);
  const Rk4Result oracle = rk4_stronge(K, u0, mu, e, 1e-6);
  CHECK((r.p_c - oracle.p).norm() <= 1e-7);
  CHECK(std::abs(r.work_normal - oracle.W) <= 1e-7);
  // And the tolerance knob converges toward the tight solution.
  const Vec3 tight =
      integrate_collision(K, u0, params_for(mu, e, RestitutionLaw::kStronge, 1e-13)).p_c;
  CHECK((tight - oracle.p).norm() <= 1e-8);
  CHECK((r.p_c - tight).norm() <= 1e-6);
  CHECK((integrate_collision(K, u0, params_for(mu, e, RestitutionLaw::kStronge, 1e-11)).p_c - tight)
            .norm() <= 1e-9);
}

TEST_CASE("3-D slip spiralling into a stick is located to tolerance", "[impulse][curving]") {
  ContactBody b1, b2;
  b1.inv_mass = 1.0;
  b1.inv_inertia_W = Vec3(12.0, 6.0, 3.0).asDiagonal();
  b1.r_W = Vec3(-0.3, 0.2, -0.35);
  const Mat3 K = collision_matrix_W(b1, b2);
  const Vec3 u0(0.3, -0.2, -1.0);
  int sticks = 0;
  for (RestitutionLaw law : kLaws) {
    for (double mu : {0.4, 1.0, 2.0}) {
      CAPTURE(to_string(law), mu);
      const CollisionResult tight = integrate_collision(K, u0, params_for(mu, 0.5, law, 1e-13));
      const CollisionResult r = integrate_collision(K, u0, params_for(mu, 0.5, law));
      CAPTURE(phase_list(r));
      REQUIRE(r.status == CollisionStatus::kOk);
      REQUIRE(r.phase_count >= 1);
      CHECK(r.phases[0].kind == PhaseKind::kSlid);
      if (r.phase_count > 1) {
        ++sticks;
        CHECK(r.phases[1].kind == PhaseKind::kStuckStably);
      }
      CHECK((r.p_c - tight.p_c).norm() <= 1e-6);
      // The slip zero costs O(log 1/tol) steps, without a collapse of the step size.
      CHECK(r.steps < 100);
      CHECK(r.rejected_steps < 10);
    }
  }
  CHECK(sticks == 6);
}

TEST_CASE("bad input is a status, not a throw", "[impulse][status]") {
  const Vec3 u0(0.1, 0.0, -1.0);
  Mat3 not_spd = rod_K();
  not_spd(0, 0) = -1.0;
  CHECK(integrate_collision(not_spd, u0, params_for(0.5, 0.5, RestitutionLaw::kStronge)).status ==
        CollisionStatus::kFailedNotPositive);
  Mat3 nan = rod_K();
  nan(1, 1) = std::nan("");
  CHECK(integrate_collision(nan, u0, params_for(0.5, 0.5, RestitutionLaw::kStronge)).status ==
        CollisionStatus::kFailedNonFinite);
  CHECK(integrate_collision(rod_K(), u0, params_for(0.5, 1.5, RestitutionLaw::kStronge)).status ==
        CollisionStatus::kFailedNotPositive);
  const CollisionResult separating = integrate_collision(
      rod_K(), Vec3(0.1, 0.0, 0.5), params_for(0.5, 0.5, RestitutionLaw::kStronge));
  CHECK(separating.status == CollisionStatus::kSeparating);
  CHECK(separating.p_c == Vec3::Zero());
  CollisionParameters few = params_for(0.3, 0.7, RestitutionLaw::kStronge, 1e-13);
  few.max_steps = 3;
  ContactBody b1, b2;
  b1.inv_mass = 1.0;
  b1.inv_inertia_W = Vec3(12.0, 6.0, 3.0).asDiagonal();
  b1.r_W = Vec3(-0.3, 0.2, -0.35);
  CHECK(integrate_collision(collision_matrix_W(b1, b2), Vec3(1.0, 1.5, -1.0), few).status ==
        CollisionStatus::kFailedStepLimit);
}

}  // namespace
}  // namespace palpable
