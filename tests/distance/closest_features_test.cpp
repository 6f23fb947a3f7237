// closest_features: random pose pairs against a brute-force reference and libccd's MPR; spheres,
// halfspaces, compounds; the sign convention; the contact patch.
#include "distance/closest_features.hpp"

#include "distance/crosscheck/mpr.hpp"
#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
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

TEST_CASE("polyhedra overlapping beyond rounding: the axis of least overlap, its depth",
          "[distance][shapes]") {
  // V-Clip's normal for an overlap is any direction at all. A held hull's edge drifted 3e-13 m
  // into the face it was held on (a pile of 200 hulls); with V-Clip's normal the released pair
  // seemed to part at 1.4 mm/s while along the face's normal it approached. The least-overlap
  // axis is the normal, and its overlap the depth (an upper bound: a translation by it along
  // the normal separates the bodies).
  const TestShape box = cube();  // 1 m
  PairCache cache;
  for (const double depth : {3e-13, 1e-9, 1e-6, 1e-3}) {
    CAPTURE(depth);
    // A cube sunk flat into a cube, offset sideways and turned about the normal.
    const Pose top{Vec3(0.3, -0.2, 1.0 - depth), Quat(Eigen::AngleAxisd(0.2, Vec3::UnitZ()))};
    DistanceResult r = closest_features(*box.geometry, top, *box.geometry, Pose{}, cache, 100);
    CHECK(r.status == ContactStatus::kPenetrating);
    CHECK((r.n_W - Vec3::UnitZ()).norm() < 1e-12);  // from body 2 to body 1
    CHECK(std::abs(r.penetration_depth - depth) <= 1e-15);
    // A cube standing on an edge, sunk into a cube's top face.
    const Pose edge{Vec3(0.1, 0.05, 0.5 + std::sqrt(0.5) - depth),
                    Quat(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitX()))};
    r = closest_features(*box.geometry, Pose{}, *box.geometry, edge, cache, 100);
    CHECK(r.status == ContactStatus::kPenetrating);
    CHECK((r.n_W + Vec3::UnitZ()).norm() < 1e-12);
    CHECK(std::abs(r.penetration_depth - depth) <= 1e-15);
  }
  // Random overlapping poses of two boxes of unequal sides: moving body 1 out along the normal
  // by the depth (and a hair) separates the pair.
  std::mt19937_64 rng(20261130);
  const TestShape plate = make_test_shape("plate", ConvexPolyhedron::box(Vec3(0.4, 0.25, 0.05)));
  int overlapping = 0;
  for (int i = 0; i < 2000; ++i) {
    const Pose p1 = random_pose(rng, 0.3), p2 = random_pose(rng, 0.3);
    PairCache cold;
    const DistanceResult r = closest_features(*plate.geometry, p1, *box.geometry, p2, cold, 10000);
    if (r.status != ContactStatus::kPenetrating) continue;
    ++overlapping;
    INFO("case " << i);
    REQUIRE(r.penetration_depth > 0.0);
    const Pose out{p1.x_W + (r.penetration_depth * (1.0 + 1e-12) + 1e-14) * r.n_W, p1.q_WM};
    PairCache again;
    const DistanceResult moved =
        closest_features(*plate.geometry, out, *box.geometry, p2, again, 10000);
    CHECK(moved.status != ContactStatus::kPenetrating);
  }
  CHECK(overlapping > 500);
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

// ---------------------------------------------------------------------------------------------
// Smooth shapes (ellipsoid, cylinder, capsule, loaded ball).

namespace {

// Signed excess of a world point over a posed shape's surface (0 on it, < 0 inside), from each
// shape's own definition rather than its support function. An ellipsoid's is relative.
double surface_excess(const Shape& shape, const Pose& pose, const Vec3& x_W) {
  const Vec3 x = pose.q_WM.conjugate() * (x_W - pose.x_W);
  if (const auto* s = std::get_if<Sphere>(&shape)) return x.norm() - s->radius;
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    return (x.cwiseQuotient(e->semi_axes_M).norm() - 1.0) * e->semi_axes_M.minCoeff();
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    return std::max(std::hypot(x.x(), x.y()) - c->radius, std::abs(x.z()) - c->half_height);
  }
  if (const auto* c = std::get_if<Capsule>(&shape)) {
    const double z = std::clamp(x.z(), -c->half_length, c->half_length);
    return (x - Vec3(0, 0, z)).norm() - c->radius;
  }
  if (const auto* b = std::get_if<LoadedBall>(&shape))
    return (x - b->centre_M()).norm() - b->radius;
  const auto& p = std::get<ConvexPolyhedron>(shape);
  double m = -kInfinity;
  for (const PolyFace& f : p.faces()) m = std::max(m, f.normal_M.dot(x) - f.offset);
  return m;
}

