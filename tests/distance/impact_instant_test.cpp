// The instant an impact's gap closes (distance/impact_instant.hpp): a certified step never lets
// the gap below its target (brute-force distances along tumbling trajectories, fixed seed), and
// the search lands on the first instant a tumbling body reaches a plane (dense sampling of its
// lowest vertex refined by bisection), in a few queries.
#include "distance/impact_instant.hpp"

#include "core/ballistic.hpp"
#include "core/mass_properties.hpp"
#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

using namespace palpable;
using namespace palpable::test;

namespace {

const Vec3 kGravity(0.0, 0.0, -9.81);

Body dynamic(const TestShape& s, const BodyState& state) {
  Body b;
  b.name = s.name;
  b.shape = s.shape;
  b.mass = mass_properties_from_density(*s.shape, 1000.0);
  b.state = state;
  return b;
}

BodyState random_state(std::mt19937_64& rng, double half_box, double speed, double spin) {
  std::normal_distribution<double> g(0.0, 1.0);
  BodyState s;
  const Pose p = random_pose(rng, half_box);
  s.x_W = p.x_W;
  s.q_WM = p.q_WM;
  s.v_W = speed * Vec3(g(rng), g(rng), g(rng));
  s.w_W = spin * Vec3(g(rng), g(rng), g(rng));
  return s;
}

}  // namespace

TEST_CASE("a certified step keeps the gap above its target on tumbling pairs",
          "[distance][impact_instant]") {
  std::mt19937_64 rng(20261126);
  const std::vector<TestShape> shapes = {cube(), tetrahedron(), coin(), sliver(), ball()};
  int tested = 0;
  double worst = kInfinity;  // least (gap - target) / target seen
  for (int trial = 0; trial < 3000 && tested < 400; ++trial) {
    const TestShape& a = shapes[trial % shapes.size()];
    const TestShape& b = shapes[(trial / shapes.size()) % shapes.size()];
    const Body b1 = dynamic(a, random_state(rng, 1.5, 2.0, 8.0));
    Body b2 = dynamic(b, random_state(rng, 1.5, 2.0, 8.0));
    if (trial % 3 == 0) b2.motion = MotionKind::kFixed;  // a fixed partner half the time
    if (!b2.is_dynamic()) b2.mass = infinite_mass_properties();
    PairCache cache;
    const DistanceResult dr =
        closest_features(*a.geometry, Pose{b1.state.x_W, b1.state.q_WM}, *b.geometry,
                         Pose{b2.state.x_W, b2.state.q_WM}, cache, 1000);
    if (dr.status != ContactStatus::kSeparated || dr.distance > 0.5) continue;
    const double target = 0.5 * dr.distance;
    const double step = certified_step(b1, b1.state, *a.geometry, b2, b2.state, *b.geometry, dr,
                                       cache, kGravity, Settings{}, target);
    REQUIRE(step >= 0.0);
    if (!std::isfinite(step)) continue;
    ++tested;
    CAPTURE(trial, a.name, b.name, dr.distance, step);
    for (int k = 1; k <= 64; ++k) {
      const double t = step * k / 64.0;
      const BodyState s1 = advance(b1, b1.state, t, kGravity);
      const BodyState s2 = advance(b2, b2.state, t, kGravity);
      const double d = brute_force_distance(to_world(*a.shape, Pose{s1.x_W, s1.q_WM}),
                                            to_world(*b.shape, Pose{s2.x_W, s2.q_WM}));
      worst = std::min(worst, (d - target) / target);
      CHECK(d >= target * (1.0 - 1e-9));
    }
  }
  CAPTURE(worst);
  CHECK(tested >= 400);
}

TEST_CASE("the search lands on the first instant a tumbling body reaches a plane",
          "[distance][impact_instant]") {
  std::mt19937_64 rng(7);
  const TestShape plane = make_test_shape("plane", make_halfspace(Vec3::UnitZ(), 0.0));
  Body ground;
  ground.name = "ground";
  ground.motion = MotionKind::kFixed;
  ground.shape = plane.shape;
  ground.mass = infinite_mass_properties();
  for (const TestShape& shape : {tetrahedron(), cube(), coin()}) {
    int iterations = 0, searches = 0;
    for (int trial = 0; trial < 40; ++trial) {
      CAPTURE(shape.name, trial);
      BodyState s = random_state(rng, 0.0, 1.0, 6.0);
      const Body body = dynamic(shape, s);
      // Placed so that its lowest vertex is half the default envelope up (where the bound
      // leaves it), falling at 1 to 3 m/s.
      auto lowest = [&](const BodyState& st) {
        double low = kInfinity;
        for (const Vec3& v : std::get<ConvexPolyhedron>(*shape.shape).vertices()) {
          low = std::min(low, (st.x_W + st.q_WM * v).z());
        }
        return low;
      };
      s.x_W.z() += 5e-5 - lowest(s);
      s.v_W.z() = -1.0 - 2.0 * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
      Body b1 = body;
      b1.state = s;
      auto height = [&](double t) { return lowest(advance(b1, s, t, kGravity)); };
      // The oracle: the first sign change among 20,000 samples over 5 ms, then bisection.
      double lo = 0.0, hi = -1.0;
      for (int k = 1; k <= 20000; ++k) {
        const double t = 5e-3 * k / 20000;
        if (height(t) <= 0.0) {
          hi = t;
          break;
        }
        lo = t;
      }
      if (hi < 0.0) continue;  // turned away before touching
      for (int k = 0; k < 200; ++k) {
        const double m = 0.5 * (lo + hi);
        (height(m) > 0.0 ? lo : hi) = m;
      }
      PairCache cache;
      const DistanceResult dr = closest_features(*shape.geometry, Pose{s.x_W, s.q_WM},
                                                 *plane.geometry, Pose{}, cache, 1000);
      REQUIRE(dr.status == ContactStatus::kSeparated);
      // An envelope of 1 m: the search follows the gap wherever it goes (a spinning cube's
      // lowest corner rises and the next one comes down: the gap is not monotone).
      Settings wide;
      wide.envelope_m = 1.0;
      const ImpactInstant in =
          impact_instant(b1, s, *shape.geometry, ground, ground.state, *plane.geometry, dr, cache,
                         kGravity, wide, 1e-13, 32);
      REQUIRE(in.status == InstantStatus::kFound);
      CHECK(in.gap_m <= 1e-13);
      CHECK(std::abs(in.dt - lo) <= 1e-12);
      ++searches;
      iterations += in.iterations;
    }
    CAPTURE(shape.name, searches, iterations);
    CHECK(searches >= 20);
    CHECK(iterations <= 8 * searches);  // quadratic convergence: a few queries each
  }
}
