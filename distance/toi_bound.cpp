#include "distance/toi_bound.hpp"

#include "core/ballistic.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace palpable {

double rotational_term(const ToiMotion& motion, const Vec3& d_hat) {
  if (motion.kinematic) {
    const double s = motion.spin_W.cross(d_hat).norm();
    if (s == 0.0 || motion.rotation_radius == 0.0) return 0.0;
    return s * motion.rotation_radius;
  }
  if (motion.omega_bound == 0.0 || motion.rotation_radius == 0.0) return 0.0;
  // (ω x r) . d̂ = r . (d̂ x ω) <= |r| |ω x d̂|: rotation about d̂ itself moves no point along it.
  const double across = motion.omega_fixed_W.cross(d_hat).norm() + motion.omega_free;
  return std::min(motion.omega_bound, across) * motion.rotation_radius;
}

double solve_gap_closing(double a, double b, double delta) {
  // Inside the target gap already: it closes now if it is closing at all; a gap neither closing
  // nor accelerated closed (two bodies at rest together) stays as it is.
  if (!(delta > 0.0)) return b > 0.0 || a > 0.0 || std::isnan(a + b) ? 0.0 : kInfinity;
  const double disc = b * b + 2.0 * a * delta;
  if (disc < 0.0) return kInfinity;
  if (b > 0.0) return 2.0 * delta / (b + std::sqrt(disc));
  if (a > 0.0) return (-b + std::sqrt(disc)) / a;
  return kInfinity;
}

double solve_return_to_gap(double a, double b, double delta) {
  if (!(a > 0.0)) return kInfinity;
  const double disc = b * b + 2.0 * a * delta;
  return disc >= 0.0 ? (-b + std::sqrt(disc)) / a : -2.0 * b / a;
}

ToiBound toi_bound(const ToiMotion& motion1, const ToiMotion& motion2,
                   const DistanceResult& closest, double d_target, const Settings& settings) {
  ToiBound bound;
  if (closest.status != ContactStatus::kSeparated && closest.status != ContactStatus::kTouching) {
    bound.dt = 0.0;
    return bound;
  }
  const Vec3 d_hat = -closest.n_W;
  bound.closing_speed = (motion1.v_W - motion2.v_W).dot(d_hat) + rotational_term(motion1, d_hat) +
                        rotational_term(motion2, d_hat);
  bound.closing_accel =
      (motion1.a_W - motion2.a_W).dot(d_hat) + motion1.accel_slack + motion2.accel_slack;
  const double delta = closest.distance - d_target;
  const double a = bound.closing_accel, b = bound.closing_speed;
  const bool persistent = settings.contact_model == ContactModel::kPersistent;
  if (delta <= 0.0 && b < 0.0 &&
      !(persistent && closest.distance > 0.0 && -b <= settings.still_speed_mps)) {
    // Already inside the target gap but receding even with the rotational terms (the flight
    // after a microcollision). The gap stays above the parabola d - b t - a t^2 / 2, which is
    // at least d until it comes back down to d: so until the parabola falls back to d_target if
    // it rises above it (the gap is then >= d_target, as after any bound), else until it
    // returns to d, t = -2b/a; never, without a closing acceleration. Aiming at d itself, a
    // body bounced from a gap of 0 (placed exactly touching) came back to 0 and, by rounding,
    // into overlap: 1.47 million overlapping queries for a block placed on a ramp. Under the
    // persistent model a pair receding no faster than the still speed is at rest (two held
    // balls of a pile, receding at 1e-19 m/s by rounding): -2b/a shrank with each check, 5.5
    // million checks in 0.1 s, and it aims at half its gap below as a resting pair does.
    bound.dt = solve_return_to_gap(a, b, delta);
    return bound;
  }
  if (persistent && delta <= 0.0 && closest.distance > 0.0) {
    // Inside the target gap, not receding, under the persistent model: what rests there is held
    // (a ball rolling along a wall it touches, beside the floor that holds it), so the bound aims
    // at half the present gap: a pair that keeps its gap costs nothing (a rolling ball beside a
    // wall was re-checked at the progress floor, 300,000 times in balls_in_dish), one that
    // closes is checked before it can touch, and when checked approaching it collides.
    bound.dt = solve_gap_closing(a, b, 0.5 * closest.distance);
  } else {
    bound.dt = solve_gap_closing(a, b, delta);
  }
  if (bound.dt < settings.toi_min_progress_s) {
    // The progress floor keeps a pair that closes only through rotation from stalling, but it
    // may not carry the pair through contact: it is capped by the time the bound allows to close
    // the whole present gap (no overlap). Uncapped, a box landing at 2.4 m/s went 2.8e-6 m deep
    // at envelope 1e-9, and a box at 1e4 m/s 4.2 mm deep at envelope 1e-4
    // (tests/tools/extremes_test.cpp). Capped at d_target inside the target gap (as it was under
    // the microcollision model), a bowling pin spinning at 7 rad/s, whose edge's centre receded
    // while its corner closed, was carried 2.6e-8 m into the lane (bowling with microcollision
    // groups between dynamic bodies). Near contact the steps shrink
    // with the gap, and a corner still approaching at the instant of touching collides there
    // (check_pair).
    const double cap = solve_gap_closing(a, b, closest.distance);
    const double floor = std::min(settings.toi_min_progress_s, cap);
    if (bound.dt < floor) {
      bound.dt = floor;
      bound.floored = true;
    }
  }
  return bound;
}

