// `palpable compare`'s code path: a trace written to CSV, the reference spec assembled from the
// command line or a scene, thresholds, and bad input named.
#include "tools/lib/compare.hpp"
#include "tools/lib/run_scene.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>

using nlohmann::json;
using palpable::BodyState;
using palpable::Vec3;
using palpable::tools::compare_trace;
using palpable::tools::CompareOptions;

namespace {
// A solid ball launched at 3 m/s without spin on a plane with mu = 0.2 (closed form).
void write_slide_trace(const std::string& path) {
  const double mu = 0.2, g = 9.81, v0 = 3.0, t_roll = 2.0 * v0 / (7.0 * mu * g);
  std::ofstream out(path);
  out << palpable::kTraceHeader << "\n";
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.01 * k, tc = std::min(t, t_roll);
    const double v = v0 - mu * g * tc;
    BodyState ball, ground;
    ball.x_W = Vec3(v0 * tc - 0.5 * mu * g * tc * tc + v * (t - tc), 0.0, 0.1);
    ball.v_W = Vec3(v, 0.0, 0.0);
    palpable::write_trace_rows(out, t, {"ground", "ball"}, {ground, ball});
  }
}
}  // namespace

TEST_CASE("compare: figures from a trace file and --param values", "[tools][compare]") {
  const std::string path = "compare_test_slide.csv";
  write_slide_trace(path);
  CompareOptions options;
  options.trace_path = path;
  options.reference.type = "slide_to_roll";
  options.reference.params = {"body=ball", "friction=0.2", "gravity=9.81", "radius=0.1"};
  options.max = {"roll_time_error_s=1e-9", "final_speed_rel_error=1e-9"};
  auto result = compare_trace(options);
  INFO(result.figures.dump(2));
  CHECK(result.spec["body"] == "ball");
  CHECK(result.spec["friction"] == 0.2);
  CHECK(result.exceeded.empty());
  CHECK(result.figures["final_speed_closed_form"].get<double>() == Approx(15.0 / 7.0));
  CHECK(palpable::tools::compare_text(result).find("roll_time_error_s") != std::string::npos);

  // The same trace against a wrong friction: the thresholds report it (the final-speed fit
  // then starts inside the sliding phase, so it is off too).
  options.reference.params.push_back("friction=0.25");
  auto wrong = compare_trace(options);
  INFO(wrong.figures.dump(2));
  REQUIRE(!wrong.exceeded.empty());
  CHECK(wrong.exceeded[0].rfind("roll_time_error_s = ", 0) == 0);
  std::remove(path.c_str());
}

TEST_CASE("compare: the scene's reference, overridden by --param", "[tools][compare]") {
  palpable::tools::ReferenceOptions options;
  options.scene_path = std::string(PALPABLE_SOURCE_DIR) + "/scenarios/ball_on_platter.json";
  json spec = palpable::tools::reference_spec(options);
  CHECK(spec["type"] == "turntable");
  options.params = {"k=0.6666666666666666", "axis=[0,0,1]"};
  spec = palpable::tools::reference_spec(options);
  CHECK(spec["type"] == "turntable");
  CHECK(spec["k"] == 0.6666666666666666);
  CHECK(spec["axis"] == json::array({0, 0, 1}));
}

TEST_CASE("compare: bad input names the option", "[tools][compare]") {
  const std::string path = "compare_test_bad.csv";
  write_slide_trace(path);
  CompareOptions options;
  options.trace_path = path;
  CHECK_THROWS_WITH(compare_trace(options), Catch::Contains("--reference"));
  options.reference.type = "slide_to_roll";
  options.reference.params = {"body=ball", "friction=0.2", "gravity=9.81"};
  CHECK_THROWS_WITH(compare_trace(options), Catch::Contains("radius"));
  options.reference.params.push_back("radius");
  CHECK_THROWS_WITH(compare_trace(options), Catch::Contains("--param radius"));
  options.reference.params.back() = "radius=0.1";
  options.max = {"no_such_figure=1"};
  CHECK_THROWS_WITH(compare_trace(options), Catch::Contains("--max no_such_figure"));
  options.max = {"roll_time_error_s=-1"};
  CHECK_THROWS_WITH(compare_trace(options), Catch::Contains("--max"));
  options.max.clear();
  options.events_path = "compare_test_no_such_events.csv";
  CHECK_THROWS_WITH(compare_trace(options), Catch::Contains("compare_test_no_such_events.csv"));
  palpable::tools::ReferenceOptions no_reference;
  no_reference.scene_path = path;  // not JSON
  CHECK_THROWS_AS(palpable::tools::reference_spec(no_reference), palpable::InputError);
  std::remove(path.c_str());
}

TEST_CASE("compare --max fails on a figure whose closed form does not apply",
          "[tools][compare][reference]") {
  // A run whose block slid off its ramp (mu 0.6: it would stop only at 10.2 s, after 3 s): the
  // incline's figures are null, and a limit on them fails instead of passing a wrong number.
  palpable::tools::RunOptions run;
  run.scene_path = std::string(PALPABLE_SOURCE_DIR) + "/scenarios/block_on_ramp_decelerating.json";
  // The microcollision model's run, which leaves the ramp: pinned, since the default may be the
  // other.
  run.overrides = {"/settings/contact_model=microcollisions", "/materials/pairs/0/friction=0.6"};
  run.trace_path = "compare_test_off_ramp.csv";
  palpable::tools::run_scene(run);
  CompareOptions options;
  options.trace_path = run.trace_path;
  options.reference.scene_path = run.scene_path;
  options.reference.params = {"friction=0.6"};
  options.max = {"stop_time_error_s=1"};
  const auto result = compare_trace(options);
  REQUIRE(result.exceeded.size() == 1);
  CHECK(result.exceeded[0].find("stop_time_error_s is null") != std::string::npos);
  CHECK(result.exceeded[0].find("left its support") != std::string::npos);
  std::remove(run.trace_path.c_str());
}
