#include "scheduler/contact.hpp"

#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "distance/vclip.hpp"
#include "impulse/contact_torque.hpp"
#include "impulse/microcollision.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace palpable {

namespace {

// Is the point q (on the plane of the convex polygon `patch`, counter-clockwise about n) inside?
bool inside_convex_polygon(const std::vector<Vec3>& patch, const Vec3& n, const Vec3& q) {
  for (std::size_t i = 0; i < patch.size(); ++i) {
    const Vec3& p0 = patch[i];
    const Vec3& p1 = patch[(i + 1) % patch.size()];
    if ((p1 - p0).cross(q - p0).dot(n) < 0.0) return false;
  }
  return true;
}

// Where the segment from `inside` to `outside` leaves the convex polygon (both on its plane).
Vec3 exit_point(const std::vector<Vec3>& patch, const Vec3& n, const Vec3& inside,
                const Vec3& outside) {
  double s_exit = 1.0;
  const Vec3 d = outside - inside;
  for (std::size_t i = 0; i < patch.size(); ++i) {
    const Vec3& p0 = patch[i];
    const Vec3& p1 = patch[(i + 1) % patch.size()];
    // Inward edge normal m: points with m . (x - p0) >= 0 are inside.
    const Vec3 m = n.cross(p1 - p0);
    const double f0 = m.dot(inside - p0);
    const double fd = m.dot(d);
    if (fd < 0.0) s_exit = std::min(s_exit, std::max(0.0, f0 / -fd));
  }
  return inside + s_exit * d;
}

// The relative normal velocity of the bodies at the point q (< 0 approaching).
double normal_velocity_at(const Vec3& q, const Vec3& n_W, const BodyState& s1,
                          const BodyState& s2) {
  return (point_velocity_W(s1, q) - point_velocity_W(s2, q)).dot(n_W);
}

// The index of the patch point approaching fastest (the corner that lands first); among equals,
// the one nearest `foot` (the foot of the dynamic body's centre of mass).
std::size_t fastest_approaching_corner(const std::vector<Vec3>& patch, const Vec3& n_W,
                                       const BodyState& s1, const BodyState& s2, const Vec3& foot) {
  double best = kInfinity;
  std::size_t corner = 0;
  for (std::size_t i = 0; i < patch.size(); ++i) {
    const Vec3& q = patch[i];
    const double u_n = normal_velocity_at(q, n_W, s1, s2);
    const double tie = 1e-12 * (1.0 + std::abs(u_n));
    if (u_n < best - tie ||
        (std::abs(u_n - best) <= tie && (q - foot).norm() < (patch[corner] - foot).norm())) {
      best = std::min(best, u_n);
      corner = i;
    }
  }
  return corner;
}

// The point of the patch that lands first: the fastest-approaching corner `f`, or, where a
// neighbouring corner approaches as fast (an edge landing: the relative normal velocity is
// affine over the plane, so the whole edge lands at once), the point of that edge nearest
// `foot`, as the corners' own tie is broken. (Taken at one of the edge's two corners, a box
// turned and rocking about y, dropped on its edge onto a resting box, left it spinning about z
// at 0.25 rad/s in a scene with no y in it.)
Vec3 first_landing_point(const std::vector<Vec3>& patch, std::size_t f, const Vec3& n_W,
                         const BodyState& s1, const BodyState& s2, const Vec3& foot) {
  const std::size_t n = patch.size();
  if (n < 2) return patch[f];
  const double u_f = normal_velocity_at(patch[f], n_W, s1, s2);
  const double tie = 1e-12 * (1.0 + std::abs(u_f));
  for (std::size_t g : {(f + n - 1) % n, (f + 1) % n}) {  // (a segment patch: the other end)
    if (std::abs(normal_velocity_at(patch[g], n_W, s1, s2) - u_f) <= tie) {
      return closest_point_segment(patch[f], patch[g], foot);
    }
  }
  return patch[f];
}

// A face resting on a face, the only place for the centre-of-pressure rule: the body's rotation
// in the contact plane (rocking, or rolling about an edge of its patch) moves its patch relative
// to its centre of mass no faster than the microcollision speed, max over the patch points q of
// |w_in x (q - x)|. Judged by the patch's own size instead (|w_in| times the patch radius), a
// disk rolling on one narrow facet of its rim (2 mm on a 64-gon) at 24 rad/s passed as resting
// although its centre moves at 0.5 m/s, and the rule then took the rolling away (Euler's disk fell
// flat in 0.065 s); the lever about the rotation axis, not the distance, keeps a long stick
// rocking about its own axis judged by its thickness.
bool face_rests_on_face(const std::vector<Vec3>& patch, const Vec3& x_dynamic_W, const Vec3& w_in_W,
                        double rocking_limit) {
  double speed = 0.0;
  for (const Vec3& q : patch) speed = std::max(speed, w_in_W.cross(q - x_dynamic_W).norm());
  return speed <= rocking_limit;
}

// A body turning about one edge of a polygon patch onto the rest of it (a prism rolling onto
// its next face, a box tipping back onto its base, one at rest on a face it tips off) lands
// along an edge: the corner landing first and the neighbour of it landing faster (or, as fast,
// nearer the foot of the centre of mass). Both land at once unless one leads by more than the
// microcollision speed (the see-saw along the edge, judged as for an edge on a face): the
// impulse is then that of an edge on a face, over that edge. Returns true with c placed so
// (kSegment, c.patch the edge, c.point_W the point of it nearest the foot), else false with c
// unchanged. (At the first corner alone, with friction, a 128-gon's landings turned it about the
// normal and about its rolling direction; the tilt grew 1e3 times every 0.1 s until the prism
// hopped onto a corner and lost half its speed.)
bool place_on_landing_edge(Contact& c, std::size_t f, const BodyState& s1, const BodyState& s2,
                           const Vec3& foot_W) {
  const std::size_t n = c.patch.size();
  if (n < 3) return false;
  const Vec3 w_rel = c.dynamic1() ? Vec3(s1.w_W - s2.w_W) : Vec3(s2.w_W - s1.w_W);
  const std::size_t before = (f + n - 1) % n, after = (f + 1) % n;
  const double u_before = normal_velocity_at(c.patch[before], c.n_W, s1, s2);
  const double u_after = normal_velocity_at(c.patch[after], c.n_W, s1, s2);
  const double tie = 1e-12 * (1.0 + std::abs(u_before) + std::abs(u_after));
  const bool take_before = u_before < u_after - tie ||
                           (u_before <= u_after + tie &&
                            (c.patch[before] - foot_W).norm() < (c.patch[after] - foot_W).norm());
  // The edge in the patch's (counter-clockwise) order.
  const std::vector<Vec3> edge = take_before ? std::vector<Vec3>{c.patch[before], c.patch[f]}
                                             : std::vector<Vec3>{c.patch[f], c.patch[after]};
  const Vec3 s = (edge[1] - edge[0]).normalized();
  const Vec3 m = c.n_W.cross(s);
  if (s.allFinite() &&
      face_rests_on_face(edge, c.dynamic_x_W(), m * w_rel.dot(m), std::max(c.v_micro, 1e-9))) {
    c.placement = Placement::kSegment;
    c.patch = edge;
    c.segment_dir_W = s;
    const double length = (edge[1] - edge[0]).norm();
    c.point_W = edge[0] + s * std::clamp((foot_W - edge[0]).dot(s), 0.0, length);
    return true;
  }
  return false;
}

// Puts the contact at `tip_W`, the point of the patch boundary a body tips about when the patch
// cannot carry the torque of the centre-of-pressure impulse (DESIGN.md §4). If the body turns so
// fast that this point already separates, the corner landing first takes the collision: the
// relative normal velocity is affine over the contact plane, so a patch whose centre of pressure
// approaches has a corner that approaches. (A collision at the separating point does nothing a
// retry sees: the pair stays approaching at the same instant, again and again; a microcollision
// there even pushes the point away at v_micro while the patch's other end keeps landing.)
void place_tipping(Contact& c, const Vec3& tip_W, const BodyState& s1, const BodyState& s2) {
  c.placement = Placement::kPoint;
  place(c, tip_W);
  const Vec3 u_tip = contact_point_velocity_W(c.body1) - contact_point_velocity_W(c.body2);
  // (At rest, within rounding of it, the tip point takes it: a prism at rest on a face of a
  // slope it tips off, all its corners still, was struck at whichever corner rounding made first.)
  if (u_tip.dot(c.n_W) > rounding_speed(c)) {
    const Vec3& foot = c.dynamic_x_W();
    const std::size_t first = fastest_approaching_corner(c.patch, c.n_W, s1, s2, foot);
    const Vec3 corner = c.patch[first];  // (an edge placed replaces the patch)
    const bool on_edge = place_on_landing_edge(c, first, s1, s2, foot);
    place(c, on_edge ? c.point_W : corner);
  }
}

// The couples a point impulse cannot carry (impulse/contact_torque.hpp), applied after the
// impulse P_n of a collision: torsional friction about n - over a patch resolved by the
// centre-of-pressure rule, mu times the mean distance of the patch from the centre of pressure;
// at a point, the material's spinning resistance - and the material's rolling resistance
// against the in-plane relative rotation. Changes the angular velocities of cb1 and cb2 (true
// inertias, not the centre-of-pressure ones); the record's energy change is measured on the
// bodies and includes what these take out.
void resist_rotation(const Contact& c, const Material& material, double P_n, const Vec3& pressure_W,
                     ContactBody& cb1, ContactBody& cb2) {
  if (!(P_n > 0.0)) return;
  ContactBody t1 = c.body1, t2 = c.body2;
  t1.w_W = cb1.w_W;
  t2.w_W = cb2.w_W;
  // About n: Coulomb friction over a patch, or the material's spinning resistance at a point
  // (the patch's mean distance, the costly part, only if there is spin to resist).
  const bool spins = c.n_W.dot(t1.w_W - t2.w_W) != 0.0;
  const double torsion_arm =
      !spins ? 0.0
      : c.centre_of_pressure()
          ? material.friction * mean_distance_over_patch(c.patch, c.n_W, pressure_W)
          : material.spinning_resistance;
  if (torsion_arm > 0.0) {
    const AngularImpulse torsion = resisting_angular_impulse(c.n_W, t1, t2, torsion_arm * P_n);
    apply_angular_impulse(torsion.L_W, t1, t2);
  }
  if (material.rolling_resistance > 0.0) {
    const Vec3 w_rel = t1.w_W - t2.w_W;
    const Vec3 rolling = w_rel - c.n_W * c.n_W.dot(w_rel);
    const double rate = rolling.norm();
    if (rate > 0.0) {
      const AngularImpulse resistance =
          resisting_angular_impulse(rolling / rate, t1, t2, material.rolling_resistance * P_n);
      apply_angular_impulse(resistance.L_W, t1, t2);
    }
  }
  cb1.w_W = t1.w_W;
  cb2.w_W = t2.w_W;
}

// Stage 1, effective inertia: the dynamic body of a centre-of-pressure contact as the impulse
// sees it. Over a face the line of action passes through the centre of mass: no rotation change
// at all. Over a segment only the rotation about m = n x s is held: the inverse inertia of a body
// free to turn only about the segment s and the normal n, V (V^T I V)^-1 V^T with V = [s n].
void constrain_rotation(const Contact& c, ContactBody& cd) {
  if (c.placement == Placement::kFace) {
    cd.inv_inertia_W.setZero();
  } else if (c.placement == Placement::kSegment) {
    Eigen::Matrix<double, 3, 2> V;
    V.col(0) = c.segment_dir_W;
    V.col(1) = c.n_W;
    const Mat3 I_W = cd.inv_inertia_W.inverse();
    cd.inv_inertia_W = V * (V.transpose() * I_W * V).inverse() * V.transpose();
  }
}

// A face on a face between two dynamic bodies: the response of the pair whose relative rotation
// the patch holds, a body whose rotation its own support holds counted as of infinite inertia.
HeldRotationResponse stack_response(const Contact& c) {
  ContactBody b1 = c.body1, b2 = c.body2;
  if (c.rotation_held1) b1.inv_inertia_W.setZero();
  if (c.rotation_held2) b2.inv_inertia_W.setZero();
  return held_rotation_response(b1, c.x1_W, b2, c.x2_W);
}

// One pass of stages 1 and 2: the impulse at the contact's present placement.
struct Pass {
  ContactBody cb1, cb2;    // the effective bodies (stage 1)
  Mat3 R_WC;               // contact frame
  Vec3 u0_c;               // initial relative velocity, contact frame
  bool micro = false;      // a microcollision
  CollisionResult result;  // stage 2
  Vec3 p_W = Vec3::Zero();
  // A face on a dynamic face: the pair's response with the relative rotation held (else unset).
  HeldRotationResponse stack;
  int steps = 0;        // Runge-Kutta steps (of the failed integration, if it failed)
  bool failed = false;  // integration failed: the frictionless impulse stands in
};

Pass impulse_pass(const Contact& c, const ContactSide& side1, const ContactSide& side2,
                  const Material& material, const Settings& settings, double stack_mass,
                  const ResolveOptions& options) {
  Pass pass;
  CollisionParameters params = collision_parameters(material, settings);
  params.min_rebound_speed = options.microcollisions && c.g_n > 0.0 ? c.v_micro : 0.0;
  if (options.restitution >= 0.0) params.restitution = options.restitution;
  pass.R_WC = contact_frame_W(c.n_W);
  pass.cb1 = c.body1;
  pass.cb2 = c.body2;
  ContactBody& cd = c.dynamic1() ? pass.cb1 : pass.cb2;
  if (c.centre_of_pressure()) constrain_rotation(c, cd);
  const Mat3& R_WC = pass.R_WC;
  // A stack carried by the microcollision meets the impulse with its whole mass (riders).
  if (stack_mass > 0.0) cd.inv_mass = 1.0 / stack_mass;
  // The same frame problem as impulse/'s resolve_collision (its tests are this path's tests).
  FrameProblem problem = frame_problem(pass.cb1, pass.cb2, R_WC);
  if (c.placement == Placement::kFace && c.dynamic == DynamicSide::kBoth) {
    pass.stack = stack_response(c);
    problem.K_c = R_WC.transpose() * pass.stack.K_W * R_WC;
  }
  const Mat3& K_c = problem.K_c;
  pass.u0_c = problem.u0_c;
  pass.micro = options.microcollisions && is_microcollision(pass.u0_c.z(), c.v_micro, settings);
  if (pass.micro) {
    MicrocollisionContext context;
    const Vec3 a_c = R_WC.transpose() * c.a_rel_W;
    context.a_t_c = Vec2(a_c.x(), a_c.y());
    context.g_n = c.g_n;
    // The kinematic surface of the pair, if any (its partner is then the dynamic body).
    const Body* surface = side1.body.motion == MotionKind::kKinematic   ? &side1.body
                          : side2.body.motion == MotionKind::kKinematic ? &side2.body
                                                                        : nullptr;
    const Vec3 surface_w_W = surface ? surface->kinematic.angular_velocity_W : Vec3::Zero();
    if (c.centre_of_pressure()) {
      // A face resting on a turning surface sticks to it: what must vanish over the flight is
      // its displacement on the surface. (A rolling ball's orbit follows its mean slip, which
      // the first-order target already zeroes; the term made the platter's orbit rate error
      // 3 times larger.)
      context.surface_spin = surface_w_W.dot(c.n_W);
    }
    pass.result = resolve_microcollision(K_c, pass.u0_c, params, settings.microcollision_rule,
                                         context, c.v_micro);
    // On a turning surface the slip rate Omega x (v - V) depends on the velocity the dynamic
    // body flies with, which is the one after this impulse: aim once more with it.
    if (surface_w_W.squaredNorm() > 0.0 && c.slip_at_centre() && succeeded(pass.result.status)) {
      const double inv_mass = c.dynamic1() ? cd.inv_mass : -cd.inv_mass;
      const Vec3 dv_W = R_WC * pass.result.p_c * inv_mass;  // body 1 gets +p, body 2 -p
      const Vec3 da_W = surface_w_W.cross(dv_W);
      const Vec3 a2_c = R_WC.transpose() * (c.a_rel_W + (surface == &side1.body ? da_W : -da_W));
      context.a_t_c = Vec2(a2_c.x(), a2_c.y());
      pass.result = resolve_microcollision(K_c, pass.u0_c, params, settings.microcollision_rule,
                                           context, c.v_micro);
    }
  } else {
    pass.result = integrate_collision(K_c, pass.u0_c, params);
  }
  pass.steps = pass.result.steps;
  if (!succeeded(pass.result.status)) {
    // Numerical failure: fall back to the frictionless impulse (always defined for an SPD K),
    // counted. The contact still separates.
    pass.failed = true;
    CollisionParameters frictionless = params;
    frictionless.friction = 0.0;
    pass.result = integrate_collision(K_c, pass.u0_c, frictionless);
  }
  pass.p_W = R_WC * pass.result.p_c;
  return pass;
}

// Stage 3, locate the pressure: where the impulse of a centre-of-pressure contact acts, and
// whether the contact must move (once) before it can be applied.
struct PressureLocation {
  Vec3 pressure_W = Vec3::Zero();  // the centre of pressure (the contact point if no rule)
  bool move = false;               // resolve once more, at the contact moved to `to_W`
  bool tip = false;                // ... as a tipping point (else along the segment)
  Vec3 to_W = Vec3::Zero();
};

PressureLocation locate_pressure(const Contact& c, const Pass& pass, bool first_pass) {
  const Vec3& p_W = pass.p_W;
  PressureLocation at;
  at.pressure_W = c.point_W;
  const Vec3& x_D = c.dynamic_x_W();
  if (c.placement == Placement::kSegment) {
    // Where along the segment must the impulse act so that its torque about m vanishes?
    const Vec3 m = c.n_W.cross(c.segment_dir_W);
    const double denominator = c.segment_dir_W.cross(p_W).dot(m);
    const double lambda =
        denominator != 0.0 ? -(c.point_W - x_D).cross(p_W).dot(m) / denominator : 0.0;
    const double s0 = (c.point_W - c.patch[0]).dot(c.segment_dir_W);
    const double length = (c.patch[1] - c.patch[0]).norm();
    const double s_pressure = s0 + lambda;
    const bool inside = s_pressure >= 0.0 && s_pressure <= length;
    if (!inside || (first_pass && std::abs(lambda) > 1e-12 * (1.0 + length))) {
      // Inside: resolve once more at the centre of pressure (K depends on the point). Outside:
      // the segment cannot hold that torque and the body tips about the end it reaches, or,
      // if that end already separates, collides at the end landing first.
      at.move = true;
      at.tip = !inside;
      at.to_W = c.patch[0] + c.segment_dir_W * std::clamp(s_pressure, 0.0, length);
    }
  } else if (c.placement == Placement::kFace && c.dynamic == DynamicSide::kBoth) {
    // The couple L on body 1 that holds the faces parallel, I1 dw - r1 x p, moves the pressure
    // off the contact point by s with p_n (s x n) = L's in-plane part: s = n x L / p_n.
    // (From body 2's side, -I2 dw - r2 x p, if body 1's rotation is held by its own support.)
    const double pn = p_W.dot(c.n_W);
    const Vec3 dw = pass.stack.W * p_W;
    const Vec3 couple = !c.rotation_held1 ? Vec3(c.body1.inv_inertia_W.inverse() * dw -
                                                 c.body1.r_W.cross(p_W))
                        : !c.rotation_held2 ? Vec3(-(c.body2.inv_inertia_W.inverse() * dw) -
                                                   c.body2.r_W.cross(p_W))
                                            : Vec3::Zero();
    at.pressure_W = pn > 0.0 || pn < 0.0 ? Vec3(c.point_W + c.n_W.cross(couple) / pn) : c.point_W;
    if (!inside_convex_polygon(c.patch, c.n_W, at.pressure_W)) {
      at.move = at.tip = true;
      at.to_W = exit_point(c.patch, c.n_W, c.point_W, at.pressure_W);
    }
  } else if (c.placement == Placement::kFace) {
    // Where does the line of action through the centre of mass meet the contact plane?
    const double pn = p_W.dot(c.n_W);
    at.pressure_W = pn != 0.0 ? x_D + p_W * (c.n_W.dot(c.point_W - x_D) / pn) : c.point_W;
    if (!inside_convex_polygon(c.patch, c.n_W, at.pressure_W)) {
      // The patch cannot carry that torque: the body tips about the patch boundary.
      at.move = at.tip = true;
      at.to_W = exit_point(c.patch, c.n_W, c.point_W, at.pressure_W);
    }
  }
  return at;
}

}  // namespace

