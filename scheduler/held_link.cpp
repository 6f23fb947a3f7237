#include "scheduler/held_link.hpp"

#include "core/convex_polygon.hpp"
#include "distance/vclip.hpp"
#include "scheduler/island_detail.hpp"

#include <algorithm>
#include <cmath>

namespace palpable {

namespace {

// The radius of a shape that is one sphere about its origin, else 0.
double centred_sphere_radius(const ShapeGeometry& g) {
  if (g.pieces().size() != 1) return 0.0;
  const ShapeGeometry::Piece& p = g.pieces()[0];
  return p.kind == ShapeGeometry::PieceKind::kSphere && p.p_M.norm() == 0.0 ? p.radius : 0.0;
}

// The Voronoi planes of a polyhedral piece's vertex (1 point) or edge (2), given by its points in
// the body frame, turned into the body frame; empty if the piece has no such feature.
std::vector<VoronoiPlane> feature_region(const ShapeGeometry& g, int piece_index,
                                         const std::vector<Vec3>& feature_B) {
  std::vector<VoronoiPlane> out;
  if (piece_index < 0 || piece_index >= static_cast<int>(g.pieces().size())) return out;
  const ShapeGeometry::Piece& piece = g.pieces()[static_cast<std::size_t>(piece_index)];
  if (piece.kind != ShapeGeometry::PieceKind::kPolyhedron || !piece.mesh) return out;
  const FeatureMesh& mesh = *piece.mesh;
  const double tol = 1e-9 * std::max(piece.max_radius, 1e-3);
  auto vertex_at = [&](const Vec3& p_B) {
    const Vec3 p = piece.R_M.transpose() * (p_B - piece.p_M);
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if ((mesh.vertex(v) - p).norm() <= tol) return v;
    }
    return -1;
  };
  const VoronoiPlane* begin = nullptr;
  const VoronoiPlane* end = nullptr;
  if (feature_B.size() == 1) {
    const int v = vertex_at(feature_B[0]);
    if (v < 0) return out;
    begin = mesh.vertex_planes_begin(v);
    end = mesh.vertex_planes_end(v);
  } else if (feature_B.size() == 2) {
    const int v0 = vertex_at(feature_B[0]), v1 = vertex_at(feature_B[1]);
    if (v0 < 0 || v1 < 0) return out;
    for (int h = 0; h < mesh.num_half_edges() && !begin; ++h) {
      if (mesh.tail_vertex(h) == v0 && mesh.head_vertex(h) == v1) {
        begin = mesh.edge_planes(h);
        end = begin + 4;
      }
    }
    if (!begin) return out;
  } else {
    return out;
  }
  for (const VoronoiPlane* plane = begin; plane != end; ++plane) {
    // From the piece's frame to the body's: n . R^T (x - p) - offset = (R n) . x - (offset +
    // (R n) . p).
    VoronoiPlane in_body = *plane;
    in_body.normal_M = piece.R_M * plane->normal_M;
    in_body.offset = plane->offset + in_body.normal_M.dot(piece.p_M);
    out.push_back(in_body);
  }
  return out;
}

std::optional<HeldLink> point_pair_link(std::uint32_t pair, BodyId a, BodyId b,
                                        const LinkSide& side_a, const LinkSide& side_b,
                                        const DistanceResult& closest,
                                        const ContactGeometry& geometry) {
  const bool mover_is_a = side_a.body.is_dynamic();
  const LinkSide& mover = mover_is_a ? side_a : side_b;
  const LinkSide& support = mover_is_a ? side_b : side_a;
  const std::vector<Vec3>& mf = mover_is_a ? geometry.feature1 : geometry.feature2;
  const std::vector<Vec3>& sf = mover_is_a ? geometry.feature2 : geometry.feature1;
  HeldLink link;
  link.pair = pair;
  link.point_pair = true;
  link.mover = mover_is_a ? a : b;
  link.support = mover_is_a ? b : a;
  link.support_piece = mover_is_a ? closest.piece2 : closest.piece1;
  link.gap = std::max(closest.distance, 0.0);
  const Mat3 R_M = rotation(mover.state), R_S = rotation(support.state);
  link.sphere_radius = centred_sphere_radius(mover.geometry);
  link.support_sphere_radius = centred_sphere_radius(support.geometry);
  // Between two polyhedra, an edge across an edge is held while it stays the pair of closest
  // features (HeldLink::support_region). (Not held, a hull leaning on another by an edge was a
  // train of microcollisions, each lending up to the floor's energy: in a pile of 50 hulls two
  // such pairs were struck every 3 ms for seconds, +1.3e-5 J each time, and kept their cluster
  // from rest.) A vertex on an edge stays a collision. A sphere has nothing else that could
  // touch.
  const bool polyhedra = link.sphere_radius == 0.0 && link.support_sphere_radius == 0.0;
  if (polyhedra && (mf.size() != 2 || sf.size() != 2)) return std::nullopt;
  if (link.sphere_radius == 0.0) {
    if (mf.empty() || mf.size() > 2) return std::nullopt;
    for (const Vec3& p : mf)
      link.mover_feature_M.push_back(R_M.transpose() * (p - mover.state.x_W));
  }
  if (link.support_sphere_radius == 0.0) {
    if (sf.empty() || sf.size() > 2) return std::nullopt;
    for (const Vec3& p : sf)
      link.support_face_S.push_back(R_S.transpose() * (p - support.state.x_W));
  }
  // Two parallel edges: a segment, not a point (no rule holds it).
  if (link.mover_feature_M.size() == 2 && link.support_face_S.size() == 2) {
    const Vec3 e1 = mf[1] - mf[0], e2 = sf[1] - sf[0];
    if (e1.cross(e2).norm() <= 1e-9 * e1.norm() * e2.norm()) return std::nullopt;
  }
  const Vec3 n_W = mover_is_a ? closest.n_W : Vec3(-closest.n_W);
  link.normal_S = R_S.transpose() * n_W;  // the normal now (the fallback where it is undefined)
  link.t1_S = link.normal_S.unitOrthogonal();
  if (polyhedra) {
    link.feature_region = feature_region(
        mover.geometry, mover_is_a ? closest.piece1 : closest.piece2, link.mover_feature_M);
    link.support_region = feature_region(
        support.geometry, mover_is_a ? closest.piece2 : closest.piece1, link.support_face_S);
    // Edges not of the meshes (a patch clipped to the envelope): nothing to watch them by.
    if (link.feature_region.empty() || link.support_region.empty()) return std::nullopt;
  } else if (link.sphere_radius == 0.0) {
    link.feature_region = feature_region(
        mover.geometry, mover_is_a ? closest.piece1 : closest.piece2, link.mover_feature_M);
  } else if (link.support_sphere_radius == 0.0) {
    link.feature_region = feature_region(
        support.geometry, mover_is_a ? closest.piece2 : closest.piece1, link.support_face_S);
  }
  return link;
}

// The closest points of two features, each a point (1), a line through a segment (2): on the
// mover's (q_m) and on the support's (q_s).
void closest_core_points(const std::vector<Vec3>& m, const std::vector<Vec3>& s, Vec3& q_m,
                         Vec3& q_s) {
  auto on_line = [](const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 d = b - a;
    return Vec3(a + d * (d.dot(p - a) / d.squaredNorm()));
  };
  if (m.size() == 1 && s.size() == 1) {
    q_m = m[0];
    q_s = s[0];
  } else if (m.size() == 1) {
    q_m = m[0];
    q_s = on_line(q_m, s[0], s[1]);
  } else if (s.size() == 1) {
    q_s = s[0];
    q_m = on_line(q_s, m[0], m[1]);
  } else {
    // Two lines: p = m0 + u d1, q = s0 + v d2 with p - q normal to both.
    const Vec3 d1 = m[1] - m[0], d2 = s[1] - s[0], r = m[0] - s[0];
    const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(r), e = d2.dot(r);
    const double den = a * c - b * b;
    const double u = (b * e - c * d) / den, v = (a * e - b * d) / den;
    q_m = m[0] + u * d1;
    q_s = s[0] + v * d2;
  }
}

// Whether a body touches with a curved surface along a point or a line: a smooth piece
// (ellipsoid, cylinder, capsule) other than a cylinder's flat cap, or a loaded ball. Rolling moves
// such a contact over the body's surface, which a held link — material points of the mover, a
// fixed feature of the support — cannot follow; the contact stays a train of microcollisions.
bool curved_contact(const ShapeGeometry& g, int piece, const std::vector<Vec3>& feature) {
  if (piece < 0 || piece >= static_cast<int>(g.pieces().size())) return false;
  const bool curved = g.pieces()[piece].kind == ShapeGeometry::PieceKind::kSmooth ||
                      std::holds_alternative<LoadedBall>(g.shape());
  return curved && feature.size() < 3;
}

// The radius of a round side touching along a straight segment — a cylinder or a capsule lying
// on its side — else 0. Such a contact is held as a rounded segment (HeldLink::sphere_radius with
// a two-point core): its contact line is the core (the axis, material) moved by the radius
// against the normal, whichever way the body rolls about it.
double round_side_radius(const ShapeGeometry& g, int piece, const std::vector<Vec3>& feature) {
  if (piece < 0 || piece >= static_cast<int>(g.pieces().size()) || feature.size() != 2) return 0.0;
  const ShapeGeometry::Piece& p = g.pieces()[piece];
  if (p.kind != ShapeGeometry::PieceKind::kSmooth || p.smooth == nullptr) return 0.0;
  if (const auto* cylinder = std::get_if<Cylinder>(p.smooth)) return cylinder->radius;
  if (const auto* capsule = std::get_if<Capsule>(p.smooth)) return capsule->radius;
  return 0.0;
}

}  // namespace

