// Simultaneous contact under the default settings (issue 15): symmetric problems keep their
// symmetry through impacts and through the microcollision trains that follow, because contacts
// that meet at one instant are resolved as one group.
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

using namespace palpable;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A 1 s scene of `bodies` under gravity, one material (mu, e) for every pair.
Scene make_scene(const nlohmann::json& bodies, double mu, double e) {
  const nlohmann::json doc = {
      {"format", "palpable-scene/1"},
      {"name", "simultaneous"},
      {"gravity", {0, 0, -9.81}},
      {"end_time", 1.0},
      {"materials", {{"default", {{"friction", mu}, {"restitution", e}}}}},
      {"bodies", bodies}};
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
