#include "distance/crosscheck/mpr.hpp"

#include "core/check.hpp"

#include <ccd/ccd.h>

namespace palpable {

MprShape::MprShape(const ShapeGeometry& geometry, const Pose& pose, int piece) {
  PALPABLE_CHECK(piece >= 0 && piece < static_cast<int>(geometry.pieces().size()),
                 "piece index out of range");
  piece_ = &geometry.pieces()[piece];
  if (piece_->kind == ShapeGeometry::PieceKind::kHalfspace) {
    throw InputError("shape", "MPR needs a bounded convex piece, not a halfspace");
  }
  piece_p_M_ = piece_->p_M;
  piece_R_M_ = piece_->R_M;
  set_pose(pose);
}

void MprShape::set_pose(const Pose& pose) {
  const Mat3 R_WM = pose.q_WM.toRotationMatrix();
  R_W_ = R_WM * piece_R_M_;
  x_W_ = pose.x_W + R_WM * piece_p_M_;
}

Vec3 MprShape::support_W(const Vec3& direction_W) const {
  if (piece_->kind == ShapeGeometry::PieceKind::kSphere) {
    const double norm = direction_W.norm();
    return norm > 0.0 ? Vec3(x_W_ + (piece_->radius / norm) * direction_W) : x_W_;
  }
  if (piece_->kind == ShapeGeometry::PieceKind::kSmooth) {
    return x_W_ + R_W_ * smooth_support_M(*piece_->smooth, R_W_.transpose() * direction_W);
  }
  const FeatureMesh& mesh = *piece_->mesh;
  const Vec3 d_M = R_W_.transpose() * direction_W;
  int v = last_vertex_;
  double best = d_M.dot(mesh.vertex(v));
  while (true) {
    int next = -1;
    for (const VoronoiPlane* p = mesh.vertex_planes_begin(v); p != mesh.vertex_planes_end(v); ++p) {
      const int w = mesh.head_vertex(p->neighbor.index);
      const double value = d_M.dot(mesh.vertex(w));
      if (value > best) {
        best = value;
        next = w;
      }
    }
    if (next < 0) break;
    v = next;
  }
  last_vertex_ = v;
  return x_W_ + R_W_ * mesh.vertex(v);
}

namespace {

void support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto* shape = static_cast<const MprShape*>(obj);
  const Vec3 s = shape->support_W(Vec3(dir->v[0], dir->v[1], dir->v[2]));
  ccdVec3Set(out, s.x(), s.y(), s.z());
}

void center(const void* obj, ccd_vec3_t* out) {
  const Vec3& c = static_cast<const MprShape*>(obj)->center_W();
  ccdVec3Set(out, c.x(), c.y(), c.z());
}

ccd_t make_ccd(const MprSettings& settings) {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = support;
  ccd.support2 = support;
  ccd.center1 = center;
  ccd.center2 = center;
  ccd.mpr_tolerance = settings.tolerance;
  ccd.max_iterations = settings.max_iterations;
  return ccd;
}

}  // namespace

bool mpr_intersect(const MprShape& shape1, const MprShape& shape2, const MprSettings& settings) {
  const ccd_t ccd = make_ccd(settings);
  return ccdMPRIntersect(&shape1, &shape2, &ccd) != 0;
}

MprPenetration mpr_penetration(const MprShape& shape1, const MprShape& shape2,
                               const MprSettings& settings) {
  const ccd_t ccd = make_ccd(settings);
  ccd_real_t depth = 0.0;
  ccd_vec3_t dir, pos;
  MprPenetration result;
  if (ccdMPRPenetration(&shape1, &shape2, &ccd, &depth, &dir, &pos) == 0) {
    result.intersecting = true;
    result.depth = depth;
    result.direction_W = Vec3(dir.v[0], dir.v[1], dir.v[2]);
    result.position_W = Vec3(pos.v[0], pos.v[1], pos.v[2]);
  }
  return result;
}

PenetrationRecovery recover_penetration(const ShapeGeometry& g1, const Pose& pose1,
                                        const ShapeGeometry& g2, const Pose& pose2,
                                        const DistanceResult& closest,
                                        const MprSettings& settings) {
  const MprShape s1(g1, pose1, closest.piece1);
  const MprShape s2(g2, pose2, closest.piece2);
  const MprPenetration p = mpr_penetration(s1, s2, settings);
  PenetrationRecovery r;
  r.intersecting = p.intersecting;
  r.depth = p.depth;
  // libccd moves body 2 by depth * direction to separate: the normal from 2 to 1 is opposite.
  r.normal_W = -p.direction_W;
  r.position_W = p.position_W;
  return r;
}

}  // namespace palpable
