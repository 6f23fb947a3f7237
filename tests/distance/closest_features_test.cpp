// closest_features: random pose pairs against a brute-force reference and libccd's MPR; spheres,
// halfspaces, compounds; the sign convention; the contact patch.
#include "distance/closest_features.hpp"

#include "distance/crosscheck/mpr.hpp"
#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>

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

namespace {

double polygon_area(const std::vector<Vec3>& pts, const Vec3& n) {
  double area = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    area += pts[i].cross(pts[(i + 1) % pts.size()]).dot(n);
  }
  return 0.5 * area;
}

}  // namespace

TEST_CASE("sign convention: a ball dropped on the ground, pair given in either order",
          "[distance][sign]") {
  const TestShape ball_shape = ball();  // radius 0.4
  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  const TestShape slab = make_test_shape("slab", ConvexPolyhedron::box(Vec3(5.0, 5.0, 0.5)));
  const Vec3 g(0.0, 0.0, -9.81);
  for (const TestShape* floor : {&ground, &slab}) {
    const Pose floor_pose{floor == &slab ? Vec3(0, 0, -0.5) : Vec3::Zero(), Quat::Identity()};
    for (double t : {0.0, 0.2, 0.3}) {
      // Dropped from rest at height 1: centre z(t) = 1 - g t^2 / 2, velocity -g t.
      const Pose ball_pose{Vec3(0.1, -0.2, 1.0 - 0.5 * 9.81 * t * t), Quat::Identity()};
      const Vec3 v_ball = g * t;
      const double expected = ball_pose.x_W.z() - 0.4;
      PairCache c1, c2;
      const DistanceResult ab =
          closest_features(*ball_shape.geometry, ball_pose, *floor->geometry, floor_pose, c1, 100);
      const DistanceResult ba =
          closest_features(*floor->geometry, floor_pose, *ball_shape.geometry, ball_pose, c2, 100);
      CAPTURE(floor->name, t);
      REQUIRE(ab.status == ContactStatus::kSeparated);
      REQUIRE(ba.status == ContactStatus::kSeparated);
      CHECK(ab.distance == Approx(expected).epsilon(1e-14));
      CHECK(ba.distance == Approx(expected).epsilon(1e-14));
      // n points from body 2 to body 1.
      CHECK((ab.n_W - Vec3::UnitZ()).norm() < 1e-14);
      CHECK((ba.n_W + Vec3::UnitZ()).norm() < 1e-14);
      CHECK((ab.p1_W - (ball_pose.x_W - 0.4 * Vec3::UnitZ())).norm() < 1e-14);
      CHECK(std::abs(ab.p2_W.z()) < 1e-14);
      CHECK((ab.p1_W - ab.p2_W - ab.distance * ab.n_W).norm() < 1e-14);
      CHECK((ba.p1_W - ba.p2_W - ba.distance * ba.n_W).norm() < 1e-14);
      // u = u1 - u2, u_n = u . n < 0 means approaching, in both orders once it falls.
      const double un_ab = (v_ball - Vec3::Zero()).dot(ab.n_W);
      const double un_ba = (Vec3::Zero() - v_ball).dot(ba.n_W);
      CHECK(un_ab == Approx(un_ba));
      if (t > 0.0) CHECK(un_ab < 0.0);
    }
  }
}