double curved_rise(const Shape& shape, const Vec3& d, double end) {
  const double along = end != 0.0 ? d.z() * end : std::abs(d.z());
  if (const auto* cylinder = std::get_if<Cylinder>(&shape)) {
    return 2.0 *
           std::min(cylinder->half_height * along, cylinder->radius * std::hypot(d.x(), d.y()));
  }
  if (const auto* capsule = std::get_if<Capsule>(&shape)) return 2.0 * capsule->half_length * along;
  return kInfinity;
}

namespace {

// The direction d of -n in a curved link's piece frame, turned onto the end it holds (its sign
// along z; +-1e-300 where it is zero, a body standing level).
Vec3 held_direction(const HeldLink& link, Vec3 d) {
  if (link.curved_end != 0.0) d.z() = link.curved_end * std::max(std::abs(d.z()), 1e-300);
  return d;
}

}  // namespace

double landing_level(double held_height, double envelope) {
  return 0.5 * std::max(held_height, 0.5 * envelope);
}

std::optional<HeldLink> make_held_link(std::uint32_t pair, BodyId a, BodyId b,
                                       const LinkSide& side_a, const LinkSide& side_b,
                                       const DistanceResult& closest,
                                       const ContactGeometry& geometry, double envelope) {
  const bool plane1 = geometry.unbounded1 || geometry.feature1.size() >= 3;
  const bool plane2 = geometry.unbounded2 || geometry.feature2.size() >= 3;
  // A round side on the other body's plane is held as a rounded segment; any other curved contact
  // is not (see curved_contact).
  const double round1 = round_side_radius(side_a.geometry, closest.piece1, geometry.feature1);
  const double round2 = round_side_radius(side_b.geometry, closest.piece2, geometry.feature2);
  const bool curved1 =
      round1 == 0.0 && curved_contact(side_a.geometry, closest.piece1, geometry.feature1);
  const bool curved2 =
      round2 == 0.0 && curved_contact(side_b.geometry, closest.piece2, geometry.feature2);
  if (((curved1 || round1 > 0.0) && !plane2) || ((curved2 || round2 > 0.0) && !plane1)) {
    return std::nullopt;
  }
  if (!plane1 && !plane2) return point_pair_link(pair, a, b, side_a, side_b, closest, geometry);
  // Body 2's plane faces body 1 along n; body 1's faces body 2 along -n. Face on face: the
  // support is the fixed or kinematic body, or body 2.
  bool support_is_b = plane2;
  if (plane1 && plane2 && side_b.body.is_dynamic() && !side_a.body.is_dynamic()) {
    support_is_b = false;
  }
  const LinkSide& mover = support_is_b ? side_a : side_b;
  const LinkSide& support = support_is_b ? side_b : side_a;
  if (!mover.body.is_dynamic()) return std::nullopt;  // a halfspace or a fixed body never moves
  HeldLink link;
  link.pair = pair;
  link.mover = support_is_b ? a : b;
  link.support = support_is_b ? b : a;
  link.support_piece = support_is_b ? closest.piece2 : closest.piece1;
  const Vec3 n_W = support_is_b ? closest.n_W : Vec3(-closest.n_W);
  const Vec3& plane_point_W = support_is_b ? closest.p2_W : closest.p1_W;
  const Mat3 R_S = rotation(support.state);
  const Mat3 R_M = rotation(mover.state);
  link.normal_S = (R_S.transpose() * n_W).normalized();
  link.point_S = R_S.transpose() * (plane_point_W - support.state.x_W);
  link.t1_S = link.normal_S.unitOrthogonal();
  link.gap = std::max(closest.distance, 0.0);
  const std::vector<Vec3>& support_feature = support_is_b ? geometry.feature2 : geometry.feature1;
  const bool unbounded = support_is_b ? geometry.unbounded2 : geometry.unbounded1;
  if (!unbounded) {
    for (const Vec3& p : support_feature) {
      link.support_face_S.push_back(R_S.transpose() * (p - support.state.x_W));
    }
  }
  const ShapeGeometry& mg = mover.geometry;
  const double round = support_is_b ? round1 : round2;
  const bool curved = support_is_b ? curved1 : curved2;
  if (round > 0.0 || curved) {
    // On a face, the face's own plane (the query's normal from GJK is as loose as its points: a
    // plane tilted by 1e-5 would be rolled up or down).
    if (support_feature.size() >= 3) {
      Vec3 face_n = Vec3::Zero();
      for (std::size_t i = 0; i < support_feature.size(); ++i) {
        face_n += support_feature[i].cross(support_feature[(i + 1) % support_feature.size()]);
      }
      if (face_n.norm() > 0.0) {
        face_n = face_n.dot(n_W) < 0.0 ? Vec3(-face_n.normalized()) : Vec3(face_n.normalized());
        link.normal_S = R_S.transpose() * face_n;
        link.point_S = R_S.transpose() * (support_feature[0] - support.state.x_W);
        link.t1_S = link.normal_S.unitOrthogonal();
      }
    }
  }
  const ShapeGeometry::Piece* mover_piece = nullptr;
  {
    const int index = support_is_b ? closest.piece1 : closest.piece2;
    if (index >= 0 && index < static_cast<int>(mg.pieces().size())) {
      mover_piece = &mg.pieces()[static_cast<std::size_t>(index)];
    }
  }
  if (curved) {
    // The touching point is the shape's support point against the normal, found afresh at every
    // state (place_link): a smooth piece, or a loaded ball (a sphere piece about its centre,
    // whose shape places the centre itself).
    if (mover_piece == nullptr) return std::nullopt;
    if (mover_piece->kind == ShapeGeometry::PieceKind::kSmooth && mover_piece->smooth) {
      link.curved_shape = mover_piece->smooth;
      link.piece_p_M = mover_piece->p_M;
      link.piece_R_M = mover_piece->R_M;
    } else if (std::holds_alternative<LoadedBall>(mg.shape())) {
      link.curved_shape = &mg.shape();
    } else {
      return std::nullopt;
    }
    // A rim already within the landing level of its cap or its other rim (a disk all but upright
    // or flat) is not held as a point: it would land at once, be struck and held again, at one
    // instant, without end (a disk started 0.1 degrees from upright did).
    const Vec3 d = (R_M * link.piece_R_M).transpose() * -n_W;
    if (std::holds_alternative<Cylinder>(*link.curved_shape) ||
        std::holds_alternative<Capsule>(*link.curved_shape)) {
      link.curved_end = d.z() >= 0.0 ? 1.0 : -1.0;
    }
    if (curved_rise(*link.curved_shape, d, link.curved_end) <= landing_level(link.gap, envelope)) {
      return std::nullopt;
    }
  } else if (round > 0.0) {
    // The core under the contact line: the piece's own axis (exact, material), not the query's
    // points (a closest-feature query places them only to its tolerance, and a core off the axis
    // would lift and drop the body as it rolls).
    link.sphere_radius = round;
    const ShapeGeometry::Piece& piece = *mover_piece;
    link.side_shape = piece.smooth;
    link.piece_p_M = piece.p_M;
    link.piece_R_M = piece.R_M;
    double half = 0.0;
    if (const auto* cylinder = std::get_if<Cylinder>(piece.smooth)) half = cylinder->half_height;
    if (const auto* capsule = std::get_if<Capsule>(piece.smooth)) half = capsule->half_length;
    for (const double end : {-half, half}) {
      link.mover_feature_M.push_back(piece.p_M + piece.R_M * Vec3(0.0, 0.0, end));
    }
  } else if (mg.pieces().size() == 1 && mg.pieces()[0].kind == ShapeGeometry::PieceKind::kSphere &&
             mg.pieces()[0].p_M.norm() == 0.0) {
    link.sphere_radius = mg.pieces()[0].radius;
  } else {
    const std::vector<Vec3>& feature = support_is_b ? geometry.feature1 : geometry.feature2;
    if (feature.empty()) return std::nullopt;
    for (const Vec3& p : feature) {
      link.mover_feature_M.push_back(R_M.transpose() * (p - mover.state.x_W));
    }
  }
  return link;
}