// The separation of two posed convex shapes along unit u (from 2 to 1): min over body 1 of u . x
// minus max over body 2 — a lower bound on their distance for every u, equal to it at the best u
// (the separating-axis theorem).
double separation(const TestShape& s1, const Pose& p1, const TestShape& s2, const Pose& p2,
                  const Vec3& u) {
  return u.dot(support_W(*s1.shape, p1.x_W, p1.q_WM, -u)) -
         u.dot(support_W(*s2.shape, p2.x_W, p2.q_WM, u));
}

// Brute force: the best separation over 2000 random directions, then Nelder-Mead in the tangent
// plane at each of the best 4 (the separation has narrow ridges on the sphere, along which a
// compass or random search stalls; the simplex stretches along them), restarted until it stops
// improving. A lower bound on the distance that approaches it.
double brute_separation(const TestShape& s1, const Pose& p1, const TestShape& s2, const Pose& p2,
                        std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  auto random_unit = [&] { return Vec3(g(rng), g(rng), g(rng)).normalized(); };
  std::vector<std::pair<double, Vec3>> starts;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 u = random_unit();
    starts.emplace_back(separation(s1, p1, s2, p2, u), u);
  }
  std::partial_sort(starts.begin(), starts.begin() + 4, starts.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first; });
  double overall = -kInfinity;
  for (int start = 0; start < 4; ++start) {
    auto [best, centre] = starts[start];
    double size = 0.05;
    for (int restart = 0; restart < 8; ++restart) {
      const Vec3 t1 = centre.unitOrthogonal();
      const Vec3 t2 = centre.cross(t1);
      auto f = [&](const Eigen::Vector2d& x) {
        return -separation(s1, p1, s2, p2, (centre + x.x() * t1 + x.y() * t2).normalized());
      };
      std::array<Eigen::Vector2d, 3> x = {Eigen::Vector2d(0, 0), Eigen::Vector2d(size, 0),
                                          Eigen::Vector2d(0, size)};
      std::array<double, 3> fx = {f(x[0]), f(x[1]), f(x[2])};
      for (int it = 0; it < 3000; ++it) {
        std::array<int, 3> o = {0, 1, 2};
        std::sort(o.begin(), o.end(), [&](int a, int b) { return fx[a] < fx[b]; });
        const int lo = o[0], mid = o[1], hi = o[2];
        if ((x[hi] - x[lo]).norm() < 1e-13) break;
        const Eigen::Vector2d c = 0.5 * (x[lo] + x[mid]);
        const Eigen::Vector2d r = c + (c - x[hi]);
        const double fr = f(r);
        if (fr < fx[lo]) {
          const Eigen::Vector2d e = c + 2.0 * (c - x[hi]);
          const double fe = f(e);
          if (fe < fr) {
            x[hi] = e, fx[hi] = fe;
          } else {
            x[hi] = r, fx[hi] = fr;
          }
        } else if (fr < fx[mid]) {
          x[hi] = r, fx[hi] = fr;
        } else {
          const Eigen::Vector2d k = c + 0.5 * (x[hi] - c);
          const double fk = f(k);
          if (fk < fx[hi]) {
            x[hi] = k, fx[hi] = fk;
          } else {
            for (int i : {mid, hi}) x[i] = x[lo] + 0.5 * (x[i] - x[lo]), fx[i] = f(x[i]);
          }
        }
      }
      const int lo = static_cast<int>(std::min_element(fx.begin(), fx.end()) - fx.begin());
      const double value = -fx[lo];
      const Vec3 u = (centre + x[lo].x() * t1 + x[lo].y() * t2).normalized();
      const bool improved = value > best + 1e-15;
      if (value > best) best = value, centre = u;
      if (!improved) break;
      size = std::max(1e-6, 0.1 * size);
    }
    overall = std::max(overall, best);
  }
  return overall;
}

std::vector<TestShape> smooth_test_shapes() {
  return {make_test_shape("ellipsoid", make_ellipsoid(Vec3(0.3, 0.5, 0.7))),
          make_test_shape("disk", make_cylinder(0.4, 0.02)),
          make_test_shape("cylinder", make_cylinder(0.3, 0.4)),
          make_test_shape("capsule", make_capsule(0.2, 0.35)),
          make_test_shape("loaded ball", make_loaded_ball(0.3, 0.1))};
}

}  // namespace

