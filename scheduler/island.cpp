#include "scheduler/island.hpp"

#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "core/convex_polygon.hpp"
#include "core/event_location.hpp"
#include "impulse/microcollision.hpp"
#include "scheduler/island_detail.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace palpable {

namespace {

bool is_sphere(const Body& b) {
  return std::holds_alternative<Sphere>(*b.shape);
}

// The spherical-inertia test of the ballistic code: a sphere's orientation never matters.
bool spherical_inertia(const Body& b, const Settings& settings) {
  const Vec3& I = b.mass.principal_moments;
  return I.z() - I.x() <= settings.inertia_symmetry_tolerance * I.z();
}

// The smallest t > 0 with c0 + c1 t + c2 t^2 / 2 = 0 crossing from positive to negative
// (+inf if none): when a quantity that is positive now first becomes negative.
double first_negative(double c0, double c1, double c2) {
  if (c0 < 0.0) return 0.0;
  double best = kInfinity;
  auto consider = [&](double t) {
    if (t > 0.0 && t < best) {
      // Negative just after t: the derivative there is negative (or zero with c2 < 0).
      const double slope = c1 + c2 * t;
      if (slope < 0.0 || (slope == 0.0 && c2 < 0.0)) best = t;
    }
  };
  if (c2 == 0.0) {
    if (c1 < 0.0) consider(-c0 / c1);
    return best;
  }
  const double disc = c1 * c1 - 2.0 * c2 * c0;
  if (disc < 0.0) return best;
  const double root = std::sqrt(disc);
  // Both roots of c2/2 t^2 + c1 t + c0 without cancellation.
  const double q = -(c1 + (c1 >= 0.0 ? root : -root));
  if (q != 0.0) {
    consider(q / c2);
    consider(2.0 * c0 / q);
  } else {
    consider(0.0);
  }
  return best;
}

// A body's world inertia.
Mat3 inertia_W(const Body& b, const Quat& q_WM) {
  const Mat3 R = q_WM.toRotationMatrix();
  return R * b.mass.inertia_M * R.transpose();
}

}  // namespace

const char* to_string(IslandEvent::Kind kind) {
  switch (kind) {
    case IslandEvent::Kind::kNone: return "none";
    case IslandEvent::Kind::kSlipStop: return "stick";
    case IslandEvent::Kind::kSpinStop: return "spin_stop";
    case IslandEvent::Kind::kRollStop: return "roll_stop";
    case IslandEvent::Kind::kSlipStart: return "slip";
    case IslandEvent::Kind::kLiftOff: return "lift_off";
    case IslandEvent::Kind::kTip: return "tip";
    case IslandEvent::Kind::kLanding: return "landing";
    case IslandEvent::Kind::kSegmentEnd: return "segment_end";
    case IslandEvent::Kind::kChunkEnd: return "chunk_end";
  }
  return "unknown";
}

namespace {

// The contact problem of an island at given states: its bodies, and a contact per link.
struct Problem {
  std::vector<HeldBody> bodies;
  std::vector<HeldContact> contacts;
  bool placed = true;     // every link found its patch
  std::vector<int> lost;  // links whose patch vanished
};

KnownMotion known_motion(const Body& b, const BodyState& s) {
  KnownMotion k;
  k.x_W = s.x_W;
  if (b.motion != MotionKind::kKinematic) return k;
  const KinematicMotion& m = b.kinematic;
  k.v_W = s.v_W;
  k.w_W = m.angular_velocity_W;
  const Vec3 axis_point = m.point_W + m.velocity_W * s.t;
  k.a_W = m.angular_velocity_W.cross(m.angular_velocity_W.cross(s.x_W - axis_point));
  return k;
}

// A body's state at t: its integrated state `states` if it is one of the island's, else its own
// motion advanced to t (a fixed, kinematic or free body the island's links touch).
BodyState body_state_at(const Island& island, const World& world,
                        const std::vector<BodyState>& states, BodyId id, double t) {
  const int k = island.index_of(id);
  if (k >= 0) return states[static_cast<std::size_t>(k)];
  const Body& b = world.bodies[id.index];
  return t > b.state.t ? advance(b, b.state, t, world.gravity_W, world.settings) : b.state;
}

Vec2 plane_coords(const HeldContact& c, const Vec3& v) {
  return Vec2(v.dot(c.t1_W), v.dot(c.t2_W));
}

// A held contact's relative spin about its normal and its relative rolling, given its relative
// angular velocity dw, as speeds at the contact's size (judged against the still speed, or the
// integration's slip floor, when a spinning or rolling contact follows its direction).
double spin_speed(const HeldContact& c, const Vec3& dw) {
  return std::abs(dw.dot(c.n_W)) * (c.torsion_arm / std::max(c.friction, 1e-300));
}
double roll_speed(const HeldContact& c, const Vec3& dw) {
  return plane_coords(c, dw).norm() * point_size(c);
}

// Whether a held contact's slip (kind 0: friction), spin about its normal (1: torsion) or
// rolling (2: rolling resistance, a point contact) slides rather than sticks.
bool slides(const HeldContact& c, int kind) {
  switch (kind) {
    case 0: return c.friction > 0.0 && !c.sticks;
    case 1: return c.torsion_arm > 0.0 && !c.spin_sticks;
    default: return c.patch == PatchKind::kPoint && c.rolling_resistance > 0.0 && !c.roll_sticks;
  }
}

// The largest reach of an island's bodies (1 where that is not a positive finite length).
double island_size(const std::vector<BodyId>& bodies,
                   const std::vector<const ShapeGeometry*>& geometry) {
  double size = 0.0;
  for (BodyId id : bodies) size = std::max(size, geometry[id.index]->reach());
  return size > 0.0 && std::isfinite(size) ? size : 1.0;
}

// The slip floor of an integrated motion of bodies as large as `size` starting at `states`
// (Island::integrate): the integration resolves speeds to its tolerance times the motion's speed
// scale - the fastest body's speed at the start, at least that of a fall through its size - and a
// slip (spin, rolling) smaller than that only chatters in direction from step to step.
double motion_slip_floor(const Settings& settings, double g, double size,
                         const std::vector<BodyState>& states, double* speed_scale = nullptr) {
  double scale = std::sqrt(g * size);
  for (const BodyState& s : states) scale = std::max(scale, s.v_W.norm() + s.w_W.norm() * size);
  if (speed_scale != nullptr) *speed_scale = scale;
  return std::max(settings.still_speed_mps, 1e3 * settings.integration_tolerance * scale);
}

// The bodies' states at time t: island bodies from `states`, the others extrapolated.
// `follow`: sliding contacts take the direction of their present relative motion (see below);
// `slip_before` and `dw_before`, each contact's slip and relative angular velocity at the
// start of the integration step (world): for a slip, spin or rolling that has fallen below the
// floor within the step, and for one below it at the step's start, which keeps its rule all
// step.
Problem build_problem(const Island& island, const World& world,
                      const std::vector<BodyState>& states, double t, bool follow = false,
                      double slip_floor = 0.0, const std::vector<Vec3>* slip_before = nullptr,
                      const std::vector<Vec3>* dw_before = nullptr) {
  Problem p;
  p.bodies.reserve(island.bodies.size());
  p.contacts.reserve(island.links.size());
  for (std::size_t k = 0; k < island.bodies.size(); ++k) {
    const Body& b = world.bodies[island.bodies[k].index];
    const BodyState& s = states[k];
    HeldBody h;
    h.mass = b.mass.mass;
    h.inertia_W = inertia_W(b, s.q_WM);
    h.inv_inertia_W = inverse_inertia_W(b, s.q_WM);
    h.x_W = s.x_W;
    h.v_W = s.v_W;
    h.w_W = s.w_W;
    h.force_W = b.mass.mass * world.gravity_W;
    p.bodies.push_back(h);
  }
  auto state_of = [&](BodyId id) { return body_state_at(island, world, states, id, t); };
  for (std::size_t i = 0; i < island.links.size(); ++i) {
    const HeldLink& link = island.links[i];
    const BodyState sm = state_of(link.mover);
    const BodyState ss = state_of(link.support);
    HeldContact c;
    if (!place_link(link, sm, ss, c)) {
      p.placed = false;
      p.lost.push_back(static_cast<int>(i));
      c.active = false;
    }
    c.mover = island.index_of(link.mover);
    c.support = island.index_of(link.support);
    if (c.mover < 0) c.mover_known = known_motion(world.bodies[link.mover.index], sm);
    if (c.support < 0) c.support_known = known_motion(world.bodies[link.support.index], ss);
    const Material& m = world.material(link.mover, link.support);
    c.friction = m.friction;
    c.spinning_resistance = m.spinning_resistance;
    // Rolling resistance acts at a point of a sphere or a curved surface
    // (impulse/contact_dynamics.hpp), not along a rounded segment's line.
    c.rolling_resistance =
        (link.sphere_radius > 0.0 && link.mover_feature_M.empty()) || link.curved_shape
            ? m.rolling_resistance
            : 0.0;
    set_torsion_arm(c);
    c.sticks = link.sticks;
    c.slip_dir = link.slip_dir;
    c.spin_sticks = link.spin_sticks;
    c.spin_sign = link.spin_sign;
    c.roll_sticks = link.roll_sticks;
    c.roll_dir = link.roll_dir;
    p.contacts.push_back(c);
  }
  if (follow) {
    // Along an integrated motion, what slides is resisted against its present direction (a
    // slip, spin or rolling that turns); the directions chosen at the plan only start it.
    // Below the floor the direction is not followed (it only chatters there). A slip that falls
    // below it within a step goes on being resisted against its direction at the step's start:
    // its stop event lies in this step. (Resisted against the plan's direction instead - the
    // slip may have turned since - it was thrown back above the floor, and sat there sliding,
    // its stop never reached, in steps of a few nanoseconds: in a pile of 100 balls, half the
    // integration steps were rejected and 24 integrated motions broke down in 0.4 s.) So too a
    // spin and a rolling: a ball's rolling on another ball, resisted against the plan's
    // direction below the floor, sat at 1.002 times the floor for 0.067 s of a pile of 100
    // balls, in 4,096 steps of 2e-8 s on the clock, and its motion broke down after 1,001
    // rejected steps.
    // A slip below the floor at the step's start too slides along the direction its slip
    // accelerates in at each state (vanishing_slip_direction: the acceleration-level law, as it
    // started from rest), where there is one. (Resisted against the plan's direction, the slip
    // of Euler's disk sliding at its cone - its rate 1e-4 m/s^2 along that direction at the
    // plan, the disk's precession turning the direction it needed at 70 rad/s - grew across it
    // to the floor in 1e-4 s and sat there, followed above it and the plan's below: 92 % of its
    // integration steps were rejected and 701 motions broke down in 9 s.)
    // A slip, spin or rolling below the floor at the step's start keeps that rule for the whole
    // step, though it rise above the floor within it: it follows its present direction from the
    // next step on. Where it grew from below the floor, its present direction is not yet the one
    // it is resisted along below it (the slip left from before turns towards it at a rate of
    // order mu g / |slip|, the stiff mode the rule takes as turned already), and switching there
    // within a step made the accelerations jump from one stage to the next: the step's error fell
    // only in proportion to its length, so steps shrank to nanoseconds. (In 40 s of CPU from
    // 0.75 s of the pile of 100 balls of seed 1, 10,363 of 18,563 integration steps were
    // rejected, most with an error of first order in the step, at a slip or a rolling switching
    // rules between stages; kept for the step, 6,453 of 30,451, and the pile went 0.086 s
    // instead of 0.041 s.)
    const std::vector<HeldContactMotion> now = held_velocities(p.bodies, p.contacts);
    const double still = std::max(world.settings.still_speed_mps, slip_floor);
    std::vector<std::size_t> vanishing;
    for (std::size_t i = 0; i < p.contacts.size(); ++i) {
      HeldContact& c = p.contacts[i];
      const Vec2 slip = plane_coords(c, now[i].slip_W);
      if (!c.sticks) {
        const bool known = slip_before != nullptr && i < slip_before->size();
        const Vec2 before = known ? plane_coords(c, (*slip_before)[i]) : Vec2::Zero();
        if (known && before.norm() <= still) {
          if (c.active && c.friction > 0.0) vanishing.push_back(i);
        } else if (slip.norm() > still) {
          c.slip_dir = slip.normalized();
        } else if (known) {
          c.slip_dir = before.normalized();
        }
      }
      // The relative angular velocity a spin or rolling follows: none (the plan's) where it was
      // below the floor at the step's start, else the present one above the floor and the step
      // start's below it.
      const Vec3* before =
          dw_before != nullptr && i < dw_before->size() ? &(*dw_before)[i] : nullptr;
      auto followed = [&](double (*speed)(const HeldContact&, const Vec3&)) -> const Vec3* {
        if (before != nullptr && speed(c, *before) <= still) return nullptr;
        if (speed(c, now[i].dw_W) > still) return &now[i].dw_W;
        return before;
      };
      if (const Vec3* dw = c.spin_sticks ? nullptr : followed(spin_speed)) {
        c.spin_sign = dw->dot(c.n_W) > 0.0 ? 1.0 : -1.0;
      }
      if (const Vec3* dw = c.roll_sticks ? nullptr : followed(roll_speed)) {
        c.roll_dir = plane_coords(c, *dw).normalized();
      }
    }
    for (std::size_t i : vanishing) vanishing_slip_direction(p.bodies, p.contacts, i);
  }
  return p;
}

// The state vector of the integrated motion: per body x, q (w, x, y, z), v, w.
constexpr int kPerBody = 13;
// The speed, in multiples of an integrated motion's slip floor, below which a decelerating slip
// puts the integration on its clock (Island::integrate). Tried on piles of 100 balls (seeds 1-8,
// 0.4 s, cut off at 60 s): 1e4 let three of five seeds run past the cut-off; 1e2 and 1e3 did
// not, 1e3 with fewer rejected steps.
constexpr double kClockSpeed = 1e3;

dopri5::State pack(const std::vector<BodyState>& states) {
  dopri5::State y(static_cast<Eigen::Index>(kPerBody * states.size()));
  for (std::size_t k = 0; k < states.size(); ++k) {
    const BodyState& s = states[k];
    const Eigen::Index o = static_cast<Eigen::Index>(kPerBody * k);
    y.segment<3>(o) = s.x_W;
    y(o + 3) = s.q_WM.w();
    y.segment<3>(o + 4) = s.q_WM.vec();
    y.segment<3>(o + 7) = s.v_W;
    y.segment<3>(o + 10) = s.w_W;
  }
  return y;
}

std::vector<BodyState> unpack(const dopri5::State& y, double t) {
  std::vector<BodyState> out(static_cast<std::size_t>(y.size() / kPerBody));
  for (std::size_t k = 0; k < out.size(); ++k) {
    const Eigen::Index o = static_cast<Eigen::Index>(kPerBody * k);
    BodyState& s = out[k];
    s.t = t;
    s.x_W = y.segment<3>(o);
    s.q_WM = Quat(y(o + 3), y(o + 4), y(o + 5), y(o + 6)).normalized();
    s.v_W = y.segment<3>(o + 7);
    s.w_W = y.segment<3>(o + 10);
  }
  return out;
}

// How far a polygon patch's centre of pressure lies inside its edge k, from vertex k to k + 1
// (counter-clockwise: negative beyond it) [m].
double inside_edge(const std::vector<Vec2>& polygon, std::size_t k, const Vec2& cop) {
  const Vec2& a = polygon[k];
  const Vec2 d = polygon[(k + 1) % polygon.size()] - a;
  return cross2(d, cop - a) / d.norm();
}

// A support's vertex watched against one of a held mover's faces (Island::integrate's landing
// event): their indices in the two pieces' meshes, and the threshold its face value must stay
// above.
struct SupportWatch {
  int vertex, face;
  double threshold;
};

// A polyhedral support piece's vertex `v` in a polyhedral mover piece's frame, the mover piece
// turned by R_mover and placed at origin_mover, the support piece by R_support at origin_support.
Vec3 vertex_in_mover(const ShapeGeometry::Piece& support, const Mat3& R_support,
                     const Vec3& origin_support, const Mat3& R_mover, const Vec3& origin_mover,
                     int v) {
  return R_mover.transpose() *
         (origin_support + R_support * support.mesh->vertex(v) - origin_mover);
}

// The support's vertices a held link watches against the mover's faces (see Island::integrate),
// each with its face and its present face value: those whose nearest face of the mover (the
// largest face value, a lower bound of the vertex's distance) lies within the envelope, facing
// the support (against n_W, the link's normal) within 0.1 rad but not parallel to the plane.
std::vector<SupportWatch> support_watch_candidates(const ShapeGeometry::Piece& mover,
                                                   const Mat3& R_mover, const Vec3& origin_mover,
                                                   const ShapeGeometry::Piece& support,
                                                   const Mat3& R_support,
                                                   const Vec3& origin_support, const Vec3& n_W,
                                                   double envelope) {
  std::vector<SupportWatch> out;
  const double cos_limit = std::cos(0.1);
  for (int v = 0; v < support.mesh->num_vertices(); ++v) {
    const Vec3 q = vertex_in_mover(support, R_support, origin_support, R_mover, origin_mover, v);
    int nearest = -1;
    double value = -kInfinity;
    for (int f = 0; f < mover.mesh->num_faces(); ++f) {
      const double fv = mover.mesh->face_eval(f, q);
      if (fv > value) {
        value = fv;
        nearest = f;
      }
    }
    if (nearest < 0 || !(value <= envelope)) continue;
    const Vec3 n_f = R_mover * mover.mesh->face_normal(nearest);
    if (!(-n_f.dot(n_W) > cos_limit) || !(n_f.cross(n_W).norm() > 1e-9)) continue;
    out.push_back({v, nearest, value});  // the value; the caller turns it into a threshold
  }
  return out;
}

}  // namespace

