// Scene parameters: expressions of named numbers, evaluated before the scene is read.
#include "scenarios/expression.hpp"

#include "core/check.hpp"
#include "scenarios/scene.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using nlohmann::json;
using palpable::evaluate_expression;
using palpable::InputError;

TEST_CASE("expressions: arithmetic, precedence, functions and names", "[scenarios][parameters]") {
  const std::map<std::string, double> names{{"a", 2.0}, {"angle_deg", 30.0}};
  CHECK(evaluate_expression("1 + 2 * 3", names, "x") == 7.0);
  CHECK(evaluate_expression("(1 + 2) * 3", names, "x") == 9.0);
  CHECK(evaluate_expression("2 ^ 3 ^ 2", names, "x") == 512.0);  // right-associative
  CHECK(evaluate_expression("-a ^ 2", names, "x") == 4.0);        // unary minus binds tighter
  CHECK(evaluate_expression("10 / 4 - 1", names, "x") == 1.5);
  CHECK(evaluate_expression("1e-3 * a", names, "x") == 2e-3);
  CHECK(evaluate_expression("sin(angle_deg * pi / 180)", names, "x") ==
        std::sin(30.0 * 3.14159265358979323846 / 180.0));
  CHECK(evaluate_expression("atan2(1, 1) * 4", names, "x") == Approx(3.14159265358979323846));
  CHECK(evaluate_expression("max(a, 3) + min(a, 3) + sqrt(16) + abs(-1)", names, "x") == 10.0);
  CHECK_THROWS_WITH(evaluate_expression("b + 1", names, "s.json:/x"),
                    Catch::Contains("s.json:/x") && Catch::Contains("unknown name \"b\""));
  CHECK_THROWS_WITH(evaluate_expression("1 +", names, "x"), Catch::Contains("ends too early"));
  CHECK_THROWS_WITH(evaluate_expression("(1", names, "x"), Catch::Contains("missing \")\""));
  CHECK_THROWS_WITH(evaluate_expression("1 / 0", names, "x"), Catch::Contains("not finite"));
  CHECK_THROWS_WITH(evaluate_expression("foo(1)", names, "x"), Catch::Contains("unknown function"));
  CHECK_THROWS_WITH(evaluate_expression("2 3", names, "x"), Catch::Contains("unexpected"));
}

TEST_CASE("a scene's parameters move every value that depends on them", "[scenarios][parameters]") {
  json doc = palpable::read_json_file(std::string(PALPABLE_SOURCE_DIR) +
                                      "/scenarios/block_on_ramp_decelerating.json");
  for (double angle : {20.0, 30.0}) {
    CAPTURE(angle);
    palpable::apply_override(doc, "/parameters/angle_deg=" + std::to_string(angle));
    palpable::apply_override(doc, "/parameters/mu=0.8");
    const palpable::Scene scene = palpable::scene_from_json(doc, "ramp.json");
    const double th = angle * 3.14159265358979323846 / 180.0;
    // Ramp and block turned by the angle; the block launched down the slope; the pair's friction.
    const palpable::Quat q = scene.world.bodies[1].state.q_WM;
    CHECK(2.0 * std::atan2(q.y(), q.w()) == Approx(th).epsilon(1e-14));
    CHECK(scene.world.bodies[1].state.v_W.x() == Approx(2.0 * std::cos(th)).epsilon(1e-14));
    CHECK(scene.world.pair_materials[0].material.friction == 0.8);
    // The reference follows: its derived angle and friction are the new ones.
    CHECK(scene.reference["angle_deg"].get<double>() == Approx(angle).epsilon(1e-12));
    CHECK(scene.reference["friction"] == 0.8);
  }
  // Errors name the value's pointer and the expression.
  json bad = doc;
  bad["bodies"][1]["mass"] = "=mass_kg * 2";
  CHECK_THROWS_WITH(palpable::scene_from_json(bad, "ramp.json"),
                    Catch::Contains("ramp.json:/bodies/1/mass") &&
                        Catch::Contains("unknown name \"mass_kg\""));
  bad = doc;
  bad["parameters"]["pi"] = 3;
  CHECK_THROWS_AS(palpable::scene_from_json(bad, "ramp.json"), InputError);
}

TEST_CASE("an expression nested too deep is bad input, not a stack overflow",
          "[scenarios][parameters][hostile]") {
  const std::map<std::string, double> names;
  const int n = 100000;
  const std::string parens = std::string(n, '(') + "1" + std::string(n, ')');
  const std::string signs = std::string(n, '-') + "1";
  std::string powers;
  for (int i = 0; i < n; ++i) powers += "1^";
  powers += "1";
  std::string calls;
  for (int i = 0; i < n; ++i) calls += "abs(";
  calls += "1" + std::string(n, ')');
  for (const std::string& text : {parens, signs, powers, calls}) {
    CHECK_THROWS_WITH(
        evaluate_expression(text, names, "s.json:/end_time"),
        Catch::Contains("s.json:/end_time") && Catch::Contains("nested deeper than 256 levels"));
  }
  // 256 levels still evaluate; the message quotes at most 60 characters of the text.
  CHECK(evaluate_expression(std::string(256, '(') + "2" + std::string(256, ')'), names, "x") ==
        2.0);
  try {
    evaluate_expression(parens, names, "x");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).size() < 200);
  }
  // A long flat expression (1+1+...+1, 2 MB) is read in linear time.
  std::string sum = "1";
  for (int i = 0; i < 1000000; ++i) sum += "+1";
  CHECK(evaluate_expression(sum, names, "x") == 1000001.0);
}