ToiBound exact_toi_sphere_sphere(const Vec3& c1_W, const Vec3& v1_W, double r1, const Vec3& c2_W,
                                 const Vec3& v2_W, double r2, double d_target) {
  ToiBound bound;
  bound.exact = true;
  const Vec3 r = c1_W - c2_W;
  const Vec3 w = v1_W - v2_W;
  const double reach = r1 + r2 + d_target;
  // |r + w t|^2 = reach^2:  A t^2 + 2 B t + C = 0.
  const double A = w.squaredNorm();
  const double B = r.dot(w);
  const double C = r.squaredNorm() - reach * reach;
  bound.closing_speed = r.norm() > 0.0 ? -B / r.norm() : 0.0;
  if (C <= 0.0) {
    // Already within the target gap: now if approaching, never again if receding.
    bound.dt = B < 0.0 ? 0.0 : kInfinity;
    return bound;
  }
  if (B >= 0.0 || A == 0.0) return bound;  // receding or at rest relative to each other
  const double disc = B * B - A * C;
  if (disc < 0.0) return bound;  // passes by
  // Smaller root without cancellation: t = C / (-B + sqrt(B^2 - A C)).
  bound.dt = C / (-B + std::sqrt(disc));
  return bound;
}

ToiBound exact_toi_sphere_plane(const Vec3& c_W, const Vec3& v_W, const Vec3& g_W, double radius,
                                const Vec3& n_W, double offset_W, const Vec3& plane_velocity_W,
                                double d_target) {
  ToiBound bound;
  bound.exact = true;
  // Gap h(t) = delta - b t - 1/2 a t^2 exactly, with b = -(v - u) . n and a = -g . n.
  const double delta = n_W.dot(c_W) - offset_W - radius - d_target;
  bound.closing_speed = -(v_W - plane_velocity_W).dot(n_W);
  bound.closing_accel = -g_W.dot(n_W);
  const double a = bound.closing_accel;
  const double b = bound.closing_speed;
  if (delta <= 0.0 && b < 0.0) {
    // Inside the target gap and receding (the flight after a microcollision).
    bound.dt = solve_return_to_gap(a, b, delta);
    return bound;
  }
  bound.dt = solve_gap_closing(a, b, delta);
  return bound;
}

