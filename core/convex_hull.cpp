// Convex hull of a point set as merged polygon faces. Qhull (Barber, Dobkin, Huhdanpaa 1996)
// computes the hull with its default merging of coplanar facets ("C-0 Qx"); the facets whose
// planes still agree within the coplanarity tolerance are then merged here, and each merged face
// is ordered by a 2-d convex hull in its plane.
#include "core/convex_hull.hpp"

#include "core/check.hpp"
#include "core/settings.hpp"

#include <libqhullcpp/Qhull.h>
#include <libqhullcpp/QhullError.h>
#include <libqhullcpp/QhullFacet.h>
#include <libqhullcpp/QhullFacetList.h>
#include <libqhullcpp/QhullFacetSet.h>
#include <libqhullcpp/QhullVertex.h>
#include <libqhullcpp/QhullVertexSet.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>
#include <string>

namespace palpable {

namespace {

struct Facet {
  std::vector<int> vertices;  // input point indices
  std::vector<int> neighbours;
  Vec3 normal = Vec3::Zero();
  double area = 0.0;
};

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Rejects inputs without a solid hull before Qhull sees them, with a message saying why.
void check_points(const std::vector<Vec3>& points, double tolerance_m, double diagonal) {
  if (diagonal == 0.0) throw InputError("points", "all points are identical");
  const Vec3& p0 = points[0];
  std::size_t a = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if ((points[i] - p0).squaredNorm() > (points[a] - p0).squaredNorm()) a = i;
  }
  const Vec3 axis = (points[a] - p0).normalized();
  std::size_t b = 0;
  double b_distance = -1.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d = (points[i] - p0).cross(axis).norm();
    if (d > b_distance) {
      b_distance = d;
      b = i;
    }
  }
  if (b_distance <= tolerance_m) {
    throw InputError("points", "the points are collinear (within " + std::to_string(tolerance_m) +
                                   " m of a line); a solid needs 4 points not in one plane");
  }
  const Vec3 normal = axis.cross(points[b] - p0).normalized();
  double thickness = 0.0;
  for (const Vec3& p : points) thickness = std::max(thickness, std::abs(normal.dot(p - p0)));
  if (thickness <= tolerance_m) {
    throw InputError("points", "the points are coplanar (within " + std::to_string(tolerance_m) +
                                   " m of a plane); a solid needs 4 points not in one plane");
  }
}