void place(Contact& c, const Vec3& point_W) {
  c.point_W = point_W;
  const double height = c.n_W.dot(point_W - c.plane2_W);  // above body 2's surface
  c.body1.r_W = point_W + c.n_W * (c.gap - height) - c.x1_W;
  c.body2.r_W = point_W - c.n_W * height - c.x2_W;
}

double rounding_speed(const Contact& c) {
  return kVelocityRounding *
         (contact_point_velocity_W(c.body1).norm() + contact_point_velocity_W(c.body2).norm());
}

Placement place_over_patch(Contact& c, const BodyState& s1, const BodyState& s2, const Vec3& foot_W,
                           const Settings& settings) {
  const BodyState& sd = c.dynamic1() ? s1 : s2;
  const BodyState& ss = c.dynamic1() ? s2 : s1;
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& q : c.patch) centroid += q;
  centroid /= static_cast<double>(c.patch.size());
  double patch_radius = 0.0;
  for (const Vec3& q : c.patch) patch_radius = std::max(patch_radius, (q - centroid).norm());
  const Vec3 w_rel = sd.w_W - ss.w_W;
  const Vec3 w_in = w_rel - c.n_W * c.n_W.dot(w_rel);
  // The rule applies to a dynamic body on a fixed or kinematic one, touching over a polygon and
  // not rocking faster than the microcollision speed.
  const bool one_dynamic = c.dynamic == DynamicSide::kFirst || c.dynamic == DynamicSide::kSecond;
  const double rocking_limit = std::max(c.v_micro, 1e-9);
  const Vec3 along = c.patch.size() == 2 ? (c.patch[1] - c.patch[0]).normalized() : Vec3::Zero();
  const Vec3& x_dynamic = c.dynamic1() ? c.x1_W : c.x2_W;
  if (settings.centre_of_pressure && one_dynamic && c.patch.size() >= 3 &&
      face_rests_on_face(c.patch, x_dynamic, w_in, rocking_limit)) {
    c.point_W = foot_W;
    return Placement::kFace;
  }
  if (settings.centre_of_pressure && c.dynamic == DynamicSide::kBoth && c.patch.size() >= 3 &&
      face_rests_on_face(c.patch, c.x1_W, w_in, rocking_limit) &&
      face_rests_on_face(c.patch, c.x2_W, w_in, rocking_limit)) {
    // Two dynamic bodies face to face (a stack): the patch holds their relative rotation
    // (held_rotation_response), whose impulse is the same at every point of the patch; the
    // centroid is where it starts, the centre of pressure is found from the couple it needs.
    c.point_W = centroid;
    return Placement::kFace;
  }
  if (settings.centre_of_pressure && one_dynamic && c.patch.size() == 2 && along.allFinite() &&
      face_rests_on_face(c.patch, x_dynamic, c.n_W.cross(along) * w_rel.dot(c.n_W.cross(along)),
                         rocking_limit)) {
    // Edge on face: the point of the segment nearest the foot of the centre of mass.
    c.segment_dir_W = along;
    const double length = (c.patch[1] - c.patch[0]).norm();
    c.point_W = c.patch[0] + along * std::clamp((foot_W - c.patch[0]).dot(along), 0.0, length);
    return Placement::kSegment;
  }
  const std::size_t first = fastest_approaching_corner(c.patch, c.n_W, s1, s2, foot_W);
  if (settings.centre_of_pressure && one_dynamic &&
      place_on_landing_edge(c, first, s1, s2, foot_W)) {
    return Placement::kSegment;
  }
  c.point_W = first_landing_point(c.patch, first, c.n_W, s1, s2, foot_W);
  return Placement::kPoint;
}