namespace {

// The normal of a point-pair link at the given states (from the support's feature to the
// mover's), its contact point on the mover, and whether the closest points lie on the features
// (and a sphere's centre within the Voronoi region of a polyhedron's feature held against it).
bool point_pair_normal(const HeldLink& link, const BodyState& mover, const BodyState& support,
                       Vec3& n, Vec3& c, double* region_margin = nullptr) {
  const Mat3 R_M = rotation(mover), R_S = rotation(support);
  std::vector<Vec3> m, s;
  if (link.sphere_radius > 0.0) {
    m.push_back(mover.x_W);
  } else {
    for (const Vec3& p : link.mover_feature_M) m.push_back(mover.x_W + R_M * p);
  }
  if (link.support_sphere_radius > 0.0) {
    s.push_back(support.x_W);
  } else {
    for (const Vec3& p : link.support_face_S) s.push_back(support.x_W + R_S * p);
  }
  Vec3 q_m, q_s;
  closest_core_points(m, s, q_m, q_s);
  const Vec3 d = q_m - q_s;
  const double length = d.norm();
  n = length > 0.0 ? Vec3(d / length) : Vec3(R_S * link.normal_S);
  // Across edges the normal is e1 x e2, which keeps its sense while the edges move.
  if (m.size() == 2 && s.size() == 2 && length == 0.0) {
    n = (m[1] - m[0]).cross(s[1] - s[0]).normalized();
    if (n.dot(R_S * link.normal_S) < 0.0) n = -n;
  }
  c = q_m - link.sphere_radius * n;
  // Within the features: a closest point past an edge's end leaves the contact.
  auto within = [](const std::vector<Vec3>& f, const Vec3& q) {
    if (f.size() != 2) return true;
    const Vec3 e = f[1] - f[0];
    const double u = e.dot(q - f[0]) / e.squaredNorm();
    return u >= -1e-9 && u <= 1.0 + 1e-9;
  };
  // Within the polyhedron's feature's Voronoi region: the sphere's centre, in its body frame.
  // Two polyhedra's edges: each edge's region, at a point of the other's side one edge length
  // from its closest point along the normal. (Touching, the closest points lie on both edges,
  // on the boundary of both regions whatever the edges' directions; it is the normal that
  // leaves an edge's region when the other edge turns to lie in one of its faces, as V-Clip
  // tests edge against edge. At the closest points themselves a box edge turning across a fixed
  // ridge's edge went on down into the ridge's face, 6 cm deep.)
  double size = std::max(link.sphere_radius, link.support_sphere_radius);
  const bool edges = !link.support_region.empty();
  if (edges) size = std::max((m[1] - m[0]).norm(), (s[1] - s[0]).norm());
  double margin = kInfinity;
  if (!link.feature_region.empty()) {
    const bool on_mover = link.sphere_radius == 0.0;
    const BodyState& poly = on_mover ? mover : support;
    const Vec3 other_W = edges ? Vec3(q_s - size * n) : on_mover ? support.x_W : mover.x_W;
    const Vec3 centre_B = (on_mover ? R_M : R_S).transpose() * (other_W - poly.x_W);
    for (const VoronoiPlane& plane : link.feature_region) {
      margin = std::min(margin, plane.eval(centre_B));
    }
  }
  if (edges) {
    const Vec3 q_B = R_S.transpose() * (q_m + size * n - support.x_W);
    for (const VoronoiPlane& plane : link.support_region)
      margin = std::min(margin, plane.eval(q_B));
  }
  if (region_margin) *region_margin = margin;
  return within(m, q_m) && within(s, q_s) && margin >= -1e-9 * size;
}

// A body moved rigidly by dt at its present velocities (for the normal's rate).
BodyState drift(const BodyState& s, double dt) {
  BodyState out = s;
  out.x_W += s.v_W * dt;
  out.q_WM = (rotation_quat(s.w_W * dt) * s.q_WM).normalized();
  return out;
}

}  // namespace

