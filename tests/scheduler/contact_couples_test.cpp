// Torsional friction and rolling resistance in whole runs, against the continuous-contact closed
// forms: a coin spinning flat on a table slows at mu m g r_eff / I_n; a solid sphere rolling with
// rolling resistance d decelerates at 5 d g / (7 r).
#include "scheduler/simulation.hpp"
#include "tests/support/test_world.hpp"

#include "core/mass_properties.hpp"
#include "core/shape.hpp"
#include "impulse/contact_torque.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace palpable;

namespace {

struct Samples : SimulationObserver {
  std::vector<double> t;
  std::vector<BodyState> s;
  void on_sample(double time, const std::vector<BodyState>& states) override {
    t.push_back(time);
    s.push_back(states[1]);
  }
};

// Least-squares slope of y against x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= x.size();
  my /= y.size();
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxy / sxx;
}

// Least-squares slope against time of f(state of body 1) over the samples with t0 < t < t1;
// requires more than 20 such samples.
template <class F>
double slope_over(const Samples& rec, double t0, double t1, F f) {
  std::vector<double> ts, ys;
  for (std::size_t i = 0; i < rec.t.size(); ++i) {
    if (rec.t[i] > t0 && rec.t[i] < t1) {
      ts.push_back(rec.t[i]);
      ys.push_back(f(rec.s[i]));
    }
  }
  REQUIRE(ts.size() > 20);
  return slope(ts, ys);
}

}  // namespace

TEST_CASE("a coin spinning flat on a table slows at mu m g r_eff / I_n and stops", "[scheduler]") {
  const double R = 0.012, half = 0.001, mass = 0.0075, mu = 0.05, w0 = 20.0, g = 9.81;
  const int sides = 32;
  World world;
  world.gravity_W = Vec3(0, 0, -g);
  world.default_material = Material{mu, 0.0};
  world.settings.envelope_m = 1e-5;
  world.add(test::fixed_ground("table"));
  Body coin;
  coin.name = "coin";
  coin.shape = std::make_shared<const Shape>(ConvexPolyhedron::prism(R, half, sides));
  coin.mass = mass_properties_from_mass(*coin.shape, mass);
  coin.state.x_W = Vec3(0, 0, half);
  coin.state.w_W = Vec3(0, 0, w0);
  world.add(coin);

  // The face: the prism's regular polygon, pressure at its centre.
  std::vector<Vec3> face;
  for (int i = 0; i < sides; ++i) {
    const double a = 2.0 * std::acos(-1.0) * i / sides;
    face.emplace_back(R * std::cos(a), R * std::sin(a), 0.0);
  }
  const double r_eff = mean_distance_over_patch(face, Vec3::UnitZ(), Vec3::Zero());
  const double I_n = 1.0 / world.bodies[1].mass.inv_inertia_M()(2, 2);
  const double rate = mu * mass * g * r_eff / I_n;
  const double t_stop = w0 / rate;
  CAPTURE(r_eff, I_n, rate, t_stop);

  Simulation sim(world, SimulationOptions{t_stop / 40.0});
  Samples rec;
  sim.run_until(1.5 * t_stop, &rec);
  const auto spin = [](const BodyState& st) { return st.w_W.z(); };
  // Spin is taken out once per microcollision (about g / (2 v_micro) per second): the slope of
  // the staircase matches the continuous rate to within a fraction of one step.
  CHECK(slope_over(rec, 0.1 * t_stop, 0.9 * t_stop, spin) == Approx(-rate).epsilon(0.02));
  const BodyState end = sim.state_at(BodyId{1}, 1.5 * t_stop);
  CHECK(std::abs(end.w_W.z()) <= 1e-12 * w0);
  CHECK(end.v_W.head<2>().norm() < 1e-9);
  // A resting body bounces on microcollisions: it collides anywhere within the envelope and
  // rises by at most one envelope more.
  CHECK(std::abs(end.x_W.z() - half) <= 2.0 * world.settings.envelope_m);
  CHECK(sim.stats().impulse_failures == 0);
}

