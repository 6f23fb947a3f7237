// Dormand-Prince 5(4) (core/dormand_prince.hpp): its order on a closed form, and the dense
// output's one-component evaluation (a clocked island step finds its time by bisection on it,
// scheduler/island.cpp) against the whole state's.
#include "core/dormand_prince.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

namespace palpable {
namespace {

// y' = A y: a rotation in the plane of y0, y1 at rate 2, and y2 decaying at rate 1.
dopri5::State rotation_rhs(double /*t*/, const dopri5::State& y) {
  dopri5::State dy(3);
  dy << -2.0 * y(1), 2.0 * y(0), -y(2);
  return dy;
}

TEST_CASE("dopri5: adaptive steps follow a rotation and a decay to the tolerance",
          "[core][dopri5]") {
  dopri5::State y(3);
  y << 1.0, 0.0, 1.0;
  double t = 0.0, h = 1e-3;
  const double rtol = 1e-10, end = 3.0;
  dopri5::State k0 = rotation_rhs(t, y);
  dopri5::Step step;
  dopri5::StepController controller;
  int taken = 0;
  while (t < end) {
    h = std::min(h, end - t);
    dopri5::take_step(rotation_rhs, t, y, k0, h, rtol, rtol, step);
    if (step.error <= 1.0) {
      t += h;
      y = step.y1;
      k0 = step.k[6];
      ++taken;
      h = controller.accepted(h, step.error);
    } else {
      h = controller.rejected(h, step.error);
    }
  }
  CHECK(std::abs(y(0) - std::cos(2.0 * end)) < 1e-8);
  CHECK(std::abs(y(1) - std::sin(2.0 * end)) < 1e-8);
  CHECK(std::abs(y(2) - std::exp(-end)) < 1e-8);
  CHECK(taken < 200);  // fifth order: a few dozen steps for 1e-10, not thousands
}

// The restricted three-body problem's Arenstorf orbit (Hairer, Norsett & Wanner, Solving ODE I,
// II.0): periodic with period T, its step sizes ranging over three decades along it.
dopri5::State arenstorf_rhs(double /*t*/, const dopri5::State& y) {
  const double mu = 0.012277471, mu_hat = 1.0 - mu;
  const double d1 = std::pow((y(0) + mu) * (y(0) + mu) + y(1) * y(1), 1.5);
  const double d2 = std::pow((y(0) - mu_hat) * (y(0) - mu_hat) + y(1) * y(1), 1.5);
  dopri5::State dy(4);
  dy << y(2), y(3), y(0) + 2.0 * y(3) - mu_hat * (y(0) + mu) / d1 - mu * (y(0) - mu_hat) / d2,
      y(1) - 2.0 * y(2) - mu_hat * y(1) / d1 - mu * y(1) / d2;
  return dy;
}

struct OrbitRun {
  dopri5::State y;
  int taken = 0, rejected = 0;
  // The largest growth proposed after a step accepted right after a rejection.
  double longest_after_rejection = 0.0;
};

// One period of the orbit at tolerance 1e-9; `plain`: next_step_size's proportional rule alone,
// h min(5, max(0.2, 0.9 err^-1/5)), also right after a rejection.
OrbitRun arenstorf_period(bool plain) {
  const double period = 17.0652165601579625588917206249;
  OrbitRun run;
  run.y = dopri5::State(4);
  run.y << 0.994, 0.0, 0.0, -2.00158510637908252240537862224;
  dopri5::StepController controller;
  dopri5::State k0 = arenstorf_rhs(0.0, run.y);
  dopri5::Step step;
  double t = 0.0, h = 1e-4;
  bool after_rejection = false;
  while (t < period) {
    h = std::min(h, period - t);
    dopri5::take_step(arenstorf_rhs, t, run.y, k0, h, 1e-9, 1e-9, step);
    const double proportional = dopri5::next_step_size(h, step.error);
    if (step.error <= 1.0) {
      t += h;
      run.y = step.y1;
      k0 = step.k[6];
      ++run.taken;
      const double next = plain ? proportional : controller.accepted(h, step.error);
      if (after_rejection) {
        run.longest_after_rejection = std::max(run.longest_after_rejection, next / h);
      }
      after_rejection = false;
      h = next;
    } else {
      ++run.rejected;
      after_rejection = true;
      h = plain ? proportional : controller.rejected(h, step.error);
    }
  }
  return run;
}

TEST_CASE("dopri5: the step controller follows the Arenstorf orbit round with few rejections",
          "[core][dopri5]") {
  const OrbitRun held = arenstorf_period(false), plain = arenstorf_period(true);
  INFO("controller: " << held.taken << " steps, " << held.rejected << " rejected; plain: "
                      << plain.taken << " steps, " << plain.rejected << " rejected");
  // Back where it started after one period (to the tolerance's order, as the plain one).
  const double closure = std::hypot(held.y(0) - 0.994, held.y(1));
  CHECK(closure < 1e-5);
  CHECK(closure < 10.0 * std::hypot(plain.y(0) - 0.994, plain.y(1)) + 1e-9);
  // Not growing right after a rejection: fewer steps thrown away, no more taken.
  CHECK(held.rejected < plain.rejected);
  CHECK(held.taken <= plain.taken);
  // The step after one accepted right after a rejection is no longer than it (the proportional
  // rule alone grows it).
  CHECK(held.longest_after_rejection <= 1.0);
  CHECK(plain.longest_after_rejection > 1.0);
}

TEST_CASE("dopri5: one component of the dense output is that component of the whole state",
          "[core][dopri5]") {
  dopri5::State y(3);
  y << 0.3, -0.7, 2.0;
  dopri5::Step step;
  dopri5::take_step(rotation_rhs, 0.5, y, rotation_rhs(0.5, y), 0.4, 1e-6, 1e-6, step);
  for (int i = 0; i <= 64; ++i) {
    const double theta = i / 64.0;
    const dopri5::State all = step.at(theta);
    for (Eigen::Index c = 0; c < 3; ++c) {
      CAPTURE(theta, c);
      CHECK(step.at(theta, c) == all(c));  // the same sums in the same order: the same double
    }
  }
  // And the interpolant meets the step's ends.
  for (Eigen::Index c = 0; c < 3; ++c) {
    CHECK(step.at(0.0, c) == y(c));
    CHECK(std::abs(step.at(1.0, c) - step.y1(c)) <= 1e-15 * (1.0 + std::abs(step.y1(c))));
  }
}

}  // namespace
}  // namespace palpable