ToiMotion toi_motion(const Body& body, const BodyState& state, const ShapeGeometry& geometry,
                     const Vec3& gravity_W, const Vec3& other_center_W, double other_reach_m,
                     const Settings& settings) {
  ToiMotion m;
  switch (body.motion) {
    case MotionKind::kFixed: return m;
    case MotionKind::kDynamic:
      m.v_W = state.v_W;
      m.a_W = gravity_W;
      m.rotation_radius = geometry.rotation_radius();
      m.omega_bound = m.rotation_radius > 0.0 ? angular_speed_bound(body, state, settings) : 0.0;
      if (m.omega_bound > 0.0) {
        switch (classify_inertia(body.mass.principal_moments, settings.inertia_symmetry_tolerance)) {
          case InertiaSymmetry::kSpherical:  // ω is constant in free flight
            m.omega_fixed_W = state.w_W;
            m.omega_free = 0.0;
            break;
          case InertiaSymmetry::kAxisymmetric: {  // ω precesses about L at constant magnitude
            const Mat3 R_WB = principal_orientation_W(body.mass, state.q_WM).toRotationMatrix();
            const Vec3 L_W =
                R_WB * body.mass.principal_moments.cwiseProduct(R_WB.transpose() * state.w_W);
            if (L_W.norm() > 0.0) {
              const Vec3 l = L_W.normalized();
              m.omega_fixed_W = l * l.dot(state.w_W);
              m.omega_free = (state.w_W - m.omega_fixed_W).norm();
            } else {
              m.omega_free = m.omega_bound;
            }
            break;
          }
          case InertiaSymmetry::kAsymmetric: m.omega_free = m.omega_bound; break;
        }
      }
      return m;
    case MotionKind::kKinematic: {
      const KinematicMotion& k = body.kinematic;
      m.kinematic = true;
      m.v_W = k.velocity_W;
      m.spin_W = k.angular_velocity_W;
      const double spin = m.spin_W.norm();
      if (spin == 0.0) return m;
      const Vec3 axis = m.spin_W / spin;
      const Vec3 axis_point = k.point_W + k.velocity_W * state.t;
      auto from_axis = [&](const Vec3& x) {
        const Vec3 r = x - axis_point;
        return (r - r.dot(axis) * axis).norm();
      };
      const bool unbounded = !std::isfinite(geometry.reach());
      m.rotation_radius = unbounded ? from_axis(other_center_W) + other_reach_m
                                    : from_axis(state.x_W) + geometry.rotation_radius();
      return m;
    }
  }
  return m;
}

const ShapeGeometry::Piece* halfspace(const ShapeGeometry& g) {
  if (g.pieces().size() != 1) return nullptr;
  const ShapeGeometry::Piece& p = g.pieces()[0];
  return p.kind == ShapeGeometry::PieceKind::kHalfspace ? &p : nullptr;
}

double vertex_bound_above_plane(const BodyState& s, const ShapeGeometry& g, const BodyState& plane,
                                const ShapeGeometry::Piece& half, const Vec3& accel_W,
                                double accel_slack, double spin, double d_target) {
  for (const ShapeGeometry::Piece& piece : g.pieces()) {
    if (piece.kind != ShapeGeometry::PieceKind::kPolyhedron || !piece.mesh) return -1.0;
  }
  const Vec3 n_W = plane.q_WM * half.normal_M;
  const double offset = half.offset + n_W.dot(plane.x_W);
  const double closing = -n_W.dot(accel_W) + accel_slack;
  const Mat3 R_WM = s.q_WM.toRotationMatrix();
  double best = kInfinity;
  for (const ShapeGeometry::Piece& piece : g.pieces()) {
    for (int k = 0; k < piece.mesh->num_vertices(); ++k) {
      const Vec3 r = R_WM * (piece.p_M + piece.R_M * piece.mesh->vertex(k));
      const double h = n_W.dot(s.x_W + r) - offset;
      if (!(h >= 0.0)) return -1.0;  // overlapping (to rounding, or more): not this bound's case
      const double b = -n_W.dot(s.v_W + s.w_W.cross(r));
      const double a = closing + r.norm() * spin;
      const double delta = h - d_target;
      const double dt = delta <= 0.0 && b < 0.0 ? solve_return_to_gap(a, b, delta)
                                                : solve_gap_closing(a, b, delta);
      best = std::min(best, dt);
      if (!(best > 0.0)) return 0.0;
    }
  }
  return best;
}

