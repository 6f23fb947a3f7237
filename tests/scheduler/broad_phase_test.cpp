// The hierarchical hash grid against the brute-force oracle (every stored box tested): random
// boxes of sizes spread over six decades, moved and removed, plus infinite, half-infinite,
// degenerate and far-out boxes; the cost of a query following the neighbours, not the size; and
// in the event loop, no pair of two fixed or kinematic bodies ever made or even compared.
#include "scheduler/broad_phase.hpp"

#include "core/mass_properties.hpp"
#include "core/shape.hpp"
#include "scheduler/simulation.hpp"

#include <catch2/catch.hpp>

#include <random>

using namespace palpable;

namespace {

Aabb box_at(const Vec3& centre, const Vec3& half) {
  return Aabb{centre - half, centre + half};
}

std::vector<std::uint32_t> brute_force(const std::vector<Aabb>& boxes,
                                       const std::vector<bool>& present, const Aabb& query,
                                       std::uint32_t self) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < boxes.size(); ++i) {
    if (present[i] && i != self && boxes[i].overlaps(query)) out.push_back(i);
  }
  return out;
}

}  // namespace

TEST_CASE("broad phase: queries equal the brute-force oracle on random boxes",
          "[scheduler][broad_phase]") {
  const std::uint64_t seed = 20261121;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto random_box = [&]() -> Aabb {
    const double kind = unit(rng);
    const Vec3 centre = (Vec3(unit(rng), unit(rng), unit(rng)) - Vec3::Constant(0.5)) * 20.0;
    if (kind < 0.03) {  // a halfspace-like box: infinite on some sides
      Aabb b{Vec3::Constant(-kInfinity), Vec3::Constant(kInfinity)};
      b.max_W.z() = centre.z();
      return b;
    }
    if (kind < 0.05) return box_at(centre, Vec3::Zero());                 // a point
    if (kind < 0.07) return box_at(centre * 1e12, Vec3::Constant(1e-3));  // far out
    // Sizes log-uniform over 1e-4 .. 1e2 m, each axis its own.
    const auto size = [&] { return std::pow(10.0, -4.0 + 6.0 * unit(rng)); };
    return box_at(centre, Vec3(size(), size(), size()));
  };
  const std::uint32_t n = 600;
  BroadPhase grid;
  std::vector<Aabb> boxes(n);
  std::vector<bool> present(n, false);
  for (std::uint32_t i = 0; i < n; ++i) {
    boxes[i] = random_box();
    present[i] = true;
    grid.set(i, boxes[i]);
  }
  std::uniform_int_distribution<std::uint32_t> pick(0, n - 1);
  for (int step = 0; step < 4000; ++step) {
    CAPTURE(seed, step);
    const std::uint32_t id = pick(rng);
    const double action = unit(rng);
    if (action < 0.1 && present[id]) {
      grid.remove(id);
      present[id] = false;
    } else if (action < 0.6) {
      boxes[id] = random_box();
      present[id] = true;
      grid.set(id, boxes[id]);
    }
    REQUIRE(grid.size() ==
            static_cast<std::size_t>(std::count(present.begin(), present.end(), true)));
    // Query with a stored box (as the scheduler does) and with a fresh one.
    for (const Aabb& query : {boxes[id], random_box()}) {
      std::vector<std::uint32_t> found = {12345u};  // results are appended after this
      grid.query(query, id, found);
      std::vector<std::uint32_t> expected = brute_force(boxes, present, query, id);
      expected.insert(expected.begin(), 12345u);
      REQUIRE(found == expected);
    }
  }
}

TEST_CASE("broad phase: NaN and empty boxes overlap nothing, as Aabb::overlaps says",
          "[scheduler][broad_phase]") {
  BroadPhase grid;
  grid.set(0, box_at(Vec3::Zero(), Vec3::Constant(1.0)));
  grid.set(1, Aabb{});  // empty: min = +inf, max = -inf
  Aabb nan_box = box_at(Vec3::Zero(), Vec3::Constant(1.0));
  nan_box.min_W.x() = std::nan("");
  grid.set(2, nan_box);
  std::vector<std::uint32_t> found;
  grid.query(box_at(Vec3::Zero(), Vec3::Constant(0.5)), 99, found);
  CHECK(found == std::vector<std::uint32_t>{0});
  found.clear();
  grid.query(nan_box, 99, found);
  CHECK(found.empty());
}

