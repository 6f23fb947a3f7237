// Convex hulls from points: merged coplanar facets (exact face/edge/vertex counts), dropped
// interior and duplicate points, and rejection of inputs without a solid hull.
#include "core/convex_hull.hpp"

#include "core/check.hpp"
#include "core/shape.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

using namespace palpable;

namespace {

std::vector<Vec3> box_corners(const Vec3& half, const Vec3& centre, const Quat& q) {
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i) {
    const Vec3 c((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                 (i & 4) ? half.z() : -half.z());
    corners.push_back(centre + q * c);
  }
  return corners;
}

void require_counts(const ConvexPolyhedron& p, int v, int e, int f) {
  CHECK(static_cast<int>(p.vertices().size()) == v);
  CHECK(p.num_edges() == e);
  CHECK(static_cast<int>(p.faces().size()) == f);
}

}  // namespace

TEST_CASE("Box from its 8 corners has 6 faces, 12 edges, 8 vertices") {
  const Vec3 half(0.3, 0.5, 0.7);
  SECTION("axis-aligned, off-centre") {
    const auto p =
        ConvexPolyhedron::from_points(box_corners(half, Vec3(1, 2, 3), Quat::Identity()));
    require_counts(p, 8, 12, 6);
    CHECK(polyhedron_defect(p, 1e-12) == "");
    CHECK((p.com_shift_M() - Vec3(1, 2, 3)).norm() < 1e-14);
    for (const Vec3& v : p.vertices()) {
      CHECK((v.cwiseAbs() - half).norm() < 1e-14);
    }
  }
  SECTION("rotated: rounding makes the faces only nearly planar") {
    const Quat q = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
    const auto p = ConvexPolyhedron::from_points(box_corners(half, Vec3(-4, 5, 0.5), q));
    require_counts(p, 8, 12, 6);
    CHECK(polyhedron_defect(p, 1e-12) == "");
  }
}

TEST_CASE("Cube with interior, duplicate and edge/face-midpoint points keeps only the corners") {
  std::vector<Vec3> points = box_corners(Vec3(1, 1, 1), Vec3::Zero(), Quat::Identity());
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> u(-0.99, 0.99);
  for (int i = 0; i < 200; ++i) points.emplace_back(u(rng), u(rng), u(rng));
  for (int i = 0; i < 8; ++i) points.push_back(points[i]);  // duplicates
  points.emplace_back(1.0, 0.0, 0.0);                       // a face centre
  points.emplace_back(1.0, 1.0, 0.25);                      // on an edge
  points.emplace_back(0.5, -1.0, 0.5);                      // on a face
  const auto p = ConvexPolyhedron::from_points(points);
  require_counts(p, 8, 12, 6);
  CHECK(polyhedron_defect(p, 1e-12) == "");
  CHECK(p.com_shift_M().norm() < 1e-14);
}

TEST_CASE("Prism from points: 2n vertices, 3n edges, n + 2 faces") {
  for (int n : {3, 4, 5, 7, 16, 64}) {
    CAPTURE(n);
    std::vector<Vec3> points;
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * M_PI * k / n;
      points.emplace_back(0.4 * std::cos(a), 0.4 * std::sin(a), -0.1);
      points.emplace_back(0.4 * std::cos(a), 0.4 * std::sin(a), 0.1);
    }
    const auto p = ConvexPolyhedron::from_points(points);
    require_counts(p, 2 * n, 3 * n, n + 2);
    CHECK(polyhedron_defect(p, 1e-12) == "");
  }
}

TEST_CASE("Hull polygons of a tetrahedron are its four triangles") {
  const std::vector<Vec3> points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1),
                                    Vec3(0.1, 0.1, 0.1)};
  const HullPolygons hull = convex_hull_polygons(points, -1.0);
  REQUIRE(hull.faces.size() == 4);
  for (const auto& loop : hull.faces) CHECK(loop.size() == 3);
  for (std::size_t f = 0; f < 4; ++f) {
    for (int v : hull.faces[f]) CHECK(v != 4);
    CHECK(std::abs(hull.normals[f].norm() - 1.0) < 1e-15);
  }
}

TEST_CASE("Hulls reject inputs without a solid, saying why") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto message = [](const std::vector<Vec3>& points) {
    try {
      ConvexPolyhedron::from_points(points);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  using Catch::Matchers::Contains;
  CHECK_THAT(message({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, nan)}),
             Contains("points/3") && Contains("non-finite"));
  CHECK_THAT(message({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}),
             Contains("at least 4 points, got 3"));
  CHECK_THAT(
      message({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(0.3, 0.2, 0)}),
      Contains("coplanar"));
  CHECK_THAT(message({Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(-1, -1, -1)}),
             Contains("collinear"));
  CHECK_THAT(message(std::vector<Vec3>(6, Vec3(1, 2, 3))), Contains("identical"));
  // Thinner than the coplanarity tolerance counts as coplanar.
  CHECK_THAT(message({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 1e-12)}),
             Contains("coplanar"));
}

