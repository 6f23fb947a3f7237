// Shapes: half-edge convex polyhedra (built directly or from a Qhull hull with coplanar facets
// merged into polygon faces), validation, support points and bounding boxes (DESIGN.md §2-3).
#include "core/shape.hpp"

#include "core/check.hpp"
#include "core/convex_hull.hpp"
#include "core/mass_properties.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <sstream>
#include <utility>

namespace palpable {

namespace {

std::string format_vec(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

bool is_finite(const Vec3& v) {
  return v.allFinite();
}

// Newell's method: the area-weighted normal of a closed polygon (twice the vector area).
Vec3 newell_normal(const std::vector<Vec3>& vertices, const std::vector<int>& loop) {
  Vec3 n = Vec3::Zero();
  const std::size_t count = loop.size();
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3& a = vertices[loop[i]];
    const Vec3& b = vertices[loop[(i + 1) % count]];
    n += a.cross(b);
  }
  return n;
}

}  // namespace

// Builds the half-edge mesh of a polyhedron from polygon loops; the only code that writes a
// ConvexPolyhedron's members.
class ConvexPolyhedronBuilder {
 public:
  // `faces`: vertex-index loops counter-clockwise about the outward normal. `normals`/`offsets`:
  // the face planes (computed from the loops when empty). Unused vertices are dropped. Returns
  // "" or the defect that stops the mesh from being built.
  static std::string build(const std::vector<Vec3>& vertices,
                           const std::vector<std::vector<int>>& faces,
                           const std::vector<Vec3>& normals, const std::vector<double>& offsets,
                           ConvexPolyhedron* out) {
    ConvexPolyhedron p;
    // Used vertices keep their order (box vertex i has the sign bits of i; prism vertex k is at
    // angle 2 pi k / n; hull vertices follow the input points).
    std::vector<int> new_index(vertices.size(), -1);
    for (const auto& loop : faces) {
      if (loop.size() < 3) return "a face has fewer than 3 vertices";
      for (int v : loop) {
        if (v < 0 || v >= static_cast<int>(vertices.size())) return "a face index is out of range";
        new_index[v] = 0;
      }
    }
    for (std::size_t v = 0; v < vertices.size(); ++v) {
      if (new_index[v] < 0) continue;
      new_index[v] = static_cast<int>(p.vertices_.size());
      p.vertices_.push_back(vertices[v]);
    }
    std::map<std::pair<int, int>, int> by_ends;
    p.vertex_half_edge_.assign(p.vertices_.size(), -1);
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const auto& loop = faces[f];
      const int first = static_cast<int>(p.half_edges_.size());
      const int count = static_cast<int>(loop.size());
      std::vector<int> mapped(loop.size());
      for (int i = 0; i < count; ++i) mapped[i] = new_index[loop[i]];
      for (int i = 0; i < count; ++i) {
        HalfEdge h;
        h.tail = mapped[i];
        h.next = first + (i + 1) % count;
        h.prev = first + (i + count - 1) % count;
        h.face = static_cast<int>(f);
        const int index = first + i;
        if (!by_ends.emplace(std::make_pair(h.tail, mapped[(i + 1) % count]), index).second) {
          return "an edge is used twice in the same direction (faces not consistently oriented)";
        }
        if (p.vertex_half_edge_[h.tail] < 0) p.vertex_half_edge_[h.tail] = index;
        p.half_edges_.push_back(h);
      }
      PolyFace face;
      face.half_edge = first;
      if (normals.empty()) {
        const Vec3 n = newell_normal(p.vertices_, mapped);
        if (!(n.norm() > 0.0)) return "a face has zero area";
        face.normal_M = n.normalized();
        double sum = 0.0;
        for (int v : mapped) sum += face.normal_M.dot(p.vertices_[v]);
        face.offset = sum / count;
      } else {
        face.normal_M = normals[f];
        face.offset = offsets[f];
      }
      p.faces_.push_back(face);
    }
    for (auto& h : p.half_edges_) {
      const int head = p.half_edges_[h.next].tail;
      const auto it = by_ends.find(std::make_pair(head, h.tail));
      if (it == by_ends.end())
        return "an edge belongs to only one face (the surface is not closed)";
      h.twin = it->second;
    }
    p.max_radius_ = 0.0;
    for (const Vec3& v : p.vertices_) p.max_radius_ = std::max(p.max_radius_, v.norm());
    *out = std::move(p);
    return "";
  }