TEST_CASE("a rolling sphere with rolling resistance d decelerates at 5 d g / 7 r", "[scheduler]") {
  const double r = 0.03, mass = 0.2, v0 = 0.5, g = 9.81;
  for (double d : {0.0, 2e-4}) {
    CAPTURE(d);
    World world;
    world.gravity_W = Vec3(0, 0, -g);
    world.default_material = Material{0.3, 0.0, d};
    world.settings.envelope_m = 1e-5;
    world.add(test::fixed_ground("table"));
    Body ball;
    ball.name = "ball";
    ball.shape = std::make_shared<const Shape>(make_sphere(r));
    ball.mass = mass_properties_from_mass(*ball.shape, mass);
    ball.state.x_W = Vec3(0, 0, r);
    ball.state.v_W = Vec3(v0, 0, 0);
    ball.state.w_W = Vec3(0, v0 / r, 0);  // rolling
    world.add(ball);
    const double decel = 5.0 * d * g / (7.0 * r);
    const double t_end = d > 0.0 ? 1.5 * v0 / decel : 1.0;
    Simulation sim(world, SimulationOptions{t_end / 60.0});
    Samples rec;
    sim.run_until(t_end, &rec);
    const double window_end = d == 0.0 ? t_end : 0.9 * v0 / decel;
    const double v_slope =
        slope_over(rec, 0.05 * t_end, window_end, [](const BodyState& st) { return st.v_W.x(); });
    const BodyState end = sim.state_at(BodyId{1}, t_end);
    if (d == 0.0) {
      // The control: without d, no deceleration, and no acceleration either. (Before each
      // body's velocity was taken at its own surface, the microcollisions sped the ball up by
      // 2.4e-5 v0 in this second: the slip at the midpoint of the gap.)
      CHECK(std::abs(v_slope) < 1e-9 * v0);
      CHECK(end.v_W.x() == Approx(v0).epsilon(1e-9));
    } else {
      CHECK(v_slope == Approx(-decel).epsilon(0.02));
      CHECK(end.v_W.head<2>().norm() < 1e-9);
      CHECK(end.w_W.norm() * r < 1e-6);
      // Where it stops: v0^2 / (2 decel).
      CHECK(end.x_W.x() == Approx(v0 * v0 / (2.0 * decel)).epsilon(0.02));
    }
    CHECK(std::abs(end.x_W.z() - r) <= 2.0 * world.settings.envelope_m);
  }
}

TEST_CASE("a sphere spinning about the vertical with spinning resistance s slows at 5 s g / 2 r^2",
          "[scheduler]") {
  const double r = 0.02, mass = 0.0335, w0 = 10.0, g = 9.81, s = 1e-4;
  World world;
  world.gravity_W = Vec3(0, 0, -g);
  world.default_material = Material{0.3, 0.0, 0.0, s};
  world.settings.envelope_m = 1e-5;
  world.add(test::fixed_ground("table"));
  Body ball;
  ball.name = "ball";
  ball.shape = std::make_shared<const Shape>(make_sphere(r));
  ball.mass = mass_properties_from_mass(*ball.shape, mass);
  ball.state.x_W = Vec3(0, 0, r);
  ball.state.w_W = Vec3(0, 0, w0);
  world.add(ball);
  const double rate = 5.0 * s * g / (2.0 * r * r);
  const double t_stop = w0 / rate;
  Simulation sim(world, SimulationOptions{t_stop / 40.0});
  Samples rec;
  sim.run_until(1.5 * t_stop, &rec);
  const auto spin = [](const BodyState& st) { return st.w_W.z(); };
  CHECK(slope_over(rec, 0.1 * t_stop, 0.9 * t_stop, spin) == Approx(-rate).epsilon(0.02));
  const BodyState end = sim.state_at(BodyId{1}, 1.5 * t_stop);
  CHECK(end.w_W.norm() <= 1e-12 * w0);
  CHECK(end.x_W.head<2>().norm() < 1e-12);  // spinning in place: no sideways motion
}