double held_feature_height(const HeldLink& link, const BodyState& mover, const BodyState& support) {
  const Mat3 R_S = rotation(support);
  const Mat3 R_M = rotation(mover);
  const Vec3 n = R_S * link.normal_S;
  const Vec3 plane = support.x_W + R_S * link.point_S;
  double lowest = kInfinity;
  for (const Vec3& f : link.mover_feature_M) {
    lowest = std::min(lowest, n.dot(mover.x_W + R_M * f - plane));
  }
  return lowest;
}

bool place_link(const HeldLink& link, const BodyState& mover, const BodyState& support,
                HeldContact& out) {
  if (link.point_pair) {
    Vec3 n, c;
    if (!point_pair_normal(link, mover, support, n, c, &out.feature_margin)) return false;
    out.n_W = n;
    out.t1_W = n.unitOrthogonal();
    out.t2_W = n.cross(out.t1_W);
    out.c_W = c;
    out.sphere_radius = link.sphere_radius;
    out.patch = PatchKind::kPoint;
    out.polygon.clear();
    out.edge_on_edge = !link.support_region.empty();
    // The normal's rate by a central difference over the bodies' rigid motion (it depends on
    // velocities only): steps that move the features by a millionth of their size.
    const double size = std::max(
        {link.sphere_radius, link.support_sphere_radius, 1e-3, (mover.x_W - support.x_W).norm()});
    const double speed =
        (mover.v_W - support.v_W).norm() + (mover.w_W.norm() + support.w_W.norm()) * size;
    // A polyhedral mover's edge: its point closest to the sphere's centre x runs along it,
    // q = a + ((x - a) . e) e for unit e, at ((x' - a') . e + (x - a) . e') e over the edge's own
    // motion (a' = v + w x (a - x_M), e' = w x e).
    out.mover_slide_W.setZero();
    if (link.sphere_radius == 0.0 && link.mover_feature_M.size() == 2 &&
        link.support_sphere_radius > 0.0) {
      const Mat3 R_M = rotation(mover);
      const Vec3 a = mover.x_W + R_M * link.mover_feature_M[0];
      const Vec3 e = (R_M * (link.mover_feature_M[1] - link.mover_feature_M[0])).normalized();
      const Vec3 a_dot = mover.v_W + mover.w_W.cross(a - mover.x_W);
      const Vec3 e_dot = mover.w_W.cross(e);
      out.mover_slide_W = ((support.v_W - a_dot).dot(e) + (support.x_W - a).dot(e_dot)) * e;
    }
    out.has_n_dot = true;
    out.n_dot_W.setZero();
    if (speed > 0.0) {
      const double dt = 1e-6 * size / speed;
      Vec3 n_plus, n_minus, c_plus, c_minus;
      point_pair_normal(link, drift(mover, dt), drift(support, dt), n_plus, c_plus);
      point_pair_normal(link, drift(mover, -dt), drift(support, -dt), n_minus, c_minus);
      out.n_dot_W = (n_plus - n_minus) / (2.0 * dt);
      // An edge across an edge: the contact point runs along the mover's edge too (the edges'
      // closest point), at its own velocity less the mover's material point's there.
      if (!link.support_region.empty()) {
        out.mover_slide_W =
            (c_plus - c_minus) / (2.0 * dt) - (mover.v_W + mover.w_W.cross(c - mover.x_W));
      }
    }
    return true;
  }
  const Mat3 R_S = rotation(support);
  const Mat3 R_M = rotation(mover);
  const Vec3 n = R_S * link.normal_S;
  const Vec3 t1 = R_S * link.t1_S;
  const Vec3 t2 = n.cross(t1);
  const Vec3 origin = support.x_W + R_S * link.point_S;
  auto project = [&](const Vec3& p) { return Vec2(t1.dot(p - origin), t2.dot(p - origin)); };
  out.n_W = n;
  out.t1_W = t1;
  out.t2_W = t2;
  out.sphere_radius = link.sphere_radius;
  std::vector<Vec2> feature;
  std::vector<double> heights;
  out.curved = link.curved_shape != nullptr;
  if (out.curved) {
    // The curved surface's lowest point against the plane, and how it moves over the surface.
    const Mat3 R = R_M * link.piece_R_M;
    const Vec3 d = held_direction(link, R.transpose() * -n);
    const Vec3 c = mover.x_W + R_M * link.piece_p_M + R * smooth_support_M(*link.curved_shape, d);
    feature.push_back(project(c));
    heights.push_back(n.dot(c - origin));
    out.curvature_W = R * smooth_support_derivative_M(*link.curved_shape, d) * R.transpose();
    out.curved_size = max_radius(*link.curved_shape);
  } else if (link.sphere_radius > 0.0 && link.mover_feature_M.empty()) {
    const Vec3 c = mover.x_W - link.sphere_radius * n;
    feature.push_back(project(c));
    heights.push_back(n.dot(c - origin));
  } else {
    // A polyhedron's feature, or a rounded segment's contact line (its core less R n).
    for (const Vec3& p_M : link.mover_feature_M) {
      const Vec3 p = mover.x_W + R_M * p_M - link.sphere_radius * n;
      feature.push_back(project(p));
      heights.push_back(n.dot(p - origin));
    }
  }
  double scale = 1e-300;
  for (const Vec2& p : feature) scale = std::max(scale, p.norm());
  const double tol = 1e-12 * scale;
  std::vector<Vec2> patch = tidy(feature, tol);
  if (!link.support_face_S.empty() && !patch.empty()) {
    std::vector<Vec2> face;
    for (const Vec3& p_S : link.support_face_S) face.push_back(project(support.x_W + R_S * p_S));
    face = tidy(face, tol);
    if (patch.size() == 1) {
      // A point: on the face if inside every edge.
      bool inside = true;
      for (std::size_t i = 0; i < face.size() && face.size() >= 3; ++i) {
        const Vec2 e = face[(i + 1) % face.size()] - face[i];
        inside = inside && cross2(e, patch[0] - face[i]) >= -tol * e.norm();
      }
      if (!inside) patch.clear();
    } else {
      patch = tidy(intersect(patch, face), tol);
    }
  }
  if (patch.empty()) return false;
  double height = 0.0;
  for (double h : heights) height += h;
  height /= static_cast<double>(heights.size());
  const Vec2 c2 = centroid(patch);
  out.c_W = origin + c2.x() * t1 + c2.y() * t2 + height * n;
  out.core_offset_W = link.sphere_radius > 0.0 && !link.mover_feature_M.empty()
                          ? Vec3(out.c_W + link.sphere_radius * n - mover.x_W)
                          : Vec3::Zero();
  out.polygon.clear();
  if (patch.size() >= 3) {
    out.patch = PatchKind::kPolygon;
    for (const Vec2& p : patch) out.polygon.push_back(p - c2);
  } else if (patch.size() == 2) {
    out.patch = PatchKind::kSegment;
    const Vec2 d = patch[1] - patch[0];
    const double length = d.norm();
    out.segment_W = (d.x() * t1 + d.y() * t2) / length;
    out.segment_lo = -0.5 * length;
    out.segment_hi = 0.5 * length;
  } else {
    out.patch = PatchKind::kPoint;
  }
  return true;
}

