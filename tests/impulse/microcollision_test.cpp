// Tests of microcollisions (impulse/microcollision.hpp): the rebound floor under both rules, the
// targets each rule aims at, and an exact-flight model of a flat block resting on a ramp that
// shows Mirtich's reversal rule creeping in the band mu/2 < tan(theta) <= mu while the drift-free
// rule does not (DESIGN.md §4, "Continuous contact").
#include "impulse/microcollision.hpp"
#include "impulse_test_support.hpp"

#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <iostream>
#include <random>

namespace palpable {
namespace {

using palpable::test::params_for;

TEST_CASE("v_micro = sqrt(2 g_n envelope) unless set, the test has a little slack",
          "[impulse][micro]") {
  Settings settings;
  settings.envelope_m = 1e-4;
  CHECK(microcollision_speed(settings, 9.81) == Approx(std::sqrt(2.0 * 9.81 * 1e-4)));
  CHECK(microcollision_speed(settings, -3.0) == 0.0);
  settings.microcollision_speed_mps = 0.05;
  CHECK(microcollision_speed(settings, 9.81) == 0.05);
  CHECK(is_microcollision(-0.05, 0.05, settings));
  CHECK(is_microcollision(-0.05 * (1.0 + 1e-7), 0.05, settings));
  CHECK_FALSE(is_microcollision(-0.051, 0.05, settings));
}

TEST_CASE("the rebound floor: every microcollision separates at >= v_micro, under both rules",
          "[impulse][micro]") {
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> zero_one(0.0, 1.0);
  int in_cone[2] = {0, 0}, fallback[2] = {0, 0};
  for (int i = 0; i < 20000; ++i) {
    const Mat3 A = Mat3::NullaryExpr([&](Eigen::Index, Eigen::Index) { return unit(rng); });
    const Mat3 K = A * A.transpose() + 0.1 * Mat3::Identity();
    const double v_micro = 1e-3 + 0.05 * zero_one(rng);
    // Approach slower than v_micro, including exactly resting (u_z0 = 0) and tangential slip.
    const double u_z0 = i % 5 == 0 ? 0.0 : -v_micro * zero_one(rng);
    const Vec3 u0(0.1 * unit(rng) * (i % 2), 0.1 * unit(rng) * (i % 2), u_z0);
    MicrocollisionContext context;
    context.g_n = 10.0 * zero_one(rng);
    context.a_t_c = Vec2(5.0 * unit(rng), 5.0 * unit(rng));
    const CollisionParameters params =
        params_for(2.0 * zero_one(rng), zero_one(rng), RestitutionLaw::kStronge);
    for (int rule = 0; rule < 2; ++rule) {
      const MicrocollisionRule which =
          rule == 0 ? MicrocollisionRule::kDriftFree : MicrocollisionRule::kReversal;
      const CollisionResult r = resolve_microcollision(K, u0, params, which, context, v_micro);
      CAPTURE(i, rule);
      REQUIRE(r.status == CollisionStatus::kOk);
      CHECK(r.u_final_c.z() >= v_micro * (1.0 - 1e-12));
      CHECK(std::hypot(r.p_c.x(), r.p_c.y()) <= params.friction * r.p_c.z() * (1.0 + 1e-8));
      REQUIRE(r.phase_count >= 1);
      if (r.phases[0].kind == PhaseKind::kMicroFallback) {
        ++fallback[rule];
      } else if (r.phases[0].kind == PhaseKind::kDriftFreeConeBoundary) {
        // On the cone boundary, reaching the normal target exactly.
        ++fallback[rule];
        CHECK(std::hypot(r.p_c.x(), r.p_c.y()) ==
              Approx(params.friction * r.p_c.z()).epsilon(1e-12));
        CHECK(r.u_final_c.z() ==
              Approx(std::max(-params.restitution * u_z0, v_micro)).epsilon(1e-12));
      } else {
        ++in_cone[rule];
        if (which == MicrocollisionRule::kReversal) {
          CHECK((r.u_final_c.head<2>() + u0.head<2>()).norm() <= 1e-12);
          CHECK(r.u_final_c.z() == Approx(std::max(-u_z0, v_micro)).epsilon(1e-12));
        } else {
          const double u_z = std::max(-params.restitution * u_z0, v_micro);
          const double tau = 2.0 * u_z / context.g_n;
          CHECK((r.u_final_c.head<2>() + 0.5 * tau * context.a_t_c).norm() <= 1e-12);
        }
      }
    }
  }
  // Both branches of both rules were exercised.
  CHECK(in_cone[0] > 100);
  CHECK(in_cone[1] > 100);
  CHECK(fallback[0] > 100);
  CHECK(fallback[1] > 100);
}

// Exact-flight model of a flat block at rest on a fixed plane tilted at theta (centre-of-pressure
// contact, so K = 1/m for the translational part, DESIGN.md §4): every microcollision is
// followed by a ballistic flight of tau = 2 u_n' / g_n, during which the slip changes by a_t tau.
// Returns the along-slope displacement after `duration`, per second.
struct CreepRun {
  double creep_per_second = 0.0;
  int bounces = 0;
};

CreepRun ramp_creep(MicrocollisionRule rule, double theta, double mu, double envelope,
                    double duration, double initial_slip = 0.0, double settle = 0.0) {
  const double g = 9.81, m = 2.0;
  const Mat3 K = Mat3::Identity() / m;
  MicrocollisionContext context;
  context.g_n = g * std::cos(theta);
  context.a_t_c = Vec2(g * std::sin(theta), 0.0);  // t1 points down the slope
  Settings settings;
  settings.envelope_m = envelope;
  const double v_micro = microcollision_speed(settings, context.g_n);
  const CollisionParameters params = params_for(mu, 0.5, RestitutionLaw::kStronge);
  Vec3 u(initial_slip, 0.0, 0.0);  // in contact, sliding down at initial_slip (or at rest)
  double x = 0.0, t = 0.0, x_settled = 0.0, t_settled = 0.0;
  bool settled = settle == 0.0;
  CreepRun run;
  while (t < settle + duration) {
    if (!settled && t >= settle) {
      settled = true;
      x_settled = x;
      t_settled = t;
    }
    const CollisionResult r = resolve_microcollision(K, u, params, rule, context, v_micro);
    REQUIRE(r.status == CollisionStatus::kOk);
    const Vec3 u1 = r.u_final_c;
    const double tau = 2.0 * u1.z() / context.g_n;
    x += u1.x() * tau + 0.5 * context.a_t_c.x() * tau * tau;
    u = Vec3(u1.x() + context.a_t_c.x() * tau, u1.y(), -u1.z());
    t += tau;
    ++run.bounces;
  }
  run.creep_per_second = (x - x_settled) / (t - t_settled);
  return run;
}

TEST_CASE("on a turning surface the drift-free target zeroes the displacement, not the mean slip",
          "[impulse][micro]") {
  // A block resting on a platter turning at Omega about n: over the flight tau the slip
  // u(t) = u' + a_t t, seen in the platter's frame, integrates to the displacement
  // D = integral of R(t)^T u(t) dt, R(t) the rotation by Omega t about n. The target
  // u_t' = -a_t tau / 2 + (Omega n x a_t) tau^2 / 12 makes D vanish to second order in
  // Omega tau; the first-order target leaves |Omega x a_t| tau^3 / 12.
  const Mat3 K = Vec3(2.0, 2.0, 1.0).asDiagonal();  // a sphere-like contact, mass 1
  const double g = 9.81, v_micro = 0.044, omega = 2.0 * M_PI;
  const Vec3 u0(0.0, 0.0, -v_micro);
  MicrocollisionContext context;
  context.g_n = g;
  context.a_t_c = Vec2(0.0, -omega * 0.3 * omega);  // -Omega x (v - V) for a body 0.3 m out
  const CollisionParameters params = params_for(10.0, 0.0, RestitutionLaw::kStronge);
  const double tau = 2.0 * v_micro / g;
  auto displacement = [&](const Vec3& u_final) {
    // Simpson's rule on the rotated slip over [0, tau].
    Vec2 D = Vec2::Zero();
    const int n = 2000;
    for (int k = 0; k <= n; ++k) {
      const double t = tau * k / n;
      const Vec2 slip = u_final.head<2>() + context.a_t_c * t;
      const double c = std::cos(-omega * t), s = std::sin(-omega * t);
      const Vec2 rotated(c * slip.x() - s * slip.y(), s * slip.x() + c * slip.y());
      const double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
      D += w * rotated;
    }
    return Vec2(D * tau / (3.0 * n));
  };
  const CollisionResult flat =
      resolve_microcollision(K, u0, params, MicrocollisionRule::kDriftFree, context, v_micro);
  context.surface_spin = omega;
  const CollisionResult turning =
      resolve_microcollision(K, u0, params, MicrocollisionRule::kDriftFree, context, v_micro);
  REQUIRE(succeeded(flat.status));
  REQUIRE(succeeded(turning.status));
  const double first_order = omega * context.a_t_c.norm() * std::pow(tau, 3) / 12.0;
  CAPTURE(first_order, displacement(flat.u_final_c).norm(), displacement(turning.u_final_c).norm());
  CHECK(displacement(flat.u_final_c).norm() == Approx(first_order).epsilon(0.01));
  CHECK(displacement(turning.u_final_c).norm() < 0.01 * first_order);
}

TEST_CASE("a block resting on a ramp: the reversal rule creeps, the drift-free rule does not",
          "[impulse][micro][creep]") {
  // The decelerating-block scene's ramp: tan 30 deg = 0.577 in the band mu/2 < tan <= mu = 0.7.
  const double theta = M_PI / 6.0, mu = 0.7;
  for (double envelope : {1e-4, 1e-6}) {
    const CreepRun reversal = ramp_creep(MicrocollisionRule::kReversal, theta, mu, envelope, 1.0);
    const CreepRun drift_free =
        ramp_creep(MicrocollisionRule::kDriftFree, theta, mu, envelope, 1.0);
    std::cout << "ramp creep over 1 s at envelope " << envelope << ": reversal "
              << reversal.creep_per_second << " m (" << reversal.bounces << " bounces), drift-free "
              << drift_free.creep_per_second << " m (" << drift_free.bounces << " bounces)\n";
    CAPTURE(envelope, reversal.creep_per_second, drift_free.creep_per_second);
    // Reversal: sticks at zero slip each bounce and slides a_t tau / 2 on average,
    // a_t tau / 2 = g sin(theta) sqrt(2 g_n envelope) / g_n (2.4e-2 m/s at 1e-4).
    const double g_n = 9.81 * std::cos(theta);
    const double expected = 9.81 * std::sin(theta) * std::sqrt(2.0 * g_n * envelope) / g_n;
    CHECK(reversal.creep_per_second > 1e-3 * std::sqrt(envelope / 1e-4));
    CHECK(reversal.creep_per_second == Approx(expected).epsilon(0.05));
    CHECK(std::abs(drift_free.creep_per_second) < 1e-5);
  }
  // A block that slides down onto the contact at 0.05 m/s (the decelerating block): it stops
  // (mu > tan theta) through ordinary integrations with the floor, then rests. Creep measured
  // over the second after the first.
  const CreepRun stopping_reversal =
      ramp_creep(MicrocollisionRule::kReversal, theta, mu, 1e-4, 1.0, 0.05, 1.0);
  const CreepRun stopping_drift_free =
      ramp_creep(MicrocollisionRule::kDriftFree, theta, mu, 1e-4, 1.0, 0.05, 1.0);
  std::cout << "after stopping from 0.05 m/s, creep over the next 1 s at envelope 1e-4: reversal "
            << stopping_reversal.creep_per_second << " m, drift-free "
            << stopping_drift_free.creep_per_second << " m\n";
  CHECK(stopping_reversal.creep_per_second > 1e-3);
  CHECK(std::abs(stopping_drift_free.creep_per_second) < 1e-5);
  // Below the band (tan theta <= mu / 2) Mirtich's rule settles into the two-bounce reversal
  // cycle inside the cone and does not creep either.
  const CreepRun shallow = ramp_creep(MicrocollisionRule::kReversal, 0.25, mu, 1e-4, 1.0);
  CHECK(std::abs(shallow.creep_per_second) < 1e-5);
}

}  // namespace
}  // namespace palpable