Contact make_contact(const ContactSide& side1, const ContactSide& side2, const DistanceResult& dr,
                     const Settings& settings, const Vec3& gravity_W, bool with_patch) {
  const Body& b1 = side1.body;
  const Body& b2 = side2.body;
  const BodyState& s1 = side1.state;
  const BodyState& s2 = side2.state;
  Contact c;
  c.a = side1.id;
  c.b = side2.id;
  c.dynamic = b1.is_dynamic() ? (b2.is_dynamic() ? DynamicSide::kBoth : DynamicSide::kFirst)
                              : (b2.is_dynamic() ? DynamicSide::kSecond : DynamicSide::kNeither);
  c.n_W = dr.n_W;
  c.point_W = 0.5 * (dr.p1_W + dr.p2_W);
  c.x1_W = s1.x_W;
  c.x2_W = s2.x_W;

  // A held body's acceleration, or free flight's. A held polyhedron's at the contact point: its
  // corner there is a point of the body, so its rotation's terms count (a hull held leaning on a
  // wall, tipping towards it, pressed its corner against the wall at 8 m/s^2 while its centre
  // moved along the wall). Not a curved body's: its contact point is no point of it (a rolling
  // ball's material point there accelerates towards its centre, its gap does not).
  auto acceleration = [&](const ContactSide& side) -> Vec3 {
    if (!side.acceleration_W) return side.body.is_dynamic() ? gravity_W : Vec3::Zero();
    if (!side.angular_acceleration_W ||
        !std::holds_alternative<ConvexPolyhedron>(*side.body.shape)) {
      return *side.acceleration_W;
    }
    const Vec3 r = c.point_W - side.state.x_W;
    return *side.acceleration_W + side.angular_acceleration_W->cross(r) +
           side.state.w_W.cross(side.state.w_W.cross(r));
  };
  c.held_acceleration = side1.acceleration_W || side2.acceleration_W;
  c.g_n = -(acceleration(side1) - acceleration(side2)).dot(c.n_W);
  if (c.dynamic == DynamicSide::kBoth && !c.held_acceleration) {
    // Same gravity on both: use the upper body's weight along n (DESIGN.md §4).
    c.g_n = std::abs(gravity_W.dot(c.n_W));
  }
  c.g_n = std::max(c.g_n, 0.0);
  c.v_micro = microcollision_speed(settings, c.g_n);

  auto fill = [&](ContactBody& cb, const Body& b, const BodyState& s) {
    cb.inv_mass = b.mass.inv_mass;
    cb.inv_inertia_W = b.is_dynamic() ? inverse_inertia_W(b, s.q_WM) : Mat3::Zero();
    cb.v_W = s.v_W;
    cb.w_W = s.w_W;
  };
  fill(c.body1, b1, s1);
  fill(c.body2, b2, s2);

  if (with_patch && dr.status != ContactStatus::kPenetrating) {
    c.patch = contact_patch(side1.geometry, Pose{s1.x_W, s1.q_WM}, side2.geometry,
                            Pose{s2.x_W, s2.q_WM}, dr, settings.envelope_m);
  }
  if (c.patch.size() >= 2) {
    // Foot of the dynamic body's centre of mass on the contact plane.
    const Vec3& x_D = c.dynamic1() ? s1.x_W : s2.x_W;
    const Vec3 foot = x_D - c.n_W * c.n_W.dot(x_D - dr.p2_W);
    c.placement = place_over_patch(c, s1, s2, foot, settings);
  }
  const Body* dynamic_body = c.dynamic1() ? &b1 : (c.dynamic2() ? &b2 : nullptr);
  if (c.placement == Placement::kPoint && dynamic_body &&
      std::holds_alternative<Sphere>(*dynamic_body->shape)) {
    c.placement = Placement::kSphere;
  }
  c.gap = c.n_W.dot(dr.p1_W - dr.p2_W);
  c.plane2_W = dr.p2_W;
  place(c, c.point_W);
  c.u_n = (contact_point_velocity_W(c.body1) - contact_point_velocity_W(c.body2)).dot(c.n_W);

  // Rate of change of the slip at the moving contact location over the next flight
  // (DESIGN.md §4): gravity, the rotational terms of a rotating contact point, and for a
  // kinematic surface the change of its velocity under the moving location, Omega x (p' - V).
  const ContactBody& cd = c.dynamic_body();
  Vec3 location_velocity = Vec3::Zero();
  if (dynamic_body) {
    location_velocity = c.slip_at_centre() ? cd.v_W : contact_point_velocity_W(cd);
  }
  auto accel = [&](const Body& b, const ContactBody& cb) -> Vec3 {
    if (b.is_dynamic()) {
      Vec3 a = gravity_W;
      if (!c.slip_at_centre()) a += cb.w_W.cross(cb.w_W.cross(cb.r_W));
      return a;
    }
    if (b.motion == MotionKind::kKinematic) {
      return b.kinematic.angular_velocity_W.cross(location_velocity - b.kinematic.velocity_W);
    }
    return Vec3::Zero();
  };
  c.a_rel_W = accel(b1, c.body1) - accel(b2, c.body2);
  return c;
}