int Island::index_of(BodyId id) const {
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    if (bodies[k] == id) return static_cast<int>(k);
  }
  return -1;
}

}  // namespace palpable

namespace palpable {

namespace {

// The two world points of a reduced contact's segment, or its one point.
std::vector<Vec3> contact_points_W(const HeldContact& c) {
  if (c.patch == PatchKind::kSegment) {
    return {c.c_W + c.segment_lo * c.segment_W, c.c_W + c.segment_hi * c.segment_W};
  }
  return {c.c_W};
}

// The point of a feature (a face's plane, an edge's line, a vertex) under q along n.
Vec3 on_feature(const std::vector<Vec3>& feature, const Vec3& n, const Vec3& q) {
  if (feature.size() >= 3) {
    // The face's plane: through its first vertex, normal to two of its edges.
    Vec3 normal = (feature[1] - feature[0]).cross(feature[2] - feature[0]);
    for (std::size_t i = 3; normal.norm() == 0.0 && i < feature.size(); ++i) {
      normal = (feature[1] - feature[0]).cross(feature[i] - feature[0]);
    }
    const double along = normal.dot(n);
    if (along == 0.0) return q;
    return q + n * (normal.dot(feature[0] - q) / along);
  }
  if (feature.size() == 2) {
    // The edge's point whose projection on the plane is q's.
    const Vec3 e = feature[1] - feature[0];
    const Vec3 e_in = e - n * n.dot(e);
    const double s = e_in.squaredNorm() > 0.0 ? e_in.dot(q - feature[0]) / e_in.squaredNorm() : 0.0;
    return feature[0] + std::clamp(s, 0.0, 1.0) * e;
  }
  return feature.empty() ? q : feature[0];
}

}  // namespace

// (island.hpp) Chosen one at a time, two coupled contacts each restarted the other: in a pile of
// 100 balls (seed 1, at 0.7202 s) a ball's rolling on the floor stopped and, the slip against the
// ball on it being left to slide at 8e-8 m/s, rolled again from rest; that slip stopped 2e-8 s
// later and, chosen from rest along a new direction, turned the rolling back to its stop - a
// cycle of three stops every 1.5e-7 s, 3,500 times, each re-planning an island of 29 balls.
void stop_imminent(const std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts,
                   double resolution, double floor) {
  // Run at every plan: where nothing slides (an island sticking everywhere, at rest), there is
  // nothing to stop and no solve to make.
  const auto sliding = [](const HeldContact& c) {
    return c.active && (slides(c, 0) || slides(c, 1) || slides(c, 2));
  };
  if (std::none_of(contacts.begin(), contacts.end(), sliding)) return;
  // Its motion holds the velocities (slip_W, dw_W) beside their rates, with what slides resisted
  // against its present direction, as the motion would follow it (a plan's direction may be
  // stale by now).
  std::vector<HeldContact> present = contacts;
  const std::vector<HeldContactMotion> now = held_velocities(bodies, contacts);
  for (std::size_t i = 0; i < present.size(); ++i) {
    HeldContact& c = present[i];
    const Vec2 slip = plane_coords(c, now[i].slip_W), roll = plane_coords(c, now[i].dw_W);
    const double spin = now[i].dw_W.dot(c.n_W);
    if (slides(c, 0) && slip.norm() > 0.0) c.slip_dir = slip.normalized();
    if (slides(c, 1) && spin != 0.0) c.spin_sign = spin > 0.0 ? 1.0 : -1.0;
    if (slides(c, 2) && roll.norm() > 0.0) c.roll_dir = roll.normalized();
  }
  const HeldSolution going = solve_held(bodies, present);
  if (going.status != HeldStatus::kOk) return;
  // A component moving at v whose rate along its motion is -a (a > 0) stops by v / a; `size`
  // turns v into a speed at the contact (0: the floor does not apply).
  auto soon = [&](const Vec2& v, const Vec2& rate, double size) {
    const double speed = v.norm();
    const double along = speed > 0.0 ? v.dot(rate) / speed : 0.0;
    return speed > 0.0 && along < 0.0 &&
           (speed <= -along * resolution || (size > 0.0 && speed * size <= floor));
  };
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    HeldContact& c = contacts[i];
    if (!c.active) continue;
    const HeldContactMotion& m = going.motion[i];
    if (slides(c, 0) && soon(plane_coords(c, m.slip_W), plane_coords(c, m.slip_rate_W), 1.0)) {
      c.slip_stopped = true;
    }
    if (slides(c, 1) &&
        soon(Vec2(m.dw_W.dot(c.n_W), 0.0), Vec2(m.dalpha_W.dot(c.n_W), 0.0), /*size=*/0.0)) {
      c.spin_stopped = true;
    }
    if (slides(c, 2) &&
        soon(plane_coords(c, m.dw_W), plane_coords(c, m.roll_rate_W), point_size(c))) {
      c.roll_stopped = true;
    }
  }
}