namespace {

// Whether direction n lies in the normal cone of an edge whose faces have normals a and b (n a
// non-negative combination of them; n is perpendicular to the edge, so it lies in their plane).
bool in_normal_cone(const Vec3& n, const Vec3& a, const Vec3& b) {
  const double ab = a.dot(b);
  return n.dot(a) - ab * n.dot(b) >= 0.0 && n.dot(b) - ab * n.dot(a) >= 0.0;
}

}  // namespace

double edge_separation(const FeatureMesh& support, const Mat3& R_support,
                       const Vec3& origin_support, const FeatureMesh& mover, const Mat3& R_mover,
                       const Vec3& origin_mover, const EdgeWatch& watch) {
  const Vec3 p = origin_support + R_support * support.tail(watch.support_edge);
  const Vec3 q = origin_mover + R_mover * mover.tail(watch.mover_edge);
  Vec3 n = (R_support * (support.head(watch.support_edge) - support.tail(watch.support_edge)))
               .cross(R_mover * (mover.head(watch.mover_edge) - mover.tail(watch.mover_edge)));
  if (n.dot(watch.axis_W) < 0.0) n = -n;                          // the orientation chosen
  if (!(n.dot(watch.axis_W) > 0.5 * n.norm())) return kInfinity;  // turned through parallel
  return n.dot(q - p) / n.norm();
}