  static void shift(ConvexPolyhedron* p, const Vec3& shift_M) {
    for (Vec3& v : p->vertices_) v -= shift_M;
    // Offsets again through each face's outermost vertex: subtracting normal . shift from a far
    // face's offset would round at the scale of the far position, not of the shape.
    for (PolyFace& f : p->faces_) {
      f.offset = -kInfinity;
      int h = f.half_edge;
      do {
        f.offset = std::max(f.offset, f.normal_M.dot(p->vertices_[p->half_edges_[h].tail]));
        h = p->half_edges_[h].next;
      } while (h != f.half_edge);
    }
    p->max_radius_ = 0.0;
    for (const Vec3& v : p->vertices_) p->max_radius_ = std::max(p->max_radius_, v.norm());
    p->com_shift_M_ = shift_M;
  }
};

ConvexPolyhedron ConvexPolyhedron::from_faces(const std::vector<Vec3>& vertices,
                                              const std::vector<std::vector<int>>& faces,
                                              double tolerance_m) {
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    if (!is_finite(vertices[i])) {
      throw InputError("vertices", "vertex " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  ConvexPolyhedron p;
  const std::string built = ConvexPolyhedronBuilder::build(vertices, faces, {}, {}, &p);
  if (!built.empty()) throw InputError("faces", built);
  const std::string defect = polyhedron_defect(p, tolerance_m);
  if (!defect.empty()) throw InputError("faces", defect);
  return p;
}

ConvexPolyhedron ConvexPolyhedron::from_points(const std::vector<Vec3>& points,
                                               double coplanar_tolerance) {
  // Build, recentre, then validate: the checks run on coordinates at the scale of the shape, not
  // of its position. The centroid comes from the same integrals the mass properties use
  // (Mirtich 1996 on the polygon faces), so they find the centre of mass at the origin too.
  auto build = [](const HullPolygons& hull, ConvexPolyhedron* p) {
    std::string defect =
        ConvexPolyhedronBuilder::build(hull.vertices, hull.faces, hull.normals, hull.offsets, p);
    if (!defect.empty()) return defect;
    ConvexPolyhedronBuilder::shift(p, volume_integrals(*p).centroid);
    return polyhedron_defect(*p, hull.tolerance_m);
  };
  HullPolygons hull = convex_hull_polygons(points, coplanar_tolerance);
  ConvexPolyhedron p;
  std::string defect = build(hull, &p);
  if (!defect.empty() && hull.merged) {
    // The tolerance-merged faces did not close into a valid mesh (near-degenerate input): fall
    // back to Qhull's own facets.
    hull = convex_hull_polygons(points, 0.0);
    defect = build(hull, &p);
  }
  if (!defect.empty()) {
    throw InputError("points", "the convex hull is degenerate at the coplanarity tolerance " +
                                   std::to_string(hull.tolerance_m) + " m: " + defect);
  }
  return p;
}

ConvexPolyhedron ConvexPolyhedron::box(const Vec3& half_extents) {
  for (int i = 0; i < 3; ++i) {
    if (!(std::isfinite(half_extents[i]) && half_extents[i] > 0.0)) {
      throw InputError("half_extents",
                       "must be positive and finite, got " + format_vec(half_extents));
    }
  }
  const double x = half_extents.x();
  const double y = half_extents.y();
  const double z = half_extents.z();
  // Vertex i has coordinate signs from its bits: bit 0 -> x, bit 1 -> y, bit 2 -> z.
  std::vector<Vec3> vertices;
  for (int i = 0; i < 8; ++i) {
    vertices.emplace_back((i & 1) ? x : -x, (i & 2) ? y : -y, (i & 4) ? z : -z);
  }
  const std::vector<std::vector<int>> faces = {
      {1, 3, 7, 5}, {0, 4, 6, 2},  // +x, -x
      {2, 6, 7, 3}, {0, 1, 5, 4},  // +y, -y
      {4, 5, 7, 6}, {0, 2, 3, 1},  // +z, -z
  };
  const std::vector<Vec3> normals = {Vec3::UnitX(),  -Vec3::UnitX(), Vec3::UnitY(),
                                     -Vec3::UnitY(), Vec3::UnitZ(),  -Vec3::UnitZ()};
  const std::vector<double> offsets = {x, x, y, y, z, z};
  ConvexPolyhedron p;
  const std::string defect = ConvexPolyhedronBuilder::build(vertices, faces, normals, offsets, &p);
  PALPABLE_CHECK(defect.empty(), defect);
  return p;
}

ConvexPolyhedron ConvexPolyhedron::prism(double radius, double half_height, int sides) {
  if (!(std::isfinite(radius) && radius > 0.0)) {
    throw InputError("radius", "must be positive and finite, got " + std::to_string(radius));
  }
  if (!(std::isfinite(half_height) && half_height > 0.0)) {
    throw InputError("half_height",
                     "must be positive and finite, got " + std::to_string(half_height));
  }
  if (sides < 3) {
    throw InputError("sides", "a prism needs at least 3 sides, got " + std::to_string(sides));
  }
  const double kPi = 3.14159265358979323846;
  // Vertices 0..n-1 on the bottom (z = -h), n..2n-1 on the top, vertex k at angle 2 pi k / n.
  std::vector<Vec3> vertices(2 * sides);
  for (int k = 0; k < sides; ++k) {
    const double angle = 2.0 * kPi * k / sides;
    const double c = radius * std::cos(angle);
    const double s = radius * std::sin(angle);
    vertices[k] = Vec3(c, s, -half_height);
    vertices[sides + k] = Vec3(c, s, half_height);
  }
  std::vector<std::vector<int>> faces;
  std::vector<Vec3> normals;
  std::vector<double> offsets;
  std::vector<int> top(sides), bottom(sides);
  for (int k = 0; k < sides; ++k) {
    top[k] = sides + k;
    bottom[k] = sides - 1 - k;
  }
  faces.push_back(top);
  normals.push_back(Vec3::UnitZ());
  offsets.push_back(half_height);
  faces.push_back(bottom);
  normals.push_back(-Vec3::UnitZ());
  offsets.push_back(half_height);
  const double apothem = radius * std::cos(kPi / sides);
  for (int k = 0; k < sides; ++k) {
    const int k1 = (k + 1) % sides;
    faces.push_back({k, k1, sides + k1, sides + k});
    const double angle = (2.0 * k + 1.0) * kPi / sides;
    normals.emplace_back(std::cos(angle), std::sin(angle), 0.0);
    offsets.push_back(apothem);
  }
  ConvexPolyhedron p;
  const std::string defect = ConvexPolyhedronBuilder::build(vertices, faces, normals, offsets, &p);
  PALPABLE_CHECK(defect.empty(), defect);
  return p;
}

Vec3 ConvexPolyhedron::support(const Vec3& direction_M) const {
  // Linear scan over the vertices. A hill-climb over the half-edge graph (from a cached start
  // vertex) is the planned upgrade for polyhedra with many vertices.
  int best = 0;
  double best_dot = direction_M.dot(vertices_[0]);
  for (int i = 1; i < static_cast<int>(vertices_.size()); ++i) {
    const double d = direction_M.dot(vertices_[i]);
    if (d > best_dot) {
      best_dot = d;
      best = i;
    }
  }
  return vertices_[best];
}

namespace {
constexpr double kPiShape = 3.14159265358979323846;
constexpr std::int64_t kExhaustiveConvexity = std::int64_t{1} << 22;
}  // namespace

std::string polyhedron_defect(const ConvexPolyhedron& p, double tolerance_m) {
  const auto& hs = p.half_edges();
  const auto& vs = p.vertices();
  const auto& fs = p.faces();
  const int num_h = static_cast<int>(hs.size());
  const int num_v = static_cast<int>(vs.size());
  const int num_f = static_cast<int>(fs.size());
  auto fail = [](const std::string& what, int index) {
    return what + " (index " + std::to_string(index) + ")";
  };
  if (num_v < 4 || num_f < 4 || num_h % 2 != 0) return "too few vertices or faces";
  auto valid = [](int i, int n) { return i >= 0 && i < n; };
  for (int h = 0; h < num_h; ++h) {
    const HalfEdge& e = hs[h];
    if (!valid(e.tail, num_v) || !valid(e.twin, num_h) || !valid(e.next, num_h) ||
        !valid(e.prev, num_h) || !valid(e.face, num_f)) {
      return fail("half-edge index out of range", h);
    }
    if (e.twin == h || hs[e.twin].twin != h) return fail("twin of twin is not the half-edge", h);
    if (hs[e.next].prev != h || hs[e.prev].next != h) return fail("next/prev not inverse", h);
    if (hs[e.next].face != e.face) return fail("next leaves the face", h);
    if (hs[e.twin].tail != hs[e.next].tail) return fail("twin does not run the other way", h);
    if (hs[e.twin].face == e.face) return fail("both sides of an edge on the same face", h);
  }
  if (static_cast<int>(p.vertex_half_edge().size()) != num_v) return "vertex_half_edge size";
  for (int v = 0; v < num_v; ++v) {
    const int h0 = p.vertex_half_edge()[v];
    if (!valid(h0, num_h) || hs[h0].tail != v) return fail("vertex_half_edge wrong", v);
    // Walk the half-edges leaving v: the next one is twin(prev(h)).
    int degree = 0;
    int h = h0;
    do {
      ++degree;
      h = hs[hs[h].prev].twin;
      if (hs[h].tail != v || degree > num_h) return fail("vertex star broken", v);
    } while (h != h0);
    if (degree < 3) return fail("vertex of degree < 3", v);
  }
  // Every vertex against every face plane is exact but costs faces x vertices (a hull of 10^6
  // points: over 300 s); past a few million pairs the local checks below stand for it.
  const bool exhaustive =
      static_cast<std::int64_t>(num_f) * static_cast<std::int64_t>(num_v) <= kExhaustiveConvexity;
  std::vector<int> visits(num_h, 0);
  for (int f = 0; f < num_f; ++f) {
    const PolyFace& face = fs[f];
    if (!valid(face.half_edge, num_h) || hs[face.half_edge].face != f) {
      return fail("face half_edge wrong", f);
    }
    if (!(std::abs(face.normal_M.norm() - 1.0) <= 1e-12)) return fail("face normal not unit", f);
    std::vector<int> loop;
    int h = face.half_edge;
    do {
      loop.push_back(hs[h].tail);
      ++visits[h];
      h = hs[h].next;
      if (static_cast<int>(loop.size()) > num_h) return fail("face loop does not close", f);
    } while (h != face.half_edge);
    if (loop.size() < 3) return fail("face with fewer than 3 vertices", f);
    if (newell_normal(vs, loop).dot(face.normal_M) <= 0.0) {
      return fail("face loop not counter-clockwise about its normal", f);
    }
    const std::size_t count = loop.size();
    for (std::size_t i = 0; i < count; ++i) {
      const Vec3& a = vs[loop[i]];
      const Vec3& b = vs[loop[(i + 1) % count]];
      const Vec3& c = vs[loop[(i + 2) % count]];
      if (std::abs(face.normal_M.dot(a) - face.offset) > tolerance_m) {
        return fail("face not planar", f);
      }
      // Convex corner at b: b lies outward of the chord a->c (to its right seen from outside);
      // a reflex corner is allowed only within tolerance of the chord. (Measuring the turn from
      // the short edge a->b instead would amplify a tolerated offset of b by |c - b| / |b - a|.)
      const Vec3 ac = c - a;
      const Vec3 inward = face.normal_M.cross(ac);
      if (inward.dot(b - a) > tolerance_m * ac.norm()) return fail("face not convex", f);
    }
    if (exhaustive) {
      for (int v = 0; v < num_v; ++v) {
        if (face.normal_M.dot(vs[v]) - face.offset > tolerance_m) {
          return fail("a vertex lies outside a face plane (not convex or normal not outward)", f);
        }
      }
    } else {
      // Convex at each edge: the next vertex of the face across it lies inside this face's plane
      // (that face is planar and convex, so all of it does).
      int e = face.half_edge;
      do {
        const int across = hs[hs[hs[e].twin].next].next;
        if (face.normal_M.dot(vs[hs[across].tail]) - face.offset > tolerance_m) {
          return fail("a vertex lies outside a face plane (not convex or normal not outward)", f);
        }
        e = hs[e].next;
      } while (e != face.half_edge);
    }
  }
  if (!exhaustive) {
    // Convex at each vertex: its star winds once about the vertex. Seen along the mean of the
    // normals of the faces around it, the edges leaving it turn through 2 pi in all, not 4 pi
    // (convex edges and a star wound twice could still close up into a sphere's topology). With
    // convex edges and vertices, a closed surface of a sphere's topology is convex (Alexandrov),
    // so these O(E) checks stand for the one of every vertex against every face.
    for (int v = 0; v < num_v; ++v) {
      const int h0 = p.vertex_half_edge()[v];
      Vec3 axis = Vec3::Zero();
      int h = h0;
      do {
        axis += fs[hs[h].face].normal_M;
        h = hs[hs[h].prev].twin;
      } while (h != h0);
      if (!(axis.norm() > 1e-9)) return fail("vertex star wound more than once", v);
      axis.normalize();
      double turning = 0.0;
      auto projected = [&](int edge) {
        const Vec3 d = vs[hs[hs[edge].next].tail] - vs[v];
        return Vec3(d - axis * axis.dot(d));
      };
      h = h0;
      do {
        const int g = hs[hs[h].prev].twin;
        const Vec3 a = projected(h), b = projected(g);
        turning += std::atan2(axis.dot(a.cross(b)), a.dot(b));
        h = g;
      } while (h != h0);
      if (std::abs(std::abs(turning) - 2.0 * kPiShape) > 0.5 * kPiShape) {
        return fail("vertex star wound more than once", v);
      }
    }
  }
  for (int h = 0; h < num_h; ++h) {
    if (visits[h] != 1) return fail("half-edge not on exactly one face loop", h);
  }
  if (num_v - num_h / 2 + num_f != 2) return "Euler characteristic V - E + F != 2";
  return "";
}

Sphere make_sphere(double radius) {
  if (!(std::isfinite(radius) && radius > 0.0)) {
    throw InputError("radius", "must be positive and finite, got " + std::to_string(radius));
  }
  return Sphere{radius};
}

Halfspace make_halfspace(const Vec3& normal_M, double offset) {
  const double length = normal_M.norm();
  if (!(is_finite(normal_M) && length > 0.0 && std::isfinite(length))) {
    throw InputError("normal", "must be a finite non-zero vector, got " + format_vec(normal_M));
  }
  if (!std::isfinite(offset)) throw InputError("offset", "must be finite");
  return Halfspace{normal_M / length, offset};
}

namespace {

double positive_finite(const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw InputError(name, "must be positive and finite, got " + std::to_string(value));
  }
  return value;
}

}  // namespace

Ellipsoid make_ellipsoid(const Vec3& semi_axes_M, double com_offset) {
  for (int i = 0; i < 3; ++i) {
    if (!(std::isfinite(semi_axes_M[i]) && semi_axes_M[i] > 0.0)) {
      throw InputError("semi_axes", "must be positive and finite, got " + format_vec(semi_axes_M));
    }
  }
  if (!(std::isfinite(com_offset) && std::abs(com_offset) < semi_axes_M.z())) {
    throw InputError("com_offset", "must be finite and smaller in size than the z semi-axis " +
                                       std::to_string(semi_axes_M.z()) + ", got " +
                                       std::to_string(com_offset));
  }
  return Ellipsoid{semi_axes_M, com_offset};
}

Cylinder make_cylinder(double radius, double half_height) {
  return Cylinder{positive_finite("radius", radius), positive_finite("half_height", half_height)};
}

Capsule make_capsule(double radius, double half_length) {
  return Capsule{positive_finite("radius", radius), positive_finite("half_length", half_length)};
}

LoadedBall make_loaded_ball(double radius, double com_offset) {
  positive_finite("radius", radius);
  if (!(std::isfinite(com_offset) && std::abs(com_offset) < radius)) {
    throw InputError("com_offset", "must be finite and smaller in size than the radius " +
                                       std::to_string(radius) + ", got " +
                                       std::to_string(com_offset));
  }
  return LoadedBall{radius, com_offset};
}

bool is_smooth_convex(const Shape& shape) {
  return std::holds_alternative<Ellipsoid>(shape) || std::holds_alternative<Cylinder>(shape) ||
         std::holds_alternative<Capsule>(shape) || std::holds_alternative<LoadedBall>(shape);
}

Vec3 smooth_support_M(const Shape& shape, const Vec3& d) {
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    // x = A^2 d / |A d| with A = diag(a) maximises d . x over x^T A^-2 x <= 1.
    const Vec3 ad = e->semi_axes_M.cwiseProduct(d);
    const double length = ad.norm();
    if (!(length > 0.0)) return e->centre_M();
    return e->centre_M() + e->semi_axes_M.cwiseProduct(ad) / length;
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    const double radial = std::hypot(d.x(), d.y());
    const double z = d.z() > 0.0 ? c->half_height : (d.z() < 0.0 ? -c->half_height : 0.0);
    if (!(radial > 0.0)) return Vec3(0.0, 0.0, z);
    return Vec3(c->radius * d.x() / radial, c->radius * d.y() / radial, z);
  }
  if (const auto* c = std::get_if<Capsule>(&shape)) {
    const double length = d.norm();
    const double z = d.z() > 0.0 ? c->half_length : (d.z() < 0.0 ? -c->half_length : 0.0);
    if (!(length > 0.0)) return Vec3(0.0, 0.0, z);
    return Vec3(0.0, 0.0, z) + (c->radius / length) * d;
  }
  if (const auto* b = std::get_if<LoadedBall>(&shape)) {
    const double length = d.norm();
    if (!(length > 0.0)) return b->centre_M();
    return b->centre_M() + (b->radius / length) * d;
  }
  PALPABLE_CHECK(false, "smooth_support_M needs a smooth convex shape");
  return Vec3::Zero();
}