Island::PlanResult Island::plan(World& world, const std::vector<const ShapeGeometry*>& geometry,
                                double t) {
  PlanResult result;
  const Settings& settings = world.settings;
  const double still = settings.still_speed_mps;
  const double size = island_size(bodies, geometry);
  // The slip floor of the motion this plan ends, if it was integrated (else 0).
  const double integrated_floor = motion == Motion::kIntegrated ? slip_floor_ : 0.0;
  t0 = t;
  planned_t_ = t;
  steps_.clear();
  integration = IntegrationCount{};
  orientation_cache_.clear();
  anchor_.clear();
  for (BodyId id : bodies) {
    BodyState s = world.bodies[id.index].state;
    s.t = t;
    anchor_.push_back(s);
  }
  auto remove_links = [&](std::vector<int> drop) {
    std::sort(drop.begin(), drop.end());
    for (auto it = drop.rbegin(); it != drop.rend(); ++it) {
      result.released.push_back(links[static_cast<std::size_t>(*it)].pair);
      links.erase(links.begin() + *it);
    }
  };
  // No motion can be planned from a contact problem that is inconsistent or not finite: every
  // contact lets go, and the island's bodies fly free from the plan's instant.
  auto let_all_go = [&] {
    result.inconsistent = true;
    std::vector<int> all(links.size());
    for (std::size_t i = 0; i < links.size(); ++i) all[i] = static_cast<int>(i);
    remove_links(all);
  };
  auto state_of = [&](BodyId id) -> BodyState {
    const int k = index_of(id);
    return k >= 0 ? anchor_[static_cast<std::size_t>(k)] : world.bodies[id.index].state;
  };
  // A curved contact's point is found afresh from the shape at every state, so only the
  // integration keeps it at the held gap (the accelerations hold the gap's second derivative at
  // zero, to the integration's tolerance): Euler's disk rose 6e-9 m in 2 s. That drift is taken
  // out here, moving the body along the normal, where the link is the body's only one.
  for (const HeldLink& link : links) {
    const int km = index_of(link.mover);
    if (!link.curved_shape || km < 0) continue;
    const auto touches = [&](const HeldLink& l) {
      return l.mover == link.mover || l.support == link.mover;
    };
    if (std::count_if(links.begin(), links.end(), touches) != 1) continue;
    BodyState& sm = anchor_[static_cast<std::size_t>(km)];
    const BodyState ss = state_of(link.support);
    HeldContact c;
    if (!place_link(link, sm, ss, c)) continue;
    const double height = c.n_W.dot(c.c_W - (ss.x_W + rotation(ss) * link.point_S));
    if (std::abs(height - link.gap) <= 0.5 * settings.envelope_m) {
      sm.x_W += (link.gap - height) * c.n_W;
    }
  }
  HeldModes modes;
  Problem p;
  std::vector<HeldContact> before;  // the contacts before the modes are chosen
  // What made this plan: the event the motion reached (the loop sets it), or nothing (a
  // collision, a hold): a stale planned event must not count.
  IslandEvent cause = trigger;
  trigger = IslandEvent{};
  for (int attempt = 0;; ++attempt) {
    bool forced = false;
    p = build_problem(*this, world, anchor_, t);
    if (!p.lost.empty()) {
      // A vertex or an edge that slid off the support's face keeps touching its boundary: the
      // contact goes on as a point contact with the boundary edge nearest to it; a face that
      // left it, lets go.
      std::vector<int> drop;
      for (int lost : p.lost) {
        HeldLink& link = links[static_cast<std::size_t>(lost)];
        if (!to_point_pair(link, state_of(link.mover), state_of(link.support))) {
          drop.push_back(lost);
        }
      }
      remove_links(drop);
      cause = IslandEvent{};  // (its link's index may have moved)
      continue;
    }
    if (links.empty()) return result;
    if (cause.link >= 0 && cause.link < static_cast<int>(p.contacts.size())) {
      // The contact whose slip (spin, rolling) stopped, and every other one slipping as fast to
      // within 1e-3: the motion's event finds one stop, at the integration's slip floor (1e3
      // times its resolution of speeds, Island::integrate), and a mirror image of it stops at
      // that instant too. (Two balls rolling out under a ball on a floor reached it 2.2e-6 apart
      // relative; judged by the still speed, one slid on alone for 4e-8 s, and the ball on the
      // two came out 1e-8 m asymmetric.)
      const std::vector<HeldContactMotion> now = held_velocities(p.bodies, p.contacts);
      auto measure = [&](std::size_t i) {
        const HeldContact& c = p.contacts[i];
        switch (cause.kind) {
          case IslandEvent::Kind::kSlipStop: return plane_coords(c, now[i].slip_W).norm();
          case IslandEvent::Kind::kSpinStop: return std::abs(now[i].dw_W.dot(c.n_W));
          case IslandEvent::Kind::kRollStop: return plane_coords(c, now[i].dw_W).norm();
          default: return kInfinity;
        }
      };
      const std::size_t ci = static_cast<std::size_t>(cause.link);
      const double stopped = measure(ci);
      for (std::size_t i = 0; i < p.contacts.size(); ++i) {
        HeldContact& c = p.contacts[i];
        if (i != ci && !(c.active && std::abs(measure(i) - stopped) <= 1e-3 * stopped)) continue;
        c.slip_stopped = cause.kind == IslandEvent::Kind::kSlipStop && (i == ci || !c.sticks);
        c.spin_stopped = cause.kind == IslandEvent::Kind::kSpinStop && (i == ci || !c.spin_sticks);
        c.roll_stopped = cause.kind == IslandEvent::Kind::kRollStop && (i == ci || !c.roll_sticks);
      }
      // And the stopped contact's other slip, spin or rolling, where the integrated motion had
      // already carried it below its slip floor: what the motion resolved of it is rest too, and
      // the contact's modes are chosen again from rest together (its friction and its torsion
      // share one pressure). (Left sliding, a hull's floor patch that could hold neither its
      // friction nor its torsion alone alternated between a spin stop and a slip stop every
      // 1e-7 s, 43,000 times in 2 ms, both below 1e-7 m/s: 50 hulls, seed 12. Stopping every
      // such component of the island, not only the contact's, whether it decelerated or not,
      // made others of those piles' motions much harder to integrate: seeds 17 and 22, 5 times
      // the CPU. The island's decelerating slips and rollings are stopped below, where the next
      // motion's floor is above them.)
      if (integrated_floor > 0.0 && p.contacts[ci].active) {
        HeldContact& c = p.contacts[ci];
        const Vec3& dw = now[ci].dw_W;
        if (slides(c, 0) && plane_coords(c, now[ci].slip_W).norm() <= integrated_floor) {
          c.slip_stopped = true;
        }
        if (slides(c, 1) && spin_speed(c, dw) <= integrated_floor) c.spin_stopped = true;
        if (slides(c, 2) && roll_speed(c, dw) <= integrated_floor) c.roll_stopped = true;
      }
    }
    // And the island's other slips, spins and rollings that decelerate so fast that they would
    // stop within the progress floor anyway (at a stop), and its decelerating slips and rollings
    // that already move no faster than the slip floor of the motion this plan starts (at any
    // plan: its speed scale may be above the last one's, a body of the island falling faster):
    // that motion could not resolve them, and their stop events, below the floor from the start,
    // would never fire (stop_imminent). Their modes are chosen from rest with the rest of the
    // island's. (Chosen sliding at 6.65e-7 m/s under a floor of 6.7e-7 m/s, the slip of a ball
    // on a ball wedged on three others sat at the floor for 1e-4 s, its friction turning between
    // its own direction and the vanishing slip's from stage to stage: 92 % of the integration's
    // steps were rejected, 16.1 s of CPU for 0.2 s of seven balls cut from a pile of 100; 6.1 s
    // now.)
    const bool stop = cause.kind == IslandEvent::Kind::kSlipStop ||
                      cause.kind == IslandEvent::Kind::kSpinStop ||
                      cause.kind == IslandEvent::Kind::kRollStop;
    stop_imminent(p.bodies, p.contacts, stop ? settings.toi_min_progress_s : 0.0,
                  motion_slip_floor(settings, world.gravity_W.norm(), size, anchor_));
    std::vector<int> separating;
    // What separates faster than a microcollision would rebound lets go; slower is held (the
    // hand-over rule of a collision, DESIGN.md §8.1).
    const double separation = microcollision_speed(settings, world.gravity_W.norm());
    // A face that lifts off on one side while an edge of it stays down, on a body that would tip
    // about that edge anyway (the centre of pressure the whole face would need lies beyond it),
    // keeps only that edge: a prism rolling down a slope lands on its next face turning about the
    // leading edge, and holding the whole face would take an impulse pulling the rising side down,
    // which a contact cannot give - it would stop the prism dead at every face. (On a face it can
    // stand on, the rocking is a landing's remainder, taken out by the projection below, as
    // before.)
    if (cause.kind != IslandEvent::Kind::kTip) {
      const std::vector<HeldContactMotion> now = held_velocities(p.bodies, p.contacts);
      std::optional<HeldSolution> statics;  // solved only for a face that has such an edge
      for (std::size_t i = 0; i < p.contacts.size(); ++i) {
        HeldContact& c = p.contacts[i];
        if (!c.active || c.patch != PatchKind::kPolygon || c.mover < 0) continue;
        const std::size_t n = c.polygon.size();
        std::vector<double> rise(n);
        double highest = -kInfinity;
        for (std::size_t k = 0; k < n; ++k) {
          const Vec3 r = c.polygon[k].x() * c.t1_W + c.polygon[k].y() * c.t2_W;
          rise[k] = (now[i].slip_W + now[i].dw_W.cross(r)).dot(c.n_W);
          highest = std::max(highest, rise[k]);
        }
        if (!(highest > still)) continue;
        // Of the edges that stay down (neither end rises), the body tips about the one the
        // centre of pressure the whole face would need lies beyond, farthest. (Not the edge that
        // sinks fastest: a prism landing one corner first has its other landing corner still
        // coming down, and its end edge, from that corner to the pivot's, sinks too.)
        int edge = -1;
        double beyond = 0.0;
        for (std::size_t k = 0; k < n; ++k) {
          if (std::max(rise[k], rise[(k + 1) % n]) > still) continue;
          if (!statics) {
            // That pressure at the velocities the projection below would leave (the rocking
            // taken out), not at those of now: at those the rotation about the landing edge is
            // in the problem, and a 128-gon rolling at 12.7 rad/s, near lift-off, found its
            // pressure inside the face, was held flat and stopped dead.
            std::vector<HeldBody> held = p.bodies;
            project_held_velocities(held, p.contacts, still, separation, nullptr);
            statics = solve_held(held, p.contacts);
          }
          if (statics->status != HeldStatus::kOk) break;
          const double margin = inside_edge(c.polygon, k, statics->forces[i].centre_of_pressure);
          if (margin < beyond) {
            beyond = margin;
            edge = static_cast<int>(k);
          }
        }
        if (edge < 0) continue;
        if (!forced) before = p.contacts;
        reduce_patch(c, edge);
        forced = true;
      }
    }
    result.projection_energy +=
        project_held_velocities(p.bodies, p.contacts, still, separation, &separating);
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      anchor_[k].v_W = p.bodies[k].v_W;
      anchor_[k].w_W = p.bodies[k].w_W;
    }
    if (!separating.empty()) {
      // Contacts that an impact sent apart let go; the rest are planned again without them.
      remove_links(separating);
      cause = IslandEvent{};
      continue;
    }
    if (cause.kind == IslandEvent::Kind::kTip && cause.link >= 0 &&
        cause.link < static_cast<int>(links.size())) {
      // The centre of pressure reached the edge of the support's face: the mover slides off it
      // and tips over that edge.
      HeldLink& link = links[static_cast<std::size_t>(cause.link)];
      const int k_m = index_of(link.mover), k_s = index_of(link.support);
      const BodyState sm =
          k_m >= 0 ? anchor_[static_cast<std::size_t>(k_m)] : world.bodies[link.mover.index].state;
      const BodyState ss = k_s >= 0 ? anchor_[static_cast<std::size_t>(k_s)]
                                    : world.bodies[link.support.index].state;
      const std::size_t li = static_cast<std::size_t>(cause.link);
      const HeldContact& c = p.contacts[li];
      const Vec2 cop = solve_held(p.bodies, p.contacts).forces[li].centre_of_pressure;
      const int edge = support_edge_under(link, ss, {c.c_W + cop.x() * c.t1_W + cop.y() * c.t2_W});
      cause = IslandEvent{};
      if (edge >= 0) {
        if (!swap_roles(link, edge, sm, ss) && !to_point_pair(link, sm, ss)) {
          remove_links({static_cast<int>(li)});
        }
        continue;
      }
      if (!c.active || c.patch == PatchKind::kPoint) {
        // A point has nothing to tip about: its patch vanished along the motion (a point pair's
        // point left its edge), and re-planned as it is it vanishes again at once. It lets go;
        // its pair's check finds what touches there now. (A ball held against a bowling pin's
        // edge re-planned one ulp at a time, tens of thousands of times.)
        remove_links({static_cast<int>(li)});
        continue;
      }
      // Else it reached the boundary of the mover's own feature: the body tips about the edge
      // (or end) nearest to the centre of pressure. (At the event the pressure is on that
      // boundary to the integration's accuracy: the choice of modes alone may not see it cross.)
      before = p.contacts;
      HeldContact& t = p.contacts[li];
      if (t.patch == PatchKind::kPolygon) {
        int nearest = 0;
        double margin = kInfinity;
        for (std::size_t e = 0; e < t.polygon.size(); ++e) {
          const double m = inside_edge(t.polygon, e, cop);
          if (m < margin) {
            margin = m;
            nearest = static_cast<int>(e);
          }
        }
        reduce_patch(t, nearest);
      } else if (t.patch == PatchKind::kSegment) {
        const double along = t.segment_W.dot(t.t1_W) * cop.x() + t.segment_W.dot(t.t2_W) * cop.y();
        reduce_patch(t, along - t.segment_lo < t.segment_hi - along ? 0 : 1);
      }
      forced = true;
    }
    if (!forced) before = p.contacts;
    modes = choose_held_modes(p.bodies, p.contacts, still, 1e-9);
    if (modes.solution.status != HeldStatus::kOk) {
      let_all_go();
      return result;
    }
    // Patches that were reduced (the body tips): about its own edge or vertex, the link keeps
    // that feature; about the edge of the support's face, the roles turn round.
    bool again = false;
    std::vector<int> drop;
    for (std::size_t i = 0; i < links.size(); ++i) {
      HeldContact& c = p.contacts[i];
      if (!c.active) continue;
      if (c.patch == before[i].patch) continue;
      HeldLink& link = links[i];
      const int k_m = index_of(link.mover), k_s = index_of(link.support);
      const BodyState sm =
          k_m >= 0 ? anchor_[static_cast<std::size_t>(k_m)] : world.bodies[link.mover.index].state;
      const BodyState ss = k_s >= 0 ? anchor_[static_cast<std::size_t>(k_s)]
                                    : world.bodies[link.support.index].state;
      const std::vector<Vec3> points = contact_points_W(c);
      const int edge = support_edge_under(link, ss, points);
      if (edge >= 0) {
        if (!swap_roles(link, edge, sm, ss)) drop.push_back(static_cast<int>(i));
        again = true;
      } else if (link.sphere_radius > 0.0 && !link.mover_feature_M.empty()) {
        // A rounded segment tipping about an end of its line (a disk stood on its side, a
        // cylinder half off a face): its contact leaves the side for that end's rim (a capsule:
        // its end cap), held as a curved point of it; without the piece, it lets go.
        if (link.side_shape == nullptr) {
          drop.push_back(static_cast<int>(i));
        } else {
          const Vec3 end_W = contact_points_W(c).front();
          const Mat3 R = rotation(sm);
          const Vec3 a = sm.x_W + R * link.mover_feature_M[0];
          const Vec3 b = sm.x_W + R * link.mover_feature_M[1];
          // mover_feature_M runs from the piece's -z end to its +z end.
          link.curved_end = (end_W - a).squaredNorm() <= (end_W - b).squaredNorm() ? -1.0 : 1.0;
          link.curved_shape = link.side_shape;
          link.sphere_radius = 0.0;
          link.mover_feature_M.clear();
        }
        again = true;
      } else if (link.sphere_radius == 0.0) {
        // The reduced patch's points lie at the patch's mean height; the feature kept is the
        // mover's own surface under them (a tilted edge's real end, not a point beside it).
        const Mat3 R = rotation(sm);
        std::vector<Vec3> feature;
        for (const Vec3& q : link.mover_feature_M) feature.push_back(sm.x_W + R * q);
        std::vector<Vec3> kept;
        for (const Vec3& q : points)
          kept.push_back(R.transpose() * (on_feature(feature, c.n_W, q) - sm.x_W));
        link.mover_feature_M = kept;
      }
    }
    if (!drop.empty()) remove_links(drop);
    if (again && attempt < 4) continue;
    break;
  }
  // Modes back into the links; contacts that let go leave the island.
  std::vector<int> released;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const HeldContact& c = p.contacts[i];
    HeldLink& link = links[i];
    if (!c.active) {
      released.push_back(static_cast<int>(i));
      continue;
    }
    link.sticks = c.sticks;
    link.slip_dir = c.slip_dir;
    link.spin_sticks = c.spin_sticks;
    link.spin_sign = c.spin_sign;
    link.roll_sticks = c.roll_sticks;
    link.roll_dir = c.roll_dir;
  }
  remove_links(released);
  event = IslandEvent{};
  if (links.empty()) {
    for (std::size_t k = 0; k < bodies.size(); ++k)
      world.bodies[bodies[k].index].state = anchor_[k];
    return result;
  }
  // Rebuild for the contacts that remain (their modes are now the links').
  p = build_problem(*this, world, anchor_, t);
  // Its modes were chosen from a solve of this problem; rounding can still leave this one
  // inconsistent, and classify reads every contact's motion from it.
  const HeldSolution sol = solve_held(p.bodies, p.contacts);
  if (sol.status == HeldStatus::kOk) {
    classify(world, geometry, p.contacts, sol);
  } else {
    let_all_go();
  }
  for (std::size_t k = 0; k < bodies.size(); ++k) world.bodies[bodies[k].index].state = anchor_[k];
  return result;
}

}  // namespace palpable

