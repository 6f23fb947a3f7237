// Scene parsing and validation: a good scene round-trips into bodies; every case of the bad-scene
// corpus (tests/scenarios/bad_scenes.json) is rejected with a message naming its JSON path.
#include "scenarios/scene.hpp"
#include "scenarios/json_reader.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <cmath>
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

TEST_CASE("the smooth shapes' keys build their shapes, masses and compound parts",
          "[scenarios][scene][smooth]") {
  json scene = load_corpus()["base"];
  scene["bodies"][1] =
      json::parse(R"({"name": "ball", "mass": 0.02, "inertia": [1.3e-6, 1.3e-6, 1.2e-6],
      "shape": {"type": "loaded_ball", "radius": 0.02, "com_offset": -0.005}, "position": [0, 0, 0.5]})");
  scene["bodies"][2]["shape"] =
      json::parse(R"({"type": "cylinder", "radius": 0.1, "half_height": 0.02})");
  scene["bodies"].push_back(json::parse(R"({"name": "egg", "density": 1000, "position": [2, 0, 1],
      "shape": {"type": "ellipsoid", "semi_axes": [0.02, 0.03, 0.05]}})"));
  scene["bodies"].push_back(json::parse(R"({"name": "pill", "mass": 2.0, "position": [3, 0, 1],
      "shape": {"type": "capsule", "radius": 0.01, "half_length": 0.03}})"));
  scene["bodies"].push_back(
      json::parse(R"({"name": "rack", "motion": "fixed", "position": [5, 0, 1],
      "shape": {"type": "compound", "parts": [
        {"shape": {"type": "cylinder", "radius": 0.1, "half_height": 0.5}, "position": [0, 0, 0]},
        {"shape": {"type": "capsule", "radius": 0.05, "half_length": 0.2}, "position": [0, 1, 0]},
        {"shape": {"type": "ellipsoid", "semi_axes": [0.1, 0.2, 0.3]}, "position": [0, 2, 0]}]}})"));
  const palpable::Scene s = palpable::scene_from_json(scene, "smooth.json");
  const auto& bodies = s.world.bodies;
  REQUIRE(bodies.size() == 6);
  const auto& ball = std::get<palpable::LoadedBall>(*bodies[1].shape);
  CHECK(ball.radius == 0.02);
  CHECK(ball.com_offset == -0.005);
  // The given inertia, ascending principal moments.
  CHECK(bodies[1].mass.mass == 0.02);
  CHECK(bodies[1].mass.principal_moments.x() == Approx(1.2e-6).epsilon(1e-12));
  CHECK(bodies[1].mass.principal_moments.z() == Approx(1.3e-6).epsilon(1e-12));
  // A 0.1 x 0.04 m cylinder at 1000 kg/m^3: pi r^2 2h rho.
  const double kPi = 3.14159265358979323846;
  CHECK(std::get<palpable::Cylinder>(*bodies[2].shape).half_height == 0.02);
  CHECK(bodies[2].mass.mass == Approx(kPi * 0.01 * 0.04 * 1000).epsilon(1e-14));
  CHECK(bodies[3].mass.mass == Approx(4.0 / 3.0 * kPi * 0.02 * 0.03 * 0.05 * 1000).epsilon(1e-14));
  CHECK(std::get<palpable::Capsule>(*bodies[4].shape).half_length == 0.03);
  CHECK(bodies[4].mass.mass == Approx(2.0).epsilon(1e-15));
  const auto& rack = std::get<palpable::Compound>(*bodies[5].shape);
  REQUIRE(rack.parts.size() == 3);
  CHECK(std::holds_alternative<palpable::Cylinder>(*rack.parts[0].shape));
  CHECK(std::holds_alternative<palpable::Capsule>(*rack.parts[1].shape));
  CHECK(std::holds_alternative<palpable::Ellipsoid>(*rack.parts[2].shape));
}

