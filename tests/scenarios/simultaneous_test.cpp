// Simultaneous contact under the default settings (issue 15): symmetric problems keep their
// symmetry through impacts and through the microcollision trains that follow, because contacts
// that meet at one instant are resolved as one group.
#include "impulse/microcollision.hpp"
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace palpable;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A 1 s scene of `bodies` under gravity g (downwards), one material (mu, e) for every pair;
// `settings` (a JSON object) if given.
Scene make_scene(const nlohmann::json& bodies, double mu, double e, double g = 9.81,
                 const nlohmann::json& settings = nullptr) {
  nlohmann::json doc = {{"format", "palpable-scene/1"},
                        {"name", "simultaneous"},
                        {"gravity", {0, 0, -g}},
                        {"end_time", 1.0},
                        {"materials", {{"default", {{"friction", mu}, {"restitution", e}}}}},
                        {"bodies", bodies}};
  if (!settings.is_null()) doc["settings"] = settings;
  return scene_from_json(doc, "simultaneous.json");
}

// Runs the scene to its end, calling `at(sim, t)` every 10 ms.
template <class At>
void every_10_ms(const Scene& scene, At at) {
  Simulation sim(scene.world, SimulationOptions{0.01});
  for (int k = 1; k <= 100; ++k) {
    const double t = 0.01 * k;
    sim.run_until(t, nullptr);
    at(sim, t);
  }
  CHECK(sim.stats().groups > 0);
}

}  // namespace

TEST_CASE("a ball dropped into a V-groove stays on its axis, impacts and microcollisions alike",
          "[scenarios][group]") {
  const double radius = 0.05;
  for (double angle_deg : {90.0, 60.0}) {
    for (double e : {0.0, 0.5}) {
      for (double mu : {0.0, 0.5}) {
        CAPTURE(angle_deg, e, mu);
        // Each wall through the origin at half the groove's angle from the vertical; the solid
        // is normal . x <= 0, normal (+-cos h, 0, sin h) pointing away from the free side.
        const double h = angle_deg / 2.0 * kPi / 180.0;
        nlohmann::json bodies = nlohmann::json::array();
        for (double side : {1.0, -1.0}) {
          bodies.push_back({{"name", side > 0 ? "left" : "right"},
                            {"motion", "fixed"},
                            {"shape",
                             {{"type", "halfspace"},
                              {"normal", {side * std::cos(h), 0.0, std::sin(h)}},
                              {"offset", 0.0}}}});
        }
        const double z_rest = radius / std::sin(h);
        bodies.push_back({{"name", "ball"},
                          {"mass", 0.1},
                          {"shape", {{"type", "sphere"}, {"radius", radius}}},
                          {"position", {0.0, 0.0, z_rest + 0.1}}});
        const Scene scene = make_scene(bodies, mu, e);
        double lateral = 0.0;
        every_10_ms(scene, [&](const Simulation& sim, double t) {
          const BodyState s = sim.state_at(BodyId{2}, t);
          lateral = std::max({lateral, std::abs(s.x_W.x()), std::abs(s.x_W.y())});
          CHECK(s.x_W.z() >= z_rest - 1e-12);  // never into a wall
          // Settled on the axis by the end: at rest within the envelope's microcollision train.
          if (t == 1.0) {
            CHECK(s.x_W.z() - z_rest <= 2.0 * scene.world.settings.envelope_m / std::sin(h));
          }
        });
        CHECK(lateral <= 1e-9);
      }
    }
  }
}

TEST_CASE("two balls dropped symmetrically onto a resting third stay mirror images",
          "[scenarios][group]") {
  const double radius = 0.05;
  for (double mu : {0.0, 0.5}) {
    CAPTURE(mu);
    nlohmann::json bodies = {
        {{"name", "floor"},
         {"motion", "fixed"},
         {"shape", {{"type", "halfspace"}, {"normal", {0, 0, 1}}, {"offset", 0}}}},
        {{"name", "base"},
         {"mass", 0.1},
         {"shape", {{"type", "sphere"}, {"radius", radius}}},
         {"position", {0, 0, radius}}}};
    const double a = 30.0 * kPi / 180.0, d = 2.0 * radius + 0.05;
    for (double side : {1.0, -1.0}) {
      bodies.push_back({{"name", side > 0 ? "L" : "R"},
                        {"mass", 0.1},
                        {"shape", {{"type", "sphere"}, {"radius", radius}}},
                        {"position", {side * d * std::sin(a), 0.0, radius + d * std::cos(a)}}});
    }
    double asymmetry = 0.0;
    every_10_ms(make_scene(bodies, mu, 0.5), [&](const Simulation& sim, double t) {
      const BodyState l = sim.state_at(BodyId{2}, t), r = sim.state_at(BodyId{3}, t);
      const BodyState base = sim.state_at(BodyId{1}, t);
      asymmetry = std::max({asymmetry, std::abs(l.x_W.x() + r.x_W.x()),
                            std::abs(l.x_W.z() - r.x_W.z()), std::abs(base.x_W.x())});
    });
    CHECK(asymmetry <= 1e-9);
  }
}

