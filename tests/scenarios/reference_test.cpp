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

TEST_CASE("slide_to_roll reference: the closed-form slide has zero error",
          "[scenarios][reference]") {
  // A solid ball (k = 2/5) launched at 3 m/s along x without spin, mu = 0.2: rolls from
  // 2 v0 / (7 mu g) at 5 v0 / 7.
  const double mu = 0.2, g = 9.81, v0 = 3.0, R = 0.1, k = 0.4;
  const double t_roll = 2.0 * v0 / (7.0 * mu * g);
  const double v_final = 5.0 * v0 / 7.0;
  auto closed_form = [&](double t, double deceleration, double t_r) {
    BodyState s;
    const double tc = std::min(t, t_r);
    const double x = v0 * tc - 0.5 * deceleration * tc * tc;
    const double v = v0 - deceleration * tc;
    s.x_W = Vec3(x + v * (t - tc), 0.0, R);
    s.v_W = Vec3(v, 0.0, 0.0);
    return s;
  };
  json spec{{"type", "slide_to_roll"},
            {"body", "ball"},
            {"friction", mu},
            {"gravity", g},
            {"radius", R},
            {"k", k}};
  Trace trace = single_body_trace("ball", 0.01, 200,
                                  [&](double t) { return closed_form(t, mu * g, t_roll); });
  json f = palpable::compare_with_reference(spec, trace, "test");
  INFO(f.dump(2));
  CHECK(f["mode"] == "slide_then_roll");
  CHECK(f["roll_time_closed_form_s"].get<double>() == Approx(t_roll).epsilon(1e-14));
  CHECK(f["final_speed_closed_form"].get<double>() == Approx(v_final).epsilon(1e-14));
  CHECK(std::abs(f["roll_time_error_s"].get<double>()) < 1e-9);
  CHECK(std::abs(f["final_speed_rel_error"].get<double>()) < 1e-9);
  CHECK(std::abs(f["deceleration_rel_error"].get<double>()) < 1e-9);
  CHECK(f["height_deviation_max_m"].get<double>() == 0.0);

  // A backspin w0 = -v0/R about y gives slip 2 v0 along x: the general formula
  // (v0 + k R w x n)/(1 + k) = (v0 - k v0)/(1 + k) = 3/7 v0, reached after 2 k v0/((1+k) mu g).
  Trace spun = trace;
  spun.samples[0][0].w_W = Vec3(0.0, -v0 / R, 0.0);
  json b = palpable::compare_with_reference(spec, spun, "test");
  CHECK(b["initial_slip_speed"].get<double>() == Approx(2.0 * v0).epsilon(1e-14));
  CHECK(b["roll_time_closed_form_s"].get<double>() ==
        Approx(2.0 * k * v0 / ((1.0 + k) * mu * g)).epsilon(1e-14));
  CHECK(b["final_speed_closed_form"].get<double>() == Approx(3.0 * v0 / 7.0).epsilon(1e-14));
  // The same launch state given as parameters instead of read from the first sample.
  json given = spec;
  given["angular_velocity"] = {0.0, -v0 / R, 0.0};
  json c = palpable::compare_with_reference(given, trace, "test");
  CHECK(c["initial_slip_speed"].get<double>() == b["initial_slip_speed"].get<double>());
  given["velocity"] = "fast";
  CHECK_THROWS_WITH(palpable::compare_with_reference(given, trace, "test"),
                    Catch::Contains("test/velocity"));

  // Friction 5 % too weak in the trace: slower deceleration, later rolling, same final speed
  // (5 v0 / 7 does not depend on mu).
  Trace weak = single_body_trace(
      "ball", 0.01, 200, [&](double t) { return closed_form(t, 0.95 * mu * g, t_roll / 0.95); });
  json w = palpable::compare_with_reference(spec, weak, "test");
  INFO(w.dump(2));
  CHECK(w["deceleration_rel_error"].get<double>() == Approx(-0.05).epsilon(1e-9));
  CHECK(w["roll_time_error_s"].get<double>() == Approx(t_roll / 0.95 - t_roll).epsilon(1e-9));
  CHECK(std::abs(w["final_speed_rel_error"].get<double>()) < 1e-9);

  // Rolling 10 % early (the slip stops too soon): final speed 2 % high, roll time early.
  Trace early = single_body_trace("ball", 0.01, 200,
                                  [&](double t) { return closed_form(t, mu * g, 0.9 * t_roll); });
  json r = palpable::compare_with_reference(spec, early, "test");
  INFO(r.dump(2));
  CHECK(r["final_speed_rel_error"].get<double>() ==
        Approx(mu * g * 0.1 * t_roll / v_final).epsilon(1e-9));
  CHECK(r["roll_time_error_s"].get<double>() == Approx(-0.1 * t_roll).epsilon(1e-9));
}