Mat3 smooth_support_derivative_M(const Shape& shape, const Vec3& d_in) {
  const double length = d_in.norm();
  if (!(length > 0.0)) return Mat3::Zero();
  const Vec3 d = d_in / length;
  const Mat3 I = Mat3::Identity();
  // A ball of radius r about a centre: s = centre + r d / |d|, ds/dd = r (I - d d^T) at |d| = 1.
  auto ball = [&](double r) { return Mat3(r * (I - d * d.transpose())); };
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    // s = A^2 d / L with L = |A d|: ds/dd = (A^2 - s s^T) / L (dL/dd = s).
    const Vec3 a2 = e->semi_axes_M.cwiseProduct(e->semi_axes_M);
    const double L = e->semi_axes_M.cwiseProduct(d).norm();
    const Vec3 s = a2.cwiseProduct(d) / L;
    return (Mat3(a2.asDiagonal()) - s * s.transpose()) / L;
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    // On a rim: s = (r d_xy / |d_xy|, +-h); ds/dd = r / |d_xy| (P_xy - e e^T), e = d_xy / |d_xy|.
    const double radial = std::hypot(d.x(), d.y());
    if (!(radial > 0.0) || d.z() == 0.0) return Mat3::Zero();
    const Vec3 e(d.x() / radial, d.y() / radial, 0.0);
    Mat3 P = Mat3::Zero();
    P(0, 0) = P(1, 1) = 1.0;
    return c->radius / radial * (P - e * e.transpose());
  }
  if (const auto* c = std::get_if<Capsule>(&shape)) {
    if (d.z() == 0.0) return Mat3::Zero();
    return ball(c->radius);
  }
  if (const auto* b = std::get_if<LoadedBall>(&shape)) return ball(b->radius);
  PALPABLE_CHECK(false, "smooth_support_derivative_M needs a smooth convex shape");
  return Mat3::Zero();
}

