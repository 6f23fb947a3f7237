// Inputs outside what can be simulated (issue 7, "The extremes"): an InputError naming the JSON
// path before anything runs - e > 1, mu < 0, a zero or negative envelope, mass or radius, a
// non-numeric velocity, a body placed into the ground, non-finite states from a program.
#include "core/check.hpp"
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"
#include "tests/support/test_world.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <limits>
#include <string>
#include <vector>

using namespace palpable;

namespace {
// A ball at height z over a ground.
nlohmann::json ball_over_ground(double z) {
  nlohmann::json doc = nlohmann::json::parse(R"({
    "format": "palpable-scene/1", "end_time": 1.0,
    "settings": { "envelope": 1e-4 },
    "materials": { "default": { "friction": 0.5, "restitution": 0.5 } },
    "bodies": [
      { "name": "ground", "motion": "fixed",
        "shape": { "type": "halfspace", "normal": [0, 0, 1], "offset": 0 } },
      { "name": "ball", "mass": 1.0, "shape": { "type": "sphere", "radius": 0.1 },
        "position": [0, 0, 0.5], "velocity": [0, 0, 0] } ] })");
  doc["bodies"][1]["position"][2] = z;
  return doc;
}
}  // namespace

TEST_CASE("inputs outside what can be simulated are rejected naming the JSON path",
          "[extremes][input]") {
  const nlohmann::json base = ball_over_ground(0.5);
  REQUIRE_NOTHROW(scene_from_json(base, "x.json"));
  struct Bad {
    std::string pointer;
    nlohmann::json value;
    std::string named;  // the path the error must name
  };
  const std::vector<Bad> bad = {
      {"/materials/default/restitution", 1.5, ""},  // e > 1 creates energy
      {"/materials/default/friction", -1.0, ""},
      {"/settings/envelope", 0.0, ""},
      {"/settings/envelope", -1e-9, ""},
      {"/bodies/1/mass", 0.0, ""},
      {"/bodies/1/shape/radius", 0.0, ""},
      {"/bodies/1/velocity/0", "fast", ""},
      // Into the ground: found by the Simulation's start check, which names the body.
      {"/bodies/1/position", nlohmann::json::array({0, 0, -0.05}), "/bodies/1"},
  };
  for (const Bad& b : bad) {
    CAPTURE(b.pointer, b.value.dump());
    nlohmann::json doc = base;
    doc[nlohmann::json::json_pointer(b.pointer)] = b.value;
    bool threw = false;
    try {
      const Scene scene = scene_from_json(doc, "x.json");
      Simulation sim(scene.world, SimulationOptions{});  // overlap is checked here, before a run
    } catch (const InputError& e) {
      threw = true;
      INFO(e.what());
      const std::string named = b.named.empty() ? b.pointer : b.named;
      CHECK(std::string(e.what()).find(named) != std::string::npos);
    }
    CHECK(threw);
  }
  // Non-finite states from a program (JSON cannot hold them).
  World world;
  world.add(test::fixed_ground());
  world.add(test::sphere_body("ball", 0.1, 1.0, Vec3(0, 0, 0.5),
                              Vec3(std::numeric_limits<double>::infinity(), 0, 0)));
  CHECK_THROWS_WITH(Simulation(world, SimulationOptions{}), Catch::Contains("/bodies/1"));
}

TEST_CASE("a run whose clock stops advancing ends with an error naming the bodies and the time",
          "[extremes][input][hostile]") {
  // Gravity of 1e300 (the loader refuses it; a program building a World need not): the ball's
  // microcollisions come at t ~ 1e-146 and the clock no longer moves. The progress guard stops the
  // run instead of letting it go on until killed.
  Scene scene = scene_from_json(ball_over_ground(0.1), "x.json");
  scene.world.gravity_W = Vec3(0, 0, -1e300);
  // The microcollision model's trains: pinned, since the default may be the other.
  scene.world.settings.contact_model = ContactModel::kMicrocollisions;
  Simulation simulation(scene.world, SimulationOptions{});
  CHECK_THROWS_WITH(simulation.run_until(1.0, nullptr),
                    Catch::StartsWith("t = ") && Catch::Contains("clock stopped advancing") &&
                        Catch::Contains("\"ground\" and \"ball\""));
}

TEST_CASE("a halfspace normal too long or too short to square is normalised, not zeroed",
          "[extremes][input][hostile][fuzz]") {
  // tests/fuzz/findings/engine_timeout_distance_steps.bin set bowling's lane normal to
  // (9e190, 0, 1): its squared length overflows, so normalising made (0, 0, 0) and the lane a
  // plane no body could leave or enter; the pins fell through it. The normal is a direction of
  // any finite length: here the plane x = 0, a wall the ball at the origin sits in.
  auto normal_of = [](const Scene& scene) {
    return std::get<Halfspace>(*scene.world.bodies[0].shape).normal_M;
  };
  nlohmann::json doc = ball_over_ground(0.5);
  doc["bodies"][0]["shape"]["normal"] = {9.034376816953001e+190, 0, 1};
  doc["bodies"][0]["shape"]["offset"] = 9.034376816953001e+190;  // x <= 1
  Scene scene = scene_from_json(doc, "x.json");
  CHECK(normal_of(scene).x() == 1.0);
  CHECK(std::abs(normal_of(scene).z()) < 1e-190);
  CHECK(std::get<Halfspace>(*scene.world.bodies[0].shape).offset == 1.0);
  CHECK_THROWS_WITH(Simulation(scene.world, SimulationOptions{}),
                    Catch::Contains("/bodies/1") && Catch::Contains("overlaps"));
  // A length whose square underflows is a direction too.
  doc["bodies"][0]["shape"]["normal"] = {0, 0, 1e-170};
  doc["bodies"][0]["shape"]["offset"] = 0;
  scene = scene_from_json(doc, "x.json");
  CHECK(normal_of(scene) == Vec3::UnitZ());
  Simulation(scene.world, SimulationOptions{}).run_until(0.5, nullptr);  // lands, no overlap
  // A length past the largest double is not.
  doc["bodies"][0]["shape"]["normal"] = {1.5e308, 1.5e308, 0};
  CHECK_THROWS_WITH(scene_from_json(doc, "x.json"),
                    Catch::Contains("x.json:/bodies/0/shape/normal") &&
                        Catch::Contains("expected a non-zero vector"));
}