std::vector<EdgeWatch> edge_watch_candidates(const ShapeGeometry::Piece& mover, const Mat3& R_mover,
                                             const Vec3& origin_mover,
                                             const std::vector<bool>& held_vertex,
                                             const ShapeGeometry::Piece& support,
                                             const Mat3& R_support, const Vec3& origin_support,
                                             double envelope) {
  std::vector<EdgeWatch> out;
  const FeatureMesh& support_mesh = *support.mesh;
  const FeatureMesh& mover_mesh = *mover.mesh;
  std::vector<Vec3> mover_W(static_cast<std::size_t>(mover_mesh.num_vertices()));
  for (int v = 0; v < mover_mesh.num_vertices(); ++v)
    mover_W[v] = origin_mover + R_mover * mover_mesh.vertex(v);
  const double reach = mover_mesh.max_radius() + envelope;
  for (int hs = 0; hs < support_mesh.num_half_edges(); ++hs) {
    if (support_mesh.twin(hs) < hs) continue;
    const Vec3 p = origin_support + R_support * support_mesh.tail(hs);
    const Vec3 u = R_support * (support_mesh.head(hs) - support_mesh.tail(hs));
    // Beyond the mover's bounding sphere: nothing of the mover near this edge.
    const double along = std::clamp((origin_mover - p).dot(u) / u.squaredNorm(), 0.0, 1.0);
    if ((p + along * u - origin_mover).norm() > reach) continue;
    const Vec3 a = R_support * support_mesh.face_normal(support_mesh.face_of(hs));
    const Vec3 b =
        R_support * support_mesh.face_normal(support_mesh.face_of(support_mesh.twin(hs)));
    for (int hm = 0; hm < mover_mesh.num_half_edges(); ++hm) {
      if (mover_mesh.twin(hm) < hm) continue;
      if (held_vertex[mover_mesh.tail_vertex(hm)] && held_vertex[mover_mesh.head_vertex(hm)])
        continue;
      const Vec3& q = mover_W[mover_mesh.tail_vertex(hm)];
      const Vec3 v = mover_W[mover_mesh.head_vertex(hm)] - q;
      const Vec3 n = u.cross(v);
      const double n_norm = n.norm();
      if (!(n_norm > 1e-3 * u.norm() * v.norm())) continue;  // nearly parallel: faces'
      const double gap = n.dot(q - p) / n_norm;  // the lines' distance, at most the edges'
      if (!(std::abs(gap) <= envelope)) continue;
      // The edges' closest points, inside both (a segment's closest point clamped to an end
      // means the lines' lies beyond it): then the edges' distance is the lines'.
      double s = 0.0, t = 0.0;
      Vec3 on_support, on_mover;
      closest_params_segment_segment(p, p + u, q, q + v, s, t, on_support, on_mover);
      if (!(s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0)) continue;
      const Vec3 c = R_mover * mover_mesh.face_normal(mover_mesh.face_of(hm));
      const Vec3 d = R_mover * mover_mesh.face_normal(mover_mesh.face_of(mover_mesh.twin(hm)));
      for (const double sign : {1.0, -1.0}) {
        const Vec3 axis = sign * n;
        if (in_normal_cone(axis, a, b) && in_normal_cone(-axis, c, d)) {
          // The separation now; the caller turns it into a threshold.
          out.push_back({hs, hm, axis / n_norm, sign * gap});
          break;
        }
      }
    }
  }
  return out;
}