bool approaching(const Contact& c) {
  // u_n = 0 with gravity pressing the bodies together counts as approaching: a body left at
  // rest in contact by an e = 0 collision must collide again (DESIGN.md §4). Without it, an
  // approach within rounding of the bodies' speeds (what an e = 0 collision leaves) is rest.
  // Two dynamic bodies share gravity, so nothing presses them together at rest: a body resting
  // on another rides along when the lower one bounces on its support (see carries_riders).
  if (c.g_n > 0.0 && (c.dynamic != DynamicSide::kBoth || c.held_acceleration)) {
    return c.u_n <= kRestingApproachSlack * c.v_micro;
  }
  return c.u_n < -rounding_speed(c);
}

bool patch_approaching(const Contact& c, const BodyState& s1, const BodyState& s2) {
  const double rounding = rounding_speed(c);
  for (const Vec3& q : c.patch) {
    if (normal_velocity_at(q, c.n_W, s1, s2) < -rounding) return true;
  }
  return false;
}

double initial_normal_velocity(const Contact& c) {
  return frame_problem(c.body1, c.body2, contact_frame_W(c.n_W)).u0_c.z();
}

bool carries_riders(const Contact& c, const Settings& settings, const Vec3& gravity_W) {
  // A body bouncing on its support carries what rests on it (shock propagation, as in
  // Guendelman, Bridson & Fedkiw 2003, for the microcollision train): the microcollision acts
  // on the stack's whole mass and every rider gets the same change of velocity. Otherwise a
  // light body under a heavy one must pass the heavy one's weight on in its own collisions, a
  // storm of m_heavy / m_light of them (tests/tools/extremes_test.cpp). Only over a face resting
  // on its support (the centre-of-pressure rule: the carrier does not turn, so the stack's mass
  // is all the impulse meets).
  if (c.placement != Placement::kFace || c.dynamic == DynamicSide::kBoth) return false;
  if (!is_microcollision(initial_normal_velocity(c), c.v_micro, settings)) return false;
  if (gravity_W.squaredNorm() == 0.0) return false;
  const Vec3 n_up = c.dynamic1() ? c.n_W : Vec3(-c.n_W);  // from the support up
  return n_up.dot(-gravity_W.normalized()) > kSupportCosine;
}