TEST_CASE("smooth shapes: distance, closest points and normal against brute force",
          "[distance][smooth]") {
  std::mt19937_64 rng(1604);
  const std::vector<TestShape> smooth = smooth_test_shapes();
  std::vector<TestShape> others = smooth_test_shapes();
  for (const TestShape& t : {cube(), tetrahedron(), hull1280(), coin(), sliver(), ball()}) {
    others.push_back(t);
  }
  long separated = 0, penetrating = 0;
  double worst_gap = 0.0, worst_point = 0.0, worst_brute = 0.0;
  for (const TestShape& s1 : smooth) {
    for (const TestShape& s2 : others) {
      for (int trial = 0; trial < 24; ++trial) {
        Pose p1 = random_pose(rng, 0.8), p2 = random_pose(rng, 0.8);
        const bool swap = trial % 2 == 1;  // the smooth shape as body 1, then as body 2
        const TestShape& a = swap ? s2 : s1;
        const TestShape& b = swap ? s1 : s2;
        CAPTURE(a.name, b.name, trial);
        PairCache cache;
        const DistanceResult r = closest_features(*a.geometry, p1, *b.geometry, p2, cache, 1000);
        REQUIRE(r.status != ContactStatus::kFailed);
        const double brute = brute_separation(a, p1, b, p2, rng);
        CAPTURE(r.distance, brute);
        if (r.status == ContactStatus::kPenetrating) {
          ++penetrating;
          // Overlapping: no direction separates them.
          CHECK(brute <= 1e-9);
          continue;
        }
        ++separated;
        // The closest points lie on the surfaces, the distance between them, along n.
        const double scale = 1.0;
        CHECK(std::abs(surface_excess(*a.shape, p1, r.p1_W)) <= 1e-12 * scale);
        CHECK(std::abs(surface_excess(*b.shape, p2, r.p2_W)) <= 1e-12 * scale);
        CHECK((r.p1_W - r.p2_W - r.distance * r.n_W).norm() <= 1e-12);
        CHECK(r.n_W.norm() == Approx(1.0).epsilon(1e-14));
        // n is a separating axis that certifies the distance (the lower bound along it equals
        // it), and brute force finds no better axis.
        const double along_n = separation(a, p1, b, p2, r.n_W);
        CHECK(r.distance - along_n <= 1e-11);
        CHECK(brute <= r.distance + 1e-11);
        CHECK(r.distance - brute <= 1e-12);
        worst_brute = std::max(worst_brute, std::abs(r.distance - brute));
        worst_gap = std::max(worst_gap, r.distance - along_n);
        worst_point = std::max({worst_point, std::abs(surface_excess(*a.shape, p1, r.p1_W)),
                                std::abs(surface_excess(*b.shape, p2, r.p2_W))});
        // Moved together past contact along n, they penetrate.
        p1.x_W -= (r.distance + 1e-3) * r.n_W;
        PairCache fresh;
        const DistanceResult over = closest_features(*a.geometry, p1, *b.geometry, p2, fresh, 1000);
        CHECK(over.status == ContactStatus::kPenetrating);
      }
    }
  }
  INFO("separated " << separated << ", penetrating " << penetrating << ", worst certificate gap "
                    << worst_gap << " m, worst surface excess " << worst_point << " m");
  CHECK(separated > 200);
  CHECK(penetrating > 50);
  WARN("smooth pairs: separated " << separated << ", penetrating " << penetrating
                                  << ", worst certificate gap " << worst_gap
                                  << " m, worst surface excess " << worst_point
                                  << " m, worst disagreement with brute force " << worst_brute
                                  << " m");
}

TEST_CASE("smooth shapes against a halfspace: closed form, either order", "[distance][smooth]") {
  std::mt19937_64 rng(1605);
  const TestShape ground = make_test_shape("ground", make_halfspace(Vec3::UnitZ(), 0.0));
  for (const TestShape& s : smooth_test_shapes()) {
    for (int trial = 0; trial < 200; ++trial) {
      CAPTURE(s.name, trial);
      Pose p = random_pose(rng, 1.0);
      // The lowest point by the definition of each shape, sampled densely: the support point must
      // be at least as low, and on the surface.
      const Vec3 low = support_W(*s.shape, p.x_W, p.q_WM, -Vec3::UnitZ());
      const double exact = low.z();
      for (bool swap : {false, true}) {
        PairCache cache;
        const DistanceResult r =
            swap ? closest_features(*ground.geometry, Pose{}, *s.geometry, p, cache, 100)
                 : closest_features(*s.geometry, p, *ground.geometry, Pose{}, cache, 100);
        const Vec3 n_expected = swap ? Vec3(-Vec3::UnitZ()) : Vec3(Vec3::UnitZ());
        if (exact > 0.0) {
          REQUIRE(r.status == ContactStatus::kSeparated);
          CHECK(r.distance == Approx(exact).margin(1e-15));
          CHECK((r.n_W - n_expected).norm() == 0.0);
          const Vec3& on_shape = swap ? r.p2_W : r.p1_W;
          CHECK(std::abs(surface_excess(*s.shape, p, on_shape)) <= 1e-14);
        } else {
          CHECK(r.status == ContactStatus::kPenetrating);
          CHECK(r.penetration_depth == Approx(-exact).margin(1e-15));
        }
      }
      // No surface point lies below the support point.
      std::normal_distribution<double> g(0.0, 1.0);
      for (int k = 0; k < 200; ++k) {
        const Vec3 u = Vec3(g(rng), g(rng), g(rng)).normalized();
        CHECK(support_W(*s.shape, p.x_W, p.q_WM, u).z() >= exact - 1e-15);
      }
    }
  }
}

