#pragma once
// Dormand & Prince, "A family of embedded Runge-Kutta formulae", J. Comp. Appl. Math. 6, 1980: the
// 5(4) pair with first-same-as-last and Shampine's 4th-order dense output (the coefficients of
// Hairer's DOPRI5 and SciPy's RK45), for a state of any size. Used where a motion has no closed
// form: held contact between events (scheduler/island.hpp). One step at a time, so that the caller
// decides what an event is and where a step must end.
#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>

namespace palpable::dopri5 {

using State = Eigen::VectorXd;

inline constexpr double kC[7] = {0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0};
inline constexpr double kA[7][6] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5.0, 0, 0, 0, 0, 0},
    {3.0 / 40.0, 9.0 / 40.0, 0, 0, 0, 0},
    {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0, 0, 0},
    {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0, 0},
    {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0},
    {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0}};
// Fifth-order weights minus fourth-order ones: the error estimate.
inline constexpr double kE[7] = {71.0 / 57600.0,      0.0,          -71.0 / 16695.0, 71.0 / 1920.0,
                                 -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0};
// Dense output: y(theta) = y0 + h sum_i k_i (P_i1 theta + P_i2 theta^2 + P_i3 theta^3 + P_i4
// theta^4).
inline constexpr double kP[7][4] = {
    {1.0, -8048581381.0 / 2820520608.0, 8663915743.0 / 2820520608.0,
     -12715105075.0 / 11282082432.0},
    {0.0, 0.0, 0.0, 0.0},
    {0.0, 131558114200.0 / 32700410799.0, -68118460800.0 / 10900136933.0,
     87487479700.0 / 32700410799.0},
    {0.0, -1754552775.0 / 470086768.0, 14199869525.0 / 1410260304.0, -10690763975.0 / 1880347072.0},
    {0.0, 127303824393.0 / 49829197408.0, -318862633887.0 / 49829197408.0,
     701980252875.0 / 199316789632.0},
    {0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0, -1453857185.0 / 822651844.0},
    {0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0}};

// One step from (t, y) of length h, with its stages kept for the dense output.
struct Step {
  double t = 0.0, h = 0.0;
  State y0, y1;
  std::array<State, 7> k;  // k[0] = f(t, y0), k[6] = f(t + h, y1)
  double error = 0.0;      // the error norm, relative to atol + rtol |y| (<= 1: accept)

  // The state at t + theta h, theta in [0, 1] (4th order).
  State at(double theta) const {
    const double t1 = theta, t2 = t1 * theta, t3 = t2 * theta, t4 = t3 * theta;
    State sum = State::Zero(y0.size());
    for (int i = 0; i < 7; ++i) {
      sum += (kP[i][0] * t1 + kP[i][1] * t2 + kP[i][2] * t3 + kP[i][3] * t4) * k[i];
    }
    return y0 + h * sum;
  }
  // One component of at(theta).
  double at(double theta, Eigen::Index i) const {
    const double t1 = theta, t2 = t1 * theta, t3 = t2 * theta, t4 = t3 * theta;
    double sum = 0.0;
    for (int j = 0; j < 7; ++j) {
      sum += (kP[j][0] * t1 + kP[j][1] * t2 + kP[j][2] * t3 + kP[j][3] * t4) * k[j](i);
    }
    return y0(i) + h * sum;
  }
};

// Takes the step of length h from (t, y0) with k0 = f(t, y0); f(t, y) -> dy/dt. The error norm
// is the root mean square of the error estimate over atol + rtol max(|y0|, |y1|) per component.
template <class F>
void take_step(F&& f, double t, const State& y0, const State& k0, double h, double rtol,
               double atol, Step& s) {
  s.t = t;
  s.h = h;
  s.y0 = y0;
  s.k[0] = k0;
  for (int i = 1; i < 7; ++i) {
    State y = y0;
    for (int j = 0; j < i; ++j) {
      if (kA[i][j] != 0.0) y += h * kA[i][j] * s.k[j];
    }
    if (i == 6) s.y1 = y;
    s.k[i] = f(t + kC[i] * h, y);
  }
  State err = State::Zero(y0.size());
  for (int i = 0; i < 7; ++i) {
    if (kE[i] != 0.0) err += h * kE[i] * s.k[i];
  }
  double sum = 0.0;
  for (Eigen::Index i = 0; i < y0.size(); ++i) {
    const double scale = atol + rtol * std::max(std::abs(y0(i)), std::abs(s.y1(i)));
    const double e = err(i) / scale;
    sum += e * e;
  }
  s.error = std::sqrt(sum / static_cast<double>(std::max<Eigen::Index>(1, y0.size())));
}

// The next step size after a step of size h with error norm `error` (Hairer's controller, safety
// 0.9, growth between 0.2 and 5).
inline double next_step_size(double h, double error) {
  if (!(error > 0.0)) return 5.0 * h;
  const double factor = 0.9 * std::pow(error, -0.2);
  return h * std::min(5.0, std::max(0.2, factor));
}

// The step sizes of an integration: next_step_size after each step, except that a step that
// follows a rejection is no longer than the one that was accepted (Hairer, Norsett & Wanner,
// Solving ODE I, 2nd ed., II.4: growing at once again after a rejection is rejected again). On
// the Arenstorf orbit at 1e-9 it rejects 7 steps where next_step_size alone rejects 11, for the
// same 502 accepted (tests/core/dormand_prince_test.cpp).
class StepController {
 public:
  // The next step size after an accepted step of size h with error norm `error` (<= 1).
  double accepted(double h, double error) {
    const double next = next_step_size(h, error);
    const bool after_rejection = rejected_;
    rejected_ = false;
    return after_rejection ? std::min(next, h) : next;
  }
  // The size to retry a rejected step of size h with error norm `error` (> 1, or NaN) at.
  double rejected(double h, double error) {
    rejected_ = true;
    return next_step_size(h, error);
  }

 private:
  bool rejected_ = false;
};

}  // namespace palpable::dopri5