TEST_CASE("spheres and halfspaces: closed forms, touching, penetration depth",
          "[distance][shapes]") {
  const TestShape a = make_test_shape("a", Sphere{0.5});
  const TestShape b = make_test_shape("b", Sphere{0.25});
  PairCache cache;
  const Pose pa{Vec3(0, 0, 0), Quat::Identity()};
  auto query = [&](const Vec3& x) {
    return closest_features(*a.geometry, pa, *b.geometry, Pose{x, Quat::Identity()}, cache, 100);
  };
  DistanceResult r = query(Vec3(1.0, 0.0, 0.0));
  CHECK(r.status == ContactStatus::kSeparated);
  CHECK(r.distance == Approx(0.25));
  CHECK((r.n_W - Vec3(-1, 0, 0)).norm() < 1e-15);
  r = query(Vec3(0.0, 0.75, 0.0));
  CHECK(r.status == ContactStatus::kTouching);
  r = query(Vec3(0.0, 0.0, 0.6));
  CHECK(r.status == ContactStatus::kPenetrating);
  CHECK(r.distance == 0.0);
  CHECK(r.penetration_depth == Approx(0.15));

  // A tilted cube above the ground: the lowest vertex, found by a walk from the cached vertex.
  const TestShape box = cube();
  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  PairCache ground_cache;
  int total_steps = 0;
  for (int i = 0; i < 100; ++i) {
    const Quat q(Eigen::AngleAxisd(0.01 * i, Vec3(1, 1, 0).normalized()));
    const Pose pose{Vec3(0, 0, 2.0), q};
    const DistanceResult g =
        closest_features(*box.geometry, pose, *ground.geometry, Pose{}, ground_cache, 100);
    double lowest = kInfinity;
    for (const Vec3& v : std::get<ConvexPolyhedron>(*box.shape).vertices()) {
      lowest = std::min(lowest, (pose.x_W + q * v).z());
    }
    CHECK(g.distance == Approx(lowest).epsilon(1e-14));
    CHECK(g.n_W.z() == 1.0);
    total_steps += g.steps;
  }
  CHECK(total_steps <= 10);  // coherent: the lowest vertex rarely changes
  const DistanceResult sunk =
      closest_features(*box.geometry, Pose{Vec3(0, 0, 0.3), Quat::Identity()}, *ground.geometry,
                       Pose{}, ground_cache, 100);
  CHECK(sunk.status == ContactStatus::kPenetrating);
  CHECK(sunk.penetration_depth == Approx(0.2));
}

TEST_CASE("compounds pair piece by piece", "[distance][shapes]") {
  // A dish of two boxes; a ball above the right one.
  auto piece = [](const Vec3& half, const Vec3& at) {
    return CompoundPart{std::make_shared<const Shape>(ConvexPolyhedron::box(half)), at,
                        Quat::Identity()};
  };
  const TestShape dish =
      make_test_shape("dish", make_compound({piece(Vec3(1, 1, 0.1), Vec3(-1, 0, 0)),
                                             piece(Vec3(1, 1, 0.1), Vec3(1.5, 0, 0.3))}));
  const TestShape ball_shape = ball();
  PairCache cache;
  const DistanceResult r =
      closest_features(*ball_shape.geometry, Pose{Vec3(1.5, 0, 1.0), Quat::Identity()},
                       *dish.geometry, Pose{}, cache, 100);
  CHECK(r.status == ContactStatus::kSeparated);
  CHECK(r.piece2 == 1);
  CHECK(r.distance == Approx(1.0 - 0.4 - 0.4));
  REQUIRE(cache.compound);
  CHECK(cache.compound->pieces.size() == 2);
  const DistanceResult left =
      closest_features(*ball_shape.geometry, Pose{Vec3(-1.0, 0, 0.8), Quat::Identity()},
                       *dish.geometry, Pose{}, cache, 100);
  CHECK(left.piece2 == 0);
  CHECK(left.distance == Approx(0.8 - 0.1 - 0.4));
}

