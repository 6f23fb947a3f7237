#pragma once
// libccd cross-check and penetration recovery (DESIGN.md §1, §3): Minkowski Portal Refinement
// (ccdMPRIntersect, ccdMPRPenetration) on posed convex pieces. This is the only place in the
// project that includes libccd; it is a separate library, `palpable_distance_crosscheck`, linked
// by the tests and tools and optionally by the simulator for recovering from a detected
// penetration. The penetration direction is MPR's portal direction, not the minimum translation:
// recover along it with care.
//
// Supports: a sphere's centre plus its radius; a polyhedron's vertex by a hill-climbing walk
// over the vertex graph started at the last answer (the usual fast support for hulls); a smooth
// shape's closed-form support. A halfspace has no support point and is not accepted (its
// penetration depth is exact in DistanceResult).
#include "core/types.hpp"
#include "distance/closest_features.hpp"

namespace palpable {

struct MprPenetration {
  bool intersecting = false;
  double depth = 0.0;               // [m] translate body 2 by depth * direction_W to separate
  Vec3 direction_W = Vec3::Zero();  // unit, libccd's portal direction (points into body 1 ->
                                    // out of body 2 is -direction: see mpr_test)
  Vec3 position_W = Vec3::Zero();   // a point in the overlap
};

// A convex piece (piece index of a compound; 0 otherwise) posed in the world, for libccd.
class MprShape {
 public:
  MprShape(const ShapeGeometry& geometry, const Pose& pose, int piece = 0);
  void set_pose(const Pose& pose);
  Vec3 support_W(const Vec3& direction_W) const;
  const Vec3& center_W() const { return x_W_; }

 private:
  const ShapeGeometry::Piece* piece_;
  Vec3 piece_p_M_;
  Mat3 piece_R_M_;
  Mat3 R_W_;
  Vec3 x_W_;
  mutable int last_vertex_ = 0;
};

// Settings of the libccd calls: tolerance of the portal refinement [m] and iteration cap.
struct MprSettings {
  double tolerance = 1e-13;
  unsigned long max_iterations = 1000;
};

bool mpr_intersect(const MprShape& shape1, const MprShape& shape2,
                   const MprSettings& settings = {});
MprPenetration mpr_penetration(const MprShape& shape1, const MprShape& shape2,
                               const MprSettings& settings = {});

// Recovery from a penetration detected by closest_features (status kPenetrating): MPR on the
// piece pair the result names. `normal_W` follows DESIGN.md §3 (from body 2 to body 1): moving
// body 1 by depth along it (or body 2 against it) separates the pieces along MPR's portal
// direction, which is not necessarily the minimum translation.
struct PenetrationRecovery {
  bool intersecting = false;
  double depth = 0.0;              // [m]
  Vec3 normal_W = Vec3::Zero();    // unit, from body 2 to body 1
  Vec3 position_W = Vec3::Zero();  // a point in the overlap
};
PenetrationRecovery recover_penetration(const ShapeGeometry& g1, const Pose& pose1,
                                        const ShapeGeometry& g2, const Pose& pose2,
                                        const DistanceResult& closest,
                                        const MprSettings& settings = {});

}  // namespace palpable