TEST_CASE("Many points on the faces of a rotated box merge into its 6 faces") {
  const std::uint64_t seed = 4242;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    CAPTURE(seed, trial);
    const Vec3 half(0.5 + 0.4 * u(rng), 0.5 + 0.4 * u(rng), 0.5 + 0.4 * u(rng));
    const Quat q = Quat(u(rng), u(rng), u(rng), u(rng)).normalized();
    const Vec3 centre(3 * u(rng), 3 * u(rng), 3 * u(rng));
    std::vector<Vec3> points = box_corners(half, centre, q);
    for (int i = 0; i < 300; ++i) {
      Vec3 local(u(rng) * half.x(), u(rng) * half.y(), u(rng) * half.z());
      const int axis = i % 3;
      local[axis] = (i % 2 ? 1.0 : -1.0) * half[axis];
      points.push_back(centre + q * local);
    }
    const auto p = ConvexPolyhedron::from_points(points);
    require_counts(p, 8, 12, 6);
    CHECK(polyhedron_defect(p, 1e-12) == "");
    CHECK((p.com_shift_M() - centre).norm() < 1e-13);
  }
}

TEST_CASE("Hull of points on a sphere is a valid triangulated-or-merged mesh") {
  std::mt19937_64 rng(8);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 2000; ++i) points.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
  const auto p = ConvexPolyhedron::from_points(points);
  CHECK(polyhedron_defect(p, 1e-9 * 2 * std::sqrt(3.0)) == "");
  CHECK(p.vertices().size() == 2000);
  CHECK(p.max_radius() <= 1.0 + 1e-3);
}

TEST_CASE("Noise below the coplanarity tolerance is merged away, above it, faces stay apart") {
  const std::uint64_t seed = 99;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::vector<Vec3> corners = box_corners(Vec3(1, 1, 1), Vec3::Zero(), Quat::Identity());
  // Default tolerance: 1e-9 times the diagonal 2 sqrt(3).
  for (double noise : {1e-12, 1e-10}) {
    CAPTURE(seed, noise);
    std::vector<Vec3> points = corners;
    for (int i = 0; i < 60; ++i) {
      Vec3 p(0.9 * u(rng), 0.9 * u(rng), 0.9 * u(rng));
      p[i % 3] = (i % 2 ? 1.0 : -1.0) * (1.0 + noise * std::abs(u(rng)));  // slightly outside
      points.push_back(p);
    }
    const auto p = ConvexPolyhedron::from_points(points);
    require_counts(p, 8, 12, 6);
    CHECK(polyhedron_defect(p, 1e-9 * 2 * std::sqrt(3.0)) == "");
  }
  // A face point raised by 1e-3 (far above the tolerance) is a real apex: 4 triangles replace
  // the top face.
  std::vector<Vec3> points = corners;
  points.emplace_back(0.0, 0.0, 1.001);
  const auto p = ConvexPolyhedron::from_points(points);
  require_counts(p, 9, 16, 9);
  CHECK(polyhedron_defect(p, 1e-12) == "");
  // With an explicit tolerance above the rise, the apex is merged into the top face.
  const auto flat = ConvexPolyhedron::from_points(points, 2e-3);
  require_counts(flat, 8, 12, 6);
  CHECK(polyhedron_defect(flat, 2e-3) == "");
}

TEST_CASE("An oversized coplanarity tolerance still yields a valid hull") {
  const std::uint64_t seed = 123;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  for (double tolerance : {0.05, 0.2, 0.5}) {
    CAPTURE(seed, tolerance);
    std::vector<Vec3> points;
    for (int i = 0; i < 300; ++i) points.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
    const auto p = ConvexPolyhedron::from_points(points, tolerance);
    CHECK(polyhedron_defect(p, tolerance) == "");
    // Facets were merged (the merged mesh closed, no fall-back to Qhull's facets).
    CHECK(p.faces().size() < ConvexPolyhedron::from_points(points).faces().size());
    for (const Vec3& q : points) {
      for (const PolyFace& f : p.faces()) {
        CHECK(f.normal_M.dot(q - p.com_shift_M()) - f.offset <= tolerance);
      }
    }
  }
}

