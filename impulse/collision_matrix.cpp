#include "impulse/collision_matrix.hpp"

#include <Eigen/LU>

#include <cmath>

namespace palpable {

Mat3 collision_matrix_W(const ContactBody& body1, const ContactBody& body2) {
  const Mat3 r1 = skew(body1.r_W);
  const Mat3 r2 = skew(body2.r_W);
  Mat3 K = (body1.inv_mass + body2.inv_mass) * Mat3::Identity();
  K -= r1 * body1.inv_inertia_W * r1;
  K -= r2 * body2.inv_inertia_W * r2;
  // Symmetric by construction in exact arithmetic; symmetrise the rounding.
  return 0.5 * (K + K.transpose());
}

Vec3 contact_point_velocity_W(const ContactBody& body) {
  return body.v_W + body.w_W.cross(body.r_W);
}

Mat3 contact_frame_W(const Vec3& n_W) {
  const Vec3 n = n_W.normalized();
  Eigen::Index axis = 0;
  n.cwiseAbs().minCoeff(&axis);
  const Vec3 t1 = Vec3::Unit(axis).cross(n).normalized();
  const Vec3 t2 = n.cross(t1);
  Mat3 R;
  R.col(0) = t1;
  R.col(1) = t2;
  R.col(2) = n;
  return R;
}

void apply_impulse(const Vec3& p_W, ContactBody& body1, ContactBody& body2) {
  body1.v_W += body1.inv_mass * p_W;
  body1.w_W += body1.inv_inertia_W * body1.r_W.cross(p_W);
  body2.v_W -= body2.inv_mass * p_W;
  body2.w_W -= body2.inv_inertia_W * body2.r_W.cross(p_W);
}

HeldRotationResponse held_rotation_response(const ContactBody& body1, const Vec3& x1_W,
                                            const ContactBody& body2, const Vec3& x2_W) {
  HeldRotationResponse response;
  const Mat3 d = skew(x2_W - x1_W);
  if (!body1.inv_inertia_W.isZero(0.0) && !body2.inv_inertia_W.isZero(0.0)) {
    const Mat3 inertia_sum = body1.inv_inertia_W.inverse() + body2.inv_inertia_W.inverse();
    response.W = inertia_sum.inverse() * d;
  }
  const Mat3 K = (body1.inv_mass + body2.inv_mass) * Mat3::Identity() - d * response.W;
  response.K_W = 0.5 * (K + K.transpose());
  return response;
}

FrameProblem frame_problem(const ContactBody& body1, const ContactBody& body2, const Mat3& R_WC) {
  FrameProblem problem;
  // K is symmetrised in collision_matrix_W; R^T K R keeps that to rounding, which the integrator
  // accepts (symmetric within 1e-12 of its scale).
  problem.K_c = R_WC.transpose() * collision_matrix_W(body1, body2) * R_WC;
  problem.u0_c =
      R_WC.transpose() * (contact_point_velocity_W(body1) - contact_point_velocity_W(body2));
  return problem;
}

CollisionResult resolve_collision(const ContactBody& body1, const ContactBody& body2,
                                  const Mat3& R_WC, const CollisionParameters& params) {
  const FrameProblem problem = frame_problem(body1, body2, R_WC);
  CollisionResult result = integrate_collision(problem.K_c, problem.u0_c, params);
  result.p_W = R_WC * result.p_c;
  return result;
}

}  // namespace palpable
