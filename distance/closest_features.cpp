#include "distance/closest_features.hpp"

#include "core/convex_polygon.hpp"
#include "distance/gjk.hpp"

#include "core/check.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace palpable {

ShapeGeometry::ShapeGeometry(std::shared_ptr<const Shape> shape) : shape_(std::move(shape)) {
  PALPABLE_CHECK(shape_ != nullptr, "ShapeGeometry needs a shape");
  meshes_.push_back(std::make_unique<FeatureMesh>(FeatureMesh::point()));
  if (const auto* compound = std::get_if<Compound>(shape_.get())) {
    for (const CompoundPart& part : compound->parts) {
      PALPABLE_CHECK(part.shape != nullptr, "compound part without a shape");
      add_piece(*part.shape, part.position_M, part.orientation_M.normalized().toRotationMatrix());
    }
  } else {
    add_piece(*shape_, Vec3::Zero(), Mat3::Identity());
  }
  for (const Piece& piece : pieces_) {
    const double reach = piece.p_M.norm() + piece.max_radius;
    reach_ = std::max(reach_, reach);
    const bool centred_sphere = piece.kind == PieceKind::kSphere && piece.p_M.norm() == 0.0;
    if (!centred_sphere) rotation_radius_ = std::max(rotation_radius_, reach);
  }
  if (std::holds_alternative<LoadedBall>(*shape_)) {
    // A ball's surface maps onto itself under rotation about its centre, so rotation about the
    // centre of mass moves its support point along any direction only as fast as the centre,
    // |omega| |com_offset|; the radius does not count.
    rotation_radius_ = pieces_.front().p_M.norm();
  }
}

void ShapeGeometry::add_piece(const Shape& shape, const Vec3& p_M, const Mat3& R_M) {
  Piece piece;
  piece.p_M = p_M;
  piece.R_M = R_M;
  if (const auto* sphere = std::get_if<Sphere>(&shape)) {
    piece.kind = PieceKind::kSphere;
    piece.mesh = meshes_.front().get();
    piece.radius = sphere->radius;
    piece.max_radius = sphere->radius;
  } else if (const auto* poly = std::get_if<ConvexPolyhedron>(&shape)) {
    piece.kind = PieceKind::kPolyhedron;
    meshes_.push_back(std::make_unique<FeatureMesh>(*poly));
    piece.mesh = meshes_.back().get();
    piece.max_radius = piece.mesh->max_radius();
  } else if (const auto* ball = std::get_if<LoadedBall>(&shape)) {
    // A sphere posed at its geometric centre, off the centre of mass.
    piece.kind = PieceKind::kSphere;
    piece.mesh = meshes_.front().get();
    piece.radius = ball->radius;
    piece.max_radius = ball->radius;
    piece.p_M = p_M + R_M * ball->centre_M();
  } else if (is_smooth_convex(shape)) {
    piece.kind = PieceKind::kSmooth;
    piece.smooth = &shape;
    piece.max_radius = max_radius(shape);
    if (const auto* capsule = std::get_if<Capsule>(&shape)) piece.radius = capsule->radius;
  } else if (const auto* half = std::get_if<Halfspace>(&shape)) {
    piece.kind = PieceKind::kHalfspace;
    piece.normal_M = half->normal_M.normalized();
    piece.offset = half->offset;
    piece.max_radius = kInfinity;
  } else {
    throw InputError("shape", "a compound part must be a convex shape or a halfspace");
  }
  pieces_.push_back(piece);
}