// A ball dropped onto the point where two resting balls touch: it lands on both at once, then
// rests on both while they roll apart, in microcollision trains between dynamic bodies that must
// be grouped too (one ball at a time, the top was pushed 2.5 cm sideways by 1 s, frictionless),
// and grouped through every body they share (one hop from the first contact only, a group met
// the floor under one lower ball and not under the other: 2.3 cm by 1 s for 1 kg balls dropped
// 0.11 m, mu 0, e 0; 2.3 cm with mu 0.5, e 0.5). With mu 0.5 and e 0 the trains still break the
// symmetry by 4 mm: not asserted here (issue 15's note).
TEST_CASE("a ball dropped onto two touching balls lands on both and stays centred",
          "[scenarios][group]") {
  const double radius = 0.05;
  struct Case {
    double mass, drop, mu, e;
  };
  for (const Case& k : {Case{0.1, 0.05, 0.0, 0.0}, Case{0.1, 0.05, 0.0, 0.5},
                        Case{1.0, 0.2 - 2 * radius * std::cos(kPi / 6), 0.0, 0.0},
                        Case{1.0, 0.2 - 2 * radius * std::cos(kPi / 6), 0.5, 0.5}}) {
    CAPTURE(k.mass, k.drop, k.mu, k.e);
    const nlohmann::json ball = {{"type", "sphere"}, {"radius", radius}};
    const nlohmann::json bodies = {
        {{"name", "floor"},
         {"motion", "fixed"},
         {"shape", {{"type", "halfspace"}, {"normal", {0, 0, 1}}, {"offset", 0}}}},
        {{"name", "L"}, {"mass", k.mass}, {"shape", ball}, {"position", {-radius, 0, radius}}},
        {{"name", "R"}, {"mass", k.mass}, {"shape", ball}, {"position", {radius, 0, radius}}},
        {{"name", "top"},
         {"mass", k.mass},
         {"shape", ball},
         {"position", {0, 0, radius + 2 * radius * std::cos(kPi / 6) + k.drop}}}};
    double asymmetry = 0.0;
    every_10_ms(make_scene(bodies, k.mu, k.e), [&](const Simulation& sim, double t) {
      const BodyState l = sim.state_at(BodyId{1}, t), r = sim.state_at(BodyId{2}, t);
      const BodyState top = sim.state_at(BodyId{3}, t);
      asymmetry =
          std::max({asymmetry, std::abs(l.x_W.x() + r.x_W.x()), std::abs(l.x_W.z() - r.x_W.z()),
                    std::abs(top.x_W.x()), std::abs(top.x_W.y())});
    });
    CHECK(asymmetry <= 1e-9);
  }
}

