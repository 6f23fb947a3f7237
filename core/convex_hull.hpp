#pragma once
// Convex hull of a point set as polygon faces (Qhull, reentrant API, plus a merge of facets whose
// planes agree within a tolerance so that a box from its corners has exactly 6 faces). Internal to
// core: ConvexPolyhedron::from_points turns the polygons into a half-edge mesh.
#include "core/types.hpp"

#include <vector>

namespace palpable {

struct HullPolygons {
  std::vector<Vec3> vertices;           // the input points (unused ones are never referenced)
  std::vector<std::vector<int>> faces;  // vertex loops, counter-clockwise about the normal
  std::vector<Vec3> normals;            // unit outward normals
  std::vector<double> offsets;          // planes normal . x = offset [m]
  // Planarity/convexity tolerance the faces satisfy [m]: the merge tolerance plus rounding at the
  // scale of the points (64 ulps of the bounding-box diagonal), for meshes validated near the
  // origin.
  double tolerance_m = 0.0;
  bool merged = false;  // true if facets were merged beyond Qhull's own merging
};

// Throws InputError for fewer than 4 points, non-finite coordinates, and identical, collinear or
// coplanar point sets (thinner than the tolerance). `coplanar_tolerance` [m]; negative: the
// default kHullCoplanarTolerance times the diagonal of the points' bounding box; zero:
// no merging beyond Qhull's (validation then uses the default tolerance).
HullPolygons convex_hull_polygons(const std::vector<Vec3>& points, double coplanar_tolerance);

}  // namespace palpable