namespace palpable {

namespace {

bool fixed_side(const World& world, int island_index, BodyId id) {
  return island_index < 0 && world.bodies[id.index].motion == MotionKind::kFixed;
}

// Does a known side move uniformly (translate at constant velocity, no turning)?
bool uniform_known(const KnownMotion& k) {
  return k.w_W.squaredNorm() == 0.0 && k.a_W.squaredNorm() == 0.0 && k.alpha_W.squaredNorm() == 0.0;
}

}  // namespace

void Island::classify(const World& world, const std::vector<const ShapeGeometry*>& geometry,
                      const std::vector<HeldContact>& contacts, const HeldSolution& sol) {
  const Settings& settings = world.settings;
  const double still = settings.still_speed_mps;
  const double a_floor = 1e-9 * (world.gravity_W.norm() + 1.0);
  const std::size_t nb = bodies.size();
  std::vector<double> reach(nb);
  std::vector<bool> sphere(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    const Body& b = world.bodies[bodies[k].index];
    reach[k] = geometry[bodies[k].index]->reach();
    sphere[k] = is_sphere(b) && spherical_inertia(b, settings);
  }
  a_.assign(nb, Vec3::Zero());
  alpha_.assign(nb, Vec3::Zero());
  bounds_.assign(nb, MotionBound{});
  turning_.assign(nb, false);
  t_end = kInfinity;
  event = IslandEvent{};

  // At rest: still bodies on fixed supports, not accelerated (equilibrium holds).
  bool rest = true;
  for (std::size_t i = 0; i < links.size() && rest; ++i) {
    const HeldContact& c = contacts[i];
    rest = (c.mover >= 0 || fixed_side(world, c.mover, links[i].mover)) &&
           (c.support >= 0 || fixed_side(world, c.support, links[i].support));
  }
  for (std::size_t k = 0; k < nb && rest; ++k) {
    const BodyState& s = anchor_[k];
    rest = s.v_W.norm() <= still && s.w_W.norm() * reach[k] <= still &&
           sol.a_W[k].norm() <= a_floor && sol.alpha_W[k].norm() * reach[k] <= a_floor;
  }
  if (rest) {
    motion = Motion::kRest;
    for (BodyState& s : anchor_) {
      s.v_W.setZero();
      s.w_W.setZero();
    }
    return;
  }

  // A sphere rolling on a turntable.
  if (nb == 1 && links.size() == 1 && sphere[0] && links[0].sphere_radius > 0.0 &&
      links[0].support_face_S.empty()) {
    const HeldContact& c = contacts[0];
    const Body& support = world.bodies[links[0].support.index];
    const Body& ball = world.bodies[bodies[0].index];
    if (c.mover == 0 && c.support < 0 && support.motion == MotionKind::kKinematic &&
        support.kinematic.velocity_W.squaredNorm() == 0.0 && c.sticks &&
        c.rolling_resistance == 0.0 && c.spinning_resistance == 0.0) {
      const Vec3& W = support.kinematic.angular_velocity_W;
      const double spin = W.dot(c.n_W);
      const double R = links[0].sphere_radius;
      const double k = ball.mass.principal_moments.x() / (ball.mass.mass * R * R);
      if (W.cross(c.n_W).norm() <= 1e-12 * W.norm() && spin != 0.0) {
        motion = Motion::kTurntable;
        turn_axis_ = c.n_W;
        turn_w_ = W;
        turn_point_ = support.kinematic.point_W;
        turn_rate_ = k / (1.0 + k) * spin;
        radius_ = R;
        const BodyState& s = anchor_[0];
        turn_centre_ = s.x_W + turn_axis_.cross(s.v_W) / turn_rate_;
        bounds_[0].a_slack = std::abs(turn_rate_) * s.v_W.norm();
        bounds_[0].alpha_slack = kInfinity;  // its w turns with the ball: not bounded here
        return;
      }
    }
  }

  // Bodies that roll about a fixed axis of their own: a cylinder or capsule held only along
  // rounded segments of its side (all along one axis d), its centre of mass on that axis, its
  // inertia symmetric about it, turning and accelerated about d alone (to what the model
  // resolves). Its contact lines then stay put relative to its centre, its world inertia stays
  // constant and the gyroscopic term vanishes: like a sphere's, its accelerations are constant
  // while the modes hold, and its orientation is the rotation by w0 t + alpha t^2 / 2 about d.
  std::vector<bool> roller(nb, false);
  std::vector<Vec3> roll_axis(nb, Vec3::Zero());
  for (std::size_t k = 0; k < nb; ++k) {
    if (sphere[k]) continue;
    bool ok = true, found = false;
    Vec3 d = Vec3::Zero();
    for (std::size_t i = 0; i < links.size() && ok; ++i) {
      const HeldLink& l = links[i];
      if (l.support == bodies[k]) ok = false;
      if (!ok || l.mover != bodies[k]) continue;
      if (!(l.sphere_radius > 0.0 && l.mover_feature_M.size() == 2) || !contacts[i].active) {
        ok = false;
        continue;
      }
      const Vec3 e =
          (rotation(anchor_[k]) * (l.mover_feature_M[1] - l.mover_feature_M[0])).normalized();
      const Vec3& r_q = contacts[i].core_offset_W;
      ok = (!found || e.cross(d).norm() <= 1e-12) &&
           (r_q - e * e.dot(r_q)).norm() <= 1e-12 * reach[k];
      d = e;
      found = true;
    }
    if (!ok || !found) continue;
    const Body& b = world.bodies[bodies[k].index];
    const Mat3 I = inertia_W(b, anchor_[k].q_WM);
    const double i_d = d.dot(I * d);
    const double i_p = 0.5 * (I.trace() - i_d);
    const Mat3 dd = d * d.transpose();
    const Mat3 symmetric = i_p * (Mat3::Identity() - dd) + i_d * dd;
    const Vec3 w = anchor_[k].w_W, alpha = sol.alpha_W[k];
    roller[k] = (I - symmetric).norm() <= 1e-12 * I.norm() &&
                (w - d * d.dot(w)).norm() * reach[k] <= still &&
                (alpha - d * d.dot(alpha)).norm() * reach[k] <= a_floor;
    roll_axis[k] = d;
  }

  // Uniformly accelerated: no body turns but spheres and rollers, no plane turns, every slip
  // keeps its direction.
  bool uniform = true;
  for (std::size_t k = 0; k < nb && uniform; ++k) {
    if (sphere[k] || roller[k]) continue;
    uniform =
        anchor_[k].w_W.norm() * reach[k] <= still && sol.alpha_W[k].norm() * reach[k] <= a_floor;
  }
  for (std::size_t i = 0; i < contacts.size() && uniform; ++i) {
    const HeldContact& c = contacts[i];
    if (c.has_n_dot) {
      // A normal that follows two features' closest points (a ball on a ball) turns now, or
      // will as soon as their relative acceleration across it moves them. (Judged by its rate
      // alone, a ball at rest on a ball, starting to roll off it along its rolling acceleration,
      // was planned as accelerating uniformly along the tangent: it left the lower ball's surface
      // and no event ended the motion.)
      const Vec3 a_m =
          c.mover >= 0 ? sol.a_W[static_cast<std::size_t>(c.mover)] : c.mover_known.a_W;
      const Vec3 a_s =
          c.support >= 0 ? sol.a_W[static_cast<std::size_t>(c.support)] : c.support_known.a_W;
      const Vec3 across = (a_m - a_s) - c.n_W * c.n_W.dot(a_m - a_s);
      if (c.n_dot_W.squaredNorm() != 0.0 || across.norm() > a_floor) uniform = false;
    }
    if (c.support < 0 && !uniform_known(c.support_known)) uniform = false;
    if (c.mover < 0 && !uniform_known(c.mover_known)) uniform = false;
    const HeldContactMotion& m = sol.motion[i];
    auto parallel = [](const Vec2& rate, const Vec2& dir) {
      return std::abs(cross2(rate, dir)) <= 1e-12 * rate.norm();
    };
    if (!c.sticks && c.friction > 0.0) {
      uniform = uniform && parallel(plane_coords(c, m.slip_rate_W), c.slip_dir);
    }
    if (!c.roll_sticks && c.rolling_resistance > 0.0) {
      uniform = uniform && parallel(plane_coords(c, m.roll_rate_W), c.roll_dir);
    }
  }
  // A contact at a point or along a segment cannot move its centre of pressure across itself:
  // where the side it alone holds slides against it (a box sliding over a table's edge, held on
  // that edge once its pressure reached it), the moments change along the motion, and the side
  // turns. (Taken as uniform, such a box slid on over the void without turning, held up by the
  // edge, and fell only where its slip stopped.)
  LinksByBody touching;  // each body's links, made where first needed
  if (uniform) {
    for (std::size_t k = 0; k < nb; ++k) a_[k] = sol.a_W[k];
    for (std::size_t i = 0; i < contacts.size() && uniform; ++i) {
      const HeldContact& c = contacts[i];
      if (!c.active || c.patch == PatchKind::kPolygon) continue;
      if (touching.empty()) touching = links_by_body();
      const int km = index_of(links[i].mover);
      const Vec3 v_m = km >= 0 ? anchor_[static_cast<std::size_t>(km)].v_W : c.mover_known.v_W;
      const Vec3 a_m = km >= 0 ? a_[static_cast<std::size_t>(km)] : c.mover_known.a_W;
      const PressureMotion moves = pressure_motion(world, contacts, sol, i, touching);
      auto across = [&](Vec3 d) {
        d -= c.n_W * c.n_W.dot(d);
        if (c.patch == PatchKind::kSegment) d -= c.segment_W * c.segment_W.dot(d);
        return d.norm();
      };
      uniform = across(moves.v_W - v_m) <= still && across(moves.a_W - a_m) <= a_floor;
    }
  }
  if (uniform) {
    motion = Motion::kUniform;
    for (std::size_t k = 0; k < nb; ++k) {
      a_[k] = sol.a_W[k];
      if (sphere[k]) {
        alpha_[k] = sol.alpha_W[k];
        turning_[k] = anchor_[k].w_W.cross(alpha_[k]).norm() >
                      1e-15 * anchor_[k].w_W.norm() * alpha_[k].norm();
      } else if (roller[k]) {
        // About its axis alone (what lies off it is below what the model resolves, snapped).
        const Vec3& d = roll_axis[k];
        alpha_[k] = d * d.dot(sol.alpha_W[k]);
        anchor_[k].w_W = d * d.dot(anchor_[k].w_W);
      } else {
        anchor_[k].w_W.setZero();  // below what the model resolves (snapped, see above)
      }
    }
    find_uniform_event(world, contacts, sol, touching);
    for (std::size_t k = 0; k < nb; ++k) {
      bounds_[k].a_W = a_[k];
      bounds_[k].alpha_W = alpha_[k];
      const double span = std::isfinite(t_end) ? t_end - t0 : kInfinity;
      bounds_[k].w_bound = alpha_[k].squaredNorm() == 0.0
                               ? anchor_[k].w_W.norm()
                               : anchor_[k].w_W.norm() + alpha_[k].norm() * span;
    }
    return;
  }
  motion = Motion::kIntegrated;
  integrate(world, geometry);
}

void Island::extend(const World& world, const std::vector<const ShapeGeometry*>& geometry,
                    double t) {
  t0 = t;
  steps_.clear();
  integration = IntegrationCount{};
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    anchor_[k] = world.bodies[bodies[k].index].state;
    anchor_[k].t = t;
  }
  event = IslandEvent{};
  integrate(world, geometry, /*extending=*/true);
}

