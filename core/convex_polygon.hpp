#pragma once
// Small convex sets in a plane, as the contact patch of two bodies is: a point (1 vertex), a
// segment (2) or a convex polygon (3 or more, counter-clockwise).
#include "core/types.hpp"

#include <vector>

namespace palpable {

using Vec2 = Eigen::Vector2d;

inline double cross2(const Vec2& a, const Vec2& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Removes repeated points (closer than `tol`) and makes a polygon counter-clockwise; a polygon of
// collinear points (area within tol^2) becomes the segment between its extremes.
std::vector<Vec2> tidy(const std::vector<Vec2>& points, double tol);

// Intersection of two convex sets given as points (1 point, a segment of 2, or a counter-clockwise
// polygon); a point is returned as is (the caller knows it lies on the other set).
std::vector<Vec2> intersect(const std::vector<Vec2>& a, const std::vector<Vec2>& b);

// The centroid of a convex set: the point, the segment's middle, the polygon's area centroid.
Vec2 centroid(const std::vector<Vec2>& set);

}  // namespace palpable