int support_edge_under(const HeldLink& link, const BodyState& support,
                       const std::vector<Vec3>& points) {
  const std::size_t n = link.support_face_S.size();
  if (n < 3) return -1;
  const Mat3 R = rotation(support);
  double size = 0.0;
  for (const Vec3& p : link.support_face_S) size = std::max(size, p.norm());
  const double tol = 1e-9 * std::max(size, 1e-300);
  for (std::size_t e = 0; e < n; ++e) {
    const Vec3 a = support.x_W + R * link.support_face_S[e];
    const Vec3 b = support.x_W + R * link.support_face_S[(e + 1) % n];
    const Vec3 normal = R * link.normal_S;
    // The edge's direction within the plane: the face may be tilted from the link's normal (a
    // face-on-face link takes the query's normal, 1e-4 rad off a hull's face), and measured along
    // the edge itself, points on it were 1e-6 m off it: a hull tipping over the edge of another's
    // face kept its own edge there instead of turning the roles round, and that edge, on the
    // face's boundary, left the face at once: the link was integrated without a contact, and the
    // hull went 0.8 mm into the other (50 hulls, seed 8).
    Vec3 d = b - a;
    d = (d - normal * normal.dot(d)).normalized();
    bool on = true;
    for (const Vec3& p : points) {
      // Distance within the plane from the edge's line (the points sit `gap` above it).
      Vec3 r = p - a;
      r -= normal * normal.dot(r);
      on = on && (r - d * d.dot(r)).norm() <= tol;
    }
    if (on) return static_cast<int>(e);
  }
  return -1;
}

