#pragma once
// Shapes in a body's modelling frame M (origin at the body's centre of mass; DESIGN.md §2).
// Immutable after building; building validates its input and throws InputError naming what is
// wrong. Convex polyhedra are half-edge meshes whose coplanar facets are merged into single convex
// polygon faces (a box has 6 faces, 12 edges, 8 vertices — never triangulated).
#include "core/types.hpp"

#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace palpable {

struct Sphere {
  double radius = 0.0;  // [m] > 0
};

// Smooth convex shapes (issue 16), each centred so that the modelling frame's origin is the centre
// of mass. Build them with the validated make_* functions below.

// The solid { x : sum ((x - centre_M())_i / a_i)^2 <= 1 }, semi-axes a = semi_axes_M along M's
// axes [m]. Centred (com_offset 0) unless its centre of mass lies com_offset along +z from its
// geometric centre, |com_offset| < a_z (a rattleback's, Kane & Levinson's: below it); then, as for
// a loaded ball, its mass and inertia are given.
struct Ellipsoid {
  Vec3 semi_axes_M = Vec3::Ones();
  double com_offset = 0.0;  // [m]
  Vec3 centre_M() const { return Vec3(0.0, 0.0, -com_offset); }
};

// A round cylinder, axis along M's z: { x : x^2 + y^2 <= radius^2, |z| <= half_height }. A disk or
// coin when thin; its two rims are sharp circles.
struct Cylinder {
  double radius = 0.0;       // [m] > 0
  double half_height = 0.0;  // [m] > 0
};

// The points within `radius` of the segment from -half_length to +half_length along M's z.
struct Capsule {
  double radius = 0.0;       // [m] > 0
  double half_length = 0.0;  // [m] > 0 (0 would be a sphere: use Sphere)
};

// A sphere whose centre of mass is not at its centre (the tippe top's textbook model): the ball of
// `radius` centred at centre_M() = (0, 0, -com_offset), so the centre of mass (M's origin) lies
// com_offset along +z from the geometric centre; |com_offset| < radius. Uniform density cannot
// put the centre of mass there, so its mass and inertia are given (mass_properties_from_inertia;
// a scene gives "mass" and "inertia").
struct LoadedBall {
  double radius = 0.0;      // [m] > 0
  double com_offset = 0.0;  // [m], |com_offset| < radius
  Vec3 centre_M() const { return Vec3(0.0, 0.0, -com_offset); }
};

// The infinite solid { x : normal_M . x <= offset }. Only for fixed or kinematic bodies.
struct Halfspace {
  Vec3 normal_M = Vec3::UnitZ();  // unit outward normal
  double offset = 0.0;            // [m]
};

// A half-edge of a convex polyhedron. Half-edge h runs from vertex `tail` to the tail of
// `next`; `twin` runs the other way along the same edge; `face` is on h's left seen from outside
// (faces' half-edges circulate counter-clockwise about the outward normal).
struct HalfEdge {
  int tail = -1;
  int twin = -1;
  int next = -1;
  int prev = -1;
  int face = -1;
};

struct PolyFace {
  int half_edge = -1;            // any half-edge of the face
  Vec3 normal_M = Vec3::Zero();  // unit outward normal
  double offset = 0.0;           // plane: normal_M . x = offset
};

class ConvexPolyhedron {
 public:
  // The convex hull of `points` (at least 4 not coplanar), via Qhull, coplanar facets merged.
  // `coplanar_tolerance` [m]: facets whose planes agree within it are merged into one face;
  // negative: kHullCoplanarTolerance (core/settings.hpp) times the points' bounding-box diagonal;
  // zero: Qhull's own merging only. Interior and duplicate points are dropped; vertices within the
  // tolerance of an edge or face are not corners and are dropped too. Throws InputError for
  // fewer than 4 points, non-finite coordinates, identical, collinear or coplanar points.
  // The vertices are shifted so that the centre of mass of the solid (uniform density) is at the
  // origin; `com_shift_M` reports the shift that was subtracted (points_given - shift = stored).
  static ConvexPolyhedron from_points(const std::vector<Vec3>& points,
                                      double coplanar_tolerance = -1.0 /* relative default */);
  // Axis-aligned box centred at the origin.
  static ConvexPolyhedron box(const Vec3& half_extents);
  // Regular n-gonal prism, axis along z, centred at the origin; vertices on radius `radius`,
  // the first at +x. A coin or cylinder as sides grow.
  static ConvexPolyhedron prism(double radius, double half_height, int sides);
  // A polyhedron from its vertices and its faces, each face a list of vertex indices
  // counter-clockwise about the outward normal. Validated like from_points (throws InputError
  // naming the defect); not recentred. `tolerance_m` bounds the planarity and convexity errors.
  static ConvexPolyhedron from_faces(const std::vector<Vec3>& vertices,
                                     const std::vector<std::vector<int>>& faces,
                                     double tolerance_m);