Island::LinksByBody Island::links_by_body() const {
  LinksByBody out(bodies.size());
  for (std::size_t j = 0; j < links.size(); ++j) {
    const int km = index_of(links[j].mover), ks = index_of(links[j].support);
    if (km >= 0) out[static_cast<std::size_t>(km)].emplace_back(static_cast<int>(j), ks);
    if (ks >= 0) out[static_cast<std::size_t>(ks)].emplace_back(static_cast<int>(j), km);
  }
  return out;
}

Island::PressureMotion Island::pressure_motion(const World& world,
                                               const std::vector<HeldContact>& contacts,
                                               const HeldSolution& sol, std::size_t i,
                                               const LinksByBody& touching) const {
  const HeldLink& link = links[i];
  const int km = index_of(link.mover), ks = index_of(link.support);
  auto v_of = [&](int k) { return anchor_[static_cast<std::size_t>(k)].v_W; };
  auto a_of = [&](int k) { return a_[static_cast<std::size_t>(k)]; };
  const PressureMotion on_mover{km >= 0 ? v_of(km) : contacts[i].mover_known.v_W,
                                km >= 0 ? a_of(km) : contacts[i].mover_known.a_W, true};
  // The bodies joined to `from` by the island's other active links, in `side`; false where they
  // reach a body outside the island (a fixed or kinematic one) or `other`.
  auto apart = [&](int from, int other, std::vector<int>& side) {
    std::vector<char> seen(bodies.size(), 0);
    side = {from};
    seen[static_cast<std::size_t>(from)] = 1;
    for (std::size_t head = 0; head < side.size(); ++head) {
      for (const auto& [j, next] : touching[static_cast<std::size_t>(side[head])]) {
        if (j == static_cast<int>(i) || !contacts[static_cast<std::size_t>(j)].active) continue;
        if (next < 0 || next == other) return false;
        if (!seen[static_cast<std::size_t>(next)]) {
          seen[static_cast<std::size_t>(next)] = 1;
          side.push_back(next);
        }
      }
    }
    return true;
  };
  // The pressure of a side that this contact alone holds: its bodies' moments about the contact
  // balance the contact's force, so the force's line of action - the centre of pressure, where
  // it meets the plane - moves with the side (with its one body, where they move as one).
  auto riding = [&](const std::vector<int>& side, int root, double sign) -> PressureMotion {
    const bool one = std::all_of(side.begin(), side.end(), [&](int k) {
      return v_of(k) == v_of(root) && a_of(k) == a_of(root);
    });
    if (one) return {v_of(root), a_of(root), root == km};
    // Bodies of the side moving against each other: (p - O) x F = sum_k (x_k - O) x m_k (a_k - g)
    // + I_k alpha_k (constant), so p's rates in the plane follow from those of the right side.
    const HeldContact& c = contacts[i];
    const HeldContactForces& f = sol.forces[i];
    const Vec3 F = sign * (f.normal * c.n_W + f.friction.x() * c.t1_W + f.friction.y() * c.t2_W);
    const double N = F.dot(c.n_W);
    if (!(std::abs(N) > 0.0)) return on_mover;
    Vec3 T1 = Vec3::Zero(), T2 = Vec3::Zero();
    for (const int k : side) {
      const Vec3 load = world.bodies[bodies[static_cast<std::size_t>(k)].index].mass.mass *
                        (a_of(k) - world.gravity_W);
      T1 += v_of(k).cross(load);
      T2 += a_of(k).cross(load);
    }
    auto in_plane = [&](const Vec3& T) {
      return Vec3((-T.dot(c.t2_W) / N) * c.t1_W + (T.dot(c.t1_W) / N) * c.t2_W);
    };
    return {in_plane(T1), in_plane(T2), false};
  };
  std::vector<int> side;
  if (km >= 0 && apart(km, ks, side)) return riding(side, km, 1.0);
  if (ks >= 0 && apart(ks, km, side)) return riding(side, ks, -1.0);
  return on_mover;  // held on both sides: taken as riding on the mover
}

void Island::find_uniform_event(const World& world, const std::vector<HeldContact>& contacts,
                                const HeldSolution& sol, LinksByBody& touching) {
  auto consider = [&](double dt, IslandEvent::Kind kind, std::size_t link) {
    if (dt < t_end - t0) {
      t_end = t0 + dt;
      event = IslandEvent{kind, static_cast<int>(link)};
    }
  };
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const HeldContact& c = contacts[i];
    const HeldContactMotion& m = sol.motion[i];
    // A slip (spin, rolling) that decreases at a constant rate stops when it reaches zero.
    if (!c.sticks && c.friction > 0.0) {
      const double s = plane_coords(c, m.slip_W).dot(c.slip_dir);
      const double rate = plane_coords(c, m.slip_rate_W).dot(c.slip_dir);
      if (rate < 0.0) consider(s / -rate, IslandEvent::Kind::kSlipStop, i);
    }
    if (!c.spin_sticks && c.torsion_arm > 0.0) {
      const double s = m.dw_W.dot(c.n_W) * c.spin_sign;
      const double rate = m.dalpha_W.dot(c.n_W) * c.spin_sign;
      if (rate < 0.0) consider(s / -rate, IslandEvent::Kind::kSpinStop, i);
    }
    if (!c.roll_sticks && c.rolling_resistance > 0.0) {
      const double s = plane_coords(c, m.dw_W).dot(c.roll_dir);
      const double rate = plane_coords(c, m.roll_rate_W).dot(c.roll_dir);
      if (rate < 0.0) consider(s / -rate, IslandEvent::Kind::kRollStop, i);
    }
    // The centre of pressure reaching an edge of the support's face, or of the mover's.
    const HeldLink& link = links[i];
    if (link.support_face_S.size() < 3) continue;
    const int km = index_of(link.mover), ks = index_of(link.support);
    const Vec3 v_m = km >= 0 ? anchor_[static_cast<std::size_t>(km)].v_W : c.mover_known.v_W;
    const Vec3 v_s = ks >= 0 ? anchor_[static_cast<std::size_t>(ks)].v_W : c.support_known.v_W;
    const Vec3 a_m = km >= 0 ? a_[static_cast<std::size_t>(km)] : Vec3::Zero();
    const Vec3 a_s = ks >= 0 ? a_[static_cast<std::size_t>(ks)] : Vec3::Zero();
    const BodyState& ss =
        ks >= 0 ? anchor_[static_cast<std::size_t>(ks)] : world.bodies[link.support.index].state;
    const Vec2& cop = sol.forces[i].centre_of_pressure;
    const Vec3 p = c.c_W + cop.x() * c.t1_W + cop.y() * c.t2_W;
    if (touching.empty()) touching = links_by_body();
    const PressureMotion moves = pressure_motion(world, contacts, sol, i, touching);
    auto watch = [&](const std::vector<Vec3>& face_B, const BodyState& s, const Vec3& v_edge,
                     const Vec3& a_edge) {
      const Mat3 R = rotation(s);
      const std::size_t n = face_B.size();
      Vec3 centre = Vec3::Zero();
      for (const Vec3& q : face_B) centre += s.x_W + R * q;
      centre /= static_cast<double>(n);
      for (std::size_t e = 0; e < n; ++e) {
        const Vec3 a = s.x_W + R * face_B[e];
        const Vec3 b = s.x_W + R * face_B[(e + 1) % n];
        // Inward normal of the edge in the plane.
        Vec3 inward = c.n_W.cross(b - a).normalized();
        if (inward.dot(centre - a) < 0.0) inward = -inward;
        const double f0 = inward.dot(p - a);
        const double f1 = inward.dot(moves.v_W - v_edge);
        const double f2 = inward.dot(moves.a_W - a_edge);
        const double dt = first_negative(f0, f1, f2);
        if (std::isfinite(dt)) consider(dt, IslandEvent::Kind::kTip, i);
      }
    };
    watch(link.support_face_S, ss, v_s, a_s);
    // Where the pressure does not ride on the mover (it rides on the support: a box sliding on a
    // longer block that holds it from below), it can reach an edge of the mover's own face.
    if (!moves.on_mover && km >= 0 && link.mover_feature_M.size() >= 3) {
      watch(link.mover_feature_M, anchor_[static_cast<std::size_t>(km)], v_m, a_m);
    }
  }
}

}  // namespace palpable

