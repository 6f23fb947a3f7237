// GJK on support mappings: against V-Clip on polyhedra (an independent exact algorithm), the
// closed form for balls, and the simplex step against brute force.
#include "distance/gjk.hpp"

#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

#include <random>

using namespace palpable;
using namespace palpable::test;

namespace {

Vec3 posed_support(const Shape& shape, const Pose& pose, const Vec3& d) {
  return support_W(shape, pose.x_W, pose.q_WM, d);
}

}  // namespace

TEST_CASE("gjk: the simplex step finds the closest point of a tetrahedron (brute force)",
          "[distance][gjk]") {
  std::mt19937_64 rng(1602);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    CAPTURE(trial);
    GjkSimplex s;
    s.count = 4;
    for (int i = 0; i < 4; ++i) s.points[i].w = Vec3(u(rng), u(rng), u(rng));
    // Brute force: the minimum of |sum l_i w_i| over a dense barycentric grid (a lower-accuracy
    // reference; the step's answer must not be worse than it, and must be a point of the hull).
    double brute = kInfinity;
    const int steps = 40;
    for (int a = 0; a <= steps; ++a) {
      for (int b = 0; a + b <= steps; ++b) {
        for (int c = 0; a + b + c <= steps; ++c) {
          const int d = steps - a - b - c;
          const Vec3 x =
              (a * s.points[0].w + b * s.points[1].w + c * s.points[2].w + d * s.points[3].w) /
              steps;
          brute = std::min(brute, x.norm());
        }
      }
    }
    const GjkSimplex before = s;
    const bool inside = reduce_to_closest_face(s);
    const double found = s.v.norm();
    CHECK(found <= brute + 1e-14);
    // The weights are a convex combination of points of the original simplex.
    double sum = 0.0;
    Vec3 v = Vec3::Zero();
    for (int i = 0; i < s.count; ++i) {
      CHECK(s.weights[i] >= 0.0);
      sum += s.weights[i];
      v += s.weights[i] * s.points[i].w;
      bool present = false;
      for (int j = 0; j < 4; ++j) present = present || s.points[i].w == before.points[j].w;
      CHECK(present);
    }
    CHECK(sum == Approx(1.0).epsilon(1e-14));
    if (!inside) CHECK((v - s.v).norm() <= 1e-15);
    // Optimality: no point of the simplex is closer along v (v . w_i >= |v|^2 for all i).
    if (!inside) {
      for (int j = 0; j < 4; ++j) CHECK(s.v.dot(before.points[j].w) >= s.v.squaredNorm() - 1e-14);
    }
  }
}

TEST_CASE("gjk: polyhedra agree with V-Clip, balls with the closed form", "[distance][gjk]") {
  std::mt19937_64 rng(1603);
  const std::vector<TestShape> shapes = {cube(), tetrahedron(), hull1280(), coin(), sliver()};
  int separated = 0, overlapping = 0, max_iterations = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const TestShape& s1 = shapes[trial % shapes.size()];
    const TestShape& s2 = shapes[(trial / shapes.size()) % shapes.size()];
    const Pose p1 = random_pose(rng, 1.2);
    const Pose p2 = random_pose(rng, 1.2);
    CAPTURE(trial, s1.name, s2.name);
    PairCache cache;
    const DistanceResult ref = closest_features(*s1.geometry, p1, *s2.geometry, p2, cache, 1000);
    GjkSettings settings;
    settings.tolerance_m = 1e-13;
    const GjkResult g = gjk_distance([&](const Vec3& d) { return posed_support(*s1.shape, p1, d); },
                                     [&](const Vec3& d) { return posed_support(*s2.shape, p2, d); },
                                     p1.x_W - p2.x_W, settings);
    max_iterations = std::max(max_iterations, g.iterations);
    if (ref.status == ContactStatus::kSeparated && ref.distance > 1e-9) {
      ++separated;
      REQUIRE(g.status == GjkResult::Status::kSeparated);
      CHECK(g.distance == Approx(ref.distance).margin(1e-12));
      CHECK((g.p_a - g.p_b).norm() == Approx(ref.distance).margin(1e-12));
    } else if (ref.status == ContactStatus::kPenetrating) {
      ++overlapping;
      CHECK(g.status != GjkResult::Status::kSeparated);
    }
  }
  INFO("separated " << separated << ", overlapping " << overlapping << ", max iterations "
                    << max_iterations);
  CHECK(separated > 500);
  CHECK(overlapping > 200);
  CHECK(max_iterations < 64);
  // Two balls: |c1 - c2| - r1 - r2, to the tolerance.
  for (int trial = 0; trial < 200; ++trial) {
    const Pose p1 = random_pose(rng, 2.0), p2 = random_pose(rng, 2.0);
    const Shape b1 = make_sphere(0.3), b2 = make_sphere(0.45);
    const double exact = (p1.x_W - p2.x_W).norm() - 0.75;
    GjkSettings settings;
    settings.tolerance_m = 1e-12;
    const GjkResult g = gjk_distance([&](const Vec3& d) { return posed_support(b1, p1, d); },
                                     [&](const Vec3& d) { return posed_support(b2, p2, d); },
                                     p1.x_W - p2.x_W, settings);
    if (exact > 1e-6) {
      REQUIRE(g.status == GjkResult::Status::kSeparated);
      CHECK(g.distance == Approx(exact).margin(1e-12));
      CHECK(g.lower_bound <= exact + 1e-15);
    } else if (exact < -1e-6) {
      CHECK(g.status != GjkResult::Status::kSeparated);
    }
  }
}