namespace {
// Height of a ball dropped from h0 at rest with restitution e (closed form, piecewise parabola).
double bouncing_height(double t, double h0, double e, double g) {
  const double t1 = std::sqrt(2.0 * h0 / g);
  if (t <= t1) return h0 - 0.5 * g * t * t;
  double start = t1, v = e * g * t1;
  while (t > start + 2.0 * v / g) {
    start += 2.0 * v / g;
    v *= e;
    if (v < 1e-9) return 0.0;
  }
  const double s = t - start;
  return v * s - 0.5 * g * s * s;
}
}  // namespace

TEST_CASE("bouncing_ball reference: closed-form bounces have zero error",
          "[scenarios][reference]") {
  const double h0 = 1.0, e = 0.8, g = 9.81, R = 0.05;
  json spec{{"type", "bouncing_ball"},
            {"body", "ball"},
            {"restitution", e},
            {"gravity", g},
            {"radius", R},
            {"apexes", 3}};
  auto trace_for = [&](double e_true) {
    return single_body_trace("ball", 0.01, 400, [&](double t) {
      BodyState s;
      s.x_W = Vec3(0.0, 0.0, R + bouncing_height(t, h0, e_true, g));
      return s;
    });
  };
  Trace trace = trace_for(e);
  const double t1 = std::sqrt(2.0 * h0 / g);
  for (int n = 0; n < 4; ++n) {  // the impacts, as an events file would give them
    double t = t1;
    for (int i = 1; i <= n; ++i) t += 2.0 * std::pow(e, i) * t1;
    trace.contacts.push_back(palpable::ContactEvent{t, 0, 0, Vec3::Zero()});
  }
  json f = palpable::compare_with_reference(spec, trace, "test");
  INFO(f.dump(2));
  CHECK(f["apexes_found"] == 3);
  CHECK(f["apex_height_closed_form_m"][0].get<double>() == Approx(e * e * h0).epsilon(1e-14));
  CHECK(f["apex_height_closed_form_m"][2].get<double>() ==
        Approx(std::pow(e, 6) * h0).epsilon(1e-14));
  CHECK(f["apex_height_rel_error_max"].get<double>() < 1e-9);
  CHECK(f["apex_time_error_max_s"].get<double>() < 1e-9);
  CHECK(f["impact_time_error_max_s"].get<double>() < 1e-12);
  CHECK(f["rest_time_closed_form_s"].get<double>() ==
        Approx(t1 * (1.0 + e) / (1.0 - e)).epsilon(1e-14));

  // A ball with e = 0.78 instead of 0.8: the first apex is (0.78/0.8)^2 - 1 = -4.9 % low.
  json w = palpable::compare_with_reference(spec, trace_for(0.78), "test");
  INFO(w.dump(2));
  CHECK(w["apex_height_rel_error"][0].get<double>() ==
        Approx(std::pow(0.78 / 0.8, 2) - 1.0).epsilon(1e-6));
  CHECK(w["apex_height_rel_error_max"].get<double>() > 0.04);
}

TEST_CASE("impact_1d reference: velocities after a 1-D impact", "[scenarios][reference]") {
  const double m1 = 1.0, m2 = 3.0, e = 0.5, v1 = 2.0, v2 = -1.0;
  const double w1 = (m1 * v1 + m2 * v2 + m2 * e * (v2 - v1)) / (m1 + m2);  // -1.375
  const double w2 = (m1 * v1 + m2 * v2 + m1 * e * (v1 - v2)) / (m1 + m2);  // 0.125
  auto make = [&](double w1_true, double w2_true) {
    Trace trace;
    trace.body_names = {"a", "b"};
    for (int k = 0; k < 2; ++k) {
      BodyState a, b;
      a.v_W = Vec3(k == 0 ? v1 : w1_true, 0.0, 0.0);
      b.v_W = Vec3(k == 0 ? v2 : w2_true, 0.0, 0.0);
      trace.times.push_back(k);
      trace.samples.push_back({a, b});
    }
    return trace;
  };
  json spec{{"type", "impact_1d"}, {"body_a", "a"}, {"body_b", "b"},
            {"restitution", e},    {"mass_a", m1},  {"mass_b", m2}};
  json f = palpable::compare_with_reference(spec, make(w1, w2), "test");
  INFO(f.dump(2));
  CHECK(f["velocity_a_closed_form"].get<double>() == Approx(-1.375).epsilon(1e-15));
  CHECK(f["velocity_b_closed_form"].get<double>() == Approx(0.125).epsilon(1e-15));
  CHECK(f["velocity_a_rel_error"].get<double>() == 0.0);
  CHECK(f["velocity_b_rel_error"].get<double>() == 0.0);
  CHECK(f["momentum_error"].get<double>() == 0.0);
  CHECK(f["restitution_fit"].get<double>() == Approx(e).epsilon(1e-15));

  // Body b 0.03 m/s too fast: 1 % of the approach speed, and momentum is no longer conserved.
  json g = palpable::compare_with_reference(spec, make(w1, w2 + 0.03), "test");
  CHECK(g["velocity_b_rel_error"].get<double>() == Approx(0.01).epsilon(1e-12));
  CHECK(g["momentum_error"].get<double>() == Approx(0.0075).epsilon(1e-12));
}