Compound make_compound(std::vector<CompoundPart> parts) {
  if (parts.empty()) throw InputError("parts", "a compound needs at least one part");
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string where = "parts/" + std::to_string(i);
    CompoundPart& part = parts[i];
    if (!part.shape) throw InputError(where, "has no shape");
    if (std::holds_alternative<Halfspace>(*part.shape) ||
        std::holds_alternative<Compound>(*part.shape)) {
      throw InputError(where, "must be a convex bounded shape (not a halfspace or a compound)");
    }
    if (!is_finite(part.position_M)) throw InputError(where + "/position", "must be finite");
    const double norm = part.orientation_M.norm();
    if (!(std::isfinite(norm) && std::abs(norm - 1.0) <= 1e-9)) {
      throw InputError(where + "/orientation", "must be a unit quaternion");
    }
    part.orientation_M.normalize();
  }
  return Compound{std::move(parts)};
}

namespace {

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

}  // namespace

bool is_bounded(const Shape& shape) {
  return std::visit(
      Overloaded{[](const Sphere&) { return true; }, [](const ConvexPolyhedron&) { return true; },
                 [](const Halfspace&) { return false; },
                 [](const Compound& c) {
                   if (c.parts.empty()) return false;
                   for (const CompoundPart& part : c.parts) {
                     if (!part.shape || !is_bounded(*part.shape)) return false;
                   }
                   return true;
                 },
                 [](const Ellipsoid&) { return true; }, [](const Cylinder&) { return true; },
                 [](const Capsule&) { return true; }, [](const LoadedBall&) { return true; }},
      shape);
}