TEST_CASE("persistent model: a ball dropped onto two held balls or a held seam stays centred",
          "[scenarios][group]") {
  // The supports rest on the floor, held (and at rest) from t = 0; a 1 kg ball falls 0.11 m
  // onto two 1 kg balls, or onto the seam of two 1 kg cubes. It meets both supports at one
  // instant: one group, with the supports' held floor contacts as plastic members; a second,
  // gentle landing is one plastic group whose contacts are then held; and a slip that stops on
  // one support stops on its mirror image at that instant. One support at a time (a0e5af1) left
  // the ball on two balls 1.9e-2 m (mu 0, e 0.5), 8.9e-4 m (mu 0.5, e 0) and 5.6e-2 m
  // (mu 0.5, e 0.5) off its mirror image within 1 s, and the ball on the seam 0.27 m (mu 0.5,
  // e 0) and 3.2e-4 m (mu 0.5, e 0.5). With mu 0 the ball on the seam stays on it: its
  // impulses are vertical, and the floor takes them under the cubes' inner edges.
  const double radius = 0.05, half = 0.05;
  const nlohmann::json settings = {{"contact_model", "persistent"}};
  struct Case {
    bool seam;
    double mu, e;
  };
  for (const Case& k :
       {Case{false, 0.0, 0.0}, Case{false, 0.0, 0.5}, Case{false, 0.5, 0.0}, Case{false, 0.5, 0.5},
        Case{true, 0.0, 0.0}, Case{true, 0.0, 0.5}, Case{true, 0.5, 0.0}, Case{true, 0.5, 0.5}}) {
    CAPTURE(k.seam, k.mu, k.e);
    const nlohmann::json support =
        k.seam ? nlohmann::json{{"type", "box"}, {"half_extents", {half, half, half}}}
               : nlohmann::json{{"type", "sphere"}, {"radius", radius}};
    const nlohmann::json bodies = {
        {{"name", "floor"},
         {"motion", "fixed"},
         {"shape", {{"type", "halfspace"}, {"normal", {0, 0, 1}}, {"offset", 0}}}},
        {{"name", "L"}, {"mass", 1.0}, {"shape", support}, {"position", {-0.05, 0, 0.05}}},
        {{"name", "R"}, {"mass", 1.0}, {"shape", support}, {"position", {0.05, 0, 0.05}}},
        {{"name", "top"},
         {"mass", 1.0},
         {"shape", {{"type", "sphere"}, {"radius", radius}}},
         {"position", {0, 0, 0.25}}}};
    double asymmetry = 0.0, spin = 0.0, top_z = 0.0;
    every_10_ms(
        make_scene(bodies, k.mu, k.e, 9.81, settings), [&](const Simulation& sim, double t) {
          const BodyState l = sim.state_at(BodyId{1}, t), r = sim.state_at(BodyId{2}, t);
          const BodyState top = sim.state_at(BodyId{3}, t);
          asymmetry =
              std::max({asymmetry, std::abs(l.x_W.x() + r.x_W.x()), std::abs(l.x_W.z() - r.x_W.z()),
                        std::abs(top.x_W.x()), std::abs(top.x_W.y())});
          spin = std::max(spin, std::abs(top.w_W.y()));
          top_z = top.x_W.z();
        });
    CHECK(asymmetry <= 1e-9);
    CHECK(spin <= 1e-6);
    // On the seam the ball ends on the cubes (centre 0.15 m up), not between them on the floor.
    CHECK((!k.seam || top_z > 0.149));
  }
}

TEST_CASE("persistent model: two balls dropped symmetrically onto a held third stay mirror images",
          "[scenarios][group]") {
  // A 1 kg ball rests held on the floor; two 1 kg balls fall 0.05 m onto it at +-30 degrees from
  // its top and meet it at one instant: one group with its held floor contact as a plastic
  // member. Struck one at a time (a0e5af1) they ended 1.7e-2 m (mu 0.5, e 0) and 9.1e-5 m
  // (mu 0.5, e 0.5) off their mirror images within 1 s.
  const double radius = 0.05;
  const nlohmann::json settings = {{"contact_model", "persistent"}};
  const nlohmann::json ball = {{"type", "sphere"}, {"radius", radius}};
  const double dx = 2 * radius * std::sin(kPi / 6);
  const double z = radius + 2 * radius * std::cos(kPi / 6) + 0.05;
  for (double mu : {0.0, 0.5}) {
    for (double e : {0.0, 0.5}) {
      CAPTURE(mu, e);
      const nlohmann::json bodies = {
          {{"name", "floor"},
           {"motion", "fixed"},
           {"shape", {{"type", "halfspace"}, {"normal", {0, 0, 1}}, {"offset", 0}}}},
          {{"name", "L"}, {"mass", 1.0}, {"shape", ball}, {"position", {-dx, 0, z}}},
          {{"name", "R"}, {"mass", 1.0}, {"shape", ball}, {"position", {dx, 0, z}}},
          {{"name", "third"}, {"mass", 1.0}, {"shape", ball}, {"position", {0, 0, radius}}}};
      double asymmetry = 0.0;
      every_10_ms(make_scene(bodies, mu, e, 9.81, settings), [&](const Simulation& sim, double t) {
        const BodyState l = sim.state_at(BodyId{1}, t), r = sim.state_at(BodyId{2}, t);
        const BodyState third = sim.state_at(BodyId{3}, t);
        asymmetry = std::max({asymmetry, std::abs(l.x_W.x() + r.x_W.x()),
                              std::abs(l.x_W.z() - r.x_W.z()), std::abs(third.x_W.x()),
                              std::abs(third.x_W.y()), std::abs(l.x_W.y()), std::abs(r.x_W.y())});
      });
      CHECK(asymmetry <= 1e-9);
    }
  }
}

