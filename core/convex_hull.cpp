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
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <tuple>

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
    throw InputError("points", "the points are collinear (within " + significant(tolerance_m) +
                                   " m of a line); a solid needs 4 points not in one plane");
  }
  const Vec3 normal = axis.cross(points[b] - p0).normalized();
  double thickness = 0.0;
  for (const Vec3& p : points) thickness = std::max(thickness, std::abs(normal.dot(p - p0)));
  if (thickness <= tolerance_m) {
    throw InputError("points", "the points are coplanar (within " + significant(tolerance_m) +
                                   " m of a plane); a solid needs 4 points not in one plane");
  }
}

// Counter-clockwise boundary of `ids` projected on the plane with unit normal n: the strict 2-d
// convex hull (Andrew's monotone chain), then every other point within tolerance_m of a hull edge
// inserted into that edge in order along it, so that a vertex shared with a neighbouring face is
// kept on both. Points farther inside are dropped.
std::vector<int> ordered_boundary(const std::vector<Vec3>& points, const std::vector<int>& ids,
                                  const Vec3& n, double tolerance_m) {
  const Vec3 u = n.unitOrthogonal();
  const Vec3 w = n.cross(u);  // (u, w, n) right-handed: counter-clockwise in 2-d is about n
  using P2 = Eigen::Vector2d;
  std::vector<std::pair<P2, int>> ps;
  for (int id : ids) ps.push_back({P2(u.dot(points[id]), w.dot(points[id])), id});
  std::sort(ps.begin(), ps.end(), [](const auto& a, const auto& b) {
    return a.first.x() < b.first.x() || (a.first.x() == b.first.x() && a.first.y() < b.first.y());
  });
  auto cross = [](const P2& o, const P2& a, const P2& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<std::size_t> hull;  // indices into ps
  for (int pass = 0; pass < 2; ++pass) {
    const std::size_t start = hull.size();
    for (std::size_t k = 0; k < ps.size(); ++k) {
      const std::size_t i = pass == 0 ? k : ps.size() - 1 - k;
      while (hull.size() >= start + 2 &&
             cross(ps[hull[hull.size() - 2]].first, ps[hull.back()].first, ps[i].first) <= 0.0) {
        hull.pop_back();
      }
      hull.push_back(i);
    }
    hull.pop_back();  // the chain's last point starts the other chain
  }
  if (hull.size() < 3) {
    std::vector<int> degenerate;
    for (std::size_t i : hull) degenerate.push_back(ps[i].second);
    return degenerate;
  }
  std::vector<bool> on_hull(ps.size(), false);
  for (std::size_t i : hull) on_hull[i] = true;
  // (edge, parameter along it, id) of the points kept on the boundary between hull vertices.
  std::vector<std::tuple<std::size_t, double, int>> inserted;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    if (on_hull[i]) continue;
    double best = kInfinity;
    std::size_t best_edge = 0;
    double best_t = 0.0;
    for (std::size_t e = 0; e < hull.size(); ++e) {
      const P2& a = ps[hull[e]].first;
      const P2& b = ps[hull[(e + 1) % hull.size()]].first;
      const P2 ab = b - a;
      const double t = std::clamp((ps[i].first - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      const double d = (ps[i].first - (a + t * ab)).norm();
      if (d < best) {
        best = d;
        best_edge = e;
        best_t = t;
      }
    }
    if (best <= tolerance_m) inserted.emplace_back(best_edge, best_t, ps[i].second);
  }
  std::sort(inserted.begin(), inserted.end());
  std::vector<int> loop;
  std::size_t next = 0;
  for (std::size_t e = 0; e < hull.size(); ++e) {
    loop.push_back(ps[hull[e]].second);
    for (; next < inserted.size() && std::get<0>(inserted[next]) == e; ++next) {
      loop.push_back(std::get<2>(inserted[next]));
    }
  }
  return loop;
}

// Runs Qhull (reentrant API) on centred coordinates; facets with input-point vertex ids, unit
// outward normals and areas. Throws QhullError, whose message then carries Qhull's report.
std::vector<Facet> run_qhull(std::vector<double>& coordinates, const char* options) {
  std::ostringstream qhull_messages;
  try {
    orgQhull::Qhull qhull;
    qhull.setErrorStream(&qhull_messages);
    qhull.setOutputStream(&qhull_messages);
    qhull.runQhull("", 3, static_cast<int>(coordinates.size() / 3), coordinates.data(), options);
    std::map<int, int> facet_index;
    for (const orgQhull::QhullFacet& f : qhull.facetList()) {
      facet_index[f.id()] = static_cast<int>(facet_index.size());
    }
    std::vector<Facet> facets;
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
    return facets;
  } catch (const orgQhull::QhullError& e) {
    // The line of Qhull's report that starts with the error code says what went wrong.
    const std::string report = qhull_messages.str();
    const std::size_t start = report.find("QH" + std::to_string(e.errorCode()) + " ");
    const std::string line = start == std::string::npos
                                 ? e.what()
                                 : report.substr(start, report.find('\n', start) - start);
    throw orgQhull::QhullError(e.errorCode(), line);
  }
}

Vec3 fitted_normal(const Vec3& weighted) {
  return weighted.norm() > 0.0 ? Vec3(weighted.normalized()) : Vec3(Vec3::UnitZ());
}

// Facets merged into groups (union-find): each root holds the sorted union of its facets'
// vertices and the area-weighted sum of their normals.
struct FacetGroups {
  std::vector<int> parent;
  std::vector<std::vector<int>> vertices;
  std::vector<Vec3> normal;
  std::vector<std::vector<int>> incident_facets;  // per input point
};

// True if a group (or the candidate union of roots a and b) has a vertex strictly inside its
// boundary that a facet of another group still uses: that facet would lose a corner and the
// mesh would not close.
bool group_swallows(FacetGroups& groups, const std::vector<Vec3>& points, double tolerance_m, int a,
                    int b, const std::vector<int>& vertices, const Vec3& n) {
  std::vector<int> boundary = ordered_boundary(points, vertices, n, tolerance_m);
  std::sort(boundary.begin(), boundary.end());
  for (int v : vertices) {
    if (std::binary_search(boundary.begin(), boundary.end(), v)) continue;
    for (int f : groups.incident_facets[v]) {
      const int root = find_root(groups.parent, f);
      if (root != a && root != b) return true;
    }
  }
  return false;
}

bool swallows_shared_vertex(FacetGroups& groups, const std::vector<Facet>& facets,
                            const std::vector<Vec3>& points, double tolerance_m) {
  for (int f = 0; f < static_cast<int>(facets.size()); ++f) {
    if (find_root(groups.parent, f) != f) continue;
    if (group_swallows(groups, points, tolerance_m, f, f, groups.vertices[f],
                       fitted_normal(groups.normal[f]))) {
      return true;
    }
  }
  return false;
}

// Merges adjacent facets, most nearly parallel first, while every vertex of the merged group stays
// within tolerance_m of one plane and no hull vertex lies beyond that plane; `strict` also
// refuses each merge that would swallow a shared vertex. With merge = false, only groups.
FacetGroups merge_facets(const std::vector<Facet>& facets, const std::vector<Vec3>& points,
                         const std::vector<int>& hull_vertices, double tolerance_m, bool strict,
                         bool merge = true) {
  const int num_facets = static_cast<int>(facets.size());
  FacetGroups groups;
  groups.parent.resize(num_facets);
  std::iota(groups.parent.begin(), groups.parent.end(), 0);
  groups.vertices.resize(num_facets);
  groups.normal.resize(num_facets);
  groups.incident_facets.resize(points.size());
  for (int f = 0; f < num_facets; ++f) {
    groups.vertices[f] = facets[f].vertices;
    std::sort(groups.vertices[f].begin(), groups.vertices[f].end());
    groups.normal[f] = facets[f].area * facets[f].normal;
    for (int v : facets[f].vertices) groups.incident_facets[v].push_back(f);
  }
  if (!merge) return groups;
  std::vector<std::pair<double, std::pair<int, int>>> pairs;
  for (int f = 0; f < num_facets; ++f) {
    for (int g : facets[f].neighbours) {
      if (f < g) pairs.push_back({-facets[f].normal.dot(facets[g].normal), {f, g}});
    }
  }
  std::sort(pairs.begin(), pairs.end());
  for (const auto& pair : pairs) {
    const int a = find_root(groups.parent, pair.second.first);
    const int b = find_root(groups.parent, pair.second.second);
    if (a == b) continue;
    std::vector<int> both;
    std::set_union(groups.vertices[a].begin(), groups.vertices[a].end(), groups.vertices[b].begin(),
                   groups.vertices[b].end(), std::back_inserter(both));
    const Vec3 n = fitted_normal(groups.normal[a] + groups.normal[b]);
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
    // Groups only grow, so a group that swallowed no shared vertex when it was formed never does.
    if (strict && group_swallows(groups, points, tolerance_m, a, b, both, n)) continue;
    groups.parent[b] = a;
    groups.vertices[a] = std::move(both);
    groups.normal[a] += groups.normal[b];
  }
  return groups;
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
  const double default_tolerance = kHullCoplanarTolerance * diagonal;
  const bool merge = coplanar_tolerance != 0.0;
  const double tolerance_m = coplanar_tolerance < 0.0 ? default_tolerance : coplanar_tolerance;
  check_points(points, std::max(tolerance_m, default_tolerance), diagonal);

  // All geometry on the points centred on their bounding box, for the best rounding.
  const Vec3 centre = 0.5 * (lo + hi);
  std::vector<Vec3> centred;
  std::vector<double> coordinates;
  coordinates.reserve(3 * points.size());
  for (const Vec3& p : points) {
    centred.push_back(p - centre);
    for (int k = 0; k < 3; ++k) coordinates.push_back(centred.back()[k]);
  }
  std::vector<Facet> facets;
  try {
    facets = run_qhull(coordinates, "Qx C-0");
  } catch (const orgQhull::QhullError& first) {
    // Qhull's merging can fail on near-degenerate input (precision error QH6297 and kin); its
    // own advice is to joggle. The joggled facets are then merged and validated against the
    // unjoggled points like any others.
    try {
      facets = run_qhull(coordinates, "QJ");
    } catch (const orgQhull::QhullError& second) {
      throw InputError("points", std::string("Qhull could not build the hull: ") + first.what() +
                                     "; joggled: " + second.what());
    }
  }

  const int num_facets = static_cast<int>(facets.size());
  std::vector<int> hull_vertices;
  for (const Facet& f : facets) {
    hull_vertices.insert(hull_vertices.end(), f.vertices.begin(), f.vertices.end());
  }
  std::sort(hull_vertices.begin(), hull_vertices.end());
  hull_vertices.erase(std::unique(hull_vertices.begin(), hull_vertices.end()), hull_vertices.end());
  FacetGroups groups;
  if (merge) {
    // Greedy merging first; if a merged face swallowed a vertex that other faces still use, redo
    // it with the check made at every merge (which cannot merge a star of facets around a
    // near-coplanar vertex one pair at a time, so it merges less).
    groups = merge_facets(facets, centred, hull_vertices, tolerance_m, false);
    if (swallows_shared_vertex(groups, facets, centred, tolerance_m)) {
      groups = merge_facets(facets, centred, hull_vertices, tolerance_m, true);
    }
  } else {
    groups = merge_facets(facets, centred, hull_vertices, tolerance_m, false, false);
  }
  HullPolygons out;
  out.vertices = points;
  const double merge_tolerance = merge ? tolerance_m : default_tolerance;
  out.tolerance_m = merge_tolerance + 64.0 * std::numeric_limits<double>::epsilon() * diagonal;
  for (int f = 0; f < num_facets; ++f) {
    if (find_root(groups.parent, f) != f) {
      out.merged = true;
      continue;
    }
    const Vec3 n = fitted_normal(groups.normal[f]);
    out.faces.push_back(ordered_boundary(centred, groups.vertices[f], n, merge_tolerance));
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
    for (int v : loop) offset = std::max(offset, out.normals[f].dot(centred[v]));
    out.offsets.push_back(offset + out.normals[f].dot(centre));
  }
  return out;
}

}  // namespace palpable
