// Shapes: half-edge invariants of built polyhedra, support points and radii against brute force,
// bounding boxes, and validation of bad sizes.
#include "core/shape.hpp"
#include "core_test_support.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

using namespace palpable;

namespace {

using palpable::test::input_error;

Vec3 brute_support(const ConvexPolyhedron& p, const Vec3& d) {
  double best = -kInfinity;
  Vec3 arg = Vec3::Zero();
  for (const Vec3& v : p.vertices()) {
    if (d.dot(v) > best) {
      best = d.dot(v);
      arg = v;
    }
  }
  return arg;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Quat(g(rng), g(rng), g(rng), g(rng)).normalized();
}

}  // namespace

TEST_CASE("box() and prism() are valid meshes with exact counts and planes") {
  const auto box = ConvexPolyhedron::box(Vec3(0.1, 0.2, 0.3));
  CHECK(box.vertices().size() == 8);
  CHECK(box.num_edges() == 12);
  CHECK(box.faces().size() == 6);
  CHECK(polyhedron_defect(box, 0.0) == "");
  CHECK(box.max_radius() == Approx(std::sqrt(0.01 + 0.04 + 0.09)).epsilon(1e-15));
  for (int n : {3, 4, 6, 17, 100}) {
    CAPTURE(n);
    const auto p = ConvexPolyhedron::prism(0.5, 0.25, n);
    CHECK(static_cast<int>(p.vertices().size()) == 2 * n);
    CHECK(p.num_edges() == 3 * n);
    CHECK(static_cast<int>(p.faces().size()) == n + 2);
    CHECK(polyhedron_defect(p, 1e-15) == "");
    CHECK(p.vertices()[n].x() == 0.5);  // first top vertex at +x
    CHECK(p.max_radius() == Approx(std::hypot(0.5, 0.25)).epsilon(1e-15));
  }
}

TEST_CASE("Random point clouds give valid hulls, support and max_radius match brute force") {
  const std::uint64_t seed = 977;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 60; ++trial) {
    const int n = 4 + trial * 5;
    CAPTURE(seed, trial, n);
    std::vector<Vec3> points;
    const Vec3 offset(u(rng) * 5, u(rng) * 5, u(rng) * 5);
    const Vec3 scale(0.2 + std::abs(u(rng)), 0.2 + std::abs(u(rng)), 0.2 + std::abs(u(rng)));
    for (int i = 0; i < n; ++i) {
      points.push_back(offset + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(scale));
    }
    const auto p = ConvexPolyhedron::from_points(points);
    const double tol = 1e-9 * 4.0;
    REQUIRE(polyhedron_defect(p, tol) == "");
    const int V = static_cast<int>(p.vertices().size());
    CHECK(V - p.num_edges() + static_cast<int>(p.faces().size()) == 2);
    // Every input point (shifted) is inside or on the hull.
    for (const Vec3& q : points) {
      for (const PolyFace& f : p.faces()) {
        CHECK(f.normal_M.dot(q - p.com_shift_M()) - f.offset <= tol);
      }
    }
    // Explicit half-edge invariants (also inside polyhedron_defect).
    const auto& hs = p.half_edges();
    for (int h = 0; h < static_cast<int>(hs.size()); ++h) {
      CHECK(hs[hs[h].twin].twin == h);
      CHECK(hs[hs[h].next].prev == h);
      CHECK(hs[hs[h].next].face == hs[h].face);
      CHECK(&p.head(h) == &p.tail(hs[h].next));
    }
    double r = 0.0;
    for (const Vec3& v : p.vertices()) r = std::max(r, v.norm());
    CHECK(p.max_radius() == r);
    CHECK(max_radius(Shape(p)) == r);
    for (int k = 0; k < 20; ++k) {
      const Vec3 d = random_unit(rng);
      CHECK(d.dot(p.support(d)) == d.dot(brute_support(p, d)));
    }
  }
}