bool swap_roles(HeldLink& link, int edge, const BodyState& mover, const BodyState& support) {
  if (link.mover_feature_M.size() < 3) return false;
  HeldLink swapped;
  swapped.pair = link.pair;
  swapped.mover = link.support;
  swapped.support = link.mover;
  swapped.support_piece = 0;
  const std::size_t n = link.support_face_S.size();
  swapped.mover_feature_M = {link.support_face_S[static_cast<std::size_t>(edge)],
                             link.support_face_S[(static_cast<std::size_t>(edge) + 1) % n]};
  swapped.support_face_S = link.mover_feature_M;
  const Vec3 n_W = rotation(support) * link.normal_S;
  swapped.normal_S = -(rotation(mover).transpose() * n_W);
  swapped.point_S = link.mover_feature_M[0];
  swapped.t1_S = swapped.normal_S.unitOrthogonal();
  swapped.gap = link.gap;
  link = swapped;
  return true;
}

bool to_point_pair(HeldLink& link, const BodyState& mover, const BodyState& support) {
  const std::size_t n = link.support_face_S.size();
  // Only a sphere has a point contact that can be held (two polyhedra: see point_pair_link).
  if (link.point_pair || link.sphere_radius == 0.0 || !link.mover_feature_M.empty() || n < 3) {
    return false;
  }
  const Mat3 R_S = rotation(support);
  const std::vector<Vec3> m = {mover.x_W};
  double best = kInfinity;
  std::size_t edge = 0;
  for (std::size_t e = 0; e < n; ++e) {
    const std::vector<Vec3> s = {support.x_W + R_S * link.support_face_S[e],
                                 support.x_W + R_S * link.support_face_S[(e + 1) % n]};
    Vec3 q_m, q_s;
    closest_core_points(m, s, q_m, q_s);
    const double d = (q_m - q_s).norm();
    if (d < best) {
      best = d;
      edge = e;
    }
  }
  if (!std::isfinite(best)) return false;
  link.support_face_S = {link.support_face_S[edge], link.support_face_S[(edge + 1) % n]};
  link.point_pair = true;
  return true;
}

}  // namespace palpable
