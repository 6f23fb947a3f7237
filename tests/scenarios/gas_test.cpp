// Cost follows interaction, not scene size (issue 7), on the code-built scenes of tools/lib/gas:
// idle bodies far away change no event and no query of the run, and add no broad-phase test;
// frictionless contacts are closed form (no Runge-Kutta step); sphere pairs are checked once per
// collision, at their exact time of impact.
#include "scenarios/gas.hpp"

#include "core/mass_properties.hpp"
#include "core/shape.hpp"
#include "scheduler/simulation.hpp"

#include <catch2/catch.hpp>

#include <random>

using namespace palpable;

namespace {

struct Recorder : SimulationObserver {
  std::vector<CollisionRecord> collisions;
  void on_collision(const CollisionRecord& r) override { collisions.push_back(r); }
};

struct Run {
  SimulationStats at_start;  // after construction
  SimulationStats at_end;
  std::vector<CollisionRecord> collisions;
};

Run run(const World& world, double t_end) {
  Simulation sim(world, SimulationOptions{});
  Run r;
  r.at_start = sim.stats();
  Recorder recorder;
  sim.run_until(t_end, &recorder);
  r.at_end = sim.stats();
  r.collisions = std::move(recorder.collisions);
  return r;
}

// Every counter of the event loop is the same. The broad phase's box tests during the run may only
// fall: on a level it shares with idle bodies the grid enumerates cells (finding none of the far
// idle bodies) where, with fewer bodies on that level, it would scan the level's short list.
void require_same_work(const Run& a, const Run& b) {
  CHECK(a.at_end.events == b.at_end.events);
  CHECK(a.at_end.pair_checks == b.at_end.pair_checks);
  CHECK(a.at_end.bound_queries == b.at_end.bound_queries);
  CHECK(a.at_end.horizon_refreshes == b.at_end.horizon_refreshes);
  CHECK(a.at_end.collisions == b.at_end.collisions);
  CHECK(a.at_end.microcollisions == b.at_end.microcollisions);
  CHECK(a.at_end.rescheduled == b.at_end.rescheduled);
  CHECK(a.at_end.exact_bounds == b.at_end.exact_bounds);
  CHECK(a.at_end.floored_bounds == b.at_end.floored_bounds);
  CHECK(a.at_end.feature_steps == b.at_end.feature_steps);
  CHECK(a.at_end.integration_steps == b.at_end.integration_steps);
  CHECK(a.at_end.pairs_created == b.at_end.pairs_created);
  CHECK(a.at_end.max_pairs == b.at_end.max_pairs);
  CHECK(b.at_end.box_tests - b.at_start.box_tests <= a.at_end.box_tests - a.at_start.box_tests);
  REQUIRE(a.collisions.size() == b.collisions.size());
  for (std::size_t i = 0; i < a.collisions.size(); ++i) {
    CAPTURE(i);
    REQUIRE(a.collisions[i].t == b.collisions[i].t);
    REQUIRE(a.collisions[i].a == b.collisions[i].a);
    REQUIRE(a.collisions[i].b == b.collisions[i].b);
    REQUIRE(a.collisions[i].impulse_W == b.collisions[i].impulse_W);
  }
}

}  // namespace

TEST_CASE("10,000 idle bodies far from a gas change no event or query, add no box test",
          "[tools][gas][cost]") {
  GasOptions options;
  options.count = 64;
  options.walls = GasWalls::kSlabs;
  const World gas = make_sphere_gas(options);
  const Vec3 far_W(3.0 * gas_container_side(options) + 100.0, 0.0, 0.0);
  const Run base = run(gas, 5.0);
  REQUIRE(base.at_end.collisions > 100);
  for (IdleKind kind : {IdleKind::kRestingSpheres, IdleKind::kFixedBoxes}) {
    CAPTURE(static_cast<int>(kind));
    World with_idle = gas;
    add_idle_bodies(with_idle, 10000, kind, far_W, 0.1);
    REQUIRE(with_idle.bodies.size() == gas.bodies.size() + 10000);
    require_same_work(base, run(with_idle, 5.0));
  }
}

