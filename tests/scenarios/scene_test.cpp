// Scene parsing and validation: a good scene round-trips into bodies; every case of the bad-scene
// corpus (tests/scenarios/bad_scenes.json) is rejected with a message naming its JSON path.
#include "scenarios/scene.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <fstream>

using nlohmann::json;
using palpable::InputError;

namespace {
json load_corpus() {
  return palpable::read_json_file(std::string(PALPABLE_SOURCE_DIR) +
                                  "/tests/scenarios/bad_scenes.json");
}
}  // namespace

TEST_CASE("the base scene of the corpus parses", "[scenarios][scene]") {
  json corpus = load_corpus();
  palpable::Scene scene = palpable::scene_from_json(corpus["base"], "base.json");
  REQUIRE(scene.world.bodies.size() == 3);
  CHECK(scene.world.bodies[0].motion == palpable::MotionKind::kFixed);
  CHECK(scene.world.bodies[0].mass.inv_mass == 0.0);
  CHECK(scene.world.bodies[1].mass.mass == Approx(1.0));
  // 0.2 m cube at 1000 kg/m^3 weighs 8 kg.
  CHECK(scene.world.bodies[2].mass.mass == Approx(8.0).epsilon(1e-12));
  CHECK(scene.world.material(palpable::BodyId{1}, palpable::BodyId{0}).friction == 0.7);
  CHECK(scene.world.material(palpable::BodyId{0}, palpable::BodyId{1}).restitution == 0.0);
  CHECK(scene.world.material(palpable::BodyId{2}, palpable::BodyId{0}).friction == 0.5);
  CHECK(scene.world.settings.envelope_m == 1e-4);
}

TEST_CASE("every bad scene is rejected naming its JSON path", "[scenarios][scene]") {
  json corpus = load_corpus();
  const json& cases = corpus["cases"];
  REQUIRE(cases.size() >= 30);
  for (const json& c : cases) {
    std::string what = c["what"];
    CAPTURE(what);
    json scene = corpus["base"].patch(c["patch"]);
    std::string expected_where = "bad.json:" + c["path"].get<std::string>();
    bool threw = false;
    try {
      palpable::scene_from_json(scene, "bad.json");
    } catch (const InputError& e) {
      threw = true;
      std::string message = e.what();
      CAPTURE(message);
      CHECK(e.where() == expected_where);
      if (c.contains("message")) {
        CHECK(message.find(c["message"].get<std::string>()) != std::string::npos);
      }
    }
    CHECK(threw);
  }
}

TEST_CASE("overrides address the scene by JSON pointer", "[scenarios][scene]") {
  json corpus = load_corpus();
  json doc = corpus["base"];
  palpable::apply_override(doc, "/materials/pairs/0/friction=0.6");
  palpable::apply_override(doc, "/settings/envelope=1e-5");
  palpable::apply_override(doc, "/settings/restitution_law=poisson");  // bare word: a string
  palpable::apply_override(doc, "/bodies/1/position=[0, 0, 2]");
  palpable::apply_override(doc, "/settings/broad_phase_max_sweep=4");
  palpable::Scene scene = palpable::scene_from_json(doc, "base.json");
  CHECK(scene.world.settings.broad_phase_max_sweep == 4.0);
  CHECK(scene.world.pair_materials[0].material.friction == 0.6);
  CHECK(scene.world.settings.envelope_m == 1e-5);
  CHECK(scene.world.settings.restitution_law == palpable::RestitutionLaw::kPoisson);
  CHECK(scene.world.bodies[1].state.x_W.z() == 2.0);

  CHECK_THROWS_WITH(palpable::apply_override(doc, "settings/envelope=1"),
                    Catch::Contains("/json/pointer=value"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/nothing/here=1"),
                    Catch::Contains("no such place"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/bodies/7/mass=1"),
                    Catch::Contains("out of range"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/bodies/9=1"), Catch::Contains("past the end"));
}

TEST_CASE("a file that is not JSON is named in the error", "[scenarios][scene]") {
  std::string path = "scene_test_not_json.json";
  {
    std::ofstream out(path);
    out << "{ \"format\": \"palpable-scene/1\", \"end_time\": NaN }";
  }
  CHECK_THROWS_WITH(palpable::read_json_file(path), Catch::StartsWith(path + ": not valid JSON"));
  std::remove(path.c_str());
  CHECK_THROWS_WITH(palpable::read_json_file("no/such/file.json"),
                    Catch::Contains("no/such/file.json: cannot open"));
}