namespace {

// The rounding of coordinates of size `scale` [m]: gaps and overlaps within it are touching
// (about 45 ulps: the rounding of a placement and of a frame mapping is a few).
double rounding_allowance(double scale) {
  return 1e-14 * scale;
}

// Status and distance from a signed distance d (negative: overlap by -d): penetration is never
// reported as a distance. An overlap within the rounding of coordinates of size `scale` (a few
// ulp) is touching: two bodies resting on each other at a gap of zero are not overlapping.
void set_signed_distance(DistanceResult& r, double d, double scale) {
  if (d > 0.0) {
    r.status = ContactStatus::kSeparated;
    r.distance = d;
  } else if (d >= -rounding_allowance(scale)) {
    r.status = ContactStatus::kTouching;
    r.distance = 0.0;
  } else {
    r.status = ContactStatus::kPenetrating;
    r.distance = 0.0;
    r.penetration_depth = -d;
  }
}

// The least overlap of polyhedra A and B (B posed in A's frame by R_AB, t_AB) over the
// separating-axis candidates: every face normal of either, every cross product of an edge of A
// with an edge of B (the directions of the faces of their Minkowski difference, among which lies
// the least translation that separates them). Along axis n the overlap is how far one's
// projection reaches past the other's, the lesser of the two ways; a translation by it along n
// separates them, so it bounds the penetration depth from above. `n_A` is set to the best axis,
// oriented from B to A. O(E_a E_b (V_a + V_b)).
double mesh_overlap(const FeatureMesh& a, const FeatureMesh& b, const Mat3& R_AB, const Vec3& t_AB,
                    Vec3& n_A) {
  double best = kInfinity;
  auto try_axis = [&](Vec3 n) {
    const double length = n.norm();
    if (!(length > 0.0)) return;
    n /= length;
    double a_low = kInfinity, a_high = -kInfinity, b_low = kInfinity, b_high = -kInfinity;
    for (int i = 0; i < a.num_vertices(); ++i) {
      const double x = n.dot(a.vertex(i));
      a_low = std::min(a_low, x);
      a_high = std::max(a_high, x);
    }
    const Vec3 n_B = R_AB.transpose() * n;
    const double offset = n.dot(t_AB);
    for (int i = 0; i < b.num_vertices(); ++i) {
      const double x = n_B.dot(b.vertex(i)) + offset;
      b_low = std::min(b_low, x);
      b_high = std::max(b_high, x);
    }
    if (b_high - a_low < best) {  // A on the + side of n
      best = b_high - a_low;
      n_A = n;
    }
    if (a_high - b_low < best) {
      best = a_high - b_low;
      n_A = -n;
    }
  };
  for (int f = 0; f < a.num_faces(); ++f) try_axis(a.face_normal(f));
  for (int f = 0; f < b.num_faces(); ++f) try_axis(R_AB * b.face_normal(f));
  for (int h = 0; h < a.num_half_edges(); ++h) {
    if (a.twin(h) < h) continue;  // each edge once
    const Vec3 e_a = a.head(h) - a.tail(h);
    for (int g = 0; g < b.num_half_edges(); ++g) {
      if (b.twin(g) < g) continue;
      try_axis(e_a.cross(R_AB * (b.head(g) - b.tail(g))));
    }
  }
  return best;
}

// The rounding check of two overlapping polyhedra runs in the event loop only where it is cheap:
// E_a E_b (V_a + V_b) up to this (a box pair: 2,304; two 12-point hulls: about 22,000). Larger
// polyhedra keep V-Clip's verdict, any overlap a penetration, with V-Clip's normal and no
// depth.
constexpr int kRoundingCheckBudget = 100000;

using Piece = ShapeGeometry::Piece;
using PieceKind = ShapeGeometry::PieceKind;

struct PosedPiece {
  const Piece* piece;
  Mat3 R_W;  // piece frame in world
  Vec3 x_W;
};

PosedPiece pose_piece(const Piece& piece, const Vec3& x_W, const Mat3& R_WM) {
  return {&piece, R_WM * piece.R_M, x_W + R_WM * piece.p_M};
}

// The vertex of `mesh` minimising direction . v, by walking downhill along edges from `start`
// (the minimum of a linear function over a convex polyhedron's vertex graph has no other local
// minimum).
int support_walk(const FeatureMesh& mesh, const Vec3& direction_M, int start, int& steps) {
  int v = start >= 0 && start < mesh.num_vertices() ? start : 0;
  double best = direction_M.dot(mesh.vertex(v));
  while (true) {
    int next = -1;
    for (const VoronoiPlane* p = mesh.vertex_planes_begin(v); p != mesh.vertex_planes_end(v); ++p) {
      const int w = mesh.head_vertex(p->neighbor.index);
      const double value = direction_M.dot(mesh.vertex(w));
      if (value < best) {
        best = value;
        next = w;
      }
    }
    if (next < 0) return v;
    v = next;
    ++steps;
  }
}

// The support point in M of a smooth piece's core (a capsule's core is its segment).
Vec3 smooth_core_support_M(const Piece& piece, const Vec3& direction_M) {
  if (const auto* capsule = std::get_if<Capsule>(piece.smooth)) {
    const double z = direction_M.z() > 0.0   ? capsule->half_length
                     : direction_M.z() < 0.0 ? -capsule->half_length
                                             : 0.0;
    return Vec3(0.0, 0.0, z);
  }
  return smooth_support_M(*piece.smooth, direction_M);
}

// Halfspace (posed) against a sphere, polyhedron or smooth shape (posed). Fills the result as if
// the halfspace were body 2 (n from halfspace to the other piece).
void halfspace_vs_convex(const PosedPiece& half, const PosedPiece& other, FeaturePair& cache,
                         DistanceResult& r, Feature& other_feature) {
  const Vec3 n_W = half.R_W * half.piece->normal_M;
  const double offset_W = half.piece->offset + n_W.dot(half.x_W);
  Vec3 deepest_W;
  if (other.piece->kind == PieceKind::kSphere) {
    deepest_W = other.x_W - other.piece->radius * n_W;
    other_feature = Feature::vertex(0);
  } else if (other.piece->kind == PieceKind::kSmooth) {
    // Closed form: the core's support point against the plane's normal, less the inflation.
    const Vec3 n_M = other.R_W.transpose() * n_W;
    deepest_W = other.x_W + other.R_W * smooth_core_support_M(*other.piece, -n_M) -
                other.piece->radius * n_W;
    other_feature = Feature::vertex(0);
  } else {
    const Vec3 n_M = other.R_W.transpose() * n_W;
    const int start = cache.a.kind == FeatureKind::kVertex ? cache.a.index : 0;
    const int v = support_walk(*other.piece->mesh, n_M, start, r.steps);
    cache.a = Feature::vertex(v);
    deepest_W = other.x_W + other.R_W * other.piece->mesh->vertex(v);
    other_feature = Feature::vertex(v);
  }
  const double d = n_W.dot(deepest_W) - offset_W;
  r.n_W = n_W;
  set_signed_distance(r, d, std::max({1.0, deepest_W.cwiseAbs().maxCoeff(), std::abs(offset_W)}));
  r.p1_W = deepest_W;
  r.p2_W = deepest_W - d * n_W;
}

// The support point in world of a piece's core (a sphere's centre, a polyhedron's vertex, a smooth
// core), relative to `origin_W`.
Vec3 core_support(const PosedPiece& p, const Vec3& direction_W, const Vec3& origin_W) {
  const Vec3 d_M = p.R_W.transpose() * direction_W;
  Vec3 s_M = Vec3::Zero();
  if (p.piece->kind == PieceKind::kSmooth) {
    s_M = smooth_core_support_M(*p.piece, d_M);
  } else if (p.piece->kind == PieceKind::kPolyhedron) {
    int steps = 0;
    s_M = p.piece->mesh->vertex(support_walk(*p.piece->mesh, -d_M, 0, steps));
  }
  return (p.x_W - origin_W) + p.R_W * s_M;
}

// The feature reported for a piece when the normal, not a feature walk, decides the contact (a GJK
// pair; two polyhedra touching by rounding): a polyhedron's vertex furthest toward the other body
// (the patch search in contact_feature looks at the faces and edges around it), else the single
// "vertex" of a point or smooth core.
Feature support_feature(const PosedPiece& p, const Vec3& toward_other_W) {
  if (p.piece->kind != PieceKind::kPolyhedron) return Feature::vertex(0);
  int steps = 0;
  return Feature::vertex(
      support_walk(*p.piece->mesh, -(p.R_W.transpose() * toward_other_W), 0, steps));
}

// A smooth (or sphere) piece across a polyhedron's face, in closed form: where the smooth core's
// support point against the face's outward normal lies in the face's Voronoi region and outside
// its plane, that point and its foot on the face are the closest points, and the face's normal
// is the contact normal - exactly. GJK's normal is the difference of two points and loses
// relative accuracy as the gap shrinks: a cylinder 1e-12 m above a 6 m box got normals 1e-4 rad
// off, failed queries and stray impulses along normals 86 degrees off, where this is exact. The
// face is the one whose normal is nearest `r.n_W` (GJK's, or a guess where GJK failed); r is kept,
// and false returned, if the closed form does not apply.
bool snap_to_face(const PosedPiece& a, const PosedPiece& b, DistanceResult& r, double scale) {
  const bool a_poly = a.piece->kind == PieceKind::kPolyhedron;
  const bool b_poly = b.piece->kind == PieceKind::kPolyhedron;
  if (a_poly == b_poly || !r.n_W.allFinite()) return false;
  const PosedPiece& poly = b_poly ? b : a;
  const PosedPiece& round = b_poly ? a : b;
  // The polyhedron's outward direction toward the round piece (n runs from b to a).
  const Vec3 toward_W = b_poly ? r.n_W : Vec3(-r.n_W);
  const FeatureMesh& mesh = *poly.piece->mesh;
  const Vec3 toward_M = poly.R_W.transpose() * toward_W;
  int face = -1;
  double best = -kInfinity;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double c = mesh.face_normal(f).dot(toward_M);
    if (c > best) {
      best = c;
      face = f;
    }
  }
  if (face < 0) return false;
  const Vec3 n_W = poly.R_W * mesh.face_normal(face);
  const Vec3 deepest_W = core_support(round, -n_W, Vec3::Zero());
  const Vec3 q_M = poly.R_W.transpose() * (deepest_W - poly.x_W);
  for (const VoronoiPlane* p = mesh.face_planes_begin(face); p != mesh.face_planes_end(face); ++p) {
    if (p->eval(q_M) < 0.0) return false;
  }
  const double core_gap = mesh.face_eval(face, q_M);
  const double d = core_gap - round.piece->radius - poly.piece->radius;
  if (!(core_gap > 0.0) || !(d > 0.0)) return false;
  const Vec3 on_round_W = deepest_W - round.piece->radius * n_W;
  const Vec3 on_face_W = deepest_W - core_gap * n_W;
  r.n_W = b_poly ? n_W : Vec3(-n_W);
  r.p1_W = b_poly ? on_round_W : on_face_W;
  r.p2_W = b_poly ? on_face_W : on_round_W;
  r.feature1 = support_feature(a, -r.n_W);
  r.feature2 = support_feature(b, r.n_W);
  set_signed_distance(r, d, scale);
  return true;
}

