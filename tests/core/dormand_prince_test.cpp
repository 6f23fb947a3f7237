// Dormand-Prince 5(4) (core/dormand_prince.hpp): its order on a closed form, and the dense
// output's one-component evaluation (a clocked island step finds its time by bisection on it,
// scheduler/island.cpp) against the whole state's.
#include "core/dormand_prince.hpp"

#include <catch2/catch.hpp>

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
  int taken = 0;
  while (t < end) {
    h = std::min(h, end - t);
    dopri5::take_step(rotation_rhs, t, y, k0, h, rtol, rtol, step);
    if (step.error <= 1.0) {
      t += h;
      y = step.y1;
      k0 = step.k[6];
      ++taken;
    }
    h = dopri5::next_step_size(h, step.error);
  }
  CHECK(std::abs(y(0) - std::cos(2.0 * end)) < 1e-8);
  CHECK(std::abs(y(1) - std::sin(2.0 * end)) < 1e-8);
  CHECK(std::abs(y(2) - std::exp(-end)) < 1e-8);
  CHECK(taken < 200);  // fifth order: a few dozen steps for 1e-10, not thousands
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