namespace palpable {

namespace {

// One event function of the integrated motion: >= 0 while the mode holds.
struct EventValue {
  IslandEvent::Kind kind;
  int link;
  double value;
  double tolerance;  // below -tolerance it has happened
};

}  // namespace

void Island::integrate(const World& world, const std::vector<const ShapeGeometry*>& geometry,
                       bool extending) {
  const Settings& settings = world.settings;
  const double rtol = settings.integration_tolerance;
  const double atol = rtol;
  double weight = 0.0;
  for (BodyId id : bodies) weight += world.bodies[id.index].mass.mass * world.gravity_W.norm();
  if (!(weight > 0.0)) weight = 1.0;
  const double size = island_size(bodies, geometry);
  // Below this relative speed a slip (spin, rolling) counts as stopped along an integrated
  // motion: the integration resolves speeds to its tolerance times the motion's speed scale, and
  // a slip smaller than that only chatters in direction from step to step.
  // (Those of the plan: a motion gone on at a chunk's end keeps them, and its count of rejected
  // steps.)
  if (!extending) {
    motion_rejected_ = 0;
    slip_floor_ = motion_slip_floor(settings, world.gravity_W.norm(), size, anchor_, &speed_scale_);
  }
  const double speed_scale = speed_scale_;
  const double slip_floor = slip_floor_;
  bool failed = false;
  // Each contact's slip and relative angular velocity at the start of the step (world): a
  // sliding contact whose slip turns against it within the step has passed through zero.
  std::vector<Vec3> slip_before, dw_before;
  // The contact problem at a state and its solution, kept for the next call: the event
  // functions at the end of a step are asked at the state of its last stage (first same as
  // last), solved already. `start` counts the changes of slip_before that change the problem.
  struct Solved {
    double t = kInfinity;
    dopri5::State y;
    std::size_t start = 0;
    Problem p;
    HeldSolution s;
  } solved;
  std::size_t start = 0;
  auto solve_at = [&](double t, const dopri5::State& y) -> const Solved& {
    if (solved.t == t && solved.start == start && solved.y.size() == y.size() &&
        (solved.y.array() == y.array()).all()) {
      return solved;
    }
    solved.t = t;
    solved.y = y;
    solved.start = start;
    solved.p = build_problem(*this, world, unpack(y, t), t, /*follow=*/true, slip_floor,
                             &slip_before, &dw_before);
    solved.s = solve_held(solved.p.bodies, solved.p.contacts);
    return solved;
  };
  auto rhs = [&](double t, const dopri5::State& y) {
    const HeldSolution& s = solve_at(t, y).s;
    if (s.status != HeldStatus::kOk) failed = true;
    dopri5::State dy(y.size());
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const Eigen::Index o = static_cast<Eigen::Index>(kPerBody * k);
      const Quat q(y(o + 3), y(o + 4), y(o + 5), y(o + 6));
      const Vec3 w = y.segment<3>(o + 10);
      const Quat dq = Quat(0.0, w.x(), w.y(), w.z()) * q;  // (1/2) [0, w] q, halved below
      dy.segment<3>(o) = y.segment<3>(o + 7);
      dy(o + 3) = 0.5 * dq.w();
      dy.segment<3>(o + 4) = 0.5 * dq.vec();
      dy.segment<3>(o + 7) = s.a_W[k];
      dy.segment<3>(o + 10) = s.alpha_W[k];
    }
    return dy;
  };
  // The event functions at a state.
  // What each link's landing event watches (see below), chosen afresh at each step's start:
  // the level its mover's lowest other vertex (a curved shape's rise) must stay above (-inf:
  // not chosen yet), and the support's vertices and pairs of edges, each with its own.
  struct LandingWatch {
    double threshold = -kInfinity;
    std::vector<SupportWatch> support;
    std::vector<EdgeWatch> edges;
  };
  std::vector<LandingWatch> landing(links.size());
  // A fixed block of event functions per link (their kinds follow the link's modes, which do not
  // change within a motion), so that the values at two states line up entry by entry.
  std::vector<bool> held_vertex;  // the mover's vertices in the link's held feature (scratch)
  auto events = [&](double t, const dopri5::State& y) {
    std::vector<EventValue> out;
    const Solved& solution = solve_at(t, y);
    const Problem& p = solution.p;
    const HeldSolution& s = solution.s;
    // Where the contact problem broke down without forces (not finite, at a state between a
    // step's stages as an event is located on its dense output), no event is read from it: the
    // step is not taken and the motion ends where it last held. (Read, its empty forces were
    // indexed: a pile of 100 hulls crashed.)
    const bool solved = s.forces.size() == links.size() && s.motion.size() == links.size();
    if (!solved) failed = true;
    const std::vector<BodyState> states = unpack(y, t);
    const double still_speed = slip_floor;
    const double ftol = 1e-9 * weight;
    // A sticking friction's event fires where the plan's choice of modes must see it slide:
    // beyond twice that choice's tolerance (worst_violation: 1e-9 of the largest normal force).
    // (At 1e-9 of the island's weight only, Euler's disk, sticking with the friction it needed
    // 3e-9 beyond its cone - below the choice's tolerance - was planned sticking again and again
    // at one instant, until its contact let go and was struck four times there, a
    // microcollision gaining 9.1e-5 J.)
    double largest_normal = 0.0;
    for (const HeldContactForces& f : s.forces) {
      largest_normal = std::max(largest_normal, std::abs(f.normal));
    }
    // So too a sticking torsion's and rolling resistance's: the choice measures their excess in
    // newtons over the torsion arm and the resistance, their events in newton metres (the floor:
    // the island's weight over its size). One rule: past the floor, and past twice the choice's
    // tolerance times the arm (1 for friction).
    auto start_tolerance = [&](double floor_length, double arm) {
      return std::max(ftol * floor_length, 2e-9 * largest_normal * arm);
    };
    for (std::size_t i = 0; i < links.size(); ++i) {
      const HeldContact& c = p.contacts[i];
      const HeldLink& link = links[i];
      const int li = static_cast<int>(i);
      const std::size_t block = out.size();
      out.push_back({IslandEvent::Kind::kLiftOff, li, kInfinity, ftol});
      out.push_back({IslandEvent::Kind::kTip, li, kInfinity, 1e-12 * size});
      out.push_back({c.sticks ? IslandEvent::Kind::kSlipStart : IslandEvent::Kind::kSlipStop, li,
                     kInfinity, c.sticks ? start_tolerance(1.0, 1.0) : 0.0});
      out.push_back({IslandEvent::Kind::kSlipStop, li, kInfinity, 0.0});
      out.push_back({c.spin_sticks ? IslandEvent::Kind::kSlipStart : IslandEvent::Kind::kSpinStop,
                     li, kInfinity, c.spin_sticks ? start_tolerance(size, c.torsion_arm) : 0.0});
      out.push_back({IslandEvent::Kind::kSpinStop, li, kInfinity, 0.0});
      out.push_back({c.roll_sticks ? IslandEvent::Kind::kSlipStart : IslandEvent::Kind::kRollStop,
                     li, kInfinity,
                     c.roll_sticks ? start_tolerance(size, c.rolling_resistance) : 0.0});
      out.push_back({IslandEvent::Kind::kRollStop, li, kInfinity, 0.0});
      out.push_back({IslandEvent::Kind::kLanding, li, kInfinity, 1e-12 * size});
      EventValue* e = &out[block];
      if (!solved) continue;
      if (!c.active) {
        e[1].value = -1.0;  // the patch vanished: the mover left the support's face
        continue;
      }
      const HeldContactForces& f = s.forces[i];
      const HeldContactMotion& m = s.motion[i];
      const double N = f.normal;
      e[0].value = N;
      // The centre of pressure within the patch (lengths).
      const Vec2& cop = f.centre_of_pressure;
      if (c.patch == PatchKind::kPolygon) {
        double margin = kInfinity;
        for (std::size_t k = 0; k < c.polygon.size(); ++k) {
          margin = std::min(margin, inside_edge(c.polygon, k, cop));
        }
        e[1].value = margin;
      } else if (c.patch == PatchKind::kSegment) {
        const double along = c.segment_W.dot(c.t1_W) * cop.x() + c.segment_W.dot(c.t2_W) * cop.y();
        e[1].value = std::min(along - c.segment_lo, c.segment_hi - along);
      } else if (link.point_pair) {
        e[1].value = c.feature_margin;  // the sphere's centre leaving the feature's region
      }
      // Friction: sticking within its cone; sliding until the slip falls to the still speed or
      // turns against its direction at the step's start (it passed through zero within the
      // step: a slip that turns as it shrinks spirals into zero in finite time, DESIGN.md §4).
      const Vec2 slip = plane_coords(c, m.slip_W);
      if (c.friction > 0.0) {
        if (c.sticks) {
          e[2].value = c.friction * N - f.friction.norm();
        } else {
          e[2].value = slip.norm() - still_speed;
          if (i < slip_before.size()) {
            const Vec2 before = plane_coords(c, slip_before[i]);
            e[3].value = slip.dot(before.norm() > still_speed ? before.normalized() : c.slip_dir);
          }
        }
      }
      if (c.torsion_arm > 0.0) {
        const double spin = m.dw_W.dot(c.n_W);
        if (c.spin_sticks) {
          e[4].value = c.torsion_arm * N - std::abs(f.torsion);
        } else {
          e[4].value = std::abs(spin) * size - still_speed;
          if (i < dw_before.size()) {
            const double before = dw_before[i].dot(c.n_W);
            e[5].value = spin * (std::abs(before) * size <= still_speed ? c.spin_sign
                                 : before >= 0.0                        ? 1.0
                                                                        : -1.0);
          }
        }
      }
      if (c.patch == PatchKind::kPoint && c.rolling_resistance > 0.0) {
        const Vec2 roll = plane_coords(c, m.dw_W);
        if (c.roll_sticks) {
          e[6].value = c.rolling_resistance * N - f.rolling.norm();
        } else {
          e[6].value = roll.norm() * point_size(c) - still_speed;
          if (i < dw_before.size()) {
            const Vec2 before = plane_coords(c, dw_before[i]);
            e[7].value = roll.dot(before.norm() * point_size(c) > still_speed ? before.normalized()
                                                                              : c.roll_dir);
          }
        }
      }
      // Another part of the mover reaching the plane: another vertex of a polyhedron; for a
      // cylinder held on a rim, the rim's far side (it lands on its cap) or the other rim (on its
      // side); for a capsule held on one end, the other end. A sphere, an ellipsoid or a loaded
      // ball has nothing else that can touch.
      // The mover may be outside the island (a fixed body's edge held on a dynamic face, after
      // the roles turned round at its tipping): its other vertices land on that face all the
      // same. (Unwatched, a box tipping over a fixed box's ridge turned into the fixed box's
      // other face, 2 cm deep.)
      if (link.sphere_radius > 0.0 || link.point_pair) continue;
      const ShapeGeometry& g = *geometry[link.mover.index];
      if (!link.curved_shape && (g.pieces().size() != 1 || !g.pieces()[0].mesh)) continue;
      const BodyState sm = body_state_at(*this, world, states, link.mover, t);
      // Heights above the support's plane: another vertex lands when it comes down to half the
      // held feature's height (a vertex lower than the feature but rising, the other end of an
      // edge the body tips up from, has not landed; one at the feature's height must go down).
      const BodyState ss = body_state_at(*this, world, states, link.support, t);
      const Mat3 R_S = rotation(ss);
      const Vec3 plane = ss.x_W + R_S * link.point_S;
      if (link.curved_shape) {
        const Vec3 d = (rotation(sm) * link.piece_R_M).transpose() * -c.n_W;
        const double rise = curved_rise(*link.curved_shape, d, link.curved_end);
        if (!std::isfinite(rise)) continue;
        // It lands when it comes within the landing level of the touching point: the contact then
        // turns into the cap's face or the side's line. Within that level already at the step's
        // start (a side just tipped onto its rim), as soon as it goes down at all.
        if (landing[i].threshold == -kInfinity) {
          const double level = landing_level(c.n_W.dot(c.c_W - plane), settings.envelope_m);
          landing[i].threshold = rise <= level ? rise - 1e-12 * size : level;
        }
        e[8].value = rise - landing[i].threshold;
        continue;
      }
      double lowest = kInfinity;
      const double feature_lowest = held_feature_height(link, sm, ss);
      const ShapeGeometry::Piece& piece = g.pieces()[0];
      const Mat3 R = rotation(sm) * piece.R_M;
      const Vec3 origin = sm.x_W + rotation(sm) * piece.p_M;
      const double tol = 1e-9 * size;
      held_vertex.assign(static_cast<std::size_t>(piece.mesh->num_vertices()), false);
      for (int v = 0; v < piece.mesh->num_vertices(); ++v) {
        const Vec3 q_M = piece.p_M + piece.R_M * piece.mesh->vertex(v);
        for (const Vec3& f : link.mover_feature_M) {
          if ((f - q_M).norm() <= tol) held_vertex[v] = true;
        }
        if (held_vertex[v]) continue;
        const Vec3 q = origin + R * piece.mesh->vertex(v);
        lowest = std::min(lowest, c.n_W.dot(q - plane));
      }
      // The threshold is set at each step's start: half the feature's height (at least a
      // quarter envelope), or half the lowest other vertex's height if that is lower: a vertex
      // that halves its height within a step lands, whatever it did before (a body rocking on
      // an edge with the rest of its face just above the plane must not sink into it).
      LandingWatch& watch = landing[i];
      const double feature_level = std::max(feature_lowest, 0.5 * settings.envelope_m);
      // A vertex on the plane already (to its resolution, kPlaneResolution of the body's size:
      // a face held at a gap of zero, its body tipped onto one of its edges) lands as soon as
      // it goes down at all.
      auto threshold = [&](double height) {
        return height <= kPlaneResolution * size
                   ? height - 1e-12 * size
                   : 0.5 * std::max(0.0, std::min(feature_level, height));
      };
      const bool fresh = watch.threshold == -kInfinity;
      if (fresh) watch.threshold = threshold(lowest);
      e[8].value = lowest - watch.threshold;
      // And the support's vertices landing on the mover: a held link keeps the mover's feature
      // at its height above the plane, and the plane is the query's normal, tilted from the faces
      // where they are not parallel; the feature sliding over it, a face of the mover tilted from
      // the plane comes down onto the support's vertices at the tilt times the slip. (In a pile
      // of 50 hulls, seed 3, a hull's edge held on another's face, 5e-3 and 8e-3 rad off their
      // faces, slid 16 um into a vertex of that face, and the pair was found overlapping 594
      // times.) Watched: each vertex of the support whose nearest face of the mover (its largest
      // face value, a lower bound of its distance) is within the envelope and faces the support
      // within 0.1 rad but not parallel to the plane (a face held flat keeps its height), from
      // that face's plane, with the other vertices' thresholds.
      const ShapeGeometry& gs = *geometry[link.support.index];
      if (gs.pieces().size() != 1 || !gs.pieces()[0].mesh) continue;
      const ShapeGeometry::Piece& sp = gs.pieces()[0];
      const Mat3 R_SP = R_S * sp.R_M;
      const Vec3 s_origin = ss.x_W + R_S * sp.p_M;
      if (fresh) {
        watch.support = support_watch_candidates(piece, R, origin, sp, R_SP, s_origin, c.n_W,
                                                 settings.envelope_m);
        for (SupportWatch& w : watch.support) w.threshold = threshold(w.threshold);
      }
      for (const SupportWatch& w : watch.support) {
        const Vec3 q = vertex_in_mover(sp, R_SP, s_origin, R, origin, w.vertex);
        e[8].value = std::min(e[8].value, piece.mesh->face_eval(w.face, q) - w.threshold);
      }
      // And an edge of the mover crossing an edge of the support, neither body's vertex inside
      // the other: the mover's edge dips below the support's face just inside its rim, where
      // another vertex of the mover hangs beyond it (the held feature kept above the tilted
      // plane, the face's own plane is not watched). In a pile of 200 hulls, seed 1, p56 held on
      // a face of p47 by an edge crossed two of p47's edges at its rim, 60.6 um deep along an
      // edge-edge axis (a brute-force separating-axis test of their states), and the pair was
      // found overlapping 54,162 times. Watched: each pair of edges whose common normal is a
      // separating axis candidate (both normal cones), within the envelope, from their separation
      // along it, with the vertices' thresholds.
      if (fresh) {
        watch.edges = edge_watch_candidates(piece, R, origin, held_vertex, sp, R_SP, s_origin,
                                            settings.envelope_m);
        for (EdgeWatch& w : watch.edges) w.threshold = threshold(w.threshold);
      }
      for (const EdgeWatch& w : watch.edges) {
        const double gap = edge_separation(*sp.mesh, R_SP, s_origin, *piece.mesh, R, origin, w);
        e[8].value = std::min(e[8].value, gap - w.threshold);
      }
    }
    return out;
  };