TEST_CASE("support_W and bounding_box_W of posed shapes") {
  std::mt19937_64 rng(31);
  const Shape poly = ConvexPolyhedron::from_points(
      {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 3), Vec3(1, 1, 1)});
  const Shape sphere = make_sphere(0.5);
  for (int trial = 0; trial < 20; ++trial) {
    CAPTURE(trial);
    const Quat q = random_rotation(rng);
    const Vec3 p(1.0, -2.0, 0.5);
    for (const Shape* shape : {&poly, &sphere}) {
      const Aabb box = bounding_box_W(*shape, p, q);
      for (int k = 0; k < 3; ++k) {
        const Vec3 e = Vec3::Unit(k);
        const Vec3 hi = support_W(*shape, p, q, e);
        const Vec3 lo = support_W(*shape, p, q, -e);
        // Tight: the box faces touch the support points (the box is built from the same
        // vertices, so equal up to the rounding of rotating them).
        CHECK(hi[k] == Approx(box.max_W[k]).margin(1e-15));
        CHECK(lo[k] == Approx(box.min_W[k]).margin(1e-15));
        CHECK(hi[k] <= box.max_W[k] + 1e-15);
        CHECK(lo[k] >= box.min_W[k] - 1e-15);
      }
    }
    // The polyhedron's support in world agrees with brute force over its posed vertices.
    const auto& ph = std::get<ConvexPolyhedron>(poly);
    const Vec3 d = random_unit(rng);
    double best = -kInfinity;
    for (const Vec3& v : ph.vertices()) best = std::max(best, d.dot(p + q * v));
    CHECK(d.dot(support_W(poly, p, q, d)) == Approx(best).margin(1e-14));
  }
  const Vec3 s = support_W(sphere, Vec3(1, 2, 3), Quat::Identity(), Vec3(0, 0, 2));
  CHECK((s - Vec3(1, 2, 3.5)).norm() == 0.0);
  CHECK_THROWS_AS(support_W(Shape(make_halfspace(Vec3::UnitZ(), 0.0)), Vec3::Zero(),
                            Quat::Identity(), Vec3::UnitZ()),
                  InvariantError);
}

TEST_CASE("Halfspace bounding boxes are finite on one side only when axis-aligned") {
  const Shape ground = make_halfspace(Vec3(0, 0, 2), 0.5);  // z <= 0.5 in M
  const Aabb a = bounding_box_W(ground, Vec3(0, 0, 1), Quat::Identity());
  CHECK(a.max_W.z() == 1.5);
  CHECK(a.min_W.z() == -kInfinity);
  CHECK(a.min_W.x() == -kInfinity);
  CHECK(a.max_W.x() == kInfinity);
  const Shape wall = make_halfspace(Vec3(-1, 0, 0), 2.0);  // x >= -2
  const Aabb b = bounding_box_W(wall, Vec3::Zero(), Quat::Identity());
  CHECK(b.min_W.x() == -2.0);
  CHECK(b.max_W.x() == kInfinity);
  const Shape tilted = make_halfspace(Vec3(1, 0, 1), 0.0);
  const Aabb c = bounding_box_W(tilted, Vec3::Zero(), Quat::Identity());
  CHECK(c.max_W.z() == kInfinity);
  CHECK(c.max_W.x() == kInfinity);
  CHECK(!is_bounded(ground));
  CHECK(max_radius(ground) == kInfinity);
}

TEST_CASE("Compounds: validated parts, union bounding box, radius") {
  auto ball = std::make_shared<const Shape>(make_sphere(0.5));
  auto cube = std::make_shared<const Shape>(ConvexPolyhedron::box(Vec3(1, 1, 1)));
  const Quat quarter(Eigen::AngleAxisd(M_PI / 4, Vec3::UnitZ()));
  const Compound c =
      make_compound({{ball, Vec3(3, 0, 0), Quat::Identity()}, {cube, Vec3(-2, 0, 0), quarter}});
  const Shape shape = c;
  CHECK(is_bounded(shape));
  // Tight: the cube's farthest corner, turned 45 degrees about z, is at (-2 - sqrt 2, 0, +-1).
  CHECK(max_radius(shape) == Approx(std::hypot(2.0 + std::sqrt(2.0), 1.0)).epsilon(1e-15));
  const Aabb box = bounding_box_W(shape, Vec3(0, 0, 1), Quat::Identity());
  CHECK(box.max_W.x() == Approx(3.5));
  CHECK(box.min_W.x() == Approx(-2.0 - std::sqrt(2.0)));
  CHECK(box.max_W.z() == Approx(2.0));
  CHECK(box.min_W.z() == Approx(0.0).margin(1e-15));
  using Catch::Matchers::Contains;
  auto plane = std::make_shared<const Shape>(make_halfspace(Vec3::UnitZ(), 0.0));
  CHECK_THAT(input_error([&] {
               make_compound({{plane, Vec3::Zero(), Quat::Identity()}});
             }),
             Contains("parts/0") && Contains("convex bounded shape"));
  CHECK_THAT(input_error([&] { make_compound({}); }), Contains("at least one part"));
  CHECK_THAT(input_error([&] {
               make_compound({{nullptr, Vec3::Zero(), Quat::Identity()}});
             }),
             Contains("no shape"));
  CHECK_THAT(input_error([&] {
               make_compound({{ball, Vec3::Zero(), Quat::Identity()},
                              {ball, Vec3::Zero(), Quat(2, 0, 0, 0)}});
             }),
             Contains("parts/1/orientation"));
}