namespace {

// Tight: the farthest posed vertex or sphere surface point of any part.
double compound_max_radius(const Compound& c) {
  double r = 0.0;
  for (const CompoundPart& part : c.parts) {
    if (const auto* poly = std::get_if<ConvexPolyhedron>(part.shape.get())) {
      for (const Vec3& v : poly->vertices()) {
        r = std::max(r, (part.position_M + part.orientation_M * v).norm());
      }
    } else {
      r = std::max(r, part.position_M.norm() + max_radius(*part.shape));
    }
  }
  return r;
}

}  // namespace

double max_radius(const Shape& shape) {
  return std::visit(
      Overloaded{[](const Sphere& s) { return s.radius; },
                 [](const ConvexPolyhedron& p) { return p.max_radius(); },
                 [](const Halfspace&) { return kInfinity; },
                 [](const Compound& c) { return compound_max_radius(c); },
                 [](const Ellipsoid& e) {
                   // |c + x|^2 <= a_max^2 + 2 |o| a_z + o^2 for x on the centred ellipsoid and
                   // c = (0, 0, -o): exact for equal semi-axes, a bound otherwise.
                   const double a = e.semi_axes_M.maxCoeff(), o = std::abs(e.com_offset);
                   return o == 0.0 ? a : std::sqrt(a * a + 2.0 * o * e.semi_axes_M.z() + o * o);
                 },
                 [](const Cylinder& c) { return std::hypot(c.radius, c.half_height); },
                 [](const Capsule& c) { return c.half_length + c.radius; },
                 [](const LoadedBall& b) { return b.radius + std::abs(b.com_offset); }},
      shape);
}

