// The closed-form comparisons, fed with traces synthesised from the closed forms themselves
// (errors must vanish) and with perturbed ones (errors must show the perturbation).
#include "scenarios/reference.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

using nlohmann::json;
using palpable::BodyState;
using palpable::Trace;
using palpable::Vec3;

namespace {
constexpr double kPi = 3.14159265358979323846;

Trace single_body_trace(const std::string& name, double dt, int n,
                        const std::function<BodyState(double)>& state_at) {
  Trace trace;
  trace.body_names = {name};
  for (int k = 0; k <= n; ++k) {
    double t = k * dt;
    trace.times.push_back(t);
    BodyState s = state_at(t);
    s.t = t;
    trace.samples.push_back({s});
  }
  return trace;
}

json incline_spec(double mu, double v0) {
  const double theta = kPi / 6.0;
  return json{{"type", "incline"},
              {"body", "block"},
              {"angle_deg", 30.0},
              {"friction", mu},
              {"gravity", 9.81},
              {"initial_speed", v0},
              {"down_slope", {std::cos(theta), 0.0, -std::sin(theta)}},
              {"normal", {std::sin(theta), 0.0, std::cos(theta)}}};
}
}  // namespace

TEST_CASE("polynomial fit recovers a quadratic exactly", "[scenarios][reference]") {
  std::vector<double> t, y;
  for (int k = 0; k < 200; ++k) {
    t.push_back(0.01 * k + 3.0);
    y.push_back(1.5 - 2.0 * t.back() + 0.25 * t.back() * t.back());
  }
  auto c = palpable::polynomial_fit(t, y, 2);
  CHECK(c[0] == Approx(1.5).epsilon(1e-9));
  CHECK(c[1] == Approx(-2.0).epsilon(1e-9));
  CHECK(c[2] == Approx(0.25).epsilon(1e-9));
}

TEST_CASE("incline reference: the closed-form decelerating block has zero error",
          "[scenarios][reference]") {
  const double theta = kPi / 6.0, mu = 0.7, g = 9.81, v0 = 2.0;
  const double a = g * (std::sin(theta) - mu * std::cos(theta));
  const double t_stop = v0 / -a;
  const Vec3 down(std::cos(theta), 0.0, -std::sin(theta));
  auto closed_form = [&](double t) {
    BodyState s;
    double tc = std::min(t, t_stop);
    s.x_W = Vec3(0, 0, 1) + down * (v0 * tc + 0.5 * a * tc * tc);
    s.v_W = down * (t < t_stop ? v0 + a * t : 0.0);
    return s;
  };
  Trace trace = single_body_trace("block", 0.01, 300, closed_form);
  json f = palpable::compare_with_reference(incline_spec(mu, v0), trace, "test");
  CHECK(f["mode"] == "slide_then_stop");
  CHECK(f["stop_time_closed_form_s"].get<double>() == Approx(1.9194).margin(5e-5));
  CHECK(std::abs(f["stop_time_error_s"].get<double>()) < 1e-9);
  CHECK(f["creep_m"].get<double>() < 1e-12);
  CHECK(f["cross_slope_max_m"].get<double>() < 1e-12);

  // A block that creeps 1 mm/s after stopping is reported.
  Trace creeping = single_body_trace("block", 0.01, 300, [&](double t) {
    BodyState s = closed_form(t);
    if (t > t_stop) s.x_W += down * 1e-3 * (t - t_stop);
    return s;
  });
  json c = palpable::compare_with_reference(incline_spec(mu, v0), creeping, "test");
  CHECK(c["creep_m"].get<double>() == Approx(1e-3 * (3.0 - (t_stop + 0.1))).margin(2e-5));
}

TEST_CASE("incline reference: accelerating block's fitted acceleration", "[scenarios][reference]") {
  const double theta = kPi / 6.0, mu = 0.3, g = 9.81;
  const double a = g * (std::sin(theta) - mu * std::cos(theta));
  const Vec3 down(std::cos(theta), 0.0, -std::sin(theta));
  Trace trace = single_body_trace("block", 0.01, 150, [&](double t) {
    BodyState s;
    s.x_W = down * 0.5 * a * t * t;
    return s;
  });
  json f = palpable::compare_with_reference(incline_spec(mu, 0.0), trace, "test");
  CHECK(f["mode"] == "accelerating");
  CHECK(std::abs(f["acceleration_rel_error"].get<double>()) < 1e-10);
}

TEST_CASE("turntable reference: the closed-form orbit has zero error", "[scenarios][reference]") {
  const double omega = 2.0 * kPi, rate = 2.0 * omega / 7.0;
  const Vec3 x0(0.3, 0.0, 0.05), v0(0.0, 0.1, 0.0);
  const Vec3 z = Vec3::UnitZ();
  const Vec3 centre = x0 + z.cross(v0) / rate;
  auto orbit = [&](double t) {
    BodyState s;
    Eigen::AngleAxisd turn(rate * t, z);
    s.x_W = centre + turn * (x0 - centre);
    s.v_W = turn * v0;
    return s;
  };
  json spec{{"type", "turntable"}, {"body", "ball"}, {"omega", omega}, {"k", 0.4}};
  Trace trace = single_body_trace("ball", 0.01, 4000, orbit);
  json f = palpable::compare_with_reference(spec, trace, "test");
  CHECK(f["radius_closed_form_m"].get<double>() == Approx(0.1 / rate));
  CHECK(std::abs(f["rate_rel_error"].get<double>()) < 1e-10);
  CHECK(f["circle_deviation_max_m"].get<double>() < 1e-12);
  CHECK(f["path_deviation_max_m"].get<double>() < 1e-12);
  CHECK(f["centre_drift_m"].get<double>() < 1e-9);

  // An orbit 1 % too fast shows up in the rate and the path but not the circle.
  Trace fast = single_body_trace("ball", 0.01, 4000, [&](double t) { return orbit(1.01 * t); });
  json g = palpable::compare_with_reference(spec, fast, "test");
  CHECK(g["rate_rel_error"].get<double>() == Approx(0.01).epsilon(1e-6));
  CHECK(g["circle_deviation_max_m"].get<double>() < 1e-12);
  CHECK(g["path_deviation_max_m"].get<double>() > 1e-3);
}

TEST_CASE("bad reference specs name the parameter", "[scenarios][reference]") {
  Trace trace = single_body_trace("ball", 0.1, 10, [](double) { return BodyState{}; });
  CHECK_THROWS_WITH(
      palpable::compare_with_reference(json{{"type", "turntable"}, {"body", "ball"}}, trace, "r"),
      Catch::Contains("r/omega"));
  CHECK_THROWS_WITH(palpable::compare_with_reference(
                        json{{"type", "turntable"}, {"body", "cube"}, {"omega", 1.0}}, trace, "r"),
                    Catch::Contains("no body \"cube\""));
  CHECK_THROWS_WITH(palpable::compare_with_reference(json{{"type", "pendulum"}}, trace, "r"),
                    Catch::Contains("r/type"));
}