TEST_CASE("Bad sizes are rejected with the argument named") {
  using Catch::Matchers::Contains;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(input_error([] { ConvexPolyhedron::box(Vec3(1, 0, 1)); }),
             Contains("half_extents") && Contains("positive"));
  CHECK_THAT(input_error([] { ConvexPolyhedron::box(Vec3(1, -1, 1)); }), Contains("half_extents"));
  CHECK_THAT(input_error([&] { ConvexPolyhedron::box(Vec3(1, nan, 1)); }),
             Contains("half_extents"));
  CHECK_THAT(input_error([] { ConvexPolyhedron::prism(1.0, 1.0, 2); }),
             Contains("sides") && Contains("at least 3"));
  CHECK_THAT(input_error([] { ConvexPolyhedron::prism(0.0, 1.0, 5); }), Contains("radius"));
  CHECK_THAT(input_error([] { ConvexPolyhedron::prism(1.0, -1.0, 5); }), Contains("half_height"));
  CHECK_THAT(input_error([] { make_sphere(0.0); }), Contains("radius") && Contains("positive"));
  CHECK_THAT(input_error([] { make_sphere(-1.0); }), Contains("radius"));
  CHECK_THAT(input_error([] { make_halfspace(Vec3::Zero(), 0.0); }), Contains("normal"));
  CHECK_THAT(input_error([&] { make_halfspace(Vec3::UnitZ(), nan); }), Contains("offset"));
  const Halfspace h = make_halfspace(Vec3(0, 3, 4), 1.0);
  CHECK((h.normal_M - Vec3(0, 0.6, 0.8)).norm() < 1e-16);
}

TEST_CASE("from_faces validates orientation, closure and convexity") {
  const std::vector<Vec3> v = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const auto tet =
      ConvexPolyhedron::from_faces(v, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, 1e-12);
  CHECK(polyhedron_defect(tet, 1e-12) == "");
  CHECK(tet.num_edges() == 6);
  using Catch::Matchers::Contains;
  CHECK_THAT(input_error([&] {
               ConvexPolyhedron::from_faces(v, {{0, 1, 2}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, 1e-12);
             }),
             Contains("faces"));
  CHECK_THAT(input_error([&] {
               ConvexPolyhedron::from_faces(v, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}}, 1e-12);
             }),
             Contains("faces"));
  // Inward-facing normals (every loop reversed) are closed and consistent but not outward.
  CHECK_THAT(input_error([&] {
               ConvexPolyhedron::from_faces(v, {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}, 1e-12);
             }),
             Contains("outside"));
}

namespace {

// Inside tests of the smooth shapes (in M), independent of their support functions.
double smooth_excess(const Shape& shape, const Vec3& x) {
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    return (x - e->centre_M()).cwiseQuotient(e->semi_axes_M).norm() - 1.0;  // relative
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    return std::max(std::hypot(x.x(), x.y()) - c->radius, std::abs(x.z()) - c->half_height);
  }
  if (const auto* c = std::get_if<Capsule>(&shape)) {
    const double z = std::clamp(x.z(), -c->half_length, c->half_length);
    return (x - Vec3(0, 0, z)).norm() - c->radius;
  }
  const auto& b = std::get<LoadedBall>(shape);
  return (x - b.centre_M()).norm() - b.radius;
}