// A pair with a smooth piece and no halfspace: GJK on the cores, then the inflation radii (a
// capsule's or sphere's). Computed about body 1's piece position, so rounding scales with the
// shapes rather than with where they are.
DistanceResult smooth_pair(const PosedPiece& a, const PosedPiece& b) {
  DistanceResult r;
  r.penetration_depth = std::numeric_limits<double>::quiet_NaN();
  const Vec3 origin_W = a.x_W;
  const double scale = std::max({a.piece->max_radius, b.piece->max_radius, 1e-300});
  GjkSettings settings;
  // Distances to a ten-thousandth of a nanometre on a body of a metre; the bound pair closes
  // linearly on curved cores, so this costs a few more iterations than 1e-12 would.
  settings.tolerance_m = 1e-13 * scale;
  const GjkResult g = gjk_distance([&](const Vec3& d) { return core_support(a, d, origin_W); },
                                   [&](const Vec3& d) { return core_support(b, d, origin_W); },
                                   a.x_W - b.x_W, settings);
  r.steps = g.iterations;
  const double r1 = a.piece->radius;
  const double r2 = b.piece->radius;
  if (g.status == GjkResult::Status::kNotConverged) {
    // Where the bodies are a round piece across a face, the face gives the answer in closed form
    // (GJK stalls there when the gap is tiny against their size).
    const Vec3 guess = g.p_a - g.p_b;
    r.n_W =
        guess.squaredNorm() > 0.0 ? Vec3(guess.normalized()) : Vec3((a.x_W - b.x_W).normalized());
    if (!snap_to_face(a, b, r, std::max(1.0, scale))) r.status = ContactStatus::kFailed;
    return r;
  }
  const bool cores_apart = g.status == GjkResult::Status::kSeparated && g.distance > 0.0;
  if (!cores_apart) {
    // The cores meet (to the tolerance): overlap by at least the inflation, or touching.
    r.n_W = (a.x_W - b.x_W).normalized();
    r.p1_W = origin_W + g.p_a;
    r.p2_W = origin_W + g.p_b;
    r.feature1 = support_feature(a, -r.n_W);
    r.feature2 = support_feature(b, r.n_W);
    const bool touching = g.status == GjkResult::Status::kTouching && r1 + r2 == 0.0;
    r.status = touching ? ContactStatus::kTouching : ContactStatus::kPenetrating;
    r.distance = 0.0;
    return r;
  }
  const Vec3 core1_W = origin_W + g.p_a;
  const Vec3 core2_W = origin_W + g.p_b;
  r.n_W = (g.p_a - g.p_b).normalized();
  r.p1_W = core1_W - r1 * r.n_W;
  r.p2_W = core2_W + r2 * r.n_W;
  r.feature1 = support_feature(a, -r.n_W);
  r.feature2 = support_feature(b, r.n_W);
  set_signed_distance(r, g.distance - r1 - r2, std::max(1.0, scale));
  if (r.status == ContactStatus::kSeparated) snap_to_face(a, b, r, std::max(1.0, scale));
  return r;
}