TEST_CASE("broad phase: a query tests its neighbours, not every box stored",
          "[scheduler][broad_phase]") {
  // 20 x 20 x 20 unit boxes on a lattice of spacing 3, plus one halfspace: a query around one
  // box meets that box, its cells' neighbours and the halfspace - never the other 7999 boxes.
  BroadPhase grid;
  std::uint32_t id = 0;
  for (int i = 0; i < 20; ++i) {
    for (int j = 0; j < 20; ++j) {
      for (int k = 0; k < 20; ++k)
        grid.set(id++, box_at(Vec3(3.0 * i, 3.0 * j, 3.0 * k), Vec3::Constant(0.5)));
    }
  }
  Aabb ground{Vec3::Constant(-kInfinity), Vec3::Constant(kInfinity)};
  ground.max_W.z() = 0.0;
  grid.set(id, ground);
  const std::uint64_t before = grid.box_tests();
  std::vector<std::uint32_t> found;
  grid.query(box_at(Vec3(30.0, 30.0, 0.0), Vec3::Constant(0.6)), 100000, found);
  CHECK(found == std::vector<std::uint32_t>{10 * 400 + 10 * 20 + 0, id});
  CHECK(grid.box_tests() - before <= 10);
}

TEST_CASE("no pair of two fixed or kinematic bodies is ever compared, created or checked",
          "[scheduler][broad_phase]") {
  // 300 fixed cubes and 100 kinematic bodies (spinning cubes, translating spheres whose horizons
  // expire) piled into one metre, overlapping each other, on a fixed ground and above a kinematic
  // halfspace spinning about its normal. Alone they cost nothing: no pair, no query, no box test
  // (the non-dynamic bodies look only among the dynamic ones). With dynamic balls dropped onto
  // them, every pair created involves a ball: Simulation checks that on each creation
  // (InvariantError otherwise).
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  World world;
  auto add_static = [&](MotionKind motion, std::shared_ptr<const Shape> shape, const Vec3& x_W,
                        const KinematicMotion& k = {}) {
    Body b;
    b.name = "static_" + std::to_string(world.bodies.size());
    b.motion = motion;
    b.shape = std::move(shape);
    b.mass = infinite_mass_properties();
    b.kinematic = k;
    b.state.x_W = x_W;
    world.add(std::move(b));
  };
  add_static(MotionKind::kFixed, std::make_shared<const Shape>(make_halfspace(Vec3::UnitZ(), 0.0)),
             Vec3::Zero());
  KinematicMotion platter;
  platter.angular_velocity_W = Vec3(0.0, 0.0, 2.0);
  add_static(MotionKind::kKinematic,
             std::make_shared<const Shape>(make_halfspace(Vec3::UnitZ(), -0.5)), Vec3::Zero(),
             platter);
  auto cube = std::make_shared<const Shape>(ConvexPolyhedron::box(Vec3::Constant(0.15)));
  auto ball = std::make_shared<const Shape>(make_sphere(0.1));
  const auto in_pile = [&] { return Vec3(unit(rng), unit(rng), 0.2 + 0.6 * unit(rng)); };
  for (int i = 0; i < 300; ++i) add_static(MotionKind::kFixed, cube, in_pile());
  for (int i = 0; i < 50; ++i) {
    KinematicMotion spin;
    spin.point_W = in_pile();
    spin.angular_velocity_W = Vec3(unit(rng), unit(rng), unit(rng)) * 3.0;
    add_static(MotionKind::kKinematic, cube, spin.point_W, spin);
  }
  for (int i = 0; i < 50; ++i) {
    KinematicMotion slide;
    slide.point_W = in_pile();
    slide.velocity_W = Vec3(unit(rng) - 0.5, unit(rng) - 0.5, 0.0) * 0.2;
    add_static(MotionKind::kKinematic, ball, slide.point_W, slide);
  }
  {
    Simulation sim(world, SimulationOptions{});
    sim.run_until(2.0, nullptr);
    const SimulationStats& s = sim.stats();
    CHECK(s.horizon_refreshes > 0);
    CHECK(s.events == s.horizon_refreshes);
    CHECK(s.box_tests == 0);
    CHECK(s.pairs_created == 0);
    CHECK(s.pair_checks == 0);
    CHECK(s.bound_queries == 0);
  }
  for (int i = 0; i < 10; ++i) {
    Body b;
    b.name = "ball_" + std::to_string(i);
    b.shape = ball;
    b.mass = mass_properties_from_mass(*ball, 1.0);
    b.state.x_W = Vec3(0.1 * i, 0.5, 1.6 + 0.25 * i);
    world.add(std::move(b));
  }
  Simulation sim(world, SimulationOptions{});
  REQUIRE_NOTHROW(sim.run_until(0.8, nullptr));
  CHECK(sim.stats().pairs_created > 10);
  CHECK(sim.stats().collisions + sim.stats().microcollisions > 0);
}