namespace {

// A face resting on a face does not rock: the pressure over the patch takes out the small
// in-plane relative rotation (a plastic slap; the spin about n stays free). Over a segment, only
// the rotation about m = n x s. The pressure acts as a couple L on the dynamic body, dw = I^-1 L
// with L in the rocking axes, sized so that the rocking stops: the plastic projection in the
// kinetic-energy metric, which never adds energy. (Zeroing the rocking components of w directly
// is the same when those axes are principal, as for a box or a coin lying flat, but adds energy
// to a body whose principal axes are tilted to them: a coin rolling on its rim's edge.)
void stop_rocking(const Contact& c, ContactBody& cb1, ContactBody& cb2) {
  if (c.dynamic == DynamicSide::kBoth) {
    // Between two dynamic bodies the couple is L on body 1 and -L on body 2, in the plane,
    // sized so that their relative rocking stops: a = T^T (I1^-1 + I2^-1) T, L = -a^-1 T^T w_rel.
    const Mat3 inv_i1 = c.rotation_held1 ? Mat3::Zero() : c.body1.inv_inertia_W;
    const Mat3 inv_i2 = c.rotation_held2 ? Mat3::Zero() : c.body2.inv_inertia_W;
    const Mat3 frame = contact_frame_W(c.n_W);
    Eigen::Matrix<double, 3, 2> T = frame.leftCols<2>();
    const Eigen::Matrix2d a = T.transpose() * (inv_i1 + inv_i2) * T;
    if (!(a.determinant() > 0.0)) return;
    const Vec3 couple = T * -(a.inverse() * (T.transpose() * (cb1.w_W - cb2.w_W)));
    cb1.w_W += inv_i1 * couple;
    cb2.w_W -= inv_i2 * couple;
    return;
  }
  ContactBody& cd = c.dynamic1() ? cb1 : cb2;
  const Vec3 w_rel = c.dynamic1() ? cb1.w_W - cb2.w_W : cb2.w_W - cb1.w_W;
  // The body's own inertia (the impulse pass saw the rule's constrained one).
  const Mat3& inv_i = (c.dynamic1() ? c.body1 : c.body2).inv_inertia_W;
  if (c.placement == Placement::kSegment) {
    const Vec3 m = c.n_W.cross(c.segment_dir_W);
    const double k = m.dot(inv_i * m);
    if (k > 0.0) cd.w_W -= inv_i * m * (m.dot(w_rel) / k);
    return;
  }
  const Mat3 frame = contact_frame_W(c.n_W);
  const Vec3 t1 = frame.col(0), t2 = frame.col(1);
  const Vec3 i_t1 = inv_i * t1, i_t2 = inv_i * t2;
  Eigen::Matrix2d a;
  a << t1.dot(i_t1), t1.dot(i_t2), t2.dot(i_t1), t2.dot(i_t2);
  const Eigen::Vector2d rocking(t1.dot(w_rel), t2.dot(w_rel));
  const double det = a.determinant();
  if (!(det > 0.0)) return;
  const Eigen::Vector2d couple = -(a.inverse() * rocking);
  cd.w_W += i_t1 * couple.x() + i_t2 * couple.y();
}

}  // namespace