// One piece pair, body 1's piece first.
DistanceResult piece_pair(const PosedPiece& a, const PosedPiece& b, FeaturePair& cache,
                          int max_steps) {
  DistanceResult r;
  r.penetration_depth = std::numeric_limits<double>::quiet_NaN();
  const bool a_half = a.piece->kind == PieceKind::kHalfspace;
  const bool b_half = b.piece->kind == PieceKind::kHalfspace;
  if (a_half && b_half) {
    r.status = ContactStatus::kFailed;  // two halfspaces are never paired (both unbounded)
    return r;
  }
  if (b_half) {
    halfspace_vs_convex(b, a, cache, r, r.feature1);
    r.feature2 = Feature::face(0);
    return r;
  }
  if (a_half) {
    // Computed with the halfspace as body 2, then swapped.
    FeaturePair swapped{cache.b, cache.a};
    halfspace_vs_convex(a, b, swapped, r, r.feature2);
    cache = {swapped.b, swapped.a};
    r.feature1 = Feature::face(0);
    std::swap(r.p1_W, r.p2_W);
    r.n_W = -r.n_W;
    return r;
  }
  if (a.piece->kind == PieceKind::kSmooth || b.piece->kind == PieceKind::kSmooth) {
    return smooth_pair(a, b);
  }
  // Convex cores (a polyhedron or a sphere's centre) by V-Clip in a's frame, then the radii.
  const Mat3 R_AB = a.R_W.transpose() * b.R_W;
  const Vec3 t_AB = a.R_W.transpose() * (b.x_W - a.x_W);
  int seed_steps = 0;
  if (!cache.a.valid() || !cache.b.valid()) {
    // Cold start: begin at each polyhedron's vertex furthest toward the other's centre (a
    // downhill walk over the vertex graph) instead of at vertex 0; the walk's steps are counted.
    cache.a = Feature::vertex(support_walk(*a.piece->mesh, -t_AB, 0, seed_steps));
    cache.b = Feature::vertex(support_walk(*b.piece->mesh, R_AB.transpose() * t_AB, 0, seed_steps));
  }
  const VClipResult v = vclip(*a.piece->mesh, *b.piece->mesh, R_AB, t_AB, cache, max_steps);
  r.steps = v.steps + seed_steps;
  r.feature1 = v.features.a;
  r.feature2 = v.features.b;
  r.n_W = a.R_W * v.n_A;
  const Vec3 core1_W = a.x_W + a.R_W * v.p_a_A;
  const Vec3 core2_W = a.x_W + a.R_W * v.p_b_A;
  const double r1 = a.piece->radius;
  const double r2 = b.piece->radius;
  r.p1_W = core1_W - r1 * r.n_W;
  r.p2_W = core2_W + r2 * r.n_W;
  if (r1 + r2 == 0.0 &&
      (v.status == ContactStatus::kPenetrating || v.status == ContactStatus::kSeparated)) {
    // Two polyhedra within the rounding of their coordinates of each other (the rule of
    // set_signed_distance for every other pair): boxes stacked at z = h/2 + h i overlap by
    // ~1e-17 m once one's vertices are mapped into the other's frame, two touching boxes flying
    // together by their rounded positions, a plank placed on a cube is 7e-18 m above it. There
    // V-Clip's normal is the direction between two points a few ulps apart, any direction at all
    // (a side face's, along which stacked boxes overlap fully; the faces' common side for a plank
    // as wide as the cube, which was then no cube's rider and fell through both). The axis of
    // least overlap (greatest separation) among the separating-axis candidates is the contact's
    // normal, and overlapping by no more than rounding along it, they touch.
    const FeatureMesh& ma = *a.piece->mesh;
    const FeatureMesh& mb = *b.piece->mesh;
    const double tolerance = rounding_allowance(
        std::max({1.0, core1_W.cwiseAbs().maxCoeff(), core2_W.cwiseAbs().maxCoeff()}));
    const double cost = static_cast<double>(ma.num_half_edges()) * mb.num_half_edges() / 4.0 *
                        (ma.num_vertices() + mb.num_vertices());
    const bool penetrating = v.status == ContactStatus::kPenetrating;
    if ((penetrating || v.distance <= tolerance) && cost <= kRoundingCheckBudget) {
      Vec3 n_A = v.n_A;
      const double overlap = mesh_overlap(ma, mb, R_AB, t_AB, n_A);
      // The features and points follow the axis: each body's vertex furthest toward the other
      // along it. V-Clip's are where it stopped, which for an overlap is any pair at all (a side
      // edge of a stacked box, from which the contact's face cannot be found, so the patch was
      // one corner and a tower's held contacts pushed at a single vertex). So too beyond
      // rounding: an edge of a held hull drifted 3e-13 m into the face it was held on (200
      // hulls), and after its release V-Clip's normal had the pair parting at 1.4 mm/s while
      // along the face's normal it approached at 4e-6 m/s: checked at the progress floor, 33
      // times, until a microcollision met it. The axis's overlap bounds the depth from above
      // (a translation by it along the axis separates the bodies).
      r.n_W = a.R_W * n_A;
      r.feature1 = support_feature(a, -r.n_W);
      r.feature2 = support_feature(b, r.n_W);
      if (penetrating) {
        // A separated pair keeps V-Clip's points: they are its closest points.
        r.p1_W = a.x_W + a.R_W * ma.vertex(r.feature1.index);
        r.p2_W = b.x_W + b.R_W * mb.vertex(r.feature2.index);
        r.penetration_depth = overlap;
        if (overlap <= tolerance) {
          r.status = ContactStatus::kTouching;
          r.distance = 0.0;
          return r;
        }
      }
    }
  }
  if (v.status == ContactStatus::kFailed || v.status == ContactStatus::kPenetrating) {
    r.status = v.status;
    r.distance = 0.0;
    return r;
  }
  const double d = v.distance - r1 - r2;
  if (r1 + r2 == 0.0) {
    r.status = v.status;
    r.distance = v.distance;
    return r;
  }
  // With a sphere, a core distance of zero means the centre is on the other surface: overlap.
  set_signed_distance(
      r, d, std::max({1.0, core1_W.cwiseAbs().maxCoeff(), core2_W.cwiseAbs().maxCoeff()}));
  return r;
}

}  // namespace

