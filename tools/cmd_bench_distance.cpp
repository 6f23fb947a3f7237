// palpable bench distance: closest-feature queries along slow motions, coherent (warm per-pair
// cache) and cold (fresh cache), against libccd's MPR intersection test on the same poses, as JSON
// lines (one per shape pair). A benchmark, not a test: medians of repeated timings. The motion
// between consecutive queries is ~1 mm and ~0.1 degree.
#include "core/point_sets.hpp"
#include "core/shape.hpp"
#include "distance/closest_features.hpp"
#include "distance/crosscheck/mpr.hpp"
#include "tools/commands.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/median.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace palpable::tools {
namespace {

struct BenchShape {
  std::string name;
  std::shared_ptr<const ShapeGeometry> geometry;
};

BenchShape bench_shape(std::string name, Shape shape) {
  return {std::move(name),
          std::make_shared<const ShapeGeometry>(std::make_shared<const Shape>(std::move(shape)))};
}

// Body 1 tumbles slowly past body 2 (fixed at the origin) at a clearance of a few centimetres:
// consecutive poses differ by ~1 mm and ~0.1 degree, the small motion between checks of an
// event-driven simulation.
std::vector<Pose> trajectory(double reach1, double reach2, int count) {
  std::vector<Pose> poses(count);
  const Vec3 axis = Vec3(1.0, 2.0, 0.5).normalized();
  for (int i = 0; i < count; ++i) {
    const double s = static_cast<double>(i) / count;
    const double angle = 2.0 * M_PI * s;
    const double height = reach1 + reach2 + 0.05;
    poses[i].x_W = Vec3(0.4 * std::cos(angle), 0.4 * std::sin(angle), height);
    poses[i].q_WM = Quat(Eigen::AngleAxisd(0.5 * angle, axis));
  }
  return poses;
}

int run(int repeats, int queries) {
  const BenchShape cube = bench_shape("cube", ConvexPolyhedron::box(Vec3(0.5, 0.5, 0.5)));
  const BenchShape hull =
      bench_shape("hull1280", ConvexPolyhedron::from_points(icosphere_points(3, 0.7)));
  const BenchShape coin = bench_shape("coin", ConvexPolyhedron::prism(0.6, 0.003, 32));
  const BenchShape ball = bench_shape("sphere", Sphere{0.4});
  struct PairSpec {
    const BenchShape* a;
    const BenchShape* b;
    double reach_a, reach_b;
  };
  const std::vector<PairSpec> pairs = {{&cube, &cube, 0.87, 0.5}, {&hull, &hull, 0.7, 0.7},
                                       {&cube, &hull, 0.87, 0.7}, {&coin, &cube, 0.6, 0.5},
                                       {&ball, &cube, 0.4, 0.5},  {&ball, &hull, 0.4, 0.7}};
  volatile double sink = 0.0;
  using Clock = std::chrono::steady_clock;
  const Pose fixed{};
  for (const PairSpec& spec : pairs) {
    const std::vector<Pose> poses = trajectory(spec.reach_a, spec.reach_b, queries);
    const ShapeGeometry& g1 = *spec.a->geometry;
    const ShapeGeometry& g2 = *spec.b->geometry;
    std::vector<double> coherent_ns, cold_ns, mpr_ns;
    long steps_coherent = 0, steps_cold = 0;
    for (int r = 0; r < repeats; ++r) {
      PairCache cache;
      closest_features(g1, poses.back(), g2, fixed, cache, 10000);  // warm the cache
      steps_coherent = 0;
      auto t0 = Clock::now();
      for (const Pose& p : poses) {
        const DistanceResult d = closest_features(g1, p, g2, fixed, cache, 10000);
        sink = sink + d.distance;
        steps_coherent += d.steps;
      }
      auto t1 = Clock::now();
      coherent_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / queries);

      steps_cold = 0;
      t0 = Clock::now();
      for (const Pose& p : poses) {
        PairCache fresh;
        const DistanceResult d = closest_features(g1, p, g2, fixed, fresh, 10000);
        sink = sink + d.distance;
        steps_cold += d.steps;
      }
      t1 = Clock::now();
      cold_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / queries);

      MprShape m1(g1, poses.front());
      const MprShape m2(g2, fixed);
      int hits = 0;
      t0 = Clock::now();
      for (const Pose& p : poses) {
        m1.set_pose(p);
        hits += mpr_intersect(m1, m2) ? 1 : 0;
      }
      t1 = Clock::now();
      sink = sink + hits;
      mpr_ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / queries);
    }
    const double coherent = median(coherent_ns), cold = median(cold_ns), mpr = median(mpr_ns);
    std::printf(
        "{\"pair\": \"%s-%s\", \"queries\": %d, \"repeats\": %d, \"coherent_ns\": %.1f, "
        "\"cold_ns\": %.1f, \"mpr_ns\": %.1f, \"coherent_vs_mpr\": %.3f, \"cold_vs_mpr\": %.3f, "
        "\"steps_coherent\": %.3f, \"steps_cold\": %.2f}\n",
        spec.a->name.c_str(), spec.b->name.c_str(), queries, repeats, coherent, cold, mpr,
        coherent / mpr, cold / mpr, static_cast<double>(steps_coherent) / queries,
        static_cast<double>(steps_cold) / queries);
  }
  return kExitOk;
}

CommandRegistration reg{
    "bench distance", [](CLI::App& app) {
      app.description(
          "Closest-feature queries (V-Clip) along slow tumbling motions, per "
          "shape pair: median ns per query with a warm per-pair cache "
          "(coherent) and a fresh one (cold), and libccd's ccdMPRIntersect "
          "on the same poses; *_vs_mpr are time ratios (< 1: faster than "
          "MPR); steps are mean feature steps per query. Many short timed "
          "bursts, median taken, so that a shared machine's preemptions "
          "fall in a minority of bursts");
      auto repeats = std::make_shared<int>(201);
      auto queries = std::make_shared<int>(2000);
      app.add_option("--repeats", *repeats, "timed repetitions (median)")
          ->check(CLI::Range(5, 1000));
      app.add_option("--queries", *queries, "queries per repetition")
          ->check(CLI::Range(100, 10000000));
      return std::function<int()>([repeats, queries] { return run(*repeats, *queries); });
    }};

}  // namespace
}  // namespace palpable::tools