TEST_CASE("10,000 fixed cubes far from balls bouncing on a ground change nothing of the run",
          "[tools][gas][cost]") {
  for (const ContactModel model : {ContactModel::kMicrocollisions, ContactModel::kPersistent}) {
    CAPTURE(std::string(to_string(model)));
    World world;
    world.settings.contact_model = model;
    Body ground;
    ground.name = "ground";
    ground.motion = MotionKind::kFixed;
    ground.shape = std::make_shared<const Shape>(make_halfspace(Vec3::UnitZ(), 0.0));
    ground.mass = infinite_mass_properties();
    world.add(ground);
    auto ball = std::make_shared<const Shape>(make_sphere(0.1));
    for (int i = 0; i < 5; ++i) {
      Body b;
      b.name = "ball_" + std::to_string(i);
      b.shape = ball;
      b.mass = mass_properties_from_mass(*ball, 1.0);
      b.state.x_W = Vec3(0.5 * i, 0.0, 0.3 + 0.2 * i);
      b.state.v_W = Vec3(0.1 * i, 0.2, 0.0);
      world.add(std::move(b));
    }
    World with_idle = world;
    // Above the ground (inside its infinite box), but fixed: never paired with it.
    add_idle_bodies(with_idle, 10000, IdleKind::kFixedBoxes, Vec3(1000.0, 1000.0, 1.0), 0.1);
    const Run base = run(world, 3.0);
    // They come to rest: in trains of microcollisions, or held.
    if (model == ContactModel::kMicrocollisions) {
      REQUIRE(base.at_end.microcollisions > 100);
    } else {
      REQUIRE(base.at_end.holds >= 5);
    }
    const Run idle = run(with_idle, 3.0);
    require_same_work(base, idle);
    CHECK(idle.at_end.holds == base.at_end.holds);
    CHECK(idle.at_end.mode_changes == base.at_end.mode_changes);
    CHECK(idle.at_end.island_plans == base.at_end.island_plans);
  }
}

TEST_CASE("a frictionless gas resolves every contact in closed form, with no Runge-Kutta step",
          "[tools][gas][cost]") {
  // Tumbling cubes in zero gravity: with friction their slip directions turn and are integrated;
  // without, every collision is the closed-form impulse along K e_z.
  GasOptions options;
  options.count = 27;
  options.walls = GasWalls::kSlabs;
  auto cube = std::make_shared<const Shape>(ConvexPolyhedron::box(Vec3::Constant(0.04)));
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (double mu : {0.0, 0.5}) {
    CAPTURE(mu);
    options.friction = mu;
    World world = make_sphere_gas(options);
    for (Body& b : world.bodies) {
      if (!b.is_dynamic()) continue;
      b.shape = cube;
      b.mass = mass_properties_from_mass(*cube, 1.0);
      b.state.w_W = 5.0 * Vec3(normal(rng), normal(rng), normal(rng));
    }
    const Run r = run(world, 2.0);
    REQUIRE(r.at_end.collisions > 50);
    CHECK(r.at_end.impulse_failures == 0);
    if (mu == 0.0) {
      CHECK(r.at_end.integration_steps == 0);
    } else {
      CHECK(r.at_end.integration_steps > 0);
    }
  }
}

TEST_CASE("in a sphere gas every pair check is a collision at an exact time of impact",
          "[tools][gas][cost]") {
  // Zero gravity, six fixed halfspaces: sphere-sphere and sphere-plane times of impact are closed
  // form, so no bound is conservative or floored and no check is wasted: each pair event finds
  // its pair within the envelope and approaching, and either collides or, still apart, moves on
  // to the exact instant its gap closes (an approach check; one per collision, and a few more
  // whose approach another collision turned away before contact). (A pair
  // may collide twice at one instant when a third sphere hits one of them at that instant:
  // counted in retries, still one check each.)
  GasOptions options;
  options.count = 125;
  const Run r = run(make_sphere_gas(options), 5.0);
  const SimulationStats& s = r.at_end;
  CAPTURE(s.pair_checks, s.collisions, s.microcollisions, s.bound_queries, s.exact_bounds,
          s.retries, s.approach_checks);
  REQUIRE(s.collisions > 1000);
  CHECK(s.floored_bounds == 0);
  CHECK(s.pair_checks == s.collisions + s.microcollisions + s.approach_checks);
  CHECK(s.integration_steps == 0);
}

TEST_CASE("the broad phase's work per refresh does not grow with the number of spheres",
          "[tools][gas][cost]") {
  // 1000 and 8000 spheres at the same density, in six halfspaces: box tests per broad-phase
  // refresh (two per collision, one per horizon) follow the neighbours, so they stay about
  // constant (the larger gas has fewer spheres near the walls, hence somewhat more neighbours
  // each: ~1.25 x measured). A brute-force broad phase would test every body: x 8.
  double per_refresh[2];
  int k = 0;
  for (int n : {1000, 8000}) {
    GasOptions options;
    options.count = n;
    Simulation sim(make_sphere_gas(options), SimulationOptions{});
    sim.run_until(0.3, nullptr);
    const SimulationStats a = sim.stats();
    sim.run_until(0.45, nullptr);
    const SimulationStats& b = sim.stats();
    const double refreshes = 2.0 * static_cast<double>(b.collisions - a.collisions) +
                             static_cast<double>(b.horizon_refreshes - a.horizon_refreshes);
    per_refresh[k++] = static_cast<double>(b.box_tests - a.box_tests) / refreshes;
    CAPTURE(n, refreshes, b.box_tests - a.box_tests);
    REQUIRE(refreshes > 100);
  }
  CAPTURE(per_refresh[0], per_refresh[1]);
  CHECK(per_refresh[1] <= 1.5 * per_refresh[0]);
}