DistanceResult closest_features(const ShapeGeometry& g1, const Pose& pose1, const ShapeGeometry& g2,
                                const Pose& pose2, PairCache& cache, int max_steps) {
  const Mat3 R1 = pose1.q_WM.toRotationMatrix();
  const Mat3 R2 = pose2.q_WM.toRotationMatrix();
  const auto& pieces1 = g1.pieces();
  const auto& pieces2 = g2.pieces();
  if (pieces1.size() == 1 && pieces2.size() == 1) {
    return piece_pair(pose_piece(pieces1[0], pose1.x_W, R1), pose_piece(pieces2[0], pose2.x_W, R2),
                      cache.single, max_steps);
  }
  const std::size_t n = pieces1.size() * pieces2.size();
  if (!cache.compound) cache.compound = std::make_unique<PairCache::Compound>();
  PairCache::Compound& compound = *cache.compound;
  if (compound.pieces.size() != n) compound.pieces.assign(n, FeaturePair{});
  if (compound.piece_results.size() != n) compound.piece_results.assign(n, DistanceResult{});
  DistanceResult best;
  best.distance = kInfinity;
  int steps = 0;
  bool have = false;
  for (std::size_t i = 0; i < pieces1.size(); ++i) {
    const PosedPiece a = pose_piece(pieces1[i], pose1.x_W, R1);
    for (std::size_t j = 0; j < pieces2.size(); ++j) {
      DistanceResult r = piece_pair(a, pose_piece(pieces2[j], pose2.x_W, R2),
                                    compound.pieces[i * pieces2.size() + j], max_steps);
      steps += r.steps;
      r.piece1 = static_cast<int>(i);
      r.piece2 = static_cast<int>(j);
      compound.piece_results[i * pieces2.size() + j] = r;
      // Failure and penetration dominate; otherwise the smallest distance.
      auto rank = [](ContactStatus s) {
        return s == ContactStatus::kFailed ? 0 : (s == ContactStatus::kPenetrating ? 1 : 2);
      };
      if (!have || rank(r.status) < rank(best.status) ||
          (rank(r.status) == rank(best.status) && r.distance < best.distance)) {
        best = r;
        have = true;
      }
    }
  }
  best.steps = steps;
  return best;
}