Resolution resolve(Contact c, const ContactSide& side1, const ContactSide& side2,
                   const Material& material, const Settings& settings,
                   const std::vector<Rider>& riders, double t, const ResolveOptions& options) {
  Resolution out;
  // Stages 1-3, at most twice over a face (the second pass at the tipping point) and at most
  // three times over a segment (moved to where its torque vanishes, then tipping if it leaves).
  double stack_mass = 0.0;
  if (!riders.empty()) {
    stack_mass = (c.dynamic1() ? side1 : side2).body.mass.mass;
    for (const Rider& r : riders) stack_mass += r.body.mass.mass;
  }
  Pass pass;
  PressureLocation at;
  for (int round = 0;; ++round) {
    // Riders ride on a face resting on its support; a tipping carrier turns and carries none.
    if (c.placement != Placement::kFace) stack_mass = 0.0;
    pass = impulse_pass(c, side1, side2, material, settings, stack_mass, options);
    out.integration_steps += pass.steps;
    if (pass.failed) ++out.impulse_failures;
    at = locate_pressure(c, pass, round == 0);
    if (!at.move) break;
    if (at.tip) {
      place_tipping(c, at.to_W, side1.state, side2.state);
      out.outcome = PressureOutcome::kTipped;
    } else {
      place(c, at.to_W);
      out.outcome = PressureOutcome::kMovedOnSegment;
    }
  }
  if (out.outcome == PressureOutcome::kAtPoint && c.centre_of_pressure()) {
    out.outcome = PressureOutcome::kWithinPatch;
  }
  const bool carried = stack_mass > 0.0;

  // Stage 4, apply and record. The kinetic energy of the dynamic bodies before, for the record:
  // the integrator's (1/2)(u0 + u').p is that of the impulse at the point it was resolved with,
  // which the centre-of-pressure rule's modified inertia and its removal of rocking make differ
  // from what the bodies show (by up to 0.015 J on a 1 kg box at envelope 1e-2).
  auto kinetic = [](const Body& b, const BodyState& s) {
    return b.is_dynamic() ? kinetic_energy(b, s) : 0.0;
  };
  double kinetic_before = kinetic(side1.body, side1.state) + kinetic(side2.body, side2.state);
  if (carried) {
    for (const Rider& r : riders) kinetic_before += kinetic(r.body, r.state);
  }
  ContactBody& cb1 = pass.cb1;
  ContactBody& cb2 = pass.cb2;
  if (c.placement == Placement::kFace && c.dynamic == DynamicSide::kBoth) {
    // The patch holds the relative rotation: both bodies turn alike (held_rotation_response).
    const Vec3 dw = pass.stack.W * pass.p_W;
    cb1.v_W += cb1.inv_mass * pass.p_W;
    cb2.v_W -= cb2.inv_mass * pass.p_W;
    cb1.w_W += dw;
    cb2.w_W += dw;
  } else {
    apply_impulse(pass.p_W, cb1, cb2);
  }
  if (c.centre_of_pressure()) stop_rocking(c, cb1, cb2);
  resist_rotation(c, material, pass.p_W.dot(c.n_W), at.pressure_W, cb1, cb2);
  out.v1_W = side1.body.is_dynamic() ? cb1.v_W : side1.state.v_W;
  out.w1_W = side1.body.is_dynamic() ? cb1.w_W : side1.state.w_W;
  out.v2_W = side2.body.is_dynamic() ? cb2.v_W : side2.state.v_W;
  out.w2_W = side2.body.is_dynamic() ? cb2.w_W : side2.state.w_W;
  PALPABLE_CHECK(
      out.v1_W.allFinite() && out.w1_W.allFinite() && out.v2_W.allFinite() && out.w2_W.allFinite(),
      "non-finite velocity after a collision");

  CollisionRecord& record = out.record;
  record.t = t;
  record.kind = pass.micro ? CollisionKind::kMicrocollision : CollisionKind::kCollision;
  record.a = c.a;
  record.b = c.b;
  record.p_W = c.point_W;
  record.n_W = c.n_W;
  record.impulse_W = pass.p_W;
  record.approach_speed = -pass.u0_c.z();
  record.phase_count = static_cast<std::uint8_t>(pass.result.phase_count);
  for (int i = 0; i < pass.result.phase_count; ++i) {
    const CollisionPhase& phase = pass.result.phases[static_cast<std::size_t>(i)];
    record.phases[static_cast<std::size_t>(i)] = phase.kind;
    if (phase.kind == PhaseKind::kResumedSliding) {
      record.resumed_direction_W = pass.R_WC * Vec3(phase.direction.x(), phase.direction.y(), 0.0);
    }
  }
  record.slip_before_W = pass.R_WC * Vec3(pass.u0_c.x(), pass.u0_c.y(), 0.0);
  record.slip_after_W =
      pass.R_WC * Vec3(pass.result.u_final_c.x(), pass.result.u_final_c.y(), 0.0);
  record.normal_impulse_compression = pass.result.p_z_compression;
  record.normal_impulse_restitution = pass.result.p_c.z() - pass.result.p_z_compression;
  BodyState after1 = side1.state, after2 = side2.state;
  after1.v_W = out.v1_W;
  after1.w_W = out.w1_W;
  after2.v_W = out.v2_W;
  after2.w_W = out.w2_W;
  double kinetic_after = kinetic(side1.body, after1) + kinetic(side2.body, after2);
  if (carried) {
    // The riders move on with the carrier along the normal (a plastic merge with the stack,
    // which the impulse on the stack's mass assumed), and friction carries the carrier's change
    // of tangential velocity to them as far as its cone allows (mu times their normal change):
    // a box on a block that floor friction slows is slowed with it, not left sliding off. They
    // keep their own sliding and spin.
    const Vec3& v_carrier = c.dynamic1() ? out.v1_W : out.v2_W;
    const Vec3 dv_carrier = v_carrier - (c.dynamic1() ? side1 : side2).state.v_W;
    const Vec3 dv_tangential = dv_carrier - c.n_W * c.n_W.dot(dv_carrier);
    for (const Rider& r : riders) {
      BodyState after = r.state;
      const double dv_normal = c.n_W.dot(v_carrier - after.v_W);
      after.v_W += c.n_W * dv_normal;
      const double limit = r.friction * std::abs(dv_normal);
      const double dv_t = dv_tangential.norm();
      after.v_W += dv_t <= limit ? dv_tangential : Vec3(dv_tangential * (limit / dv_t));
      out.rider_v_W.push_back(after.v_W);
      record.carried.push_back(r.id);
      kinetic_after += kinetic(r.body, after);
    }
  }
  record.energy_change = kinetic_after - kinetic_before;
  record.centre_of_pressure = c.centre_of_pressure();

  const double p_norm = pass.p_W.norm();
  out.energy_allowance = settings.integration_tolerance * p_norm * std::abs(pass.u0_c.z());
  if (c.g_n > 0.0 && options.microcollisions) {
    const double slack = 1.0 + settings.microcollision_speed_slack;
    // A stack carried by the microcollision (riders) leaves with its whole mass.
    const double m_red = carried ? stack_mass : 1.0 / (c.body1.inv_mass + c.body2.inv_mass);
    const Vec3 u_after = pass.result.u_final_c;
    out.energy_allowance += std::max(0.5 * p_norm * c.v_micro * slack,
                                     0.5 * m_red * u_after.squaredNorm() * slack * slack);
  }
  // Rounding of the energies themselves (each about the bodies' kinetic energy).
  out.energy_allowance += 1e-12 * (kinetic_before + kinetic_after);
  // A moving (kinematic) body does work on what it hits (a paddle, a platter): not checked.
  [[maybe_unused]] const bool driven =
      side1.body.motion == MotionKind::kKinematic || side2.body.motion == MotionKind::kKinematic;
  PALPABLE_DCHECK(settings.restitution_law == RestitutionLaw::kNewton || driven ||
                      record.energy_change <= out.energy_allowance,
                  "a collision created energy: " + significant(record.energy_change) +
                      " J > allowance " + significant(out.energy_allowance) + " J at t = " +
                      significant(t) + " (approach " + significant(-c.u_n) + " m/s)");
  return out;
}

}  // namespace palpable