// Counter-clockwise boundary (Andrew's monotone chain) of `ids` projected on the plane with unit
// normal n; points within tolerance_m inside the boundary are kept on it, so that a vertex shared
// with a neighbouring face is not dropped from one face and kept in the other.
std::vector<int> ordered_boundary(const std::vector<Vec3>& points, std::vector<int> ids,
                                  const Vec3& n, double tolerance_m) {
  const Vec3 u = n.unitOrthogonal();
  const Vec3 w = n.cross(u);  // (u, w, n) right-handed: counter-clockwise in 2-d is about n
  struct P {
    double x, y;
    int id;
  };
  std::vector<P> ps;
  for (int id : ids) ps.push_back({u.dot(points[id]), w.dot(points[id]), id});
  std::sort(ps.begin(), ps.end(),
            [](const P& a, const P& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  auto cross = [](const P& o, const P& a, const P& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  auto inward_turn = [&](const P& o, const P& a, const P& b) {
    // a more than tolerance_m to the right of the line o->b (strictly inside the boundary).
    return cross(o, a, b) < -tolerance_m * std::hypot(b.x - o.x, b.y - o.y);
  };
  std::vector<P> hull;
  for (const P& p : ps) {
    while (hull.size() >= 2 && inward_turn(hull[hull.size() - 2], hull.back(), p)) hull.pop_back();
    hull.push_back(p);
  }
  const std::size_t lower = hull.size();
  for (std::size_t k = ps.size() - 1; k-- > 0;) {
    const P& p = ps[k];
    while (hull.size() > lower && inward_turn(hull[hull.size() - 2], hull.back(), p)) {
      hull.pop_back();
    }
    hull.push_back(p);
  }
  hull.pop_back();  // the first point again
  std::vector<int> loop;
  for (const P& p : hull) loop.push_back(p.id);
  return loop;
}

}  // namespace

HullPolygons convex_hull_polygons(const std::vector<Vec3>& points, double coplanar_tolerance) {
  if (points.size() < 4) {
    throw InputError("points", "a convex polyhedron needs at least 4 points, got " +
                                   std::to_string(points.size()));
  }
  Vec3 lo = Vec3::Constant(kInfinity);
  Vec3 hi = Vec3::Constant(-kInfinity);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw InputError("points/" + std::to_string(i), "has a non-finite coordinate");
    }
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  if (!std::isfinite(coplanar_tolerance)) {
    throw InputError("coplanar_tolerance", "must be finite");
  }
  const double diagonal = (hi - lo).norm();
  const double default_tolerance = Settings{}.hull_coplanar_tolerance * diagonal;
  const bool merge = coplanar_tolerance != 0.0;
  const double tolerance_m = coplanar_tolerance < 0.0 ? default_tolerance : coplanar_tolerance;
  check_points(points, std::max(tolerance_m, default_tolerance), diagonal);

  // Qhull on points centred on their bounding box, for the best rounding.
  const Vec3 centre = 0.5 * (lo + hi);
  std::vector<double> coordinates;
  coordinates.reserve(3 * points.size());
  for (const Vec3& p : points) {
    for (int k = 0; k < 3; ++k) coordinates.push_back(p[k] - centre[k]);
  }
  std::vector<Facet> facets;
  try {
    orgQhull::Qhull qhull;
    std::ostringstream qhull_messages;
    qhull.setErrorStream(&qhull_messages);
    qhull.setOutputStream(&qhull_messages);
    qhull.runQhull("", 3, static_cast<int>(points.size()), coordinates.data(), "Qx C-0");
    std::map<int, int> facet_index;
    for (const orgQhull::QhullFacet& f : qhull.facetList()) {
      facet_index[f.id()] = static_cast<int>(facet_index.size());
    }
    for (orgQhull::QhullFacet f : qhull.facetList()) {
      Facet facet;
      for (const orgQhull::QhullVertex& v : f.vertices()) {
        facet.vertices.push_back(static_cast<int>(v.point().id()));
      }
      for (const orgQhull::QhullFacet& g : f.neighborFacets()) {
        facet.neighbours.push_back(facet_index.at(g.id()));
      }
      const double* n = f.hyperplane().coordinates();
      facet.normal = Vec3(n[0], n[1], n[2]).normalized();
      facet.area = f.facetArea();
      facets.push_back(std::move(facet));
    }
  } catch (const orgQhull::QhullError& e) {
    throw InputError("points", std::string("Qhull could not build the hull: ") + e.what());
  }

  // Merge adjacent facets, most nearly parallel first, while every vertex of the merged group
  // stays within tolerance_m of one plane and no hull vertex lies beyond that plane.
  const int num_facets = static_cast<int>(facets.size());
  std::vector<int> parent(num_facets);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::vector<int>> group_vertices(num_facets);
  std::vector<Vec3> group_normal(num_facets);  // area-weighted sum of the facet normals
  std::vector<int> hull_vertices;
  for (int f = 0; f < num_facets; ++f) {
    group_vertices[f] = facets[f].vertices;
    std::sort(group_vertices[f].begin(), group_vertices[f].end());
    group_normal[f] = facets[f].area * facets[f].normal;
    hull_vertices.insert(hull_vertices.end(), facets[f].vertices.begin(), facets[f].vertices.end());
  }
  std::sort(hull_vertices.begin(), hull_vertices.end());
  hull_vertices.erase(std::unique(hull_vertices.begin(), hull_vertices.end()), hull_vertices.end());
  auto fitted_normal = [&](const Vec3& weighted) {
    return weighted.norm() > 0.0 ? Vec3(weighted.normalized()) : Vec3(Vec3::UnitZ());
  };
  if (merge) {
    std::vector<std::pair<double, std::pair<int, int>>> pairs;
    for (int f = 0; f < num_facets; ++f) {
      for (int g : facets[f].neighbours) {
        if (f < g) pairs.push_back({-facets[f].normal.dot(facets[g].normal), {f, g}});
      }
    }
    std::sort(pairs.begin(), pairs.end());
    for (const auto& pair : pairs) {
      const int a = find_root(parent, pair.second.first);
      const int b = find_root(parent, pair.second.second);
      if (a == b) continue;
      std::vector<int> both;
      std::set_union(group_vertices[a].begin(), group_vertices[a].end(), group_vertices[b].begin(),
                     group_vertices[b].end(), std::back_inserter(both));
      const Vec3 n = fitted_normal(group_normal[a] + group_normal[b]);
      double lo_d = kInfinity;
      double hi_d = -kInfinity;
      for (int v : both) {
        lo_d = std::min(lo_d, n.dot(points[v]));
        hi_d = std::max(hi_d, n.dot(points[v]));
      }
      if (hi_d - lo_d > tolerance_m) continue;
      bool outside = false;
      for (int v : hull_vertices) {
        if (n.dot(points[v]) > hi_d + tolerance_m) {
          outside = true;
          break;
        }
      }
      if (outside) continue;
      parent[b] = a;
      group_vertices[a] = std::move(both);
      group_normal[a] += group_normal[b];
    }
  }

  HullPolygons out;
  out.vertices = points;
  out.tolerance_m = merge ? tolerance_m : default_tolerance;
  for (int f = 0; f < num_facets; ++f) {
    if (find_root(parent, f) != f) {
      out.merged = true;
      continue;
    }
    const Vec3 n = fitted_normal(group_normal[f]);
    out.faces.push_back(ordered_boundary(points, group_vertices[f], n, out.tolerance_m));
    out.normals.push_back(n);
  }
  // A vertex on fewer than 3 faces lies on an edge or inside a face (within the tolerance): it is
  // not a corner of the solid.
  std::vector<int> face_count(points.size(), 0);
  for (const auto& loop : out.faces) {
    for (int v : loop) ++face_count[v];
  }
  for (auto& loop : out.faces) {
    loop.erase(std::remove_if(loop.begin(), loop.end(), [&](int v) { return face_count[v] < 3; }),
               loop.end());
  }
  // Offsets through the outermost vertex of each face, so that every vertex is on or inside;
  // the merge kept every face's vertices within tolerance_m of its plane.
  for (std::size_t f = 0; f < out.faces.size(); ++f) {
    const auto& loop = out.faces[f];
    double offset = -kInfinity;
    for (int v : loop) offset = std::max(offset, out.normals[f].dot(points[v]));
    out.offsets.push_back(offset);
  }
  return out;
}

}  // namespace palpable