double vertex_bound_above_face(const BodyState& sa, const ShapeGeometry& ga, const VertexMotion& ma,
                               const BodyState& sb, const ShapeGeometry::Piece& piece, int face,
                               const VertexMotion& mb, double d_target) {
  for (const ShapeGeometry::Piece& p : ga.pieces()) {
    if (p.kind != ShapeGeometry::PieceKind::kPolyhedron || !p.mesh) return -1.0;
  }
  if (piece.kind != ShapeGeometry::PieceKind::kPolyhedron || !piece.mesh) return -1.0;
  const Mat3 R_B = sb.q_WM.toRotationMatrix();
  const Vec3 n = R_B * (piece.R_M * piece.mesh->face_normal(face));
  const double offset = n.dot(sb.x_W + R_B * piece.p_M) + piece.mesh->face_offset(face);
  const Vec3 da = ma.accel_W - mb.accel_W;
  const double slacks = ma.accel_slack + mb.accel_slack;
  const double accel = ma.accel_W.norm() + mb.accel_W.norm() + slacks;
  const double spin_a = ma.w_bound * ma.w_bound + ma.alpha_bound;
  const double spin_b = mb.w_bound * mb.w_bound + mb.alpha_bound;
  const Vec3 dv = sa.v_W - sb.v_W;
  const Mat3 R_A = sa.q_WM.toRotationMatrix();
  // The vertices' heights, closing speeds and offsets, once.
  struct Vertex {
    double h, b, r, rho;
  };
  std::vector<Vertex> vertices;
  for (const ShapeGeometry::Piece& p : ga.pieces()) {
    for (int k = 0; k < p.mesh->num_vertices(); ++k) {
      const Vec3 r = R_A * (p.p_M + p.R_M * p.mesh->vertex(k));
      const Vec3 rho = sa.x_W + r - sb.x_W;
      const double h = n.dot(rho) + n.dot(sb.x_W) - offset;
      if (!(h >= 0.0)) return -1.0;  // overlapping (to rounding, or more): not this bound's case
      // h' = (w_B x n) . rho + n . (v_A + w_A x r - v_B)
      const double rate = sb.w_W.cross(n).dot(rho) + n.dot(dv + sa.w_W.cross(r));
      vertices.push_back({h, -rate, r.norm(), rho.norm()});
    }
  }
  double best = 0.0;
  for (const double horizon : {1e-5, 1e-4, 1e-3, 1e-2}) {
    double dt = horizon;
    for (const Vertex& v : vertices) {
      const double U = dv.norm() + ma.w_bound * v.r + accel * horizon;
      const double A = -n.dot(da) + mb.w_bound * horizon * da.norm() + slacks + spin_a * v.r +
                       spin_b * (v.rho + U * horizon) + 2.0 * mb.w_bound * U;
      // An unbounded motion (an infinite bound, or one that turns a product into NaN) bounds
      // nothing: a vertex can be there now. (Passed on, the NaN was lost in std::min and the
      // whole horizon came back.)
      if (!std::isfinite(A) || !std::isfinite(v.b)) return 0.0;
      const double delta = v.h - d_target;
      const double t = delta <= 0.0 && v.b < 0.0 ? solve_return_to_gap(A, v.b, delta)
                                                 : solve_gap_closing(A, v.b, delta);
      dt = std::min(dt, t);
      if (!(dt > 0.0)) break;
    }
    best = std::max(best, dt);
  }
  return best;
}