// Dense points of the smooth shape's surface (for brute-force maxima): surface points along rays
// from the shape's centre, found by bisection on the inside test.
std::vector<Vec3> smooth_surface_samples(const Shape& shape, int count, std::mt19937_64& rng) {
  Vec3 centre = Vec3::Zero();
  if (const auto* b = std::get_if<LoadedBall>(&shape)) centre = b->centre_M();
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) centre = e->centre_M();
  std::vector<Vec3> out;
  for (int k = 0; k < count; ++k) {
    const Vec3 u = random_unit(rng);
    double lo = 0.0, hi = 2.0 * max_radius(shape);
    for (int it = 0; it < 80; ++it) {
      const double mid = 0.5 * (lo + hi);
      (smooth_excess(shape, centre + mid * u) <= 0.0 ? lo : hi) = mid;
    }
    out.push_back(centre + lo * u);
  }
  return out;
}

}  // namespace

TEST_CASE("Smooth shapes: validated builders name the bad argument") {
  CHECK_THAT(input_error([] { make_ellipsoid(Vec3(1, 0, 1)); }), Catch::Contains("semi_axes"));
  CHECK_THAT(input_error([] { make_ellipsoid(Vec3(1, kInfinity, 1)); }),
             Catch::Contains("semi_axes"));
  CHECK_THAT(input_error([] { make_cylinder(-1.0, 1.0); }), Catch::Contains("radius"));
  CHECK_THAT(input_error([] { make_cylinder(1.0, std::nan("")); }), Catch::Contains("half_height"));
  CHECK_THAT(input_error([] { make_capsule(0.0, 1.0); }), Catch::Contains("radius"));
  CHECK_THAT(input_error([] { make_capsule(1.0, -2.0); }), Catch::Contains("half_length"));
  CHECK_THAT(input_error([] { make_loaded_ball(-1.0, 0.0); }), Catch::Contains("radius"));
  CHECK_THAT(input_error([] { make_loaded_ball(1.0, 1.0); }), Catch::Contains("com_offset"));
  CHECK_THAT(input_error([] { make_loaded_ball(1.0, -1.5); }), Catch::Contains("com_offset"));
  CHECK(input_error([] { make_loaded_ball(1.0, -0.5); }) == "accepted");
  // An ellipsoid's centre of mass lies within its z semi-axis of its centre.
  CHECK_THAT(input_error([] { make_ellipsoid(Vec3(3, 2, 1), 1.0); }),
             Catch::Contains("com_offset"));
  CHECK_THAT(input_error([] { make_ellipsoid(Vec3(3, 2, 1), -1.5); }),
             Catch::Contains("com_offset"));
  CHECK_THAT(input_error([] { make_ellipsoid(Vec3(3, 2, 1), std::nan("")); }),
             Catch::Contains("com_offset"));
  CHECK(input_error([] { make_ellipsoid(Vec3(3, 2, 1), -0.9); }) == "accepted");
  // Smooth shapes may be compound parts.
  CompoundPart part;
  part.shape = std::make_shared<const Shape>(make_cylinder(1.0, 0.1));
  CHECK(input_error([&] { make_compound({part}); }) == "accepted");
}