TEST_CASE("Fuzz: varied clouds, scales and positions give valid recentred hulls") {
  // Sphere points, noisy box faces, clipped clouds, noisy coins, integer lattices (many exactly
  // coplanar and collinear points); sizes 1e-3..1e3 m at positions up to 5e3 m.
  const std::uint64_t seed = 2026;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g(0, 1);
  int rejected = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const int kind = trial % 5;
    const int n = 4 + static_cast<int>(rng() % 200);
    const Quat q = Quat(g(rng), g(rng), g(rng), g(rng)).normalized();
    const double noise = std::pow(10.0, -6.0 - static_cast<double>(rng() % 10));
    const double scale = std::pow(10.0, static_cast<double>(rng() % 7) - 3.0);
    const Vec3 position = Vec3(5, -3, 2) * std::pow(10.0, static_cast<double>(rng() % 4));
    CAPTURE(seed, trial, kind, n, noise, scale);
    std::vector<Vec3> points;
    for (int i = 0; i < n; ++i) {
      Vec3 p;
      if (kind == 0) {
        p = Vec3(g(rng), g(rng), g(rng)).normalized();
      } else if (kind == 1) {
        p = Vec3(u(rng), u(rng), u(rng));
        p[i % 3] = (i % 2 ? 1 : -1) * (1 + noise * u(rng));
      } else if (kind == 2) {
        p = Vec3(u(rng), u(rng), u(rng))
                .cwiseMax(Vec3::Constant(-0.5))
                .cwiseMin(Vec3::Constant(0.7));
      } else if (kind == 3) {
        const double a = 2 * M_PI * (i / 2) / (n / 2 + 1);
        p = Vec3(std::cos(a), std::sin(a), (i % 2 ? 0.1 : -0.1) + noise * u(rng));
      } else {
        p = Vec3(std::round(u(rng) * 3), std::round(u(rng) * 3), std::round(u(rng) * 3));
      }
      points.push_back(position + q * (scale * p));
    }
    Vec3 lo = points[0], hi = points[0];
    for (const Vec3& p : points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    try {
      const auto p = ConvexPolyhedron::from_points(points);
      CHECK(polyhedron_defect(p, 1e-9 * (hi - lo).norm()) == "");
    } catch (const InputError& e) {
      // Only genuinely flat inputs (tiny lattices or coins can be) may be refused.
      const std::string what = e.what();
      CAPTURE(what);
      CHECK((what.find("coplanar") != std::string::npos ||
             what.find("collinear") != std::string::npos));
      ++rejected;
    }
  }
  CAPTURE(rejected);
  CHECK(rejected < 50);
}

namespace {
// A triangulated sphere (rings x segments), each triangle counter-clockwise about its outward
// normal; `dent` moves one vertex of the middle ring to that fraction of the radius.
ConvexPolyhedron uv_sphere(int rings, int segments, double dent) {
  const double pi = 3.14159265358979323846;
  std::vector<Vec3> v{Vec3(0, 0, 1)};
  for (int k = 1; k < rings; ++k) {
    for (int j = 0; j < segments; ++j) {
      const double theta = pi * k / rings, phi = 2 * pi * j / segments;
      v.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                     std::cos(theta));
    }
  }
  v.emplace_back(0, 0, -1);
  const int south = static_cast<int>(v.size()) - 1;
  auto ring = [&](int k, int j) { return 1 + (k - 1) * segments + (j % segments); };
  std::vector<std::vector<int>> faces;
  auto add = [&](int a, int b, int c) {
    const Vec3 n = (v[b] - v[a]).cross(v[c] - v[a]);
    if (n.dot(v[a] + v[b] + v[c]) > 0) {
      faces.push_back({a, b, c});
    } else {
      faces.push_back({a, c, b});
    }
  };
  for (int j = 0; j < segments; ++j) {
    add(0, ring(1, j), ring(1, j + 1));
    add(south, ring(rings - 1, j), ring(rings - 1, j + 1));
    for (int k = 1; k + 1 < rings; ++k) {
      add(ring(k, j), ring(k + 1, j), ring(k + 1, j + 1));
      add(ring(k, j), ring(k + 1, j + 1), ring(k, j + 1));
    }
  }
  v[ring(rings / 2, 0)] *= dent;
  return ConvexPolyhedron::from_faces(v, faces, 1e-9);
}
}  // namespace

TEST_CASE("a large mesh is validated by local checks: convex passes, a dent is refused",
          "[core][hull][hostile]") {
  // 7,082 vertices x 14,160 faces: past the exhaustive check's budget.
  const ConvexPolyhedron p = uv_sphere(60, 120, 1.0);
  CHECK(p.vertices().size() == 7082);
  CHECK(polyhedron_defect(p, 1e-9) == "");
  CHECK_THROWS_WITH(uv_sphere(60, 120, 0.99), Catch::Contains("outside a face plane"));
  // The same on a small mesh, through the exhaustive check.
  CHECK_NOTHROW(uv_sphere(6, 8, 1.0));
  CHECK_THROWS_WITH(uv_sphere(6, 8, 0.9), Catch::Contains("outside a face plane"));
}

TEST_CASE("the hull of 200,000 points is built and validated in seconds", "[core][hull][hostile]") {
  std::mt19937_64 rng(20);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 200000; ++i) points.push_back(Vec3(n(rng), n(rng), n(rng)).normalized());
  const ConvexPolyhedron p = ConvexPolyhedron::from_points(points);
  CHECK(p.vertices().size() > 100000);
}
