#pragma once
// Closest features between two posed shapes (DESIGN.md §3): V-Clip for polyhedron pairs, the
// same V-Clip states with a one-point "polyhedron" for a sphere's centre against a polyhedron,
// closed forms for sphere-sphere and halfspace-sphere, a support-vertex walk for
// halfspace-polyhedron, the closed-form support point for halfspace against a smooth shape
// (ellipsoid, cylinder, capsule), GJK (distance/gjk.hpp) for a smooth shape against anything else,
// and compounds piece by piece (minimum over pieces).
//
// Sign convention (used everywhere): the pair is (body 1, body 2) and n_W points from body 2 to
// body 1; p1_W - p2_W = distance * n_W when separated.
//
// Penetration is detected, never returned as a distance: the status says kPenetrating and
// `distance` is 0. Depth and a recovery direction come from libccd's MPR in
// distance/crosscheck/mpr.hpp (a separate library, palpable_distance_crosscheck, that the
// simulator may link optionally), except for spheres and halfspaces where `penetration_depth`
// is exact, and for two polyhedra small enough for the separating-axis search (a box pair, two
// hulls of a dozen points), where it is the least overlap over the separating axes - an upper
// bound, a translation by it along n_W separates them - and n_W that axis.
//
// The query allocates nothing once the pair's cache has been used (compound pairs size their
// cache on first use).
#include "core/settings.hpp"
#include "core/shape.hpp"
#include "core/types.hpp"
#include "distance/feature_mesh.hpp"
#include "distance/vclip.hpp"

#include <memory>
#include <vector>

namespace palpable {

// Where a shape is: its modelling frame M in the world.
struct Pose {
  Vec3 x_W = Vec3::Zero();
  Quat q_WM = Quat::Identity();
};

// A shape with its precomputed Voronoi structure, built once per shape (shapes are immutable)
// and shared by every body and query using it.
class ShapeGeometry {
 public:
  // kSmooth: an ellipsoid, cylinder or capsule (a loaded ball is a kSphere piece posed at its
  // geometric centre), paired by GJK on support mappings (distance/gjk.hpp).
  enum class PieceKind : std::uint8_t { kSphere, kPolyhedron, kHalfspace, kSmooth };
  // One convex piece, posed in the shape's frame M (identity for a non-compound shape). Each
  // piece is a core (a point, a polyhedron, a segment, an ellipsoid or cylinder) inflated by
  // `radius`.
  struct Piece {
    PieceKind kind = PieceKind::kSphere;
    const FeatureMesh* mesh = nullptr;  // the polyhedron, or a single point for a sphere
    const Shape* smooth = nullptr;      // kSmooth: the Ellipsoid, Cylinder or Capsule
    double radius = 0.0;                // sphere or capsule radius [m], 0 otherwise
    Vec3 normal_M = Vec3::UnitZ();      // halfspace {x : normal . x <= offset}, in M
    double offset = 0.0;
    Vec3 p_M = Vec3::Zero();  // piece frame in M
    Mat3 R_M = Mat3::Identity();
    double max_radius = 0.0;  // about the piece frame origin [m]; +inf for a halfspace
  };

  explicit ShapeGeometry(std::shared_ptr<const Shape> shape);
  ShapeGeometry(const ShapeGeometry&) = delete;
  ShapeGeometry& operator=(const ShapeGeometry&) = delete;

  const Shape& shape() const { return *shape_; }
  const std::vector<Piece>& pieces() const { return pieces_; }
  // The largest distance from the origin of M that rotation about it can move a surface point
  // through [m]: 0 for a sphere centred at the origin (its surface maps onto itself), the distance
  // of its centre for a loaded ball (the same argument about the centre), the maximum radius
  // otherwise; +inf with a halfspace piece.
  double rotation_radius() const { return rotation_radius_; }
  // The largest distance from the origin of M to any point of the shape [m] (+inf: halfspace).
  double reach() const { return reach_; }

 private:
  void add_piece(const Shape& shape, const Vec3& p_M, const Mat3& R_M);