TEST_CASE("the sweep limit cuts a gas's pairs, not its collisions", "[tools][gas][cost]") {
  // Settings::broad_phase_max_sweep shortens the horizon of a body among moving bodies to two
  // reaches of travel: smaller boxes, fewer pairs, fewer re-bounds per collision. The broad phase
  // decides only which pairs are bounded, never when a bounded pair collides (sphere pairs at their
  // exact time of impact), so the collisions are the same ones; their times agree to rounding
  // (bounds are computed from states extrapolated at other instants) until the gas's chaos
  // amplifies that, hence the comparison over the first collisions only.
  GasOptions options;
  options.count = 125;
  World limited = make_sphere_gas(options);
  World unlimited = limited;
  REQUIRE(limited.settings.broad_phase_max_sweep == 2.0);
  unlimited.settings.broad_phase_max_sweep = 1e9;
  const Run a = run(limited, 3.0);
  const Run b = run(unlimited, 3.0);
  CAPTURE(a.at_end.max_pairs, b.at_end.max_pairs, a.at_end.bound_queries, b.at_end.bound_queries,
          a.at_end.collisions, b.at_end.collisions);
  REQUIRE(a.collisions.size() > 300);
  REQUIRE(b.collisions.size() > 300);
  for (std::size_t i = 0; i < 300; ++i) {
    CAPTURE(i);
    REQUIRE(a.collisions[i].a == b.collisions[i].a);
    REQUIRE(a.collisions[i].b == b.collisions[i].b);
    REQUIRE(std::abs(a.collisions[i].t - b.collisions[i].t) <= 1e-12);
  }
  CHECK(2 * a.at_end.max_pairs < b.at_end.max_pairs);
  const auto per_collision = [](const Run& r) {
    return static_cast<double>(r.at_end.bound_queries) / static_cast<double>(r.at_end.collisions);
  };
  CHECK(2.0 * per_collision(a) < per_collision(b));
}

TEST_CASE("a body with no moving body near keeps the whole horizon", "[tools][gas][cost]") {
  // A sphere at 10 m/s crossing 5 m of empty space to a fixed wall and back: shortening its
  // horizon would only add refreshes, so the sweep limit leaves it alone. Two such spheres, one
  // 0.3 m behind the other, are among moving bodies (their short boxes overlap): their horizons
  // are cut to two reaches (0.2 m) of travel, 0.02 s instead of 0.25 s.
  for (int spheres : {1, 2}) {
    CAPTURE(spheres);
    World world;
    world.gravity_W = Vec3::Zero();
    Body wall;
    wall.name = "wall";
    wall.motion = MotionKind::kFixed;
    wall.shape = std::make_shared<const Shape>(make_halfspace(-Vec3::UnitX(), -5.0));
    wall.mass = infinite_mass_properties();
    world.add(wall);
    auto ball = std::make_shared<const Shape>(make_sphere(0.1));
    for (int i = 0; i < spheres; ++i) {
      Body b;
      b.name = "ball_" + std::to_string(i);
      b.shape = ball;
      b.mass = mass_properties_from_mass(*ball, 1.0);
      b.state.x_W = Vec3(-0.3 * i, 0.0, 0.0);
      b.state.v_W = Vec3(10.0, 0.0, 0.0);
      world.add(std::move(b));
    }
    std::uint64_t refreshes[2];
    for (int limited = 0; limited < 2; ++limited) {
      world.settings.broad_phase_max_sweep = limited ? 2.0 : 1e9;
      const Run r = run(world, 1.0);
      REQUIRE(r.at_end.collisions >= static_cast<std::uint64_t>(spheres));  // each hits the wall
      refreshes[limited] = r.at_end.horizon_refreshes;
    }
    CAPTURE(refreshes[0], refreshes[1]);
    if (spheres == 1) {
      CHECK(refreshes[1] == refreshes[0]);
    } else {
      CHECK(refreshes[1] >= 10 * refreshes[0]);
    }
  }
}
