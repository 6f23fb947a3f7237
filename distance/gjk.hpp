#pragma once
// Distance between two convex sets given by their support mappings: GJK (Gilbert, Johnson &
// Keerthi, IEEE J. Robotics and Automation 4(2), 1988) in van den Bergen's form ("A fast and robust
// GJK implementation for collision detection of convex objects", J. Graphics Tools 4(2), 1999):
// the iterate v is the point of the current simplex (of Minkowski-difference points
// w = s_a(-v) - s_b(v)) closest to the origin; |v| is an upper bound on the distance and
// v . w / |v| a lower bound, and the loop stops when they agree within the tolerance.
//
// The closest point of a simplex (at most 4 points) is found by enumerating its faces — every
// non-empty subset of its points — and keeping, of the projections of the origin on their affine
// hulls that have non-negative barycentric coordinates, the nearest one. That point always lies in
// the simplex, so rounding in a degenerate (flat) simplex can only lose a little progress, never
// produce a point outside the Minkowski difference (the failure of Johnson's recursive
// subalgorithm that Montanari, Petrinic & Barbieri, ACM TOG 36(3), 2017, answer with signed
// volumes; the enumeration is a simpler, slower answer to the same problem, at most 15 small
// solves per iteration).
//
// Used by distance/closest_features.cpp for the smooth shapes (ellipsoid, cylinder, capsule core)
// against anything that is not a halfspace.
#include "core/types.hpp"

#include <algorithm>
#include <array>
#include <cstdint>

namespace palpable {

struct GjkSettings {
  double tolerance_m = 1e-13;  // stop when upper and lower distance bounds differ by less [m]
  int max_iterations = 256;
};

struct GjkResult {
  enum class Status : std::uint8_t {
    kSeparated,    // converged; distance > 0 within the tolerance
    kTouching,     // the distance is below the tolerance (touching, or overlapping by less)
    kOverlapping,  // the origin is inside a tetrahedron of Minkowski-difference points
    kNotConverged  // max_iterations reached with bounds further apart than the tolerance
  };
  Status status = Status::kNotConverged;
  double distance = 0.0;     // [m] the upper bound |v|; 0 when touching or overlapping
  double lower_bound = 0.0;  // [m] v . w / |v| at the last iteration
  Vec3 p_a = Vec3::Zero();   // closest point on set a (a convex combination of its support points)
  Vec3 p_b = Vec3::Zero();
  int iterations = 0;
};

// One Minkowski-difference point with the support points it came from.
struct GjkVertex {
  Vec3 w = Vec3::Zero();  // a - b
  Vec3 a = Vec3::Zero();
  Vec3 b = Vec3::Zero();
};

// The simplex of the iteration: `count` points (1..4) and their barycentric weights for the
// closest point v = sum weight_i w_i.
struct GjkSimplex {
  std::array<GjkVertex, 4> points;
  std::array<double, 4> weights{};
  int count = 0;
  Vec3 v = Vec3::Zero();
};

// Replaces the simplex by the smallest face that holds its point closest to the origin (the points
// with positive weight) and sets v and the weights. Returns true when the origin lies inside a
// full-dimensional tetrahedron (v = 0).
bool reduce_to_closest_face(GjkSimplex& simplex);

// `support_a(d)` and `support_b(d)`: a point of each set maximising d . x (any point for d = 0).
// `initial_direction`: a first guess of a - b (e.g. the difference of the centres); any non-zero
// vector works. Coordinates are best given relative to a point near both sets (rounding scales
// with their size).
template <class SupportA, class SupportB>
GjkResult gjk_distance(const SupportA& support_a, const SupportB& support_b,
                       const Vec3& initial_direction, const GjkSettings& settings) {
  GjkResult out;
  GjkSimplex simplex;
  auto vertex = [&](const Vec3& d) {
    GjkVertex p;
    p.a = support_a(d);
    p.b = support_b(Vec3(-d));
    p.w = p.a - p.b;
    return p;
  };
  Vec3 d0 = initial_direction;
  if (!(d0.squaredNorm() > 0.0) || !d0.allFinite()) d0 = Vec3::UnitX();
  simplex.points[0] = vertex(-d0);
  simplex.count = 1;
  simplex.weights[0] = 1.0;
  simplex.v = simplex.points[0].w;
  auto finish = [&](GjkResult::Status status) {
    out.status = status;
    out.p_a = Vec3::Zero();
    out.p_b = Vec3::Zero();
    for (int i = 0; i < simplex.count; ++i) {
      out.p_a += simplex.weights[i] * simplex.points[i].a;
      out.p_b += simplex.weights[i] * simplex.points[i].b;
    }
    out.distance =
        status == GjkResult::Status::kOverlapping || status == GjkResult::Status::kTouching
            ? 0.0
            : simplex.v.norm();
    return out;
  };
  for (out.iterations = 1; out.iterations <= settings.max_iterations; ++out.iterations) {
    const double v_norm = simplex.v.norm();
    if (!(v_norm > settings.tolerance_m)) return finish(GjkResult::Status::kTouching);
    const GjkVertex w = vertex(-simplex.v);
    out.lower_bound = std::max(out.lower_bound, simplex.v.dot(w.w) / v_norm);
    // Upper bound |v|, lower bound v . w / |v| (the support plane of the Minkowski difference
    // normal to v): stop when they agree.
    if (v_norm - out.lower_bound <= settings.tolerance_m) {
      return finish(GjkResult::Status::kSeparated);
    }
    // Where rounding stops progress (a support point already in the simplex, or |v| not
    // falling), the bounds are as close as the arithmetic allows: accept them if within a
    // thousand tolerances, else report the failure.
    auto stalled = [&] {
      return finish(v_norm - out.lower_bound <= 1e3 * settings.tolerance_m
                        ? GjkResult::Status::kSeparated
                        : GjkResult::Status::kNotConverged);
    };
    for (int i = 0; i < simplex.count; ++i) {
      if ((simplex.points[i].w - w.w).squaredNorm() == 0.0) return stalled();
    }
    const GjkSimplex before = simplex;
    simplex.points[simplex.count++] = w;
    if (reduce_to_closest_face(simplex)) return finish(GjkResult::Status::kOverlapping);
    if (!(simplex.v.squaredNorm() < before.v.squaredNorm())) {
      simplex = before;
      return stalled();
    }
  }
  out.iterations = settings.max_iterations;
  return finish(GjkResult::Status::kNotConverged);
}

}  // namespace palpable