TEST_CASE("bad reference specs name the parameter", "[scenarios][reference]") {
  Trace trace = single_body_trace("ball", 0.1, 10, [](double) { return BodyState{}; });
  CHECK_THROWS_WITH(
      palpable::compare_with_reference(json{{"type", "turntable"}, {"body", "ball"}}, trace, "r"),
      Catch::Contains("r/omega"));
  CHECK_THROWS_WITH(palpable::compare_with_reference(
                        json{{"type", "turntable"}, {"body", "cube"}, {"omega", 1.0}}, trace, "r"),
                    Catch::Contains("r/body: got \"cube\", expected the name of a body"));
  // Unknown keys are rejected (a misspelt parameter would otherwise be silently ignored).
  CHECK_THROWS_WITH(palpable::compare_with_reference(
                        json{{"type", "turntable"}, {"body", "ball"}, {"omega", 1.0}, {"kk", 1}},
                        trace, "r"),
                    Catch::Contains("r/kk: unknown key"));
  // A reference is checked whole before a run: kinds and body names, no trace needed.
  CHECK_THROWS_WITH(palpable::validate_reference(
                        json{{"type", "turntable"}, {"body", "ball"}, {"omega", "fast"}}, "s.json:/reference", {"ball"}),
                    Catch::Contains("s.json:/reference/omega: got \"fast\", expected a number"));
  CHECK_THROWS_WITH(palpable::validate_reference(
                        json{{"type", "turntable"}, {"body", "bal"}, {"omega", 1.0}}, "s.json:/reference", {"ball"}),
                    Catch::Contains("s.json:/reference/body"));
  CHECK_NOTHROW(palpable::validate_reference(
      json{{"type", "turntable"}, {"body", "ball"}, {"omega", 1.0}}, "s.json:/reference", {"ball"}));
  CHECK_THROWS_WITH(palpable::compare_with_reference(json{{"type", "pendulum"}}, trace, "r"),
                    Catch::Contains("r/type"));
  CHECK_THROWS_WITH(palpable::compare_with_reference(json{{"type", "slide_to_roll"},
                                                          {"body", "ball"},
                                                          {"friction", -0.1},
                                                          {"gravity", 9.81},
                                                          {"radius", 0.1}},
                                                     trace, "r"),
                    Catch::Contains("r/friction"));
  CHECK_THROWS_WITH(
      palpable::compare_with_reference(
          json{
              {"type", "bouncing_ball"}, {"body", "ball"}, {"restitution", 1.5}, {"gravity", 9.81}},
          trace, "r"),
      Catch::Contains("r/restitution"));
  CHECK_THROWS_WITH(palpable::compare_with_reference(json{{"type", "impact_1d"},
                                                          {"body_a", "ball"},
                                                          {"body_b", "ball"},
                                                          {"restitution", 0.5},
                                                          {"mass_a", 1.0},
                                                          {"mass_b", 1.0}},
                                                     trace, "r"),
                    Catch::Contains("r/body_b"));
}

TEST_CASE("the primary error of each reference type", "[scenarios][reference]") {
  using palpable::primary_error;
  CHECK(primary_error(json{{"reference", "incline"},
                           {"mode", "slide_then_stop"},
                           {"stop_time_error_s", -2e-3},
                           {"stop_time_closed_form_s", 2.0},
                           {"creep_m", 4e-3},
                           {"stop_distance_closed_form_m", 2.0}}) == Approx(2e-3));
  CHECK(primary_error(json{{"reference", "incline"},
                           {"mode", "accelerating"},
                           {"acceleration_rel_error", -3e-5}}) == Approx(3e-5));
  CHECK(primary_error(json{{"reference", "turntable"},
                           {"rate_rel_error", 1e-4},
                           {"circle_deviation_max_m", 1e-3},
                           {"radius_closed_form_m", 0.5}}) == Approx(2e-3));
  CHECK(primary_error(json{{"reference", "slide_to_roll"},
                           {"roll_time_error_s", 1e-3},
                           {"roll_time_closed_form_s", 0.25},
                           {"final_speed_rel_error", -1e-3}}) == Approx(4e-3));
  CHECK(primary_error(json{{"reference", "bouncing_ball"}, {"apex_height_rel_error_max", -0.1}}) ==
        Approx(0.1));
  CHECK(primary_error(json{{"reference", "impact_1d"},
                           {"velocity_a_rel_error", 1e-9},
                           {"velocity_b_rel_error", -2e-9}}) == Approx(2e-9));
  // A figure the error needs is missing (the block never stopped): not a number.
  CHECK(std::isnan(primary_error(json{{"reference", "incline"},
                                      {"mode", "slide_then_stop"},
                                      {"creep_m", 0.0},
                                      {"stop_distance_closed_form_m", 2.0}})));
  CHECK(std::isnan(primary_error(json())));
}
