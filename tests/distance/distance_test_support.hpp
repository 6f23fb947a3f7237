#pragma once
// Shared by the distance tests: the test shapes, random poses, and a brute-force reference
// distance (minimum over all feature pairs with exact segment-segment and point-polygon
// distances).
#include "core/point_sets.hpp"
#include "core/shape.hpp"
#include "distance/closest_features.hpp"
#include "distance/vclip.hpp"

#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace palpable::test {

struct TestShape {
  std::string name;
  std::shared_ptr<const Shape> shape;
  std::shared_ptr<const ShapeGeometry> geometry;
};

inline TestShape make_test_shape(std::string name, Shape shape) {
  auto s = std::make_shared<const Shape>(std::move(shape));
  return {std::move(name), s, std::make_shared<const ShapeGeometry>(s)};
}

inline TestShape cube() {
  return make_test_shape("cube", ConvexPolyhedron::box(Vec3(0.5, 0.5, 0.5)));
}
inline TestShape tetrahedron() {
  return make_test_shape("tetrahedron",
                         ConvexPolyhedron::from_points(
                             {{0.0, 0.0, 0.0}, {1.0, 0.1, 0.0}, {0.2, 0.9, 0.1}, {0.3, 0.2, 0.8}}));
}
inline TestShape hull1280() {
  return make_test_shape("hull1280", ConvexPolyhedron::from_points(icosphere_points(3, 0.7)));
}
inline TestShape coin() {
  return make_test_shape("coin", ConvexPolyhedron::prism(0.6, 0.003, 32));
}
inline TestShape sliver() {
  return make_test_shape("sliver", ConvexPolyhedron::box(Vec3(0.5, 0.005, 0.005)));
}
inline TestShape ball() {
  return make_test_shape("sphere", Sphere{0.4});
}

inline Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Quat q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized();
}

inline Pose random_pose(std::mt19937_64& rng, double half_box) {
  std::uniform_real_distribution<double> u(-half_box, half_box);
  return {Vec3(u(rng), u(rng), u(rng)), random_rotation(rng)};
}

// A posed polyhedron (or sphere) in world coordinates, for the brute-force reference.
struct WorldConvex {
  bool sphere = false;
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  std::vector<Vec3> vertices;
  std::vector<std::pair<int, int>> edges;
  std::vector<std::vector<int>> faces;
  std::vector<Vec3> normals;
  std::vector<double> offsets;
};

inline WorldConvex to_world(const Shape& shape, const Pose& pose) {
  WorldConvex w;
  const Mat3 R = pose.q_WM.toRotationMatrix();
  if (const auto* s = std::get_if<Sphere>(&shape)) {
    w.sphere = true;
    w.center = pose.x_W;
    w.radius = s->radius;
    return w;
  }
  const auto& p = std::get<ConvexPolyhedron>(shape);
  for (const Vec3& v : p.vertices()) w.vertices.push_back(pose.x_W + R * v);
  const auto& he = p.half_edges();
  for (int h = 0; h < static_cast<int>(he.size()); ++h) {
    if (h < he[h].twin) w.edges.emplace_back(he[h].tail, he[he[h].twin].tail);
  }
  for (const PolyFace& f : p.faces()) {
    std::vector<int> loop;
    int h = f.half_edge;
    do {
      loop.push_back(he[h].tail);
      h = he[h].next;
    } while (h != f.half_edge);
    w.faces.push_back(loop);
    const Vec3 n = R * f.normal_M;
    w.normals.push_back(n);
    w.offsets.push_back(f.offset + n.dot(pose.x_W));
  }
  return w;
}

// Distance from x to face `f` if x projects inside it, else +inf (the boundary is covered by the
// point-segment distances).
inline double point_face_distance(const WorldConvex& w, int f, const Vec3& x) {
  const auto& loop = w.faces[f];
  const Vec3& n = w.normals[f];
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Vec3& a = w.vertices[loop[i]];
    const Vec3& b = w.vertices[loop[(i + 1) % loop.size()]];
    if (n.cross(b - a).dot(x - a) < 0.0) return kInfinity;
  }
  return std::abs(n.dot(x) - w.offsets[f]);
}

// Largest signed face-plane value at x (<= 0 inside the polyhedron).
inline double max_face_eval(const WorldConvex& w, const Vec3& x) {
  double m = -kInfinity;
  for (std::size_t f = 0; f < w.faces.size(); ++f)
    m = std::max(m, w.normals[f].dot(x) - w.offsets[f]);
  return m;
}

// Distance from a point to a polyhedron's surface (exact, all features).
inline double point_polyhedron_distance(const WorldConvex& w, const Vec3& x) {
  double best = kInfinity;
  for (std::size_t f = 0; f < w.faces.size(); ++f)
    best = std::min(best, point_face_distance(w, f, x));
  for (const auto& e : w.edges) {
    best = std::min(
        best, (closest_point_segment(w.vertices[e.first], w.vertices[e.second], x) - x).norm());
  }
  return best;
}

// Brute-force distance between two separated convex bodies (a sphere or a polyhedron each):
// minimum over vertex-face and edge-edge (covering edge-vertex and vertex-vertex) pairs.
// Meaningful only when they are separated (the verdict comes from libccd's MPR).
inline double brute_force_distance(const WorldConvex& a, const WorldConvex& b) {
  if (a.sphere && b.sphere) return (a.center - b.center).norm() - a.radius - b.radius;
  if (a.sphere || b.sphere) {
    const WorldConvex& s = a.sphere ? a : b;
    const WorldConvex& p = a.sphere ? b : a;
    return point_polyhedron_distance(p, s.center) - s.radius;
  }
  double best = kInfinity;
  double best_sq = kInfinity;
  for (const Vec3& v : a.vertices) {
    for (std::size_t f = 0; f < b.faces.size(); ++f)
      best = std::min(best, point_face_distance(b, f, v));
  }
  for (const Vec3& v : b.vertices) {
    for (std::size_t f = 0; f < a.faces.size(); ++f)
      best = std::min(best, point_face_distance(a, f, v));
  }
  for (const auto& ea : a.edges) {
    const Vec3& p1 = a.vertices[ea.first];
    const Vec3& q1 = a.vertices[ea.second];
    for (const auto& eb : b.edges) {
      Vec3 c1, c2;
      best_sq = std::min(best_sq, closest_points_segment_segment(p1, q1, b.vertices[eb.first],
                                                                 b.vertices[eb.second], c1, c2));
    }
  }
  return std::min(best, std::sqrt(best_sq));
}

}  // namespace palpable::test