TEST_CASE("smooth shapes across a box's face at tiny gaps: the face's normal, exactly",
          "[distance][smooth]") {
  // A cylinder lying across a long tilted box (6 m, a ramp) and an ellipsoid over it, at gaps
  // from 1e-12 to 1e-3 m, either order: where the round piece's lowest point against the face
  // lies over the face, the face gives the distance and normal in closed form. GJK alone took
  // its normal as a difference of two points a gap apart on bodies metres long: measured here
  // before, normals 1e-4 to 6e-4 rad off or failed queries (and in the cylinder-on-a-ramp scene,
  // stray microcollisions along normals 86 degrees off).
  const double th = 10.0 * 3.14159265358979323846 / 180.0;
  const Quat q_ramp(Eigen::AngleAxisd(th, Vec3::UnitY()));
  const Vec3 n = q_ramp * Vec3::UnitZ(), down = q_ramp * Vec3::UnitX();
  const TestShape ramp = make_test_shape("ramp", ConvexPolyhedron::box(Vec3(3.0, 0.5, 0.1)));
  const Pose ramp_pose{-0.1 * n, q_ramp};
  const TestShape cylinder = make_test_shape("cylinder", make_cylinder(0.05, 0.05));
  const TestShape egg = make_test_shape("egg", make_ellipsoid(Vec3(0.02, 0.03, 0.05)));
  for (const double gap : {1e-12, 1e-9, 1e-6, 1e-3}) {
    for (const double along : {-2.0, 0.0, 0.5, 2.9}) {
      for (int which = 0; which < 2; ++which) {
        CAPTURE(gap, along, which);
        const TestShape& s = which == 0 ? cylinder : egg;
        const Quat q = which == 0
                           ? Quat(Eigen::AngleAxisd(3.14159265358979323846 / 2, Vec3::UnitX()))
                           : Quat(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
        // Place it `gap` above the face along n, `along` down the slope.
        const Vec3 low = support_W(*s.shape, Vec3::Zero(), q, -n);
        const Pose pose{along * down - n.dot(low) * n + gap * n, q};
        for (bool swap : {false, true}) {
          PairCache cache;
          const DistanceResult r =
              swap ? closest_features(*ramp.geometry, ramp_pose, *s.geometry, pose, cache, 100)
                   : closest_features(*s.geometry, pose, *ramp.geometry, ramp_pose, cache, 100);
          REQUIRE(r.status == ContactStatus::kSeparated);
          CHECK(r.distance == Approx(gap).margin(1e-15));
          CHECK((r.n_W - (swap ? Vec3(-n) : n)).norm() <= 1e-15);
        }
      }
    }
  }
}

TEST_CASE("smooth shapes: patch of a cylinder's cap, a cylinder's and a capsule's side, a point",
          "[distance][smooth][patch]") {
  const TestShape ground = make_test_shape("ground", make_halfspace(Vec3::UnitZ(), 0.0));
  const TestShape disk = make_test_shape("disk", make_cylinder(0.4, 0.02));
  const TestShape capsule = make_test_shape("capsule", make_capsule(0.2, 0.35));
  const TestShape ellipsoid = make_test_shape("ellipsoid", make_ellipsoid(Vec3(0.3, 0.5, 0.7)));
  const double envelope = 1e-4;
  auto patch_of = [&](const TestShape& s, const Pose& pose) {
    PairCache cache;
    const DistanceResult r =
        closest_features(*s.geometry, pose, *ground.geometry, Pose{}, cache, 100);
    REQUIRE(r.status == ContactStatus::kSeparated);
    return contact_patch(*s.geometry, pose, *ground.geometry, Pose{}, r, envelope);
  };
  const double gap = 3e-5;
  SECTION("a disk flat on the ground: the inscribed 16-gon of its rim") {
    const std::vector<Vec3> patch = patch_of(disk, Pose{Vec3(1, 2, 0.02 + gap), Quat::Identity()});
    REQUIRE(patch.size() == 16);
    Vec3 centre = Vec3::Zero();
    for (const Vec3& x : patch) {
      CHECK(std::hypot(x.x() - 1, x.y() - 2) == Approx(0.4).epsilon(1e-12));
      CHECK(x.z() == Approx(0.0).margin(1e-15));
      centre += x / 16.0;
    }
    CHECK((centre - Vec3(1, 2, 0)).norm() <= 1e-12);
    // Counter-clockwise about the contact normal (up).
    CHECK((patch[1] - patch[0]).cross(patch[2] - patch[1]).z() > 0.0);
  }
  SECTION("a disk on its rim, axis horizontal: the side segment") {
    const Quat q(Eigen::AngleAxisd(0.5 * 3.14159265358979323846, Vec3::UnitX()));
    const std::vector<Vec3> patch = patch_of(disk, Pose{Vec3(0, 0, 0.4 + gap), q});
    REQUIRE(patch.size() == 2);
    CHECK(std::abs((patch[0] - patch[1]).norm() - 0.04) <= 1e-12);
    for (const Vec3& x : patch) CHECK(x.z() == Approx(0.0).margin(1e-15));
  }
  SECTION("a disk tilted beyond the envelope: one point") {
    const Quat q(Eigen::AngleAxisd(0.1, Vec3::UnitX()));
    Pose pose{Vec3::Zero(), q};
    pose.x_W.z() = -support_W(*disk.shape, Vec3::Zero(), q, -Vec3::UnitZ()).z() + gap;
    CHECK(patch_of(disk, pose).size() == 1);
  }
  SECTION("a capsule lying down: its side segment; standing: one point") {
    const Quat q(Eigen::AngleAxisd(0.5 * 3.14159265358979323846, Vec3::UnitY()));
    const std::vector<Vec3> lying = patch_of(capsule, Pose{Vec3(0, 0, 0.2 + gap), q});
    REQUIRE(lying.size() == 2);
    CHECK(std::abs((lying[0] - lying[1]).norm() - 0.7) <= 1e-12);
    CHECK(patch_of(capsule, Pose{Vec3(0, 0, 0.55 + gap), Quat::Identity()}).size() == 1);
  }
  SECTION("an ellipsoid: one point, at the support point") {
    const std::vector<Vec3> patch =
        patch_of(ellipsoid, Pose{Vec3(0, 0, 0.7 + gap), Quat::Identity()});
    REQUIRE(patch.size() == 1);
    CHECK((patch[0] - Vec3::Zero()).norm() <= 1e-15);
  }
}

TEST_CASE("smooth shapes: the radii the time-of-impact bound uses", "[distance][smooth]") {
  // A loaded ball's surface turns onto itself about its centre: rotation about the centre of mass
  // moves its support point no faster than the centre moves (|omega| |offset|); every other smooth
  // shape sweeps its whole radius.
  const TestShape ball = make_test_shape("loaded ball", make_loaded_ball(0.3, -0.1));
  CHECK(ball.geometry->rotation_radius() == Approx(0.1).epsilon(1e-15));
  CHECK(ball.geometry->reach() == Approx(0.4).epsilon(1e-15));
  const TestShape disk = make_test_shape("disk", make_cylinder(0.4, 0.3));
  CHECK(disk.geometry->rotation_radius() == Approx(0.5).epsilon(1e-15));
  CHECK(disk.geometry->reach() == Approx(0.5).epsilon(1e-15));
  // Along any direction, the support point of the ball rotated by a small angle moves at most
  // |offset| times the angle.
  std::mt19937_64 rng(1607);
  for (int k = 0; k < 1000; ++k) {
    const Quat q = random_rotation(rng);
    std::normal_distribution<double> g(0.0, 1.0);
    const Vec3 axis = Vec3(g(rng), g(rng), g(rng)).normalized();
    const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
    const double angle = 1e-3;
    const Quat q2 = Quat(Eigen::AngleAxisd(angle, axis)) * q;
    const double moved = d.dot(support_W(*ball.shape, Vec3::Zero(), q2, d)) -
                         d.dot(support_W(*ball.shape, Vec3::Zero(), q, d));
    CHECK(std::abs(moved) <= 0.1 * angle * (1 + 1e-9));
  }
}
