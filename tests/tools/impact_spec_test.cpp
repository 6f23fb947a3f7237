// Tests of the `palpable impact` spec (tools/lib/impact_spec.hpp): resolving the DESIGN.md test
// vectors from JSON in both forms, and bad specs answered with an InputError that names the JSON
// path, the value found and what was expected.
#include "tools/lib/impact_spec.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace palpable::tools {
namespace {

using nlohmann::json;

json rod_spec() {
  return json::parse(R"({"K": [[2.5, 0, -1.5], [0, 4, 0], [-1.5, 0, 2.5]], "u0": [0.5, 0, -1],
                         "friction": 0.5, "restitution": 0.5, "law": "poisson"})");
}

json sphere_spec() {
  return json::parse(R"({"bodies": [
      {"mass": 1, "inertia": [[0.004, 0, 0], [0, 0.004, 0], [0, 0, 0.004]],
       "velocity": [3, 0, -2], "offset": [0, 0, -0.1]},
      {"fixed": true, "offset": [0, 0, 0]}],
    "normal": [0, 0, 1], "friction": 0.1, "restitution": 0.6, "law": "stronge"})");
}

// The InputError a bad spec raises: where it points and its message.
struct Rejection {
  std::string where, message;
};

Rejection rejection(const json& spec) {
  try {
    parse_impact_spec(spec);
  } catch (const InputError& e) {
    return {e.where(), e.what()};
  }
  FAIL("spec accepted: " << spec.dump());
  return {};
}

TEST_CASE("impact spec in the contact frame: the rod of DESIGN.md", "[tools][impact]") {
  const json out = resolve_impact(parse_impact_spec(rod_spec()));
  CHECK(out["status"] == "ok");
  // mu = 0.5, Poisson: p = (10/77, 0, 48/77), u' = (-17/154, 0, 4/11).
  CHECK(out["impulse"][0].get<double>() == Approx(10.0 / 77.0).epsilon(1e-12));
  CHECK(out["impulse"][2].get<double>() == Approx(48.0 / 77.0).epsilon(1e-12));
  CHECK(out["u_final"][0].get<double>() == Approx(-17.0 / 154.0).epsilon(1e-12));
  CHECK(out["u_final"][2].get<double>() == Approx(4.0 / 11.0).epsilon(1e-12));
  CHECK(out["phases"] == json::array({"slid", "resumed sliding in direction (-1, 0)"}));
  CHECK(out["compression_impulse"].get<double>() > 0.0);
  CHECK(out["energy_change"].get<double>() < 0.0);
  CHECK(out.contains("steps"));
}

TEST_CASE("impact spec with bodies: sphere on fixed ground", "[tools][impact]") {
  const ImpactSpec spec = parse_impact_spec(sphere_spec());
  CHECK((spec.K_c - Mat3(Vec3(3.5, 3.5, 1.0).asDiagonal())).cwiseAbs().maxCoeff() <= 1e-12);
  const json out = resolve_impact(spec);
  CHECK(out["status"] == "ok");
  CHECK(out["impulse"][2].get<double>() == Approx(3.2).epsilon(1e-12));
  CHECK(out["bodies_after"][0]["velocity"][2].get<double>() == Approx(1.2).epsilon(1e-12));
  CHECK(out["bodies_after"][0]["velocity"][0].get<double>() == Approx(2.68).epsilon(1e-12));
  CHECK(out["bodies_after"][1]["velocity"] == json::array({0.0, 0.0, 0.0}));
  // "mass": null and "mass": "inf" are the same as "fixed": true.
  json alt = sphere_spec();
  alt["bodies"][1] = json::parse(R"({"mass": null, "offset": [0, 0, 0]})");
  CHECK(resolve_impact(parse_impact_spec(alt))["impulse"] == out["impulse"]);
  alt["bodies"][1]["mass"] = "inf";
  CHECK(resolve_impact(parse_impact_spec(alt))["impulse"] == out["impulse"]);
}