  double t = t0;
  dopri5::State y = pack(anchor_);
  dopri5::State k0 = rhs(t, y);
  const double cap = planned_t_ + settings.broad_phase_horizon_s;
  double h = std::min(step_hint_ > 0.0 ? step_hint_ : 1e-3, cap - t);
  // The state is the one last solved (the step's last stage, or the first right-hand side): its
  // problem is kept, and the velocities do not depend on the directions followed. Returns
  // whether the problem at this state changed: then the step's first right-hand side, solved
  // under the last step's start, is solved again.
  auto record_step_start = [&](double time, const dopri5::State& state) {
    const Problem& p = solve_at(time, state).p;
    const std::vector<HeldContactMotion> m = held_velocities(p.bodies, p.contacts);
    // The slips at a step's start change the problem only through a sliding (spinning,
    // rolling) contact below the floor, at this start or at the last one (build_problem):
    // without one, the problem solved at this state is still the same.
    const double still = std::max(world.settings.still_speed_mps, slip_floor);
    auto below = [&](const HeldContact& c, const Vec3& slip, const Vec3& dw) {
      return (!c.sticks && plane_coords(c, slip).norm() <= still) ||
             (slides(c, 1) && spin_speed(c, dw) <= still) ||
             (slides(c, 2) && roll_speed(c, dw) <= still);
    };
    bool changes = false;
    for (std::size_t i = 0; i < m.size(); ++i) {
      const HeldContact& c = p.contacts[i];
      changes = changes || below(c, m[i].slip_W, m[i].dw_W) ||
                (i < slip_before.size() && below(c, slip_before[i], dw_before[i]));
    }
    slip_before.resize(m.size());
    dw_before.resize(m.size());
    for (std::size_t i = 0; i < m.size(); ++i) {
      slip_before[i] = m[i].slip_W;
      dw_before[i] = m[i].dw_W;
    }
    if (changes) ++start;
    return changes;
  };
  if (record_step_start(t, y)) k0 = rhs(t, y);
  std::vector<EventValue> g_prev = events(t, y);
  // Another vertex of a held body touching the plane already (its threshold is 0) and going
  // down: the contact is not where it is held (a body lying on many nearly level vertices,
  // tipped onto one of them): it lands now, and its pair is held again at the vertex that is
  // lowest.
  const dopri5::State y_soon = y + 1e-9 * k0;
  const std::vector<EventValue> g_soon = events(t + 1e-9, y_soon);
  for (std::size_t j = 0; j < g_prev.size() && j < g_soon.size(); ++j) {
    const EventValue& g = g_prev[j];
    if (g.kind == IslandEvent::Kind::kLanding && g.value <= g.tolerance &&
        g_soon[j].value < g.value) {
      t_end = t0;
      event = IslandEvent{g.kind, g.link};
      return;
    }
    // A link whose patch is gone already (the mover's feature off the support's face, placed
    // at the plan's state and not at the motion's: a vertex held again at the face's edge where
    // it had just tipped over it) is watched by nothing below, where its event function starts
    // past its crossing: it tips now. (Carried on, such a vertex of a pile's hull, p197 on a face
    // of p44 in 200 hulls, seed 1, held no force and sank 4.5 um into the face in 2.2 ms.)
    if (g.kind == IslandEvent::Kind::kTip && g.value < -g.tolerance) {
      t_end = t0;
      event = IslandEvent{g.kind, g.link};
      return;
    }
  }
  // A slip (spin, rolling) that decelerates towards its stop turns ever faster as it shrinks:
  // its direction converges as a power of the time left (DESIGN.md §4), which no polynomial
  // follows, so steps in time are a fraction of the time left, and the step-size control fought
  // it: in a pile of 100 balls as many steps were rejected as taken. Along such a motion the
  // integration runs on a clock that slows down with the slip, dt/dsigma = 1 / (1 + sum_i c /
  // (s_i - floor / 2)) over the decelerating slips s_i between the floor and c: in sigma a slip
  // decays exponentially towards half the floor and its direction converges smoothly, so it
  // crosses the floor (its stop event) at a finite sigma and no stage looks below half of it.
  // Time is then integrated as one more component of the state - the time since the step's
  // start times the motion's speed scale, so that its error is judged in metres, as the
  // positions' are (absolute time would let its error grow with the time simulated); the slips
  // on the clock are chosen at each step's start. (Measured on the piles: fewer steps rejected in
  // most seeds, steps taken about the same - the tolerance, not the smoothness, sets them; the
  // piles' total cost moved both ways with chaos, README.)
  const std::size_t n = kPerBody * bodies.size();
  const double clock_speed = kClockSpeed * slip_floor;
  struct ClockTerm {
    std::size_t link;
    int kind;  // 0 slip, 1 spin, 2 rolling
  };
  std::vector<ClockTerm> clock;
  auto term_speed = [&](const HeldContact& c, const HeldContactMotion& m, int kind) {
    switch (kind) {
      case 0: return plane_coords(c, m.slip_W).norm();
      case 1: return std::abs(m.dw_W.dot(c.n_W)) * size;
      default: return plane_coords(c, m.dw_W).norm() * point_size(c);
    }
  };
  auto term_rate = [&](const HeldContact& c, const HeldContactMotion& m, int kind) {
    switch (kind) {
      case 0: return plane_coords(c, m.slip_W).dot(plane_coords(c, m.slip_rate_W));
      case 1: return m.dw_W.dot(c.n_W) * m.dalpha_W.dot(c.n_W);
      default: return plane_coords(c, m.dw_W).dot(plane_coords(c, m.roll_rate_W));
    }
  };
  auto clock_rate = [&](const Solved& sol) {
    double sum = 1.0;
    for (const ClockTerm& term : clock) {
      if (term.link >= sol.s.motion.size()) continue;
      const double speed =
          term_speed(sol.p.contacts[term.link], sol.s.motion[term.link], term.kind);
      sum += clock_speed / std::max(speed - 0.5 * slip_floor, 1e-300);
    }
    return 1.0 / sum;
  };
  auto choose_clock = [&](double time, const dopri5::State& state) {
    clock.clear();
    const Solved& sol = solve_at(time, state);
    if (sol.s.status != HeldStatus::kOk) return;
    for (std::size_t i = 0; i < links.size() && i < sol.s.motion.size(); ++i) {
      const HeldContact& c = sol.p.contacts[i];
      if (!c.active) continue;
      for (int kind = 0; kind < 3; ++kind) {
        if (!slides(c, kind)) continue;
        const double speed = term_speed(c, sol.s.motion[i], kind);
        if (speed > slip_floor && speed < clock_speed &&
            term_rate(c, sol.s.motion[i], kind) < 0.0) {
          clock.push_back({i, kind});
        }
      }
    }
  };
  clock_scale_ = speed_scale;
  double clock_t0 = t;  // the clocked step's start
  auto rhs_clocked = [&](double /*sigma*/, const dopri5::State& Y) {
    const double time = clock_t0 + Y(static_cast<Eigen::Index>(n)) / speed_scale;
    const dopri5::State state = Y.head(static_cast<Eigen::Index>(n));
    const dopri5::State dy = rhs(time, state);
    const double g = clock_rate(solve_at(time, state));
    dopri5::State out(n + 1);
    out << g * dy, speed_scale * g;
    return out;
  };
  choose_clock(t, y);

