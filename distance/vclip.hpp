#pragma once
// V-Clip closest-feature tracking between two convex polyhedra (B. Mirtich, "V-Clip: Fast and
// Robust Polyhedral Collision Detection", ACM TOG 17(3):177-208, 1998; MERL TR-97-05).
//
// The state is one feature on each polyhedron (vertex, edge or face; never face-face). Each step
// checks whether each feature's closest point lies in the other feature's Voronoi region; if not,
// it moves one feature to a neighbour: to a lower-dimensional feature without increasing the
// distance, or to a higher-dimensional one strictly decreasing it, so the walk terminates (the
// paper's theorem 1). Edges are clipped against Voronoi planes (the only division); where an edge
// leaves a region, the sign of the derivative of the distance along the edge picks the next
// feature. Penetration is detected, never returned as a distance: an edge piercing a face inside
// the face's Voronoi region, or a vertex below every face plane of the other polyhedron (the
// local-minimum check of the V-F state over all faces).
//
// Body A's frame is the frame of computation: B's points are mapped into A by p_A = R_AB p_B +
// t_AB and A's into B by the inverse. Results are in A's frame.
#include "core/types.hpp"
#include "distance/feature_mesh.hpp"

namespace palpable {

enum class ContactStatus : std::uint8_t {
  kSeparated,    // distance > 0, closest points and features valid
  kTouching,     // distance == 0 exactly (shared point), no overlap detected
  kPenetrating,  // the interiors overlap; distance is 0 and meaningless, recover with MPR
  kFailed,       // the walk hit its step limit (a bug or an extreme numerical case; counted)
};

const char* to_string(ContactStatus status);

// The per-pair cache of the feature pair (DESIGN.md §3): the caller owns it and passes it back in,
// so a query after a small motion starts where the last one ended. A default (invalid) pair starts
// from the first vertices.
struct FeaturePair {
  Feature a;
  Feature b;
};

struct VClipResult {
  ContactStatus status = ContactStatus::kFailed;
  double distance = 0.0;      // [m]
  Vec3 p_a_A = Vec3::Zero();  // closest point on A, in A's frame
  Vec3 p_b_A = Vec3::Zero();  // closest point on B, in A's frame
  Vec3 n_A = Vec3::UnitX();   // unit normal from B to A (for penetration: the face normal
                              // of the least-penetrated face, oriented from B to A)
  FeaturePair features;       // the final feature pair (also written back to the cache)
  int steps = 0;              // feature updates taken
};

// Runs V-Clip from `cache` (updated in place). `max_steps` bounds the walk (status kFailed).
VClipResult vclip(const FeatureMesh& a, const FeatureMesh& b, const Mat3& R_AB, const Vec3& t_AB,
                  FeaturePair& cache, int max_steps);

// Closest points of segments [p1, q1] and [p2, q2] (Ericson, Real-Time Collision Detection,
// 5.1.9). Returns the squared distance.
double closest_points_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                      const Vec3& q2, Vec3& c1, Vec3& c2);
// The same with the segment parameters of the closest points (c1 = p1 + s (q1 - p1), ...).
double closest_params_segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2,
                                      const Vec3& q2, double& s, double& t, Vec3& c1, Vec3& c2);
// Closest point of segment [p, q] to x.
Vec3 closest_point_segment(const Vec3& p, const Vec3& q, const Vec3& x);

}  // namespace palpable