namespace {

// Every collision record of a run.
struct Records : SimulationObserver {
  std::vector<CollisionRecord> all;
  void on_collision(const CollisionRecord& r) override { all.push_back(r); }
};

// A 1 kg cube (0.1 m) 0.1 m above a 2 kg cube resting on a floor, in one of three poses:
// aligned with it, turned 45 degrees about the vertical (an octagonal patch), and 2 cm and 1 cm
// off centre.
constexpr double kCubeHalf = 0.05;
struct CubePose {
  const char* name;
  nlohmann::json orientation;
  double x, y;
};
std::vector<CubePose> cube_poses() {
  const double c8 = std::cos(kPi / 8), s8 = std::sin(kPi / 8);
  return {CubePose{"aligned", {1, 0, 0, 0}, 0.0, 0.0}, CubePose{"turned", {c8, 0, 0, s8}, 0.0, 0.0},
          CubePose{"off centre", {1, 0, 0, 0}, 0.02, 0.01}};
}
nlohmann::json cube_on_cube(const CubePose& v) {
  const nlohmann::json box = {{"type", "box"}, {"half_extents", {kCubeHalf, kCubeHalf, kCubeHalf}}};
  return {{{"name", "floor"},
           {"motion", "fixed"},
           {"shape", {{"type", "halfspace"}, {"normal", {0, 0, 1}}, {"offset", 0}}}},
          {{"name", "base"}, {"mass", 2.0}, {"shape", box}, {"position", {0, 0, kCubeHalf}}},
          {{"name", "top"},
           {"mass", 1.0},
           {"shape", box},
           {"position", {v.x, v.y, 5 * kCubeHalf}},
           {"orientation", v.orientation}}};
}

}  // namespace

TEST_CASE("a cube dropped flat onto a resting cube turns neither and drifts neither",
          "[scenarios][group]") {
  // A 1 kg cube (0.1 m) dropped 0.1 m onto a 2 kg cube resting on the floor, mu 0.5: aligned
  // with it, turned 45 degrees about the vertical (an octagonal patch), and 2 cm and 1 cm off
  // centre. The patch between the two holds their relative rotation, the floor holds the base's
  // (DESIGN.md §4): the landing is a sequence of pair impulses - base-top, then floor-base, ...
  // as in a cradle against a wall - each along the normal through the patch,
  // p = m (u + max(e u, v_micro)) with m the reduced mass m1 m2 / (m1 + m2) between the cubes
  // and the base's mass on the floor (the rebound never slower than the microcollision speed of
  // the default contact model), until nothing approaches faster than v_micro.
  const double half = kCubeHalf;
  for (const CubePose& v : cube_poses()) {
    for (double e : {0.0, 0.5}) {
      CAPTURE(v.name, e);
      const nlohmann::json bodies = cube_on_cube(v);
      // The impulses checked below are the microcollision model's, one pair at a time; under the
      // persistent model the landing is one group with the base's floor contacts (the next test).
      const Scene scene = make_scene(bodies, 0.5, e, 9.81, {{"contact_model", "microcollisions"}});
      Simulation sim(scene.world, SimulationOptions{0.01});
      Records records;
      double turning = 0.0, drift = 0.0;
      for (int k = 1; k <= 100; ++k) {
        const double t = 0.01 * k;
        sim.run_until(t, &records);
        const BodyState base = sim.state_at(BodyId{1}, t), top = sim.state_at(BodyId{2}, t);
        turning = std::max({turning, base.w_W.norm(), top.w_W.norm()});
        drift = std::max({drift, std::hypot(base.x_W.x(), base.x_W.y()),
                          std::hypot(top.x_W.x() - v.x, top.x_W.y() - v.y)});
        CHECK(top.x_W.z() - base.x_W.z() >= 2 * half - 1e-12);
      }
      CHECK(turning <= 1e-9);
      CHECK(drift <= 1e-9);
      // The landing: the first collision between the cubes, and the collisions of the 5 ms after
      // it (each pair's at the exact instant its gap closes: the base hovers in its own
      // microcollision train, so it meets the floor a little after it is struck).
      const auto first = std::find_if(records.all.begin(), records.all.end(), [](const auto& r) {
        return r.a == BodyId{1} && r.b == BodyId{2};
      });
      REQUIRE(first != records.all.end());
      const double v_micro = microcollision_speed(scene.world.settings, 9.81);
      int impulses = 0;
      for (const CollisionRecord& r : records.all) {
        if (r.t < first->t || r.t > first->t + 0.005 || r.kind != CollisionKind::kCollision) {
          continue;
        }
        const double m = r.a == BodyId{0} ? 2.0 : 2.0 / 3.0;
        const double u = r.approach_speed;
        CHECK(r.impulse_W.head<2>().norm() <= 1e-12 * std::abs(r.impulse_W.z()));  // rounding of n
        CHECK(-r.impulse_W.z() == Approx(m * (u + std::max(e * u, v_micro))).epsilon(1e-12));
        ++impulses;
      }
      CHECK(impulses >= 3);
    }
  }
}