  const std::vector<Vec3>& vertices() const { return vertices_; }
  const std::vector<HalfEdge>& half_edges() const { return half_edges_; }
  const std::vector<PolyFace>& faces() const { return faces_; }
  // One half-edge leaving each vertex (its tail is the vertex).
  const std::vector<int>& vertex_half_edge() const { return vertex_half_edge_; }
  int num_edges() const { return static_cast<int>(half_edges_.size()) / 2; }
  const Vec3& head(int half_edge) const {
    return vertices_[half_edges_[half_edges_[half_edge].twin].tail];
  }
  const Vec3& tail(int half_edge) const { return vertices_[half_edges_[half_edge].tail]; }

  // The vertex maximising direction_M . v (a support point), in M.
  Vec3 support(const Vec3& direction_M) const;
  // Largest distance from the origin (the centre of mass) to any point of the shape [m].
  double max_radius() const { return max_radius_; }
  const Vec3& com_shift_M() const { return com_shift_M_; }

 private:
  friend class ConvexPolyhedronBuilder;
  std::vector<Vec3> vertices_;
  std::vector<HalfEdge> half_edges_;
  std::vector<PolyFace> faces_;
  std::vector<int> vertex_half_edge_;
  double max_radius_ = 0.0;
  Vec3 com_shift_M_ = Vec3::Zero();
};

// The first broken invariant of a polyhedron's half-edge mesh, or "" if it is valid: twin/next/prev
// consistency, face loops, vertex degree >= 3, Euler V - E + F = 2, unit normals, planar convex
// faces (within `tolerance_m`), every vertex inside every face plane (outward normals).
std::string polyhedron_defect(const ConvexPolyhedron& polyhedron, double tolerance_m);

// Validated builders: a positive finite radius; a non-zero finite normal (normalised) and a finite
// offset. Throw InputError naming the argument.
Sphere make_sphere(double radius);
Halfspace make_halfspace(const Vec3& normal_M, double offset);
// Positive finite semi-axes / radius / half-height / half-length, and |com_offset| < radius (an
// ellipsoid's: < its z semi-axis). Throw InputError naming the argument.
Ellipsoid make_ellipsoid(const Vec3& semi_axes_M, double com_offset = 0.0);
Cylinder make_cylinder(double radius, double half_height);
Capsule make_capsule(double radius, double half_length);
LoadedBall make_loaded_ball(double radius, double com_offset);

struct CompoundPart;

// A union of convex pieces, for fixed non-convex bodies (a dish, a table with cushions). Each
// piece pairs separately in distance queries.
struct Compound {
  std::vector<CompoundPart> parts;
};

using Shape = std::variant<Sphere, ConvexPolyhedron, Halfspace, Compound, Ellipsoid, Cylinder,
                           Capsule, LoadedBall>;

// True for the smooth convex shapes above (Ellipsoid, Cylinder, Capsule, LoadedBall): bounded,
// convex, described by their support function rather than a mesh.
bool is_smooth_convex(const Shape& shape);
// The support point of a smooth convex shape in M: a point of the shape maximising
// direction_M . x (exact, closed form). A zero direction gives a point of the shape.
Vec3 smooth_support_M(const Shape& shape, const Vec3& direction_M);
// The derivative of that support point with respect to a unit direction d (3 x 3, symmetric, d in
// its null space): how the touching point moves over the surface as the direction turns - the
// surface's radii of curvature in the plane normal to d (R (I - d d^T) for a ball of radius R; a
// cylinder's rim, rank one along the rim: R / |d_xy| along the rim's tangent). Closed form, for a
// direction at which the support point is unique and smooth: not along a cylinder's or capsule's
// axis direction where a cap or a side would touch (a cylinder: d_xy = 0 or d_z = 0; a capsule:
// d_z = 0), where it returns zero.
Mat3 smooth_support_derivative_M(const Shape& shape, const Vec3& direction_M);

// A convex piece of a compound, posed in the compound's modelling frame.
struct CompoundPart {
  std::shared_ptr<const Shape> shape;  // bounded and convex: not a Halfspace or Compound
  Vec3 position_M = Vec3::Zero();
  Quat orientation_M = Quat::Identity();
};

// A compound from its parts, validated: at least one part, each a bounded convex shape (a Sphere,
// ConvexPolyhedron or one of the smooth shapes above), a finite position and a unit (within 1e-9)
// orientation, which is normalised. Throws InputError naming the part.
Compound make_compound(std::vector<CompoundPart> parts);

// True for shapes a dynamic body may have (finite volume).
bool is_bounded(const Shape& shape);
// Largest distance from the modelling-frame origin to any point of the shape; +inf for a halfspace.
double max_radius(const Shape& shape);
// Support point in world frame of a convex shape posed at (p_W, q_WM); throws for a halfspace or
// compound.
Vec3 support_W(const Shape& shape, const Vec3& p_W, const Quat& q_WM, const Vec3& direction_W);
// World bounding box of the shape posed at (p_W, q_WM); infinite extents for a halfspace.
Aabb bounding_box_W(const Shape& shape, const Vec3& p_W, const Quat& q_WM);

}  // namespace palpable