  dopri5::Step step;
  dopri5::StepController controller;
  std::vector<double> w_max(bodies.size(), 0.0), a_max(bodies.size(), 0.0),
      alpha_max(bodies.size(), 0.0);
  std::vector<Vec3> a_start(bodies.size(), Vec3::Zero()), alpha_start(bodies.size(), Vec3::Zero());
  t_end = cap;
  event = IslandEvent{IslandEvent::Kind::kSegmentEnd, -1};
  // A segment of at most this many steps (its dense output is kept): a motion that needs more is
  // re-planned where it ends, so memory stays bounded whatever the motion does.
  constexpr std::size_t kMaxSteps = 4096;
  // The motion is integrated kChunkSteps steps at a time (and at least the progress floor of
  // time, so that a motion in tiny steps still advances): at a chunk's end it goes on (extend),
  // with its pairs bounded again from there. Integrated to its next event at once, a motion in a
  // pile was mostly cut short by a collision or a hold elsewhere in its island: 46 % of the steps
  // of the first 0.4 s of a pile of 100 hulls were integrated past the instant their motion was
  // replaced, and its pairs were bounded by the whole motion's accelerations. Chunks of 4, 8, 12
  // and 32 steps: 13.5, 5.8, 7.6 and 12.0 s of CPU for that pile against 25.6 s (README).
  constexpr std::size_t kChunkSteps = 8;
  const double chunk_time = settings.toi_min_progress_s;
  const Eigen::Index time_index = static_cast<Eigen::Index>(n);
  while (t < cap && !failed && steps_.size() < kMaxSteps) {
    h = std::min(h, cap - t);
    const bool clocked = !clock.empty();
    double g0 = 1.0;  // dt/dsigma at the step's start; h is in time, step.h in the clock's units
    if (!clocked) {
      dopri5::take_step(rhs, t, y, k0, h, rtol, atol, step);
    } else {
      g0 = clock_rate(solve_at(t, y));
      dopri5::State Y(n + 1), K0(n + 1);
      Y << y, 0.0;
      K0 << g0 * k0, speed_scale * g0;
      clock_t0 = t;
      dopri5::take_step(rhs_clocked, 0.0, Y, K0, h / g0, rtol, atol, step);
      step.t = t;
    }
    if (failed && clocked) {
      // A clocked step too long for its stages to stay where the contact problem holds.
      failed = false;
      step.error = 1e10;
    }
    if (failed) break;
    if (std::isnan(step.error)) step.error = 1e10;  // rejected, and shrunk
    if (step.error > 1.0) {
      h = g0 * controller.rejected(step.h, step.error);
      ++integration.rejected;
      if (++motion_rejected_ > 1000 || h <= 1e-14 * std::max(1.0, t)) {
        failed = true;
        break;
      }
      continue;
    }
    auto time_at = [&](double theta) {
      return clocked ? t + step.at(theta, time_index) / speed_scale : t + theta * h;
    };
    auto y_at = [&](double theta) -> dopri5::State {
      return clocked ? dopri5::State(step.at(theta).head(time_index)) : step.at(theta);
    };
    const double t1 = clocked ? t + step.y1(time_index) / speed_scale : t + h;
    const dopri5::State y1 = clocked ? dopri5::State(step.y1.head(time_index)) : step.y1;
    const std::vector<EventValue> g_new = events(t1, y1);
    // The earliest event function crossing below its tolerance within the step.
    double theta_event = 2.0;
    IslandEvent found;
    for (std::size_t j = 0; j < g_new.size() && j < g_prev.size(); ++j) {
      if (!(g_prev[j].value >= -g_prev[j].tolerance && g_new[j].value < -g_new[j].tolerance)) {
        continue;
      }
      // Past its tolerance: -(value + tolerance) >= 0 (NaN where the function is missing).
      auto past = [&](const EventValue& e) { return -(e.value + e.tolerance); };
      const double hi = locate_crossing(
          [&](double theta) {
            const std::vector<EventValue> gm = events(time_at(theta), y_at(theta));
            return j < gm.size() ? past(gm[j]) : NAN;
          },
          0.0, past(g_prev[j]), 1.0, past(g_new[j]), 1e-15, 200);
      if (hi < theta_event) {
        theta_event = hi;
        found = IslandEvent{g_new[j].kind, g_new[j].link};
      }
    }
    if (failed) break;  // broke down within the step (above): it is not taken
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const Eigen::Index o = static_cast<Eigen::Index>(kPerBody * k);
      // A stage's rate of the three components at `at` (o + 7: the acceleration, o + 10: the
      // angular acceleration). A clocked step's stages are derivatives in sigma, dt/dsigma
      // times them.
      auto rate = [&](const dopri5::State& kk, Eigen::Index at) -> Vec3 {
        return clocked ? Vec3(kk.segment<3>(at) * speed_scale / kk(time_index))
                       : Vec3(kk.segment<3>(at));
      };
      auto acceleration = [&](const dopri5::State& kk) { return rate(kk, o + 7); };
      if (steps_.empty()) {
        a_start[k] = acceleration(step.k[0]);
        alpha_start[k] = rate(step.k[0], o + 10);
      }
      for (const dopri5::State& kk : step.k) {
        a_max[k] = std::max(a_max[k], (acceleration(kk) - a_start[k]).norm());
        alpha_max[k] = std::max(alpha_max[k], (rate(kk, o + 10) - alpha_start[k]).norm());
      }
      w_max[k] = std::max(
          {w_max[k], step.y0.segment<3>(o + 10).norm(), step.y1.segment<3>(o + 10).norm()});
    }
    steps_.push_back(step);
    if (theta_event <= 1.0 && time_at(theta_event) <= cap) {
      t_end = time_at(theta_event);
      event = found;
      break;
    }
    if (t1 >= cap) {  // a clocked step past the horizon
      t_end = cap;
      break;
    }
    // The controller's next step (in time), where this motion or its next chunk goes on.
    step_hint_ = (clocked ? step.k[6](time_index) / speed_scale : 1.0) *
                 controller.accepted(step.h, step.error);
    if (steps_.size() >= kChunkSteps && t1 - t0 >= chunk_time) {
      t_end = t1;
      event = IslandEvent{IslandEvent::Kind::kChunkEnd, -1};
      break;
    }
    h = step_hint_;
    t = t1;
    y = y1;
    k0 = clocked ? dopri5::State(step.k[6].head(time_index) * speed_scale / step.k[6](time_index))
                 : step.k[6];
    if (record_step_start(t, y)) k0 = rhs(t, y);
    for (LandingWatch& w : landing) w.threshold = -kInfinity;
    g_prev = events(t, y);
    choose_clock(t, y);
  }
  if (steps_.size() >= kMaxSteps && event.kind == IslandEvent::Kind::kSegmentEnd) t_end = t;
  integration.steps = steps_.size();
  integration.failed = failed;
  if (failed) {
    // The contact problem broke down along the way: end the segment where it last held.
    t_end = steps_.empty() ? t0 : t;  // the last accepted step's end (a clocked h is no time)
    event = IslandEvent{IslandEvent::Kind::kSegmentEnd, -1};
  }
  // The acceleration of each body from its value at the start, with a quarter more than the
  // largest departure from it seen at any stage (the stages sample the motion densely enough for
  // the step's error to be within the tolerance; the margin covers between them).
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    bounds_[k].a_W = a_start[k];
    bounds_[k].alpha_W = alpha_start[k];
    bounds_[k].a_slack = 1.25 * a_max[k] + 1e-9;
    bounds_[k].alpha_slack = 1.25 * alpha_max[k] + 1e-9;
    bounds_[k].w_bound = 1.25 * w_max[k];
  }
}

BodyState Island::state_at(std::size_t k, double t) const {
  BodyState s = anchor_[k];
  s.t = t;
  const double tau = t - t0;
  if (!(tau > 0.0)) return s;
  switch (motion) {
    case Motion::kRest: return s;
    case Motion::kUniform: {
      s.x_W = anchor_[k].x_W + anchor_[k].v_W * tau + 0.5 * a_[k] * tau * tau;
      s.v_W = anchor_[k].v_W + a_[k] * tau;
      s.w_W = anchor_[k].w_W + alpha_[k] * tau;
      s.q_WM = turning_[k] ? orientation_at(k, t)
                           : (rotation_quat(anchor_[k].w_W * tau + 0.5 * alpha_[k] * tau * tau) *
                              anchor_[k].q_WM)
                                 .normalized();
      return s;
    }
    case Motion::kTurntable: {
      const Eigen::AngleAxisd turn(turn_rate_ * tau, turn_axis_);
      s.x_W = turn_centre_ + turn * (anchor_[k].x_W - turn_centre_);
      s.v_W = turn * anchor_[k].v_W;
      s.w_W = angular_velocity_at(k, t);
      s.q_WM = orientation_at(k, t);
      return s;
    }
    case Motion::kIntegrated: {
      if (steps_.empty()) return s;
      auto it = std::upper_bound(steps_.begin(), steps_.end(), t,
                                 [](double time, const dopri5::Step& st) { return time < st.t; });
      const dopri5::Step& st = it == steps_.begin() ? steps_.front() : *(it - 1);
      const Eigen::Index n = static_cast<Eigen::Index>(kPerBody * bodies.size());
      if (st.y0.size() > n) {
        // A clocked step (integrate()): its last component is the time since its start (times
        // clock_scale_), increasing along it.
        double lo = 0.0, hi = 1.0;
        for (int i = 0; i < 60 && hi - lo > 1e-16; ++i) {
          const double mid = 0.5 * (lo + hi);
          (st.at(mid, n) < (t - st.t) * clock_scale_ ? lo : hi) = mid;
        }
        return unpack(st.at(hi).head(n), t)[k];
      }
      const double theta = std::clamp((t - st.t) / st.h, 0.0, 1.0);
      return unpack(st.at(theta), t)[k];
    }
  }
  return s;
}

Vec3 Island::angular_velocity_at(std::size_t k, double t) const {
  const double tau = t - t0;
  if (motion == Motion::kTurntable) {
    // Rolling: v + w x (-R n) = W x (x - p0), so w's in-plane part is n x (v - W x (x - p0)) / R;
    // about n nothing turns it.
    const Eigen::AngleAxisd turn(turn_rate_ * tau, turn_axis_);
    const Vec3 x = turn_centre_ + turn * (anchor_[k].x_W - turn_centre_);
    const Vec3 v = turn * anchor_[k].v_W;
    const Vec3 n = turn_axis_;
    return n * n.dot(anchor_[k].w_W) + n.cross(v - turn_w_.cross(x - turn_point_)) / radius_;
  }
  return anchor_[k].w_W + alpha_[k] * tau;
}

Quat Island::orientation_at(std::size_t k, double t) const {
  // q' = (1/2) [0, w(t)] q with w(t) known in closed form: classical Runge-Kutta steps small
  // enough that |w| dt <= 1e-2 (error ~1e-12 per radian turned), continued from the last time
  // asked for (samples come in order).
  if (orientation_cache_.size() != bodies.size()) {
    orientation_cache_.assign(bodies.size(), {kInfinity, Quat::Identity()});
  }
  auto& [t_c, q_c] = orientation_cache_[k];
  if (!(t_c <= t)) {
    t_c = t0;
    q_c = anchor_[k].q_WM;
  }
  auto f = [&](double time, const Quat& q) {
    const Vec3 w = angular_velocity_at(k, time);
    Quat d = Quat(0.0, w.x(), w.y(), w.z()) * q;
    d.coeffs() *= 0.5;
    return d;
  };
  while (t_c < t) {
    const double w = std::max(angular_velocity_at(k, t_c).norm(), 1e-300);
    const double dt = std::min(t - t_c, 1e-2 / w);
    const Quat k1 = f(t_c, q_c);
    Quat q2 = q_c;
    q2.coeffs() += 0.5 * dt * k1.coeffs();
    const Quat k2 = f(t_c + 0.5 * dt, q2);
    Quat q3 = q_c;
    q3.coeffs() += 0.5 * dt * k2.coeffs();
    const Quat k3 = f(t_c + 0.5 * dt, q3);
    Quat q4 = q_c;
    q4.coeffs() += dt * k3.coeffs();
    const Quat k4 = f(t_c + dt, q4);
    q_c.coeffs() += dt / 6.0 * (k1.coeffs() + 2.0 * k2.coeffs() + 2.0 * k3.coeffs() + k4.coeffs());
    q_c.normalize();
    t_c += dt;
  }
  return q_c;
}

Island::MotionBound Island::bound(std::size_t k) const {
  return bounds_[k];
}

}  // namespace palpable