TEST_CASE(
    "under the persistent model a cube dropped flat onto a resting cube rebounds by the group's "
    "law",
    "[scenarios][group][persistent]") {
  // The base (M = 2 kg) rests held on the floor; the top (m = 1 kg) lands flat on it at u. The
  // landing, at each point of its patch, and the base's held contacts on the floor are one group
  // (DESIGN.md §8.4): compression stops the top, the floor taking the whole impulse m u; the
  // expansion gives each contact e times its compression impulse (Poisson's law, which a group
  // of a face's redundant points is resolved by under either scene law): the top leaves at e u,
  // the base stays, nothing turns. Before, the top was struck on the base's free mass and the
  // base's approach to the floor projected away unreported: at e = 0.5 the top came to rest.
  const double m = 1.0;  // the top's mass (the base's is 2 kg: cube_on_cube)
  for (const CubePose& v : cube_poses()) {
    for (const char* law : {"stronge", "poisson"}) {
      for (double e : {0.0, 0.5, 1.0}) {
        CAPTURE(v.name, law, e);
        const nlohmann::json bodies = cube_on_cube(v);
        const Scene scene = make_scene(bodies, 0.5, e, 9.81,
                                       {{"contact_model", "persistent"}, {"restitution_law", law}});
        Simulation sim(scene.world, SimulationOptions{0.01});
        Records records;
        sim.run_until(0.2, &records);
        const auto first = std::find_if(records.all.begin(), records.all.end(), [](const auto& r) {
          return r.a == BodyId{1} && r.b == BodyId{2};
        });
        REQUIRE(first != records.all.end());
        const double t = first->t, u = first->approach_speed;
        REQUIRE(u > 1.0);
        const double rebound = e * u;
        // Just after: the top rising at the rebound (less gravity's 0.1 ms), the base still.
        const double after = t + 1e-4;
        const BodyState top = sim.state_at(BodyId{2}, after), base = sim.state_at(BodyId{1}, after);
        // (At e = 0 the top is held on the base at once.)
        CHECK(top.v_W.z() == Approx(e > 0.0 ? rebound - 9.81 * 1e-4 : 0.0).margin(1e-9));
        CHECK(base.v_W.norm() <= 1e-9);
        CHECK(top.w_W.norm() + base.w_W.norm() <= 1e-9);
        CHECK(std::hypot(top.v_W.x(), top.v_W.y()) <= 1e-9);
        // Momentum: the floor's impulses at that instant carry the landing's whole impulse.
        double landing = 0.0, floor = 0.0;
        for (const CollisionRecord& r : records.all) {
          if (r.t != t) continue;
          if (r.a == BodyId{1} && r.b == BodyId{2}) landing += -r.impulse_W.z();
          if (r.a == BodyId{0} && r.b == BodyId{1}) floor += -r.impulse_W.z();
        }
        CHECK(landing == Approx(m * (u + rebound)).epsilon(1e-9));
        CHECK(floor == Approx(landing).epsilon(1e-9));
      }
    }
  }
}