// ---------------------------------------------------------------------------------------------
// Contact patch.

namespace {

// Sides of the regular polygon inscribed in a cylinder's cap that stands for the cap in a patch.
// Inscribed, so a centre of pressure found inside it is inside the disk; 16 sides cover 97.4 % of
// the disk's area (radius within 1.9 %) and keep a patch's corners, which the rest test and the
// persistent contact model carry one unknown each, few.
constexpr int kCylinderCapSides = 16;

// The contact feature of a smooth piece (as contact_feature): a cylinder's cap, as the inscribed
// polygon counter-clockwise about the cap's outward normal, if its whole rim is within the limit;
// else the straight segment of a cylinder's or capsule's side furthest along `outward_W` if both
// its ends are; else the closest point (an ellipsoid always, a smooth body touching at one point).
template <typename Height>
std::vector<Vec3> smooth_contact_feature(const PosedPiece& p, const Vec3& outward_W,
                                         const Vec3& closest_W, Height&& height, double limit) {
  constexpr double kPi = 3.14159265358979323846;
  auto world = [&](const Vec3& v_M) { return Vec3(p.x_W + p.R_W * v_M); };
  const Vec3 o = p.R_W.transpose() * outward_W;
  double radius = 0.0, half = 0.0;
  if (const auto* cylinder = std::get_if<Cylinder>(p.piece->smooth)) {
    radius = cylinder->radius;
    half = cylinder->half_height;
    if (o.z() != 0.0) {
      const double side = o.z() > 0.0 ? 1.0 : -1.0;
      std::vector<Vec3> cap;
      for (int k = 0; k < kCylinderCapSides; ++k) {
        const double angle = side * 2.0 * kPi * k / kCylinderCapSides;
        cap.push_back(world(Vec3(radius * std::cos(angle), radius * std::sin(angle), side * half)));
        if (!(height(cap.back()) <= limit)) break;
      }
      if (static_cast<int>(cap.size()) == kCylinderCapSides && height(cap.back()) <= limit) {
        return cap;
      }
    }
  } else if (const auto* capsule = std::get_if<Capsule>(p.piece->smooth)) {
    radius = capsule->radius;
    half = capsule->half_length;
  } else {
    return {closest_W};
  }
  const double radial = std::hypot(o.x(), o.y());
  if (!(radial > 0.0)) return {closest_W};
  const Vec3 side_M(radius * o.x() / radial, radius * o.y() / radial, 0.0);
  const Vec3 a = world(side_M - half * Vec3::UnitZ());
  const Vec3 b = world(side_M + half * Vec3::UnitZ());
  if (height(a) <= limit && height(b) <= limit) return {a, b};
  return {closest_W};
}

// The contact feature of a posed piece as world points (DESIGN.md §4, "The contact point"): the
// face incident to the closest feature that is most aligned with `outward_W`, if all its
// vertices lie within `limit` of the other body's support plane (height(x) <= limit); else the
// incident edge with both ends within it; else the closest point alone. A halfspace is unbounded
// (no points, `unbounded` set); a sphere gives its closest point.
template <typename Height>
std::vector<Vec3> contact_feature(const PosedPiece& p, Feature feature, const Vec3& outward_W,
                                  const Vec3& closest_W, Height&& height, double limit,
                                  bool& unbounded) {
  unbounded = false;
  std::vector<Vec3> points;
  if (p.piece->kind == PieceKind::kHalfspace) {
    unbounded = true;
    return points;
  }
  if (p.piece->kind == PieceKind::kSmooth) {
    return smooth_contact_feature(p, outward_W, closest_W, height, limit);
  }
  if (p.piece->kind == PieceKind::kSphere || !feature.valid()) {
    points.push_back(closest_W);
    return points;
  }
  const FeatureMesh& m = *p.piece->mesh;
  auto world = [&](const Vec3& v_M) { return Vec3(p.x_W + p.R_W * v_M); };
  const Vec3 outward_M = p.R_W.transpose() * outward_W;
  int best_face = -1;
  double best_cos = -kInfinity;
  std::vector<int> edges;  // half-edges incident to the feature
  auto consider = [&](int f) {
    const double c = m.face_normal(f).dot(outward_M);
    if (c > best_cos) {
      best_cos = c;
      best_face = f;
    }
  };
  if (feature.kind == FeatureKind::kFace) {
    consider(feature.index);
  } else if (feature.kind == FeatureKind::kEdge) {
    consider(m.face_of(feature.index));
    consider(m.face_of(m.twin(feature.index)));
    edges.push_back(feature.index);
  } else {
    for (const VoronoiPlane* q = m.vertex_planes_begin(feature.index);
         q != m.vertex_planes_end(feature.index); ++q) {
      consider(m.face_of(q->neighbor.index));
      edges.push_back(q->neighbor.index);
    }
  }
  if (best_face < 0) {
    // No face scored (a non-finite direction): the closest point is all we can say.
    points.push_back(closest_W);
    return points;
  }
  const int h0 = m.face_half_edge(best_face);
  int h = h0;
  bool face_within = true;
  do {
    points.push_back(world(m.tail(h)));
    face_within = face_within && height(points.back()) <= limit;
    if (feature.kind == FeatureKind::kFace) edges.push_back(h);
    h = m.next(h);
  } while (h != h0);
  if (face_within) return points;
  points.clear();
  double best_height = kInfinity;
  for (int e : edges) {
    const Vec3 a = world(m.tail(e));
    const Vec3 b = world(m.head(e));
    const double worst = std::max(height(a), height(b));
    if (worst <= limit && worst < best_height) {
      best_height = worst;
      points = {a, b};
    }
  }
  if (points.empty()) points.push_back(closest_W);
  return points;
}

}  // namespace