TEST_CASE("an ellipsoid given its inertia matrix has its principal axes turned as the matrix says",
          "[scenarios][scene][smooth]") {
  // A rattleback's inertia (Kane & Levinson 1982): A = 2e-4, B = 1.6e-3 about x, y, product
  // D = -1.6e-5 between them, C = 1.7e-3 about z. The principal moments in the x-y plane are
  // (A + B)/2 -+ sqrt(((B - A)/2)^2 + D^2), their axes turned about z by
  // delta = atan(2 D / (A - B)) / 2 from x and y (0.65 degrees).
  json scene = load_corpus()["base"];
  scene["bodies"][1] = json::parse(R"({"name": "ball", "mass": 1.0,
      "inertia": [[2e-4, -1.6e-5, 0], [-1.6e-5, 1.6e-3, 0], [0, 0, 1.7e-3]],
      "shape": {"type": "ellipsoid", "semi_axes": [0.2, 0.03, 0.02]}, "position": [0, 0, 0.5]})");
  const palpable::Scene s = palpable::scene_from_json(scene, "rattleback.json");
  const palpable::Body& b = s.world.bodies[1];
  const double A = 2e-4, B = 1.6e-3, C = 1.7e-3, D = -1.6e-5;
  const double mid = 0.5 * (A + B), half = std::sqrt(0.25 * (B - A) * (B - A) + D * D);
  CHECK(b.mass.mass == 1.0);
  CHECK(b.mass.principal_moments.x() == Approx(mid - half).epsilon(1e-12));
  CHECK(b.mass.principal_moments.y() == Approx(mid + half).epsilon(1e-12));
  CHECK(b.mass.principal_moments.z() == Approx(C).epsilon(1e-12));
  CHECK(b.mass.inertia_M(0, 1) == Approx(D).epsilon(1e-12));
  CHECK(b.mass.inertia_M(0, 0) == Approx(A).epsilon(1e-12));
  // The smallest moment's axis: turned from x by delta about z.
  const double delta = 0.5 * std::atan(2.0 * D / (A - B));
  const Eigen::Vector3d e = b.mass.q_MB.toRotationMatrix().col(0);
  CHECK(std::abs(std::abs(e.x()) - std::cos(delta)) < 1e-12);
  CHECK(std::abs(std::abs(e.y()) - std::abs(std::sin(delta))) < 1e-12);
  CHECK(std::abs(e.z()) < 1e-12);
  // Principal moments alone, as for a loaded ball, are the diagonal.
  scene["bodies"][1]["inertia"] = json::parse("[2e-4, 1.6e-3, 1.7e-3]");
  const palpable::Scene diagonal = palpable::scene_from_json(scene, "rattleback.json");
  CHECK(diagonal.world.bodies[1].mass.inertia_M(0, 1) == 0.0);
  CHECK(diagonal.world.bodies[1].mass.principal_moments.x() == Approx(A).epsilon(1e-12));
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
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/end_time/x=1"),
                    Catch::Contains("/end_time is not an object or array"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/bodies/7/mass=1"),
                    Catch::Contains("out of range"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/bodies/9=1"), Catch::Contains("past the end"));
}

TEST_CASE("overrides create the optional objects they address", "[scenarios][scene]") {
  json corpus = load_corpus();
  json doc = corpus["base"];
  doc.erase("settings");
  doc.erase("output");
  palpable::apply_override(doc, "/settings/envelope=1e-6");
  palpable::apply_override(doc, "/output/interval=0.5");
  palpable::Scene scene = palpable::scene_from_json(doc, "base.json");
  CHECK(scene.world.settings.envelope_m == 1e-6);
  CHECK(scene.output_interval == 0.5);

  // A misspelt object is created too, and then named by the parser.
  palpable::apply_override(doc, "/setings/envelope=1");
  CHECK_THROWS_WITH(palpable::scene_from_json(doc, "base.json"),
                    Catch::Contains("base.json:/setings") && Catch::Contains("unknown key"));
}

TEST_CASE("every setting of the table is read from a scene and printed in effect",
          "[scenarios][scene][settings]") {
  const palpable::Settings defaults;
  json corpus = load_corpus();
  for (const palpable::SettingInfo& info : palpable::settings_table()) {
    const std::string key(info.key);
    CAPTURE(key);
    // The default written back reads to the same value.
    const json printed = palpable::settings_json(defaults, 9.81).at(key);
    json doc = corpus["base"];
    doc["settings"] = json::object({{key, printed}});
    const palpable::Scene scene = palpable::scene_from_json(doc, "s.json");
    CHECK(palpable::format_setting(info.get(scene.world.settings)) ==
          palpable::format_setting(info.get(defaults)));
    // A value of the wrong kind is rejected naming the pointer and the check.
    doc["settings"] = json::object({{key, json::array()}});
    CHECK_THROWS_WITH(
        palpable::scene_from_json(doc, "s.json"),
        Catch::Contains("s.json:/settings/" + key) && Catch::Contains(std::string(info.check)));
  }
  // A changed value is the one printed.
  json doc = corpus["base"];
  doc["settings"] = {{"microcollision_speed", 0.25}, {"retry_limit", 7}, {"still_speed", 0}};
  const palpable::Scene scene = palpable::scene_from_json(doc, "s.json");
  const json printed = palpable::settings_json(scene.world.settings, 9.81);
  CHECK(printed["microcollision_speed"] == 0.25);
  CHECK(printed["retry_limit"] == 7);
  CHECK(printed["still_speed"] == 0.0);
  CHECK(palpable::settings_json(palpable::Settings{}, 9.81)["microcollision_speed"] == "auto");
  // Derived: sqrt(2 g envelope) at the default envelope, half an envelope of target gap.
  const json derived = palpable::settings_json(palpable::Settings{}, 9.81)["derived"];
  CHECK(derived["microcollision_speed"].get<double>() == std::sqrt(2.0 * 9.81 * 1e-4));
  CHECK(derived["target_gap"].get<double>() == 0.5e-4);
  // Out of range: integers that are not, numbers outside the checks.
  for (const json& bad : {json{{"retry_limit", 1.5}}, json{{"retry_limit", 0}},
                          json{{"integration_tolerance", 1.0}}, json{{"envelope", -1.0}},
                          json{{"microcollision_speed", "fast"}}, json{{"contact_model", 1}}}) {
    CAPTURE(bad.dump());
    doc["settings"] = bad;
    CHECK_THROWS_AS(palpable::scene_from_json(doc, "s.json"), InputError);
  }
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

TEST_CASE("hostile JSON: too deep, out of range, on the command line too", "[scenarios][scene]") {
  // 100,000 levels crashed the formatter after parsing; any depth past the limit is refused
  // while parsing, naming the source.
  const std::string deep =
      "{\"description\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
  CHECK_THROWS_WITH(palpable::parse_json_text(deep, "deep.json"),
                    Catch::StartsWith("deep.json") && Catch::Contains("nested deeper than 256"));
  CHECK_NOTHROW(palpable::parse_json_text(std::string(255, '[') + std::string(255, ']'), "ok"));
  CHECK_THROWS_WITH(palpable::parse_json_text("{\"end_time\": 1e999}", "big.json"),
                    Catch::StartsWith("big.json") && Catch::Contains("number overflow"));
  json corpus = load_corpus();
  json doc = corpus["base"];
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/end_time=1e999"),
                    Catch::Contains("--set /end_time=1e999"));
  // Words stay words: choices, and =expressions.
  palpable::apply_override(doc, "/settings/restitution_law=poisson");
  CHECK(doc["settings"]["restitution_law"] == "poisson");
  palpable::apply_override(doc, "/end_time==2*0.5");
  CHECK(doc["end_time"] == "=2*0.5");
  CHECK(palpable::scene_from_json(doc, "s.json").end_time == 1.0);
}

TEST_CASE("hostile text: non-UTF-8 values, JSON not UTF-8, deep expressions",
          "[scenarios][scene]") {
  json doc = load_corpus()["base"];
  // A bare word that is not UTF-8 would become a JSON string no writer can print.
  CHECK_THROWS_WITH(
      palpable::apply_override(doc, "/settings/restitution_law=po\xffsson"),
      Catch::Contains("--set /settings/restitution_law=") && Catch::Contains("not valid UTF-8"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/name=\xc0\xaf"),  // overlong "/"
                    Catch::Contains("not valid UTF-8"));
  CHECK_THROWS_WITH(palpable::apply_override(doc, "/name=\xed\xa0\x80"),  // a surrogate
                    Catch::Contains("not valid UTF-8"));
  palpable::apply_override(doc, "/name=caf\xc3\xa9");  // UTF-8 is fine
  CHECK(doc["name"] == "caf\xc3\xa9");
  CHECK(palpable::is_valid_utf8("\xf0\x9f\x8e\xb3"));
  CHECK_FALSE(palpable::is_valid_utf8("\xf4\x90\x80\x80"));  // past U+10FFFF
  CHECK_FALSE(palpable::is_valid_utf8("\xe2\x82"));          // cut short
  // In a file, the parser refuses it, naming the file.
  CHECK_THROWS_WITH(palpable::parse_json_text("{\"name\": \"\xff\"}", "latin1.json"),
                    Catch::StartsWith("latin1.json"));
  // An =expression nested 100,000 deep in a scene: the file and pointer, not a stack overflow.
  doc = load_corpus()["base"];
  doc["end_time"] = "=" + std::string(100000, '(') + "1" + std::string(100000, ')');
  CHECK_THROWS_WITH(palpable::scene_from_json(doc, "s.json"),
                    Catch::StartsWith("s.json:/end_time") && Catch::Contains("nested deeper"));
}