TEST_CASE("contact patch: face on face, edge on face, vertex on face", "[distance][patch]") {
  const double envelope = 1e-3;
  const TestShape box = cube();
  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  PairCache cache;
  SECTION("cube resting on a cube, offset sideways: the overlap rectangle") {
    const Pose top{Vec3(0.3, -0.2, 1.0 + 0.4 * envelope), Quat::Identity()};
    const Pose bottom{};
    const DistanceResult r =
        closest_features(*box.geometry, top, *box.geometry, bottom, cache, 100);
    REQUIRE(r.status == ContactStatus::kSeparated);
    const auto patch = contact_patch(*box.geometry, top, *box.geometry, bottom, r, envelope);
    REQUIRE(patch.size() == 4);
    CHECK(polygon_area(patch, Vec3::UnitZ()) == Approx(0.7 * 0.8));
    for (const Vec3& p : patch) CHECK(std::abs(p.z() - 0.5) < 1e-12);
  }
  SECTION("cube on the ground, tilted within the envelope: the whole bottom face") {
    const double tilt = 0.5 * envelope;  // the far edge rises by about tilt [m]
    const Pose pose{Vec3(0, 0, 0.5 + 0.5 * tilt + 0.2 * envelope),
                    Quat(Eigen::AngleAxisd(tilt, Vec3::UnitX()))};
    const DistanceResult r =
        closest_features(*box.geometry, pose, *ground.geometry, Pose{}, cache, 100);
    REQUIRE(r.status == ContactStatus::kSeparated);
    const auto patch = contact_patch(*box.geometry, pose, *ground.geometry, Pose{}, r, envelope);
    REQUIRE(patch.size() == 4);
    CHECK(polygon_area(patch, Vec3::UnitZ()) == Approx(1.0).epsilon(1e-5));
  }
  SECTION("cube on an edge: a segment") {
    const Pose pose{Vec3(0, 0, std::sqrt(0.5) + 0.3 * envelope),
                    Quat(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitX()))};
    const DistanceResult r =
        closest_features(*box.geometry, pose, *ground.geometry, Pose{}, cache, 100);
    const auto patch = contact_patch(*box.geometry, pose, *ground.geometry, Pose{}, r, envelope);
    REQUIRE(patch.size() == 2);
    CHECK((patch[0] - patch[1]).norm() == Approx(1.0));
  }
  SECTION("cube on a vertex: one point") {
    const Quat q = Quat::FromTwoVectors(Vec3(-1, -1, -1).normalized(), -Vec3::UnitZ());
    const Pose pose{Vec3(0, 0, std::sqrt(0.75) + 0.3 * envelope), q};
    const DistanceResult r =
        closest_features(*box.geometry, pose, *ground.geometry, Pose{}, cache, 100);
    const auto patch = contact_patch(*box.geometry, pose, *ground.geometry, Pose{}, r, envelope);
    REQUIRE(patch.size() >= 1);
    for (const Vec3& p : patch) CHECK((p - r.p2_W).norm() < 2.0 * envelope);
  }
  SECTION("edge across a face of another cube: the part of the edge over the face") {
    const Pose top{Vec3(0.3, 0.4, 0.5 + std::sqrt(0.5) + 0.3 * envelope),
                   Quat(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitY()))};
    const DistanceResult r =
        closest_features(*box.geometry, top, *box.geometry, Pose{}, cache, 100);
    REQUIRE(r.status == ContactStatus::kSeparated);
    const auto patch = contact_patch(*box.geometry, top, *box.geometry, Pose{}, r, envelope);
    REQUIRE(patch.size() == 2);
    CHECK((patch[0] - patch[1]).norm() == Approx(0.6).epsilon(1e-9));  // y from -0.1 to 0.5
  }
}

namespace {
// Counts heap allocations while `counting` is set (for the allocation-free hot path check).
std::atomic<bool> counting{false};
std::atomic<long> allocations{0};
}  // namespace

// Every replaceable (unaligned) form, so that allocation and release always pair malloc/free.
void* operator new(std::size_t size) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}

TEST_CASE("coherent queries allocate nothing", "[distance][alloc]") {
  const TestShape a = cube();
  const TestShape b = hull1280();
  const TestShape s = ball();
  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  PairCache c1, c2, c3;
  double sink = 0.0;
  const Pose fixed{Vec3(0, 0, 0), Quat::Identity()};
  counting = true;
  for (int i = 0; i < 1000; ++i) {
    const Pose p{Vec3(0.001 * i, 0.2, 1.8), Quat(Eigen::AngleAxisd(0.002 * i, Vec3::UnitY()))};
    sink += closest_features(*a.geometry, p, *b.geometry, fixed, c1, 10000).distance;
    sink += closest_features(*s.geometry, p, *a.geometry, fixed, c2, 10000).distance;
    sink += closest_features(*a.geometry, p, *ground.geometry, fixed, c3, 10000).distance;
  }
  counting = false;
  CHECK(sink > 0.0);
  CHECK(allocations.load() == 0);
}