namespace {

// The single sphere of a geometry centred at its origin, or nullptr.
const ShapeGeometry::Piece* centred_sphere(const ShapeGeometry& g) {
  if (g.pieces().size() != 1) return nullptr;
  const ShapeGeometry::Piece& p = g.pieces()[0];
  return p.kind == ShapeGeometry::PieceKind::kSphere && p.p_M.norm() == 0.0 ? &p : nullptr;
}

// Sphere (dynamic) against a halfspace whose motion maps its plane onto itself.
bool exact_sphere_plane(const Body& sphere_body, const BodyState& s, double radius,
                        const Body& plane_body, const BodyState& p,
                        const ShapeGeometry::Piece& half, const Vec3& gravity_W, double d_target,
                        ToiBound& out) {
  if (!sphere_body.is_dynamic() || plane_body.is_dynamic()) return false;
  const Vec3 n_W = p.q_WM * half.normal_M;
  Vec3 plane_velocity = Vec3::Zero();
  if (plane_body.motion == MotionKind::kKinematic) {
    if (plane_body.kinematic.angular_velocity_W.cross(n_W).squaredNorm() != 0.0) return false;
    plane_velocity = plane_body.kinematic.velocity_W;
  }
  const double offset_W = half.offset + n_W.dot(p.x_W);
  out = exact_toi_sphere_plane(s.x_W, s.v_W, gravity_W, radius, n_W, offset_W, plane_velocity,
                               d_target);
  return true;
}

// A dynamic polyhedron (or compound of polyhedra) in free flight above a fixed plane
// (vertex_bound_above_plane in toi_bound.hpp, its closing acceleration gravity's): ᾱ = ω̄^2
// (I_max - I_min) / I_min bounds |ω'| in torque-free flight: ω' = -I^-1 (ω x I ω),
// |ω x I ω| <= |ω|^2 (I_max - I_min). So a vertex on the axis a body rocks or spins about closes
// only as fast as it truly does, not at ω̄ ρ: a box rocking on an edge, or spinning flat, is
// bounded by what its corners do. -1 if the pair is not of this kind.
// `w_bar`: the body's angular-speed bound ω̄ (its ToiMotion's, already computed).
double ballistic_vertex_bound(const Body& body, const BodyState& s, const ShapeGeometry& g,
                              double w_bar, const Body& plane_body, const BodyState& p,
                              const ShapeGeometry::Piece& half, const Vec3& gravity_W,
                              double d_target) {
  if (!body.is_dynamic() || plane_body.motion != MotionKind::kFixed) return -1.0;
  const Vec3& I = body.mass.principal_moments;
  const double alpha_bar = I.minCoeff() > 0.0
                               ? w_bar * w_bar * (I.maxCoeff() - I.minCoeff()) / I.minCoeff()
                               : kInfinity;
  return vertex_bound_above_plane(s, g, p, half, gravity_W, 0.0, w_bar * w_bar + alpha_bar,
                                  d_target);
}

}  // namespace