TEST_CASE("impact --trajectory: u(p_z) from u0 to u_final, and recording it changes nothing",
          "[tools][impact][trajectory]") {
  // The rod (closed-form segments: slid, then resumed sliding) and a 3D contact whose slip
  // direction turns (integrated by Dormand-Prince, with dense points inside each step).
  json turning = rod_spec();
  turning["K"] = json::parse("[[2.5, 0.3, -1.5], [0.3, 4, 0.5], [-1.5, 0.5, 2.5]]");
  turning["u0"] = json::array({0.5, 0.4, -1});
  turning["friction"] = 0.3;
  turning["law"] = "stronge";
  for (const json& spec_json : {rod_spec(), turning}) {
    const ImpactSpec spec = parse_impact_spec(spec_json);
    std::vector<ImpulsePathPoint> path;
    const json with = resolve_impact(spec, &path);
    CHECK(with == resolve_impact(spec));
    REQUIRE(path.size() >= 3);
    CHECK(path.front().p_c == Vec3::Zero());
    CHECK(path.front().u_c == spec.u0_c);
    const Vec3 p_end(with["impulse"][0].get<double>(), with["impulse"][1].get<double>(),
                     with["impulse"][2].get<double>());
    CHECK((path.back().p_c - p_end).norm() <= 1e-15 * p_end.norm());
    CHECK(path.back().u_c.z() == Approx(with["u_final"][2].get<double>()).epsilon(1e-12));
    const double p_c = with["compression_impulse"].get<double>();
    bool compression_end = false;
    for (std::size_t k = 0; k < path.size(); ++k) {
      const ImpulsePathPoint& q = path[k];
      if (k > 0) CHECK(q.p_c.z() >= path[k - 1].p_c.z());
      // Coulomb along the path, and u = u0 + K p.
      CHECK(std::hypot(q.p_c.x(), q.p_c.y()) <= spec.params.friction * q.p_c.z() * (1 + 1e-6) + 1e-15);
      CHECK((q.u_c - (spec.u0_c + spec.K_c * q.p_c)).norm() <= 1e-14);
      // Compressing before maximum compression, restituting after.
      if (q.p_c.z() < p_c * (1 - 1e-9)) CHECK(q.u_c.z() < 0.0);
      if (q.p_c.z() > p_c * (1 + 1e-9)) CHECK(q.u_c.z() > 0.0);
      if (std::abs(q.p_c.z() - p_c) <= 1e-12 * p_c) compression_end = true;
    }
    CHECK(compression_end);  // the point where u_z = 0 is on the path
  }
  // The turning slip is integrated: many points, not one per segment.
  std::vector<ImpulsePathPoint> path;
  resolve_impact(parse_impact_spec(turning), &path);
  CHECK(path.size() > 20);
  std::ostringstream csv;
  write_impulse_path_csv(csv, path);
  CHECK(csv.str().rfind("p_z,p_x,p_y,u_x,u_y,u_z\n0,0,0,0.5,0.40000000000000002,-1\n", 0) == 0);
}