  std::shared_ptr<const Shape> shape_;
  std::vector<std::unique_ptr<FeatureMesh>> meshes_;
  std::vector<Piece> pieces_;
  double rotation_radius_ = 0.0;
  double reach_ = 0.0;
};

// The per-pair cache (owned by the caller, one per body pair): the feature pair of each piece
// pair, and for halfspace pairs the support vertex.

struct DistanceResult {
  ContactStatus status = ContactStatus::kFailed;
  double distance = 0.0;           // [m] > 0 separated; 0 touching or penetrating
  double penetration_depth = 0.0;  // [m] exact for sphere/halfspace pairs, an upper bound for
                                   // polyhedra (least overlap over separating axes); NaN where
                                   // unknown (polyhedra beyond that search's budget)
  Vec3 p1_W = Vec3::Zero();        // closest point on body 1
  Vec3 p2_W = Vec3::Zero();        // closest point on body 2
  Vec3 n_W = Vec3::UnitZ();        // unit, from body 2 to body 1
  Feature feature1;                // closest feature on body 1's piece (vertex 0 of a sphere)
  Feature feature2;
  int piece1 = 0;  // which piece of a compound
  int piece2 = 0;
  int steps = 0;  // feature steps taken (all piece pairs)
};

struct PairCache {
  FeaturePair single;  // non-compound pairs
  struct Compound {
    std::vector<FeaturePair> pieces;  // [piece1 * num_pieces2 + piece2]
    // The last query's result for every piece pair (same indexing). The closest piece alone
    // does not bound when the bodies can touch: another piece may close faster.
    std::vector<DistanceResult> piece_results;
  };
  // Compound pairs only, made at their first query: the cache of a plain pair stays 24 bytes,
  // so that the scheduler's pair record fits one cache line.
  std::unique_ptr<Compound> compound;

  // The last query's piece results; empty for a non-compound pair.
  const std::vector<DistanceResult>& piece_results() const {
    static const std::vector<DistanceResult> kNone;
    return compound ? compound->piece_results : kNone;
  }
};

// `max_steps` bounds each V-Clip walk (Settings::distance_max_steps; status kFailed beyond it).
DistanceResult closest_features(const ShapeGeometry& g1, const Pose& pose1, const ShapeGeometry& g2,
                                const Pose& pose2, PairCache& cache, int max_steps);
inline DistanceResult closest_features(const ShapeGeometry& g1, const Pose& pose1,
                                       const ShapeGeometry& g2, const Pose& pose2, PairCache& cache,
                                       const Settings& settings) {
  return closest_features(g1, pose1, g2, pose2, cache, settings.distance_max_steps);
}

// The contact patch (DESIGN.md §4, "The contact point"): where the closest features are parallel
// within the envelope, the convex polygon or segment shared by the two bodies' contact features,
// in projection along n. Each body's contact feature is the face at its closest feature most
// opposed to the other body if all its vertices lie within distance + `envelope_m` of the other
// body's support plane, else such an edge, else the closest point (a halfspace has no boundary).
// The two are intersected in body 2's support plane (through p2_W, normal n_W); polygons come
// counter-clockwise about n_W. One point when the contact is at a vertex; empty unless the status
// is separated or touching. Allocates (called once per collision, not per check).
std::vector<Vec3> contact_patch(const ShapeGeometry& g1, const Pose& pose1, const ShapeGeometry& g2,
                                const Pose& pose2, const DistanceResult& closest,
                                double envelope_m);

// The same, with the contact feature of each body it was made from: a face (3 or more points,
// counter-clockwise about that body's outward normal), an edge (2), a point (1; a sphere's closest
// point), or unbounded (a halfspace: no points).
struct ContactGeometry {
  std::vector<Vec3> feature1, feature2;  // world frame, on each body's surface
  bool unbounded1 = false, unbounded2 = false;
  std::vector<Vec3> patch;  // as contact_patch
};
ContactGeometry contact_geometry(const ShapeGeometry& g1, const Pose& pose1,
                                 const ShapeGeometry& g2, const Pose& pose2,
                                 const DistanceResult& closest, double envelope_m);

}  // namespace palpable
