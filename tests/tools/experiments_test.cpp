// The paper's experiments as shipped scenes, run through `palpable run`'s code path, against what
// must physically hold: no penetration, nobody leaves the table or dish, no energy created
// beyond what the microcollision floor lends (each resting body re-lifted by up to the envelope).
#include "core/ballistic.hpp"
#include "tools/lib/run_scene.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using palpable::BodyState;
using palpable::Vec3;
using palpable::tools::RunOptions;
using palpable::tools::RunResult;

namespace {

RunResult run(const std::string& name) {
  RunOptions options;
  options.scene_path = std::string(PALPABLE_SOURCE_DIR) + "/scenarios/" + name;
  return palpable::tools::run_scene(options);
}

// Kinetic plus potential energy of the dynamic bodies in sample k.
double mechanical_energy(const RunResult& r, std::size_t k) {
  const auto& world = r.scene.world;
  double e = 0.0;
  for (std::size_t i = 0; i < world.bodies.size(); ++i) {
    const auto& body = world.bodies[i];
    if (!body.is_dynamic()) continue;
    const BodyState& s = r.trace.samples[k][i];
    e += 0.5 * body.mass.mass * s.v_W.squaredNorm() + palpable::rotational_energy(body.mass, s) -
         body.mass.mass * world.gravity_W.dot(s.x_W);
  }
  return e;
}

// What the microcollision floor may add: every dynamic body lifted by up to two envelopes.
double floor_allowance(const RunResult& r) {
  double a = 0.0;
  for (const auto& body : r.scene.world.bodies) {
    if (body.is_dynamic()) {
      a +=
          body.mass.mass * r.scene.world.gravity_W.norm() * 2.0 * r.scene.world.settings.envelope_m;
    }
  }
  return a;
}

void check_common(const RunResult& r) {
  CHECK(r.stats.penetrations == 0);
  CHECK(r.stats.retry_limit_hits == 0);
  CHECK(r.stats.impulse_failures == 0);
  CHECK(r.stats.distance_failures == 0);
  const double e0 = mechanical_energy(r, 0);
  const double allowance = floor_allowance(r);
  double worst = -1e300;
  for (std::size_t k = 0; k < r.trace.samples.size(); ++k) {
    worst = std::max(worst, mechanical_energy(r, k) - e0);
  }
  INFO("initial energy " << e0 << " J, largest gain " << worst << " J, allowance " << allowance);
  CHECK(worst <= allowance);
}

}  // namespace

TEST_CASE("chain of balls: the far ball leaves, everyone stays on the table",
          "[tools][experiments]") {
  RunResult r = run("chain_of_balls.json");
  check_common(r);
  const auto& world = r.scene.world;
  const std::size_t last = world.find_body("ball7").index;
  double fastest_last = 0.0;
  for (const auto& sample : r.trace.samples) {
    fastest_last = std::max(fastest_last, sample[last].v_W.x());
    for (std::size_t i = 1; i < world.bodies.size(); ++i) {
      const double radius = 0.0125;
      // Never through the table. Balls may hop: ball-ball friction on spinning balls has a
      // vertical component (a fraction of a millimetre here).
      CHECK(sample[i].x_W.z() >= radius);
      CHECK(sample[i].x_W.z() <= 2 * radius);
    }
  }
  // Momentum passes down the chain: the far ball moves off at most of the striker's speed.
  CHECK(fastest_last > 0.5);
}

TEST_CASE("pool break: the rack scatters, no ball leaves the table, no energy created",
          "[tools][experiments]") {
  RunResult r = run("pool_break.json");
  check_common(r);
  const auto& world = r.scene.world;
  const double radius = 0.028575, half_length = 1.27, half_width = 0.635;
  int scattered = 0;
  for (std::size_t i = 2; i < world.bodies.size(); ++i) {
    for (const auto& sample : r.trace.samples) {
      const Vec3& x = sample[i].x_W;
      CHECK(std::abs(x.x()) <= half_length - radius + world.settings.envelope_m);
      CHECK(std::abs(x.y()) <= half_width - radius + world.settings.envelope_m);
      // Never through the cloth; hops off spinning balls' friction stay below a ball radius.
      CHECK(x.z() >= radius);
      CHECK(x.z() <= 2 * radius);
    }
    if (world.bodies[i].name != "cue" &&
        (r.trace.samples.back()[i].x_W - r.trace.samples.front()[i].x_W).norm() > 0.05) {
      ++scattered;
    }
  }
  CHECK(scattered >= 10);
  CHECK(r.stats.collisions > 15);
}

TEST_CASE("balls in a dish: they land in it and stay in it", "[tools][experiments]") {
  RunResult r = run("balls_in_dish.json");
  check_common(r);
  const auto& world = r.scene.world;
  const double rim_radius = 0.08 + 0.2 * std::cos(25.0 * M_PI / 180.0);
  for (std::size_t i = 1; i < world.bodies.size(); ++i) {
    const BodyState& end = r.trace.samples.back()[i];
    CHECK(std::hypot(end.x_W.x(), end.x_W.y()) < rim_radius);
    CHECK(end.x_W.z() >= 0.02);
    CHECK(end.x_W.z() < 0.1);
  }
}