Vec3 support_W(const Shape& shape, const Vec3& p_W, const Quat& q_WM, const Vec3& direction_W) {
  if (const auto* sphere = std::get_if<Sphere>(&shape)) {
    const double length = direction_W.norm();
    if (!(length > 0.0)) return p_W;
    return p_W + (sphere->radius / length) * direction_W;
  }
  if (const auto* poly = std::get_if<ConvexPolyhedron>(&shape)) {
    return p_W + q_WM * poly->support(q_WM.conjugate() * direction_W);
  }
  if (is_smooth_convex(shape)) {
    return p_W + q_WM * smooth_support_M(shape, q_WM.conjugate() * direction_W);
  }
  PALPABLE_CHECK(false, "support_W needs a bounded convex shape");
  return p_W;
}

Aabb bounding_box_W(const Shape& shape, const Vec3& p_W, const Quat& q_WM) {
  Aabb box;
  if (const auto* sphere = std::get_if<Sphere>(&shape)) {
    box.min_W = p_W - Vec3::Constant(sphere->radius);
    box.max_W = p_W + Vec3::Constant(sphere->radius);
  } else if (const auto* poly = std::get_if<ConvexPolyhedron>(&shape)) {
    const Mat3 R_WM = q_WM.toRotationMatrix();
    for (const Vec3& v : poly->vertices()) {
      const Vec3 v_W = p_W + R_WM * v;
      box.min_W = box.min_W.cwiseMin(v_W);
      box.max_W = box.max_W.cwiseMax(v_W);
    }
  } else if (const auto* half = std::get_if<Halfspace>(&shape)) {
    box.min_W = Vec3::Constant(-kInfinity);
    box.max_W = Vec3::Constant(kInfinity);
    // Bounded on one side only when the world normal is exactly along an axis; a tilted plane
    // reaches every coordinate's infinity.
    const Vec3 n_W = q_WM * half->normal_M;
    const double offset_W = half->offset + n_W.dot(p_W);
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3;
      const int j = (k + 2) % 3;
      if (n_W[i] != 0.0 || n_W[j] != 0.0 || n_W[k] == 0.0) continue;
      if (n_W[k] > 0.0) {
        box.max_W[k] = offset_W / n_W[k];
      } else {
        box.min_W[k] = offset_W / n_W[k];
      }
    }
  } else if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    // Exact: the support along world axis i reaches |R_i. diag(a)| (row i of R diag(a)).
    const Mat3 RA = q_WM.toRotationMatrix() * e->semi_axes_M.asDiagonal();
    const Vec3 half = RA.rowwise().norm();
    const Vec3 centre_W = p_W + q_WM * e->centre_M();
    box.min_W = centre_W - half;
    box.max_W = centre_W + half;
  } else if (const auto* c = std::get_if<Cylinder>(&shape)) {
    // Exact: a disk of radius r with unit normal k spans r sqrt(1 - k_i^2) along axis i, and the
    // two caps are h |k_i| either side of the centre.
    const Vec3 k_W = q_WM * Vec3::UnitZ();
    Vec3 half;
    for (int i = 0; i < 3; ++i) {
      half[i] = c->radius * std::sqrt(std::max(0.0, 1.0 - k_W[i] * k_W[i])) +
                c->half_height * std::abs(k_W[i]);
    }
    box.min_W = p_W - half;
    box.max_W = p_W + half;
  } else if (const auto* c = std::get_if<Capsule>(&shape)) {
    const Vec3 half =
        c->half_length * (q_WM * Vec3::UnitZ()).cwiseAbs() + Vec3::Constant(c->radius);
    box.min_W = p_W - half;
    box.max_W = p_W + half;
  } else if (const auto* b = std::get_if<LoadedBall>(&shape)) {
    const Vec3 centre_W = p_W + q_WM * b->centre_M();
    box.min_W = centre_W - Vec3::Constant(b->radius);
    box.max_W = centre_W + Vec3::Constant(b->radius);
  } else {
    const auto& compound = std::get<Compound>(shape);
    for (const CompoundPart& part : compound.parts) {
      box.extend(
          bounding_box_W(*part.shape, p_W + q_WM * part.position_M, q_WM * part.orientation_M));
    }
  }
  return box;
}

}  // namespace palpable
