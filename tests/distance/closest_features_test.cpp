// closest_features: random pose pairs against a brute-force reference and libccd's MPR; spheres,
// halfspaces, compounds; the sign convention; the contact patch.
#include "distance/closest_features.hpp"

#include "distance/crosscheck/mpr.hpp"
#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>

using namespace palpable;
using namespace palpable::test;

namespace {

struct RandomStats {
  long pairs = 0;
  long separated = 0;
  long penetrating = 0;
  long failed = 0;
  long in_band = 0;
  long mpr_disagreements = 0;
  long distance_errors = 0;
  long point_errors = 0;
  double max_relative_error = 0.0;
  long steps = 0;
};

// Distance from p to the surface of the posed shape, signed: > 0 outside (exact for spheres; for
// polyhedra the largest face-plane value, which is 0 exactly on the surface).
double surface_residual(const WorldConvex& w, const Vec3& p) {
  if (w.sphere) return (p - w.center).norm() - w.radius;
  return max_face_eval(w, p);
}

void run_random_pairs(const TestShape& s1, const TestShape& s2, int count, std::uint64_t seed,
                      double half_box, RandomStats& stats) {
  std::mt19937_64 rng(seed);
  PairCache warm;
  for (int i = 0; i < count; ++i) {
    const Pose pose1 = random_pose(rng, half_box);
    const Pose pose2 = random_pose(rng, half_box);
    PairCache cold;
    PairCache& cache = (i % 2 == 0) ? cold : warm;
    const DistanceResult r =
        closest_features(*s1.geometry, pose1, *s2.geometry, pose2, cache, 10000);
    ++stats.pairs;
    stats.steps += r.steps;
    const WorldConvex w1 = to_world(*s1.shape, pose1);
    const WorldConvex w2 = to_world(*s2.shape, pose2);
    const bool mpr = mpr_intersect(MprShape(*s1.geometry, pose1), MprShape(*s2.geometry, pose2));
    INFO("pair " << s1.name << "-" << s2.name << " seed " << seed << " case " << i);
    if (r.status == ContactStatus::kFailed) {
      ++stats.failed;
      std::printf("failed (step limit): %s-%s seed %llu case %d\n", s1.name.c_str(),
                  s2.name.c_str(), static_cast<unsigned long long>(seed), i);
      continue;
    }
    if (r.status == ContactStatus::kPenetrating) {
      ++stats.penetrating;
      if (!mpr) {
        const double d_ref = brute_force_distance(w1, w2);
        if (d_ref > 1e-9) {
          ++stats.mpr_disagreements;
          UNSCOPED_INFO("penetrating but MPR and brute force say separated by " << d_ref);
        } else {
          ++stats.in_band;
        }
      }
      continue;
    }
    ++stats.separated;
    const double d_ref = brute_force_distance(w1, w2);
    if (r.distance <= 1e-9) {
      ++stats.in_band;
    } else if (mpr) {
      ++stats.mpr_disagreements;
      UNSCOPED_INFO("separated by " << r.distance << " but MPR says intersecting");
    }
    const double error = std::abs(r.distance - d_ref);
    const double relative = error / std::max(d_ref, 1e-300);
    if (d_ref > 1e-6) stats.max_relative_error = std::max(stats.max_relative_error, relative);
    if (error > 1e-10 * d_ref + 1e-14) {
      ++stats.distance_errors;
      UNSCOPED_INFO("distance " << r.distance << " reference " << d_ref << " features "
                                << static_cast<int>(r.feature1.kind) << ":" << r.feature1.index
                                << " " << static_cast<int>(r.feature2.kind) << ":"
                                << r.feature2.index);
    }
    // Any two surface points at the minimum distance are closest points.
    const double scale = 1.0;
    const bool points_ok =
        std::abs((r.p1_W - r.p2_W).norm() - r.distance) <= 1e-12 * scale &&
        std::abs(surface_residual(w1, r.p1_W)) <= 1e-12 * scale &&
        std::abs(surface_residual(w2, r.p2_W)) <= 1e-12 * scale &&
        (r.distance == 0.0 || (r.p1_W - r.p2_W - r.distance * r.n_W).norm() <= 1e-12 * scale);
    if (!points_ok) {
      ++stats.point_errors;
      UNSCOPED_INFO("closest points off: |p1-p2| " << (r.p1_W - r.p2_W).norm() << " residuals "
                                                   << surface_residual(w1, r.p1_W) << " "
                                                   << surface_residual(w2, r.p2_W));
    }
  }
}

}  // namespace

TEST_CASE("closest features agree with brute force and MPR on 100,000 random pose pairs",
          "[distance][random]") {
  const std::vector<TestShape> cheap = {cube(), tetrahedron(), coin(), sliver(), ball()};
  const TestShape hull = hull1280();
  REQUIRE(std::get<ConvexPolyhedron>(*hull.shape).faces().size() == 1280);
  RandomStats stats;
  std::uint64_t seed = 20261121;
  // 25 ordered pairs of cheap shapes x 3,600 = 90,000; the hull against each cheap shape in both
  // orders x 990 = 9,900; hull-hull 100 (the brute force is 1920^2 edge pairs each).
  for (const TestShape& a : cheap) {
    for (const TestShape& b : cheap) run_random_pairs(a, b, 3600, seed++, 0.7, stats);
  }
  for (const TestShape& b : cheap) {
    run_random_pairs(hull, b, 990, seed++, 0.8, stats);
    run_random_pairs(b, hull, 990, seed++, 0.8, stats);
  }
  run_random_pairs(hull, hull, 100, seed++, 0.9, stats);
  std::printf(
      "random pairs: %ld (separated %ld, penetrating %ld, failed %ld), max relative distance "
      "error %.3g, distance errors %ld, point errors %ld, MPR disagreements outside 1e-9 band %ld, "
      "in band %ld, mean steps %.2f\n",
      stats.pairs, stats.separated, stats.penetrating, stats.failed, stats.max_relative_error,
      stats.distance_errors, stats.point_errors, stats.mpr_disagreements, stats.in_band,
      static_cast<double>(stats.steps) / stats.pairs);
  CHECK(stats.pairs == 100000);
  CHECK(stats.failed == 0);
  CHECK(stats.distance_errors == 0);
  CHECK(stats.point_errors == 0);
  CHECK(stats.mpr_disagreements == 0);
  CHECK(stats.max_relative_error <= 1e-10);
}