namespace {

// Five equal balls in a row along x without gravity; the first `strikers` move at `v` towards
// the rest, every neighbouring pair `gap` apart. Returns the balls' x velocities after 1 s.
std::vector<double> cradle(int strikers, double gap, double e, double v) {
  const double radius = 0.05;
  nlohmann::json bodies = nlohmann::json::array();
  for (int i = 0; i < 5; ++i) {
    // The strikers start 0.1 m short of the row, keeping their own gaps.
    const double x = i * (2 * radius + gap) - (i < strikers ? 0.1 : 0.0);
    bodies.push_back({{"name", "ball" + std::to_string(i)},
                      {"mass", 0.2},
                      {"shape", {{"type", "sphere"}, {"radius", radius}}},
                      {"position", {x, 0, 0}},
                      {"velocity", {i < strikers ? v : 0.0, 0, 0}}});
  }
  const Scene scene = make_scene(bodies, 0.3, e, /*g=*/0.0);
  Simulation sim(scene.world, SimulationOptions{});
  sim.run_until(1.0, nullptr);
  std::vector<double> out;
  for (std::uint32_t i = 0; i < 5; ++i) out.push_back(sim.state_at(BodyId{i}, 1.0).v_W.x());
  return out;
}

// The oracle for balls apart: a 1-D event-driven run of the same row, two-body impacts in time
// order, each by the head-on formula for equal masses.
std::vector<double> cradle_1d(int strikers, double gap, double e, double v) {
  std::vector<double> x(5), u(5);
  for (int i = 0; i < 5; ++i) {
    x[i] = i * gap - (i < strikers ? 0.1 : 0.0);  // gaps between surfaces: radii removed
    u[i] = i < strikers ? v : 0.0;
  }
  for (int n = 0; n < 100; ++n) {
    int first = -1;
    double dt = 1e300;
    for (int i = 0; i + 1 < 5; ++i) {
      const double closing = u[i] - u[i + 1];
      if (closing > 0 && (x[i + 1] - x[i]) / closing < dt) {
        dt = (x[i + 1] - x[i]) / closing;
        first = i;
      }
    }
    if (first < 0) break;
    for (int i = 0; i < 5; ++i) x[i] += u[i] * dt;
    const double a = u[first], b = u[first + 1];
    u[first] = 0.5 * (a + b) - 0.5 * e * (a - b);
    u[first + 1] = 0.5 * (a + b) + 0.5 * e * (a - b);
  }
  return u;
}

}  // namespace

// Issue 15's cradles under the default settings: contacts separated by a gap stay separate
// events, so balls hanging apart give the textbook (sequential) outcome; touching balls do not
// approach at the striker's instant, so they stay sequential too, and a cradle's touching row
// gives the same outcome with momentum and (e = 1) energy kept.
TEST_CASE("Newton's cradles of five balls give the sequential outcome apart and touching",
          "[scenarios][group]") {
  const double v = 1.0;
  for (int strikers : {1, 2}) {
    for (double e : {1.0, 0.9}) {
      for (double gap : {1e-5, 1e-4, 1e-3}) {
        CAPTURE(strikers, e, gap);
        const std::vector<double> got = cradle(strikers, gap, e, v);
        const std::vector<double> want = cradle_1d(strikers, gap, e, v);
        for (int i = 0; i < 5; ++i) CHECK(got[i] == Approx(want[i]).margin(1e-12));
        if (e == 1.0) {
          // The textbook: as many balls leave the far end at v as struck.
          for (int i = 0; i < 5; ++i)
            CHECK(got[i] == Approx(i >= 5 - strikers ? v : 0).margin(1e-12));
        }
      }
    }
    // Touching (gap 0): momentum and, for e = 1, energy to 1e-12; the outcome is the textbook's.
    const std::vector<double> touching = cradle(strikers, 0.0, 1.0, v);
    double p = 0, ke = 0;
    for (double u : touching) {
      p += 0.2 * u;
      ke += 0.5 * 0.2 * u * u;
    }
    CHECK(p == Approx(0.2 * v * strikers).epsilon(1e-12));
    CHECK(ke == Approx(0.5 * 0.2 * v * v * strikers).epsilon(1e-12));
    for (int i = 0; i < 5; ++i) {
      CHECK(touching[i] == Approx(i >= 5 - strikers ? v : 0).margin(1e-12));
    }
  }
}
