#pragma once
// Point sets for building convex hulls (ConvexPolyhedron::from_points): shared by tests,
// benchmarks and scenes so that "the 1280-face hull" is the same everywhere.
#include "core/types.hpp"

#include <vector>

namespace palpable {

// Points of an icosahedron subdivided `levels` times, on the sphere of `radius` about the
// origin (levels = 3: 642 points, a hull of 1280 triangles).
std::vector<Vec3> icosphere_points(int levels, double radius);

}  // namespace palpable