TEST_CASE("Smooth shapes: exact support, radius and tight world box against brute force") {
  std::mt19937_64 rng(1601);
  const std::vector<Shape> shapes = {make_ellipsoid(Vec3(0.3, 0.5, 0.7)), make_cylinder(0.4, 0.05),
                                     make_capsule(0.2, 0.35), make_loaded_ball(0.25, 0.07),
                                     make_ellipsoid(Vec3(0.3, 0.5, 0.2), -0.15)};
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    CAPTURE(s);
    const Shape& shape = shapes[s];
    CHECK(is_bounded(shape));
    CHECK(is_smooth_convex(shape));
    const std::vector<Vec3> samples = smooth_surface_samples(shape, 20000, rng);
    // The support point lies on the shape and no sample lies beyond it: exact, not an estimate.
    for (int k = 0; k < 200; ++k) {
      const Vec3 d = random_unit(rng);
      const Vec3 p = smooth_support_M(shape, d);
      CHECK(std::abs(smooth_excess(shape, p)) <= 1e-14);
      double best = -kInfinity;
      for (const Vec3& x : samples) best = std::max(best, d.dot(x));
      CHECK(d.dot(p) >= best - 1e-12);
    }
    // Axis-aligned directions (a cylinder's flat cap, a capsule's pole): still on the shape.
    for (int k = 0; k < 3; ++k) {
      for (double sign : {-1.0, 1.0}) {
        const Vec3 p = smooth_support_M(shape, sign * Vec3::Unit(k));
        CHECK(std::abs(smooth_excess(shape, p)) <= 1e-14);
      }
    }
    // The radius about the centre of mass bounds every point and is reached (within the
    // samples' spacing).
    double far = 0.0;
    for (const Vec3& x : samples) far = std::max(far, x.norm());
    CHECK(far <= max_radius(shape) * (1 + 1e-15));
    // (An ellipsoid off its centre of mass: a bound only, sqrt(a_max^2 + 2 |o| a_z + o^2).)
    const auto* e = std::get_if<Ellipsoid>(&shape);
    if (!(e && e->com_offset != 0.0)) CHECK(far >= max_radius(shape) * (1 - 2e-2));
    // The world box is tight: its faces are the support points along the axes.
    for (int trial = 0; trial < 10; ++trial) {
      const Quat q = random_rotation(rng);
      const Vec3 p(0.3, -1.0, 2.0);
      const Aabb box = bounding_box_W(shape, p, q);
      for (int k = 0; k < 3; ++k) {
        CHECK(support_W(shape, p, q, Vec3::Unit(k))[k] == Approx(box.max_W[k]).margin(1e-14));
        CHECK(support_W(shape, p, q, -Vec3::Unit(k))[k] == Approx(box.min_W[k]).margin(1e-14));
      }
    }
  }
  CHECK(max_radius(Shape(make_cylinder(0.4, 0.3))) == Approx(0.5).epsilon(1e-15));
  CHECK(max_radius(Shape(make_loaded_ball(0.25, -0.07))) == Approx(0.32).epsilon(1e-15));
  CHECK(max_radius(Shape(make_ellipsoid(Vec3(0.3, 0.5, 0.2), -0.15))) ==
        Approx(std::sqrt(0.25 + 2 * 0.15 * 0.2 + 0.0225)).epsilon(1e-15));
  // Equal semi-axes: a loaded ball's reach.
  CHECK(max_radius(Shape(make_ellipsoid(Vec3(0.25, 0.25, 0.25), 0.07))) ==
        Approx(0.32).epsilon(1e-15));
}

TEST_CASE("Smooth shapes: the support point's derivative matches a central difference") {
  // The oracle: differences of the exact support point along random directions. The derivative
  // is symmetric and annihilates the direction (the support function is homogeneous of degree 1).
  std::mt19937_64 rng(1602);
  const std::vector<Shape> shapes = {make_ellipsoid(Vec3(0.3, 0.5, 0.7)), make_cylinder(0.4, 0.05),
                                     make_capsule(0.2, 0.35), make_loaded_ball(0.25, 0.07),
                                     make_ellipsoid(Vec3(0.3, 0.5, 0.2), -0.15)};
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    CAPTURE(s);
    const Shape& shape = shapes[s];
    for (int k = 0; k < 100; ++k) {
      const Vec3 d = random_unit(rng);
      const Mat3 H = smooth_support_derivative_M(shape, d);
      CHECK((H - H.transpose()).norm() <= 1e-14 * (1.0 + H.norm()));
      CHECK((H * d).norm() <= 1e-14 * (1.0 + H.norm()));
      const double h = 1e-6;
      for (int j = 0; j < 3; ++j) {
        const Vec3 e = Vec3::Unit(j);
        const Vec3 fd =
            (smooth_support_M(shape, d + h * e) - smooth_support_M(shape, d - h * e)) / (2.0 * h);
        CHECK((H * e - fd).norm() <= 1e-6 * (1.0 + H.norm()));
      }
    }
  }
  // A cylinder's cap or side direction has no unique smooth support point: zero.
  const Shape cylinder = make_cylinder(0.4, 0.05);
  CHECK(smooth_support_derivative_M(cylinder, Vec3::UnitZ()).norm() == 0.0);
  CHECK(smooth_support_derivative_M(cylinder, Vec3::UnitX()).norm() == 0.0);
  // On a rim: rank one, r / |d_xy| along the rim's tangent.
  const Vec3 d = Vec3(0.6, 0.0, -0.8);
  const Mat3 H = smooth_support_derivative_M(cylinder, d);
  CHECK(H(1, 1) == Approx(0.4 / 0.6).epsilon(1e-15));
  CHECK(H.norm() == Approx(0.4 / 0.6).epsilon(1e-15));
}