TEST_CASE("bad impact specs name the JSON path, the value and what was expected",
          "[tools][impact]") {
  SECTION("missing key") {
    json spec = rod_spec();
    spec.erase("law");
    const Rejection r = rejection(spec);
    CHECK(r.where == "/law");
    CHECK_THAT(r.message, Catch::Contains("missing"));
  }
  SECTION("wrong type") {
    json spec = rod_spec();
    spec["friction"] = "high";
    const Rejection r = rejection(spec);
    CHECK(r.where == "/friction");
    CHECK_THAT(r.message, Catch::Contains("\"high\"") && Catch::Contains("number"));
  }
  SECTION("NaN and infinity") {
    json spec = rod_spec();
    spec["u0"][1] = std::nan("");
    const Rejection r = rejection(spec);
    CHECK(r.where == "/u0/1");
    CHECK_THAT(r.message, Catch::Contains("finite"));
    try {
      parse_impact_spec_text(
          R"({"K": [[2.5, 0, -1.5], [0, 4, 0], [-1.5, 0, 1e999]], "u0": [0.5, 0, -1],
              "friction": 0.5, "restitution": 0.5, "law": "poisson"})",
          "spec.json");
      FAIL("accepted an infinite entry");
    } catch (const InputError& e) {
      // JSON has no NaN or infinity; a number beyond a double is a JSON error of the file.
      CHECK(std::string(e.where()) == "spec.json");
      CHECK_THAT(std::string(e.what()), Catch::Contains("1e999"));
    }
  }
  SECTION("K not positive definite, not symmetric, not 3x3") {
    json spec = rod_spec();
    spec["K"] = json::parse("[[1, 0, 2], [0, 1, 0], [2, 0, 1]]");
    Rejection r = rejection(spec);
    CHECK(r.where == "/K");
    CHECK_THAT(r.message, Catch::Contains("positive definite"));
    spec["K"] = json::parse("[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]");
    r = rejection(spec);
    CHECK(r.where == "/K");
    CHECK_THAT(r.message, Catch::Contains("symmetric"));
    spec["K"] = json::parse("[[1, 0, 0], [0, 1, 0]]");
    CHECK(rejection(spec).where == "/K");
    spec["K"] = json::parse("[[1, 0, 0], [0, 1], [0, 0, 1]]");
    CHECK(rejection(spec).where == "/K/1");
  }
  SECTION("unknown law") {
    json spec = rod_spec();
    spec["law"] = "hooke";
    const Rejection r = rejection(spec);
    CHECK(r.where == "/law");
    CHECK_THAT(r.message, Catch::Contains("hooke") && Catch::Contains("stronge"));
  }
  SECTION("unknown keys, at the top and inside a body") {
    json spec = rod_spec();
    spec["colour"] = "red";
    CHECK(rejection(spec).where == "/colour");
    spec = sphere_spec();
    spec["bodies"][0]["colour"] = "red";
    CHECK(rejection(spec).where == "/bodies/0/colour");
  }
  SECTION("bodies: bad mass, missing inertia, inertia on a fixed body, two fixed bodies") {
    json spec = sphere_spec();
    spec["bodies"][0]["mass"] = -1;
    Rejection r = rejection(spec);
    CHECK(r.where == "/bodies/0/mass");
    CHECK_THAT(r.message, Catch::Contains("-1") && Catch::Contains("positive"));
    spec = sphere_spec();
    spec["bodies"][0].erase("inertia");
    CHECK(rejection(spec).where == "/bodies/0/inertia");
    spec = sphere_spec();
    spec["bodies"][1]["inertia"] = json::parse("[[1, 0, 0], [0, 1, 0], [0, 0, 1]]");
    CHECK(rejection(spec).where == "/bodies/1/inertia");
    spec = sphere_spec();
    spec["bodies"][0] = spec["bodies"][1];
    CHECK(rejection(spec).where == "/bodies");
    spec = sphere_spec();
    spec["normal"] = json::array({0, 0, 0});
    CHECK(rejection(spec).where == "/normal");
  }
  SECTION("out-of-range material and tolerance; both forms at once; not JSON") {
    json spec = rod_spec();
    spec["restitution"] = 1.5;
    CHECK(rejection(spec).where == "/restitution");
    spec = rod_spec();
    spec["tolerance"] = 0;
    CHECK(rejection(spec).where == "/tolerance");
    spec = rod_spec();
    spec["normal"] = json::array({0, 0, 1});
    CHECK_THAT(rejection(spec).message, Catch::Contains("not both"));
    try {
      parse_impact_spec_text("{\"K\": ", "broken.json");
      FAIL("accepted broken JSON");
    } catch (const InputError& e) {
      CHECK(std::string(e.where()) == "broken.json");
    }
  }
}

}  // namespace
}  // namespace palpable::tools

TEST_CASE("an impact spec with a NUL in a key is bad input naming the file",
          "[tools][impact][hostile]") {
  // Found by fuzz_impact: the error re-thrown with the file name cut what() after the pointer,
  // and a key holding \u0000 ends what()'s C string early (std::out_of_range, exit 1).
  const std::string text = R"({"K\u0000": 1, "u0": [0.5, 0, -1]})";
  CHECK_THROWS_AS(palpable::tools::parse_impact_spec_text(text, "i.json"), palpable::InputError);
  try {
    palpable::tools::parse_impact_spec_text(text, "i.json");
  } catch (const palpable::InputError& e) {
    CHECK(e.where().rfind("i.json:/K", 0) == 0);
  }
}