ContactGeometry contact_geometry(const ShapeGeometry& g1, const Pose& pose1,
                                 const ShapeGeometry& g2, const Pose& pose2,
                                 const DistanceResult& closest, double envelope_m) {
  ContactGeometry out;
  if (closest.status != ContactStatus::kSeparated && closest.status != ContactStatus::kTouching) {
    return out;
  }
  const PosedPiece a =
      pose_piece(g1.pieces()[closest.piece1], pose1.x_W, pose1.q_WM.toRotationMatrix());
  const PosedPiece b =
      pose_piece(g2.pieces()[closest.piece2], pose2.x_W, pose2.q_WM.toRotationMatrix());
  const Vec3& n = closest.n_W;
  const double limit = closest.distance + envelope_m;
  // Body 1's contact feature within the limit above body 2's support plane; body 2's within the
  // limit below body 1's.
  auto height1 = [&](const Vec3& x) { return n.dot(x - closest.p2_W); };
  auto height2 = [&](const Vec3& x) { return n.dot(closest.p1_W - x); };
  out.feature1 =
      contact_feature(a, closest.feature1, -n, closest.p1_W, height1, limit, out.unbounded1);
  out.feature2 =
      contact_feature(b, closest.feature2, n, closest.p2_W, height2, limit, out.unbounded2);
  const std::vector<Vec3>& face1 = out.feature1;
  const std::vector<Vec3>& face2 = out.feature2;
  // Projection onto body 2's support plane, coordinates along (t1, t2) with t1 x t2 = n.
  const Vec3 t1 = n.unitOrthogonal();
  const Vec3 t2 = n.cross(t1);
  const Vec3& origin = closest.p2_W;
  const double scale =
      std::max({1e-300, (closest.p1_W - a.x_W).norm(), (closest.p2_W - b.x_W).norm()});
  const double tol = 1e-12 * scale;
  auto project = [&](const std::vector<Vec3>& pts) {
    std::vector<Vec2> out;
    for (const Vec3& p : pts) out.emplace_back(t1.dot(p - origin), t2.dot(p - origin));
    return tidy(out, tol);
  };
  std::vector<Vec2> patch;
  if (out.unbounded1) {
    patch = project(face2);
  } else if (out.unbounded2) {
    patch = project(face1);
  } else {
    patch = tidy(intersect(project(face1), project(face2)), tol);
  }
  if (patch.empty()) {
    out.patch.push_back(closest.p2_W);
    return out;
  }
  for (const Vec2& p : patch) out.patch.push_back(origin + p.x() * t1 + p.y() * t2);
  return out;
}

std::vector<Vec3> contact_patch(const ShapeGeometry& g1, const Pose& pose1, const ShapeGeometry& g2,
                                const Pose& pose2, const DistanceResult& closest,
                                double envelope_m) {
  return contact_geometry(g1, pose1, g2, pose2, closest, envelope_m).patch;
}

}  // namespace palpable