namespace {

ToiBound single_time_of_impact(const Body& body1, const BodyState& state1,
                               const ShapeGeometry& geometry1, const Body& body2,
                               const BodyState& state2, const ShapeGeometry& geometry2,
                               const DistanceResult& closest, const Vec3& gravity_W,
                               const Settings& settings, double d_target) {
  const ShapeGeometry::Piece* sphere1 = centred_sphere(geometry1);
  const ShapeGeometry::Piece* sphere2 = centred_sphere(geometry2);
  ToiBound exact;
  if (sphere1 && sphere2 && body1.is_dynamic() && body2.is_dynamic()) {
    // Same gravity on both: the relative motion is linear.
    return exact_toi_sphere_sphere(state1.x_W, state1.v_W, sphere1->radius, state2.x_W, state2.v_W,
                                   sphere2->radius, d_target);
  }
  if (sphere1 && halfspace(geometry2) &&
      exact_sphere_plane(body1, state1, sphere1->radius, body2, state2, *halfspace(geometry2),
                         gravity_W, d_target, exact)) {
    return exact;
  }
  if (sphere2 && halfspace(geometry1) &&
      exact_sphere_plane(body2, state2, sphere2->radius, body1, state1, *halfspace(geometry1),
                         gravity_W, d_target, exact)) {
    return exact;
  }
  const ToiMotion m1 =
      toi_motion(body1, state1, geometry1, gravity_W, state2.x_W, geometry2.reach(), settings);
  const ToiMotion m2 =
      toi_motion(body2, state2, geometry2, gravity_W, state1.x_W, geometry1.reach(), settings);
  ToiBound bound = toi_bound(m1, m2, closest, d_target, settings);
  // Only where the rotational term would storm (a floored bound: the vertex pass costs a walk
  // over the vertices) and the pair is apart (overlapping or failed: check now stands). Both are
  // lower bounds on the same instant: the larger is too.
  const bool apart =
      closest.status == ContactStatus::kSeparated || closest.status == ContactStatus::kTouching;
  double by_vertices = -1.0;
  if (bound.floored && apart && halfspace(geometry2)) {
    by_vertices = ballistic_vertex_bound(body1, state1, geometry1, m1.omega_bound, body2, state2,
                                         *halfspace(geometry2), gravity_W, d_target);
  } else if (bound.floored && apart && halfspace(geometry1)) {
    by_vertices = ballistic_vertex_bound(body2, state2, geometry2, m2.omega_bound, body1, state1,
                                         *halfspace(geometry1), gravity_W, d_target);
  }
  if (by_vertices > bound.dt) {
    bound.dt = by_vertices;
    bound.floored = false;
  }
  return bound;
}

ToiBound pair_time_of_impact(const Body& body1, const BodyState& state1,
                             const ShapeGeometry& geometry1, const Body& body2,
                             const BodyState& state2, const ShapeGeometry& geometry2,
                             const DistanceResult& closest, const PairCache& cache,
                             const Vec3& gravity_W, const Settings& settings, double d_target) {
  if (cache.piece_results().empty()) {
    return single_time_of_impact(body1, state1, geometry1, body2, state2, geometry2, closest,
                                 gravity_W, settings, d_target);
  }
  // Body-level motions bound every piece: the rotation radius and reach cover all pieces.
  const ToiMotion m1 =
      toi_motion(body1, state1, geometry1, gravity_W, state2.x_W, geometry2.reach(), settings);
  const ToiMotion m2 =
      toi_motion(body2, state2, geometry2, gravity_W, state1.x_W, geometry1.reach(), settings);
  ToiBound best;
  best.dt = kInfinity;
  for (const DistanceResult& piece : cache.piece_results()) {
    const ToiBound b = toi_bound(m1, m2, piece, d_target, settings);
    if (b.dt < best.dt) best = b;
  }
  return best;
}

}  // namespace

ToiBound time_of_impact(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                        const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                        const DistanceResult& closest, const Vec3& gravity_W,
                        const Settings& settings) {
  return single_time_of_impact(body1, state1, geometry1, body2, state2, geometry2, closest,
                               gravity_W, settings, derived_target_gap(settings));
}

ToiBound time_of_impact(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                        const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                        const DistanceResult& closest, const PairCache& cache,
                        const Vec3& gravity_W, const Settings& settings) {
  return pair_time_of_impact(body1, state1, geometry1, body2, state2, geometry2, closest, cache,
                             gravity_W, settings, derived_target_gap(settings));
}

ToiBound time_to_touch(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                       const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                       const DistanceResult& closest, const PairCache& cache,
                       const Vec3& gravity_W, const Settings& settings) {
  Settings unfloored = settings;
  unfloored.toi_min_progress_s = 0.0;
  return pair_time_of_impact(body1, state1, geometry1, body2, state2, geometry2, closest, cache,
                             gravity_W, unfloored, 0.0);
}

double co_flying_time(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                      const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                      double closing) {
  auto isotropic = [](const Body& b) {
    const Vec3& I = b.mass.principal_moments;
    return b.is_dynamic() && I.maxCoeff() - I.minCoeff() <= 1e-12 * I.maxCoeff();
  };
  if (!isotropic(body1) || !isotropic(body2)) return 0.0;
  double best = 0.0;
  for (int side = 0; side < 2; ++side) {
    const BodyState& a = side == 0 ? state1 : state2;
    const BodyState& b = side == 0 ? state2 : state1;
    const double reach_b = (side == 0 ? geometry2 : geometry1).reach();
    const Vec3 dx = b.x_W - a.x_W, dv = b.v_W - a.v_W;
    const double speed = (dv - a.w_W.cross(dx)).norm() + (b.w_W - a.w_W).norm() * reach_b;
    const double accel = a.w_W.norm() * dv.norm();
    best = std::max(best, solve_gap_closing(accel, speed, closing));
  }
  return best;
}

}  // namespace palpable
