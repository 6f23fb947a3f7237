#include "scheduler/simulation.hpp"

#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "distance/closest_features.hpp"
#include "distance/toi_bound.hpp"
#include "impulse/collision_integrator.hpp"
#include "impulse/collision_matrix.hpp"
#include "impulse/contact_torque.hpp"
#include "impulse/microcollision.hpp"
#include "scheduler/broad_phase.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace palpable {

namespace {

// The box swept by a point moving as x0 + v s + g s^2 / 2 for s in [0, dt], per axis.
Aabb parabola_box(const Vec3& x0, const Vec3& v, const Vec3& g, double dt) {
  Aabb box;
  box.min_W = x0;
  box.max_W = x0;
  auto include = [&](double s) {
    Vec3 x = x0 + v * s + 0.5 * g * s * s;
    box.min_W = box.min_W.cwiseMin(x);
    box.max_W = box.max_W.cwiseMax(x);
  };
  include(dt);
  for (int i = 0; i < 3; ++i) {
    if (g[i] != 0.0) {
      double s = -v[i] / g[i];
      if (s > 0.0 && s < dt) include(s);
    }
  }
  return box;
}

Aabb grown(Aabb box, double margin) {
  box.min_W.array() -= margin;
  box.max_W.array() += margin;
  return box;
}

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

// The patch point approaching fastest (the corner that lands first); among equals, the one
// nearest `foot` (the foot of the dynamic body's centre of mass).
Vec3 fastest_approaching_corner(const std::vector<Vec3>& patch, const Vec3& n_W,
                                const BodyState& s1, const BodyState& s2, const Vec3& foot) {
  double best = kInfinity;
  Vec3 corner = patch.front();
  for (const Vec3& q : patch) {
    const double u_n = (point_velocity_W(s1, q) - point_velocity_W(s2, q)).dot(n_W);
    const double tie = 1e-12 * (1.0 + std::abs(u_n));
    if (u_n < best - tie ||
        (std::abs(u_n - best) <= tie && (q - foot).norm() < (corner - foot).norm())) {
      best = std::min(best, u_n);
      corner = q;
    }
  }
  return corner;
}

}  // namespace

struct Simulation::Impl {
  struct BodyRuntime {
    std::shared_ptr<const ShapeGeometry> geometry;
    Aabb box;                    // swept box over [box_t, horizon]
    double horizon = kInfinity;  // absolute time the box stops being valid
    EventQueue::EventId horizon_event = EventQueue::kNoEvent;
    std::vector<std::uint32_t> pairs;
  };
  // 64 bytes, one cache line (a 10,000-sphere gas holds some 76,000 pairs, read in no useful
  // order); members ordered to leave no padding.
  struct PairRuntime {
    BodyId a, b;
    EventQueue::EventId event = EventQueue::kNoEvent;
    int collisions_at_t = 0;
    double last_collision_t = -kInfinity;
    std::uint64_t rebound_round = 0;  // the last refresh_after_collision that re-bounded it
    PairCache cache;
    bool live = false;
  };
  static_assert(sizeof(PairRuntime) <= 64, "a pair record fits one cache line");
  // Everything the collision of a pair needs, in the world frame; body 1 = a, body 2 = b.
  struct Contact {
    Vec3 point_W = Vec3::Zero();
    Vec3 n_W = Vec3::UnitZ();
    ContactBody body1, body2;
    double u_n = 0.0;             // relative normal velocity (< 0 approaching)
    double g_n = 0.0;             // relative normal acceleration toward contact (>= 0)
    double v_micro = 0.0;         // microcollision speed of this contact
    Vec3 a_rel_W = Vec3::Zero();  // slip acceleration at the moving contact location
    // The centre-of-pressure rule applies (DESIGN.md §4): over a polygon, the line of action
    // passes through the centre of mass; over a segment (edge on face), only the rotation about
    // the in-plane axis across the segment is held, and rotation about the segment stays free.
    bool centre_of_pressure = false;
    bool segment = false;
    Vec3 segment_dir_W = Vec3::Zero();  // unit, along the segment patch
    // The gap between the bodies along n and a point of body 2's support plane: each body's
    // velocity is taken where the contact point, moved along n, meets its own surface.
    double gap = 0.0;
    Vec3 plane2_W = Vec3::Zero();
    // The dynamic body is a sphere: its slip is taken at its centre's motion, as under the
    // centre-of-pressure rule (DESIGN.md §4).
    bool sphere = false;
    bool slip_at_centre() const { return sphere || centre_of_pressure; }
    // Bodies resting on the dynamic body of a microcollision with its support, carried along
    // (collected once, at the first resolution), and the stack's mass with them.
    std::vector<BodyId> riders;
    double stack_mass = 0.0;
    std::vector<Vec3> patch;
  };

  Simulation& sim;
  EventQueue queue;
  std::vector<BodyRuntime> bodies;
  std::vector<PairRuntime> pairs;
  std::vector<std::uint32_t> free_pairs;
  std::size_t live_pairs = 0;
  EventQueue::EventId sample_event = EventQueue::kNoEvent;
  std::vector<std::uint32_t> rebound_scratch;  // pairs re-bounded after a collision (reused)
  std::uint64_t rebound_round = 0;             // refresh_after_collision calls so far
  std::uint64_t next_sample = 0;
  // The swept boxes, dynamic bodies apart from fixed and kinematic ones: a non-dynamic body
  // looks only among the dynamic ones, so two non-dynamic bodies are never even compared.
  BroadPhase dynamic_boxes, static_boxes;
  std::vector<std::uint32_t> overlapping;  // scratch of refresh_broad_phase
  // Scratch of refresh_broad_phase: (the other body, the pair) for each pair of a body.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> partners;

  Impl(Simulation& s, QueueImpl impl) : sim(s), queue(impl) {}

  const Settings& settings() const { return sim.world_.settings; }
  Body& body(BodyId id) { return sim.world_.bodies[id.index]; }
  const Body& body(BodyId id) const { return sim.world_.bodies[id.index]; }
  Vec3 gravity_on(const Body& b) const {
    return b.is_dynamic() ? sim.world_.gravity_W : Vec3::Zero();
  }

  BodyState extrapolate(BodyId id, double t) const {
    const Body& b = body(id);
    if (t <= b.state.t) return b.state;
    return advance(b, b.state, t, sim.world_.gravity_W, settings());
  }
  void commit(BodyId id, double t) {
    Body& b = body(id);
    if (t > b.state.t) b.state = advance(b, b.state, t, sim.world_.gravity_W, settings());
  }

  // ---------------------------------------------------------------- broad phase

  // Recomputes the swept box of `id` from time t and stores it in the broad phase. With
  // `limit_sweep`, a dynamic body's horizon is cut to the sweep limit (see refresh_broad_phase);
  // returns whether that cut it.
  bool refresh_box(BodyId id, double t, bool limit_sweep = false) {
    const bool cut = compute_box(id, t, limit_sweep);
    (body(id).is_dynamic() ? dynamic_boxes : static_boxes).set(id.index, bodies[id.index].box);
    return cut;
  }

  bool compute_box(BodyId id, double t, bool limit_sweep) {
    BodyRuntime& rt = bodies[id.index];
    const Body& b = body(id);
    const BodyState s = extrapolate(id, t);
    const double margin = settings().envelope_m;
    const double reach = rt.geometry->reach();
    if (b.motion == MotionKind::kFixed) {
      rt.box = grown(bounding_box_W(*b.shape, s.x_W, s.q_WM), margin);
      rt.horizon = kInfinity;
      return false;
    }
    if (b.motion == MotionKind::kKinematic) {
      const KinematicMotion& k = b.kinematic;
      const bool translating = k.velocity_W.squaredNorm() > 0.0;
      const bool spinning = k.angular_velocity_W.squaredNorm() > 0.0;
      if (!std::isfinite(reach)) {
        // A halfspace: a static set unless it translates or spins about a non-normal axis.
        const Halfspace& h = std::get<Halfspace>(*b.shape);
        const Vec3 n_W = s.q_WM * h.normal_M;
        const bool maps_onto_itself =
            !translating && (!spinning || n_W.cross(k.angular_velocity_W).norm() <=
                                              1e-12 * k.angular_velocity_W.norm());
        rt.box = maps_onto_itself ? grown(bounding_box_W(*b.shape, s.x_W, s.q_WM), margin)
                                  : Aabb{Vec3::Constant(-kInfinity), Vec3::Constant(kInfinity)};
        rt.horizon = kInfinity;
        return false;
      }
      // Every material point stays within |x - c| + reach of the axis point c(t).
      const Vec3 c = k.point_W + k.velocity_W * t;
      const double radius = (s.x_W - c).norm() + reach;
      const double horizon = translating ? settings().broad_phase_horizon_s : kInfinity;
      const double dt = translating ? horizon : 0.0;
      rt.box = grown(parabola_box(c, k.velocity_W, Vec3::Zero(), dt), radius + margin);
      rt.horizon = t + horizon;
      return false;
    }
    const Vec3 g = sim.world_.gravity_W;
    if (s.v_W.squaredNorm() == 0.0 && g.squaredNorm() == 0.0) {
      rt.box = grown(parabola_box(s.x_W, s.v_W, g, 0.0), reach + margin);
      rt.horizon = kInfinity;
      return false;
    }
    double dt = settings().broad_phase_horizon_s;
    const double travel = s.v_W.norm() * dt;
    const double max_travel = settings().broad_phase_max_sweep * reach;
    const bool cut = limit_sweep && travel > max_travel;
    if (cut) dt *= max_travel / travel;
    rt.box = grown(parabola_box(s.x_W, s.v_W, g, dt), reach + margin);
    rt.horizon = t + dt;
    return cut;
  }

  void schedule_horizon(BodyId id) {
    BodyRuntime& rt = bodies[id.index];
    if (std::isfinite(rt.horizon)) {
      Event e;
      e.t = rt.horizon;
      e.kind = EventKind::kHorizon;
      e.a = id;
      if (rt.horizon_event == EventQueue::kNoEvent) {
        rt.horizon_event = queue.push(e);
      } else {
        queue.update(rt.horizon_event, e);
      }
    } else if (rt.horizon_event != EventQueue::kNoEvent) {
      queue.erase(rt.horizon_event);
      rt.horizon_event = EventQueue::kNoEvent;
    }
  }

  std::uint32_t create_pair(BodyId a, BodyId b) {
    std::uint32_t index;
    if (!free_pairs.empty()) {
      index = free_pairs.back();
      free_pairs.pop_back();
    } else {
      index = static_cast<std::uint32_t>(pairs.size());
      pairs.emplace_back();
    }
    PALPABLE_CHECK(body(a).is_dynamic() || body(b).is_dynamic(),
                   "a pair of two fixed or kinematic bodies");
    PairRuntime& p = pairs[index];
    p = PairRuntime{};
    p.a = a;
    p.b = b;
    p.live = true;
    bodies[a.index].pairs.push_back(index);
    bodies[b.index].pairs.push_back(index);
    ++live_pairs;
    ++sim.stats_.pairs_created;
    sim.stats_.max_pairs = std::max<std::uint64_t>(sim.stats_.max_pairs, live_pairs);
    return index;
  }

  void remove_pair(std::uint32_t index) {
    PairRuntime& p = pairs[index];
    if (p.event != EventQueue::kNoEvent) queue.erase(p.event);
    for (BodyId id : {p.a, p.b}) {
      auto& list = bodies[id.index].pairs;
      list.erase(std::find(list.begin(), list.end(), index));
    }
    --live_pairs;
    p.live = false;
    free_pairs.push_back(index);
  }

  // Every body whose swept box overlaps that of `id` and that may pair with it (at least one of
  // the two dynamic), ascending, into `out`. Returns how many of them are dynamic.
  std::size_t find_overlaps(BodyId id, std::vector<std::uint32_t>& out) {
    out.clear();
    const Aabb& box = bodies[id.index].box;
    dynamic_boxes.query(box, id.index, out);
    const std::size_t dynamic_count = out.size();
    if (body(id).is_dynamic()) {
      static_boxes.query(box, id.index, out);
      // Two ascending runs: sorted in place (inplace_merge allocates a buffer on every call).
      if (dynamic_count > 0 && dynamic_count < out.size()) std::sort(out.begin(), out.end());
    }
    sim.stats_.box_tests = dynamic_boxes.box_tests() + static_boxes.box_tests();
    return dynamic_count;
  }

  // Recomputes the swept box of `id` from time t and brings its pairs up to date: pairs whose
  // boxes overlap exist (never two non-dynamic bodies), others are dropped. The broad phase finds
  // the overlapping boxes in O(neighbours); the pairs are created and dropped in ascending order
  // of the other body, so pair order (and with it the event sequence) does not depend on how the
  // overlaps were found. The pairs are not re-bounded here (see refresh_body).
  //
  // A dynamic body among other moving bodies looks ahead no further than it travels, at its
  // present speed, in Settings::broad_phase_max_sweep times its reach: a longer box would pair
  // it with bodies it cannot reach before its next collision, each pair re-bounded at every one
  // of its collisions (it halves the cost per collision of a 10,000-sphere gas). A body with no
  // moving body near even its short box - a projectile in empty space, a ball bouncing alone on
  // a floor - keeps the whole horizon: shortening it would only add refreshes.
  void refresh_broad_phase(BodyId id, double t) {
    bool found = false;  // `overlapping` holds the overlaps of the box stored
    if (refresh_box(id, t, /*limit_sweep=*/true)) {
      found = find_overlaps(id, overlapping) > 0;
      if (!found) refresh_box(id, t, /*limit_sweep=*/false);
    }
    schedule_horizon(id);
    if (!found) find_overlaps(id, overlapping);
    partners.clear();
    for (std::uint32_t index : bodies[id.index].pairs) {
      const PairRuntime& p = pairs[index];
      partners.emplace_back(p.a == id ? p.b.index : p.a.index, index);
    }
    std::sort(partners.begin(), partners.end());
    auto o = overlapping.begin();
    auto q = partners.begin();
    while (o != overlapping.end() || q != partners.end()) {
      const std::uint32_t j =
          q == partners.end() || (o != overlapping.end() && *o < q->first) ? *o : q->first;
      const bool overlap = o != overlapping.end() && *o == j;
      const bool paired = q != partners.end() && q->first == j;
      const std::uint32_t pair = paired ? q->second : 0;
      if (overlap) ++o;
      if (paired) ++q;
      if (overlap == paired) continue;
      if (overlap) {
        create_pair(BodyId{std::min(id.index, j)}, BodyId{std::max(id.index, j)});
      } else {
        remove_pair(pair);
      }
    }
  }

  // Re-bounds every pair of `id` (rebound never changes the lists).
  void rebound_pairs(BodyId id, double t) {
    for (std::uint32_t index : bodies[id.index].pairs) rebound(index, t);
  }

  // A body's horizon ran out: new box, pairs, bounds.
  void refresh_body(BodyId id, double t) {
    refresh_broad_phase(id, t);
    rebound_pairs(id, t);
  }

  // After a collision: the boxes and pairs of every body it moved (the pair's and the riders
  // it carried), then every pair of those bodies re-bounded once. A fixed body's box never
  // changes, and every dynamic body overlapping it was paired with it at that body's own last
  // refresh, so refreshing a fixed body would change nothing - but cost a scan of every dynamic
  // body for a halfspace, whose box is infinite: it is skipped. So for a kinematic body, whose
  // box follows only time (its horizon event keeps it current). A fixed or kinematic body's
  // motion is not changed by a collision either, so the bounds of its other pairs stay valid:
  // only the dynamic bodies' pairs are re-bounded (a table or wall with a pair for each of n
  // bodies cost O(n^(2/3)) re-bounds per collision in a gas).
  void refresh_after_collision(const CollisionRecord& r, double t) {
    auto each_moved = [&](auto&& f) {
      f(r.a);
      f(r.b);
      for (BodyId id : r.carried) f(id);
    };
    each_moved([&](BodyId id) {
      if (body(id).is_dynamic()) refresh_broad_phase(id, t);
    });
    rebound_scratch.clear();
    ++rebound_round;
    each_moved([&](BodyId id) {
      if (!body(id).is_dynamic()) return;
      for (std::uint32_t index : bodies[id.index].pairs) {
        PairRuntime& p = pairs[index];
        if (p.rebound_round == rebound_round) continue;  // a pair of two moved bodies: once
        p.rebound_round = rebound_round;
        rebound_scratch.push_back(index);
      }
    });
    // The other bodies of these pairs lie anywhere in memory: ask for all of them before using
    // any, so that their cache misses overlap instead of following one another (see the
    // README's gas benchmark: at 10,000 spheres the bodies no longer fit the cache).
    for (std::uint32_t index : rebound_scratch) {
      const PairRuntime& p = pairs[index];
      for (BodyId id : {p.a, p.b}) {
        const Body& b = body(id);
        const char* first = reinterpret_cast<const char*>(&b);
        __builtin_prefetch(first);
        __builtin_prefetch(first + 64);
        __builtin_prefetch(first + 128);
        __builtin_prefetch(&bodies[id.index]);
      }
    }
    for (std::uint32_t index : rebound_scratch) rebound(index, t);
  }

  // ---------------------------------------------------------------- contacts

  // The contact of pair `p` whose closest features are `dr` (states at the same time).
  Contact make_contact(const PairRuntime& p, const BodyState& s1, const BodyState& s2,
                       const DistanceResult& dr, bool with_patch) const {
    const Body& b1 = body(p.a);
    const Body& b2 = body(p.b);
    Contact c;
    c.n_W = dr.n_W;
    c.point_W = 0.5 * (dr.p1_W + dr.p2_W);

    const Vec3 acc1 = gravity_on(b1), acc2 = gravity_on(b2);
    c.g_n = -(acc1 - acc2).dot(c.n_W);
    if (b1.is_dynamic() && b2.is_dynamic()) {
      // Same gravity on both: use the upper body's weight along n (DESIGN.md §4).
      c.g_n = std::abs(sim.world_.gravity_W.dot(c.n_W));
    }
    c.g_n = std::max(c.g_n, 0.0);
    c.v_micro = microcollision_speed(settings(), c.g_n);

    auto fill = [&](ContactBody& cb, const Body& b, const BodyState& s) {
      cb.inv_mass = b.mass.inv_mass;
      cb.inv_inertia_W = b.is_dynamic() ? inverse_inertia_W(b, s.q_WM) : Mat3::Zero();
      cb.v_W = s.v_W;
      cb.w_W = s.w_W;
    };
    fill(c.body1, b1, s1);
    fill(c.body2, b2, s2);

    if (with_patch && dr.status != ContactStatus::kPenetrating) {
      c.patch = contact_patch(*bodies[p.a.index].geometry, Pose{s1.x_W, s1.q_WM},
                              *bodies[p.b.index].geometry, Pose{s2.x_W, s2.q_WM}, dr,
                              settings().envelope_m);
    }
    const bool one_dynamic = b1.is_dynamic() != b2.is_dynamic();
    if (c.patch.size() >= 2) {
      const bool d_is_1 = b1.is_dynamic();
      const BodyState& sd = d_is_1 ? s1 : s2;
      const BodyState& ss = d_is_1 ? s2 : s1;
      // Foot of the dynamic body's centre of mass on the contact plane.
      const Vec3 foot = sd.x_W - c.n_W * c.n_W.dot(sd.x_W - dr.p2_W);
      Vec3 centroid = Vec3::Zero();
      for (const Vec3& q : c.patch) centroid += q;
      centroid /= static_cast<double>(c.patch.size());
      double patch_radius = 0.0;
      for (const Vec3& q : c.patch) patch_radius = std::max(patch_radius, (q - centroid).norm());
      Vec3 w_rel = sd.w_W - ss.w_W;
      const Vec3 w_in = w_rel - c.n_W * c.n_W.dot(w_rel);
      // The centre-of-pressure rule (DESIGN.md §4) for a dynamic body on a fixed or kinematic
      // one, touching over a polygon and not rocking faster than the microcollision speed.
      const double rocking_limit = std::max(c.v_micro, 1e-9);
      const Vec3 along =
          c.patch.size() == 2 ? (c.patch[1] - c.patch[0]).normalized() : Vec3::Zero();
      if (settings().centre_of_pressure && one_dynamic && c.patch.size() >= 3 &&
          w_in.norm() * patch_radius <= rocking_limit) {
        c.centre_of_pressure = true;
        c.point_W = foot;
      } else if (settings().centre_of_pressure && one_dynamic && c.patch.size() == 2 &&
                 along.allFinite() &&
                 std::abs(w_rel.dot(c.n_W.cross(along))) * patch_radius <= rocking_limit) {
        // Edge on face: the point of the segment nearest the foot of the centre of mass.
        c.centre_of_pressure = true;
        c.segment = true;
        c.segment_dir_W = along;
        const double length = (c.patch[1] - c.patch[0]).norm();
        c.point_W = c.patch[0] + along * std::clamp((foot - c.patch[0]).dot(along), 0.0, length);
      } else {
        c.point_W = fastest_approaching_corner(c.patch, c.n_W, s1, s2, foot);
      }
    }
    c.gap = c.n_W.dot(dr.p1_W - dr.p2_W);
    c.plane2_W = dr.p2_W;
    place(c, c.point_W, s1.x_W, s2.x_W);
    c.u_n = (contact_point_velocity_W(c.body1) - contact_point_velocity_W(c.body2)).dot(c.n_W);

    // Rate of change of the slip at the moving contact location over the next flight
    // (DESIGN.md §4): gravity, the rotational terms of a rotating contact point, and for a
    // kinematic surface the change of its velocity under the moving location, Omega x (p' - V).
    const Body* dynamic_body = b1.is_dynamic() ? &b1 : (b2.is_dynamic() ? &b2 : nullptr);
    const ContactBody& cd = b1.is_dynamic() ? c.body1 : c.body2;
    Vec3 location_velocity = Vec3::Zero();
    c.sphere = dynamic_body && std::holds_alternative<Sphere>(*dynamic_body->shape);
    if (dynamic_body) {
      location_velocity = c.slip_at_centre() ? cd.v_W : contact_point_velocity_W(cd);
    }
    auto accel = [&](const Body& b, const ContactBody& cb) -> Vec3 {
      if (b.is_dynamic()) {
        Vec3 a = sim.world_.gravity_W;
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

  // Puts the contact at `point_W` (between the bodies, on the contact normal's line through it):
  // the contact point offsets of both bodies are to where that line meets each body's surface.
  // (Taking both at the midpoint of a gap d would give a ball rolling at w a slip of w d / 2
  // there that its surface does not have; the microcollisions "correcting" it sped rolling balls
  // up by 2.4e-5 of their speed per second at envelope 1e-5 m.)
  static void place(Contact& c, const Vec3& point_W, const Vec3& x1_W, const Vec3& x2_W) {
    c.point_W = point_W;
    const double height = c.n_W.dot(point_W - c.plane2_W);  // above body 2's surface
    c.body1.r_W = point_W + c.n_W * (c.gap - height) - x1_W;
    c.body2.r_W = point_W - c.n_W * height - x2_W;
  }

  // Puts the contact at `tip_W`, the point of the patch boundary a body tips about when the
  // patch cannot carry the torque of the centre-of-pressure impulse (DESIGN.md §4). If the body
  // turns so fast that this point already separates, the corner landing first takes the
  // collision: the relative normal velocity is affine over the contact plane, so a patch whose
  // centre of pressure approaches has a corner that approaches. (A collision at the separating
  // point does nothing a retry sees: the pair stays approaching at the same instant, again and
  // again; a microcollision there even pushes the point away at v_micro while the patch's other
  // end keeps landing.)
  void place_tipping(Contact& c, const Vec3& tip_W, const BodyState& s1, const BodyState& s2,
                     const Vec3& x_D) const {
    place(c, tip_W, s1.x_W, s2.x_W);
    const Vec3 u_tip = contact_point_velocity_W(c.body1) - contact_point_velocity_W(c.body2);
    if (!(u_tip.dot(c.n_W) < 0.0)) {
      place(c, fastest_approaching_corner(c.patch, c.n_W, s1, s2, x_D), s1.x_W, s2.x_W);
    }
  }

  // The piece-pair result a collision would be resolved at: `dr` itself, or, for a pair with a
  // compound, the piece within the envelope approaching fastest (a ball in a crease touches two
  // pieces; the closest may be the one it is leaving).
  const DistanceResult& contact_result(const PairRuntime& p, const BodyState& s1,
                                       const BodyState& s2, const DistanceResult& dr) const {
    const DistanceResult* best = &dr;
    double best_u_n = kInfinity;
    for (const DistanceResult& r : p.cache.piece_results()) {
      if (r.status == ContactStatus::kFailed ||
          (r.status != ContactStatus::kPenetrating && r.distance > settings().envelope_m)) {
        continue;
      }
      const Contact c = make_contact(p, s1, s2, r, /*with_patch=*/false);
      if (approaching(c) && c.u_n < best_u_n) {
        best_u_n = c.u_n;
        best = &r;
      }
    }
    return *best;
  }

  bool approaching(const Contact& c) const {
    // u_n = 0 with gravity pressing the bodies together counts as approaching: a body left at
    // rest in contact by an e = 0 collision must collide again (DESIGN.md §4). Without it, an
    // approach within rounding of the bodies' speeds (what an e = 0 collision leaves) is rest.
    // Two dynamic bodies share gravity, so nothing presses them together at rest: a body
    // resting on another rides along when the lower one bounces on its support (see riders).
    const bool both_dynamic = c.body1.inv_mass > 0.0 && c.body2.inv_mass > 0.0;
    if (c.g_n > 0.0 && !both_dynamic) return c.u_n <= 1e-9 * c.v_micro;
    const double scale =
        contact_point_velocity_W(c.body1).norm() + contact_point_velocity_W(c.body2).norm();
    return c.u_n < -1e-12 * scale;
  }

  // The couples a point impulse cannot carry (impulse/contact_torque.hpp), applied after the
  // impulse P_n of a collision: torsional friction about n — over a patch resolved by the
  // centre-of-pressure rule, mu times the mean distance of the patch from the centre of pressure;
  // at a point, the material's spinning resistance — and the material's rolling resistance
  // against the in-plane relative rotation. Changes the angular
  // velocities of cb1 and cb2 (true inertias, not the centre-of-pressure ones); the record's
  // energy change is measured on the bodies and includes what these take out.
  void resist_rotation(const Contact& c, const Material& material, double P_n,
                       const Vec3& pressure_W, ContactBody& cb1, ContactBody& cb2) const {
    if (!(P_n > 0.0)) return;
    ContactBody t1 = c.body1, t2 = c.body2;
    t1.w_W = cb1.w_W;
    t2.w_W = cb2.w_W;
    // About n: Coulomb friction over a patch, or the material's spinning resistance at a point
    // (the patch's mean distance, the costly part, only if there is spin to resist).
    const bool spins = c.n_W.dot(t1.w_W - t2.w_W) != 0.0;
    const double torsion_arm =
        !spins ? 0.0
        : c.centre_of_pressure
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

  // How steep a contact normal must be to count as support, cos 60 degrees from the vertical.
  static constexpr double kSupportCosine = 0.5;

  // The dynamic bodies riding on body `id` at time t: resting on it (within two envelopes, a
  // microcollision bounces a body up to 1.5; the normal within 60 degrees of the vertical;
  // at rest on it along the normal or settling onto it slower than the microcollision speed),
  // and those riding on them, up to 8 levels. Appended to `riders` (no repeats).
  void collect_riders(BodyId id, double t, int depth, std::vector<BodyId>& riders) {
    if (depth > 8 || sim.world_.gravity_W.squaredNorm() == 0.0) return;
    const Vec3 up = -sim.world_.gravity_W.normalized();
    // query() only warms a pair's cache: the pair lists do not change here.
    for (std::uint32_t index : bodies[id.index].pairs) {
      PairRuntime& q = pairs[index];
      const BodyId other = q.a == id ? q.b : q.a;
      if (!body(other).is_dynamic() ||
          std::find(riders.begin(), riders.end(), other) != riders.end()) {
        continue;
      }
      const BodyState s1 = extrapolate(q.a, t), s2 = extrapolate(q.b, t);
      ++sim.stats_.bound_queries;
      const DistanceResult dr = query(q, s1, s2);
      if (dr.status != ContactStatus::kSeparated && dr.status != ContactStatus::kTouching) continue;
      if (dr.distance > 2.0 * settings().envelope_m) continue;
      const Vec3 n = q.a == other ? dr.n_W : Vec3(-dr.n_W);  // from `id` up to `other`
      if (n.dot(up) <= kSupportCosine) continue;
      const BodyState& s_other = q.a == other ? s1 : s2;
      const BodyState& s_id = q.a == other ? s2 : s1;
      const double v_micro =
          microcollision_speed(settings(), std::abs(sim.world_.gravity_W.dot(n)));
      // Resting on it or settling onto it, not flying off it.
      const double u_rel = n.dot(s_other.v_W - s_id.v_W);
      if (u_rel > 1e-9 * v_micro || u_rel < -v_micro * (1.0 + 1e-6)) continue;
      riders.push_back(other);
      collect_riders(other, t, depth + 1, riders);
    }
  }

  // Resolves the collision and applies it to both bodies; returns the record.
  // `depth` counts re-resolutions at a moved contact point (at most one per rule).
  CollisionRecord resolve(const PairRuntime& p, Contact& c, double t, int depth = 0) {
    const Material& material = sim.world_.material(p.a, p.b);
    CollisionParameters params = collision_parameters(material, settings());
    params.min_rebound_speed = c.g_n > 0.0 ? c.v_micro : 0.0;
    const Mat3 R_WC = contact_frame_W(c.n_W);

    ContactBody cb1 = c.body1, cb2 = c.body2;
    Body& b1 = body(p.a);
    Body& b2 = body(p.b);
    if (c.centre_of_pressure) {
      ContactBody& cd = b1.is_dynamic() ? cb1 : cb2;
      if (!c.segment) {
        // The impulse's line of action through the centre of mass: no rotation change at all.
        cd.inv_inertia_W.setZero();
      } else {
        // Rotation held about m = n x s: the inverse inertia of a body free to turn only about
        // the segment s and the normal n, V (V^T I V)^-1 V^T with V = [s n].
        Eigen::Matrix<double, 3, 2> V;
        V.col(0) = c.segment_dir_W;
        V.col(1) = c.n_W;
        const Mat3 I_W = cd.inv_inertia_W.inverse();
        cd.inv_inertia_W = V * (V.transpose() * I_W * V).inverse() * V.transpose();
      }
    }
    const Vec3 u0_c =
        R_WC.transpose() * (contact_point_velocity_W(cb1) - contact_point_velocity_W(cb2));
    const bool micro = is_microcollision(u0_c.z(), c.v_micro, settings());
    // A body bouncing on its support carries what rests on it (shock propagation, as in
    // Guendelman, Bridson & Fedkiw 2003, for the microcollision train): the microcollision acts
    // on the stack's whole mass and every rider gets the same change of velocity. Otherwise a
    // light body under a heavy one must pass the heavy one's weight on in its own collisions, a
    // storm of m_heavy / m_light of them (tests/tools/extremes_test.cpp).
    // Only over a face resting on its support (the centre-of-pressure rule: the carrier does not
    // turn, so the stack's mass is all the impulse meets); collected at the first resolution,
    // dropped if a re-resolution finds the carrier tipping.
    const bool resting_face = c.centre_of_pressure && !c.segment;
    if (!resting_face) c.riders.clear();
    if (depth == 0 && micro && resting_face) {
      const BodyId carrier = b1.is_dynamic() ? p.a : p.b;
      const Vec3 n_up = b1.is_dynamic() ? c.n_W : Vec3(-c.n_W);  // from the support up
      if (n_up.dot(-sim.world_.gravity_W.normalized()) > kSupportCosine) {
        collect_riders(carrier, t, 0, c.riders);
        c.stack_mass = body(carrier).mass.mass;
        for (BodyId r : c.riders) {
          commit(r, t);
          c.stack_mass += body(r).mass.mass;
        }
      }
    }
    if (!c.riders.empty()) (b1.is_dynamic() ? cb1 : cb2).inv_mass = 1.0 / c.stack_mass;
    const Mat3 K_c = R_WC.transpose() * collision_matrix_W(cb1, cb2) * R_WC;
    CollisionResult result;
    if (micro) {
      MicrocollisionContext context;
      const Vec3 a_c = R_WC.transpose() * c.a_rel_W;
      context.a_t_c = Vec2(a_c.x(), a_c.y());
      context.g_n = c.g_n;
      // The kinematic surface of the pair, if any (its partner is then the dynamic body).
      const Body* surface = b1.motion == MotionKind::kKinematic
                                ? &b1
                                : (b2.motion == MotionKind::kKinematic ? &b2 : nullptr);
      const Vec3 surface_w_W = surface ? surface->kinematic.angular_velocity_W : Vec3::Zero();
      if (c.centre_of_pressure) {
        // A face resting on a turning surface sticks to it: what must vanish over the flight is
        // its displacement on the surface. (A rolling ball's orbit follows its mean slip, which
        // the first-order target already zeroes; the term made the platter's orbit rate error
        // 3 times larger.)
        context.surface_spin = surface_w_W.dot(c.n_W);
      }
      result = resolve_microcollision(K_c, u0_c, params, settings().microcollision_rule, context,
                                      c.v_micro);
      // On a turning surface the slip rate Omega x (v - V) depends on the velocity the dynamic
      // body flies with, which is the one after this impulse: aim once more with it.
      if (surface_w_W.squaredNorm() > 0.0 && c.slip_at_centre() && succeeded(result.status)) {
        const ContactBody& cd = b1.is_dynamic() ? cb1 : cb2;
        const double inv_mass = b1.is_dynamic() ? cd.inv_mass : -cd.inv_mass;
        const Vec3 dv_W = R_WC * result.p_c * inv_mass;  // body 1 gets +p, body 2 -p
        const Vec3 da_W = surface_w_W.cross(dv_W);
        const Vec3 a2_c = R_WC.transpose() * (c.a_rel_W + (surface == &b1 ? da_W : -da_W));
        context.a_t_c = Vec2(a2_c.x(), a2_c.y());
        result = resolve_microcollision(K_c, u0_c, params, settings().microcollision_rule, context,
                                        c.v_micro);
      }
    } else {
      result = integrate_collision(K_c, u0_c, params);
    }
    sim.stats_.integration_steps += static_cast<std::uint64_t>(result.steps);
    if (!succeeded(result.status)) {
      // Numerical failure: fall back to the frictionless impulse (always defined for an SPD K),
      // counted. The contact still separates.
      ++sim.stats_.impulse_failures;
      CollisionParameters frictionless = params;
      frictionless.friction = 0.0;
      result = integrate_collision(K_c, u0_c, frictionless);
    }
    Vec3 p_W = R_WC * result.p_c;
    Vec3 pressure = c.point_W;  // centre of pressure over a patch

    if (c.centre_of_pressure && c.segment) {
      // Where along the segment must the impulse act so that its torque about m vanishes?
      const Vec3 x_D = b1.is_dynamic() ? b1.state.x_W : b2.state.x_W;
      const Vec3 m = c.n_W.cross(c.segment_dir_W);
      const double denominator = c.segment_dir_W.cross(p_W).dot(m);
      const double lambda =
          denominator != 0.0 ? -(c.point_W - x_D).cross(p_W).dot(m) / denominator : 0.0;
      const double s0 = (c.point_W - c.patch[0]).dot(c.segment_dir_W);
      const double length = (c.patch[1] - c.patch[0]).norm();
      const double s_pressure = s0 + lambda;
      const bool inside = s_pressure >= 0.0 && s_pressure <= length;
      if (!inside || (depth == 0 && std::abs(lambda) > 1e-12 * (1.0 + length))) {
        // Inside: resolve once more at the centre of pressure (K depends on the point). Outside:
        // the segment cannot hold that torque and the body tips about the end it reaches, or,
        // if that end already separates, collides at the end landing first.
        const Vec3 q = c.patch[0] + c.segment_dir_W * std::clamp(s_pressure, 0.0, length);
        if (inside) {
          place(c, q, b1.state.x_W, b2.state.x_W);
        } else {
          c.centre_of_pressure = c.segment = false;
          place_tipping(c, q, b1.state, b2.state, x_D);
        }
        return resolve(p, c, t, depth + 1);
      }
    } else if (c.centre_of_pressure) {
      // Where does the line of action through the centre of mass meet the contact plane?
      const bool d_is_1 = b1.is_dynamic();
      const Vec3 x_D = d_is_1 ? b1.state.x_W : b2.state.x_W;
      const double pn = p_W.dot(c.n_W);
      pressure = pn != 0.0 ? x_D + p_W * (c.n_W.dot(c.point_W - x_D) / pn) : c.point_W;
      if (!inside_convex_polygon(c.patch, c.n_W, pressure)) {
        // The patch cannot carry that torque: the body tips about the patch boundary.
        c.centre_of_pressure = false;
        place_tipping(c, exit_point(c.patch, c.n_W, c.point_W, pressure), b1.state, b2.state, x_D);
        return resolve(p, c, t, depth + 1);
      }
    }

    // The kinetic energy of the dynamic bodies before, for the record: the integrator's
    // (1/2)(u0 + u').p is that of the impulse at the point it was resolved with, which the
    // centre-of-pressure rule's modified inertia and its removal of rocking make differ from what
    // the bodies show (by up to 0.015 J on a 1 kg box at envelope 1e-2).
    auto kinetic = [](const Body& b) { return b.is_dynamic() ? kinetic_energy(b, b.state) : 0.0; };
    double kinetic_before = kinetic(b1) + kinetic(b2);
    for (BodyId r : c.riders) kinetic_before += kinetic(body(r));
    apply_impulse(p_W, cb1, cb2);
    if (c.centre_of_pressure) {
      // A face resting on a face does not rock: the pressure over the patch takes out the small
      // in-plane relative rotation (a plastic slap; the spin about n stays free). Over a segment,
      // only the rotation about m = n x s.
      ContactBody& cd = b1.is_dynamic() ? cb1 : cb2;
      const Vec3 w_rel = b1.is_dynamic() ? cb1.w_W - cb2.w_W : cb2.w_W - cb1.w_W;
      if (c.segment) {
        const Vec3 m = c.n_W.cross(c.segment_dir_W);
        cd.w_W -= m * m.dot(w_rel);
      } else {
        cd.w_W -= w_rel - c.n_W * c.n_W.dot(w_rel);
      }
    }
    resist_rotation(c, material, p_W.dot(c.n_W), pressure, cb1, cb2);
    auto store = [&](Body& b, const ContactBody& cb) {
      if (!b.is_dynamic()) return;
      b.state.v_W = cb.v_W;
      b.state.w_W = cb.w_W;
    };
    store(b1, cb1);
    store(b2, cb2);
    // The riders move on with the carrier along the normal (a plastic merge with the stack,
    // which the impulse on the stack's mass assumed); they keep their sliding and spin.
    for (BodyId r : c.riders) {
      const Vec3 v_carrier = (b1.is_dynamic() ? b1 : b2).state.v_W;
      Vec3& v = body(r).state.v_W;
      v += c.n_W * c.n_W.dot(v_carrier - v);
    }
    PALPABLE_CHECK(b1.state.v_W.allFinite() && b1.state.w_W.allFinite() &&
                       b2.state.v_W.allFinite() && b2.state.w_W.allFinite(),
                   "non-finite velocity after a collision");

    CollisionRecord record;
    record.t = t;
    record.kind = micro ? CollisionKind::kMicrocollision : CollisionKind::kCollision;
    record.a = p.a;
    record.b = p.b;
    record.p_W = c.point_W;
    record.n_W = c.n_W;
    record.impulse_W = p_W;
    record.approach_speed = -u0_c.z();
    double kinetic_after = kinetic(b1) + kinetic(b2);
    for (BodyId r : c.riders) kinetic_after += kinetic(body(r));
    record.energy_change = kinetic_after - kinetic_before;
    record.centre_of_pressure = c.centre_of_pressure;
    record.carried = std::move(c.riders);
    if (micro) {
      ++sim.stats_.microcollisions;
    } else {
      ++sim.stats_.collisions;
    }
    if (c.centre_of_pressure) ++sim.stats_.centre_of_pressure;
    return record;
  }

  // ---------------------------------------------------------------- pair events

  void schedule_pair(std::uint32_t index, double t_next) {
    PairRuntime& p = pairs[index];
    const double horizon = std::min(bodies[p.a.index].horizon, bodies[p.b.index].horizon);
    // A bound at or past a horizon needs no event: the horizon's refresh re-bounds the pair.
    if (!(t_next < horizon) || !std::isfinite(t_next)) {
      if (p.event != EventQueue::kNoEvent) {
        queue.erase(p.event);
        p.event = EventQueue::kNoEvent;
        ++sim.stats_.rescheduled;
      }
      return;
    }
    Event e;
    e.t = t_next;
    e.kind = EventKind::kPairCheck;
    e.a = p.a;
    e.b = p.b;
    e.owner = index;
    if (p.event == EventQueue::kNoEvent) {
      p.event = queue.push(e);
    } else {
      queue.update(p.event, e);
      ++sim.stats_.rescheduled;
    }
  }

  // The least step a pair's next check may take at time t [s]: settings.toi_min_progress_s, and
  // never less than 1e-12 t, so that t + step > t however long the run.
  double progress_floor(double t) const {
    return std::max(settings().toi_min_progress_s, 1e-12 * std::max(1.0, t));
  }

  // The next event time of a pair from its closest features at time t.
  // `known`: the contact check_pair already made of this very query and found not approaching
  // (saves making it again); null to make it here.
  double next_check_time(const PairRuntime& p, const BodyState& s1, const BodyState& s2,
                         const DistanceResult& dr, double t, const Contact* known = nullptr) {
    const double floor = progress_floor(t);
    if (dr.status == ContactStatus::kFailed) {
      ++sim.stats_.distance_failures;
      return t + floor;
    }
    bool resting = false;  // within the envelope, neither approaching nor accelerated together
    if (known) {
      if (dr.status == ContactStatus::kPenetrating) return t + floor;
      resting = known->g_n == 0.0;
    } else {
      const DistanceResult& contact = contact_result(p, s1, s2, dr);
      if (contact.status == ContactStatus::kPenetrating ||
          contact.distance <= settings().envelope_m) {
        const Contact c = make_contact(p, s1, s2, contact, /*with_patch=*/false);
        if (approaching(c)) return t;
        if (contact.status == ContactStatus::kPenetrating) return t + floor;
        resting = c.g_n == 0.0;
      }
    }
    const Body& b1 = body(p.a);
    const Body& b2 = body(p.b);
    ToiBound bound =
        time_of_impact(b1, s1, *bodies[p.a.index].geometry, b2, s2, *bodies[p.b.index].geometry, dr,
                       p.cache, sim.world_.gravity_W, settings());
    if (bound.floored) ++sim.stats_.floored_bounds;
    if (bound.exact) ++sim.stats_.exact_bounds;
    if (bound.exact && resting && bound.dt < floor) {
      // An exact time of impact of zero for a pair at rest in contact (an e = 0 collision without
      // gravity leaves them so, up to rounding): their relative motion is linear, so the gap
      // cannot close; only another collision (which re-bounds the pair) changes that.
      return kInfinity;
    }
    if (!(bound.dt >= 0.0)) return t + floor;  // NaN guard: never stall, never skip
    // The progress floor is applied (capped, so that it never carries a pair through contact)
    // by the bound itself; here only the resolution of the clock, so that t + dt > t.
    const double tick = 1e-12 * std::max(1.0, t);
    return t + std::max(bound.dt, bound.exact ? 0.0 : tick);
  }

  DistanceResult query(PairRuntime& p, const BodyState& s1, const BodyState& s2) {
    DistanceResult dr = closest_features(*bodies[p.a.index].geometry, Pose{s1.x_W, s1.q_WM},
                                         *bodies[p.b.index].geometry, Pose{s2.x_W, s2.q_WM},
                                         p.cache, settings().distance_max_steps);
    sim.stats_.feature_steps += static_cast<std::uint64_t>(dr.steps);
    if (dr.status == ContactStatus::kPenetrating) ++sim.stats_.penetrations;
    return dr;
  }

  void rebound(std::uint32_t index, double t) {
    PairRuntime& p = pairs[index];
    const BodyState s1 = extrapolate(p.a, t);
    const BodyState s2 = extrapolate(p.b, t);
    ++sim.stats_.bound_queries;
    DistanceResult dr = query(p, s1, s2);
    schedule_pair(index, next_check_time(p, s1, s2, dr, t));
  }

  void check_pair(std::uint32_t index, double t, SimulationObserver* observer) {
    PairRuntime& p = pairs[index];
    p.event = EventQueue::kNoEvent;  // it was just popped
    commit(p.a, t);
    commit(p.b, t);
    const BodyState& s1 = body(p.a).state;
    const BodyState& s2 = body(p.b).state;
    ++sim.stats_.pair_checks;
    DistanceResult dr = query(p, s1, s2);
    const DistanceResult& contact = contact_result(p, s1, s2, dr);
    if (contact.status != ContactStatus::kFailed &&
        (contact.status == ContactStatus::kPenetrating ||
         contact.distance <= settings().envelope_m)) {
      Contact c = make_contact(p, s1, s2, contact, /*with_patch=*/true);
      if (approaching(c)) {
        if (t == p.last_collision_t) {
          ++p.collisions_at_t;
          ++sim.stats_.retries;
          if (p.collisions_at_t > settings().retry_limit) {
            // A rounding loop: report it and move on by the progress floor.
            ++sim.stats_.retry_limit_hits;
            schedule_pair(index, t + progress_floor(t));
            return;
          }
        } else {
          p.last_collision_t = t;
          p.collisions_at_t = 0;
        }
        CollisionRecord record = resolve(p, c, t);
        if (observer) observer->on_collision(record);
        sim.stats_.riders_carried += record.carried.size();
        refresh_after_collision(record, t);  // `p` may move when pairs are created there
        return;
      }
      schedule_pair(index, next_check_time(p, s1, s2, dr, t, &c));
      return;
    }
    schedule_pair(index, next_check_time(p, s1, s2, dr, t));
  }

  void schedule_sample() {
    const double interval = sim.options_.output_interval;
    if (!(interval > 0.0)) return;
    Event e;
    e.t = static_cast<double>(next_sample) * interval;
    e.kind = EventKind::kSample;
    sample_event = queue.push(e);
  }
};

Simulation::Simulation(World world, SimulationOptions options)
    : world_(std::move(world)), options_(options) {
  impl_ = std::make_unique<Impl>(*this, options.queue);
  Impl& im = *impl_;
  // Shapes are shared between bodies: one Voronoi structure per distinct shape.
  std::map<const Shape*, std::shared_ptr<const ShapeGeometry>> geometries;
  im.bodies.resize(world_.bodies.size());
  for (std::size_t i = 0; i < world_.bodies.size(); ++i) {
    Body& b = world_.bodies[i];
    const std::string where = "/bodies/" + std::to_string(i);
    if (!b.shape) throw InputError(where + "/shape", "body has no shape");
    if (!b.state.x_W.allFinite() || !b.state.v_W.allFinite() || !b.state.w_W.allFinite() ||
        !b.state.q_WM.coeffs().allFinite()) {
      throw InputError(where, "non-finite initial state");
    }
    b.state.t = 0.0;
    if (b.motion == MotionKind::kKinematic) {
      // The state of a kinematic body at t = 0 follows from its prescribed motion.
      b.state.w_W = b.kinematic.angular_velocity_W;
      b.state.v_W = b.kinematic.velocity_W +
                    b.kinematic.angular_velocity_W.cross(b.state.x_W - b.kinematic.point_W);
    }
    auto& g = geometries[b.shape.get()];
    if (!g) g = std::make_shared<const ShapeGeometry>(b.shape);
    im.bodies[i].geometry = g;
  }
  for (std::uint32_t i = 0; i < world_.bodies.size(); ++i) im.refresh_box(BodyId{i}, 0.0);
  // Bodies may start touching (the racked pool balls sit inside each other's envelopes) but
  // never overlapping. Pairs in order (i, j), i < j, as the broad phase finds them.
  for (std::uint32_t i = 0; i < world_.bodies.size(); ++i) {
    im.find_overlaps(BodyId{i}, im.overlapping);
    for (std::uint32_t j : im.overlapping) {
      if (j < i) continue;
      PairCache cache;
      const Body& a = world_.bodies[i];
      const Body& b = world_.bodies[j];
      DistanceResult dr = closest_features(*im.bodies[i].geometry, Pose{a.state.x_W, a.state.q_WM},
                                           *im.bodies[j].geometry, Pose{b.state.x_W, b.state.q_WM},
                                           cache, world_.settings.distance_max_steps);
      if (dr.status == ContactStatus::kPenetrating) {
        throw InputError("/bodies/" + std::to_string(j),
                         "body \"" + b.name + "\" overlaps body \"" + a.name + "\" (/bodies/" +
                             std::to_string(i) +
                             ") at the start; bodies may touch but not interpenetrate");
      }
    }
  }
  for (std::uint32_t i = 0; i < world_.bodies.size(); ++i) im.refresh_broad_phase(BodyId{i}, 0.0);
  for (std::uint32_t index = 0; index < im.pairs.size(); ++index) {
    if (im.pairs[index].live) im.rebound(index, 0.0);  // each pair once
  }
  im.schedule_sample();
}

Simulation::~Simulation() = default;

BodyState Simulation::state_at(BodyId id, double t) const {
  return impl_->extrapolate(id, t);
}

void Simulation::run_until(double t_end, SimulationObserver* observer,
                           const std::function<void(double)>& progress) {
  Impl& im = *impl_;
  std::uint64_t since_progress = 0;
  while (!im.queue.empty() && im.queue.top().t <= t_end) {
    EventQueue::EventId id;
    const Event e = im.queue.pop(&id);
    PALPABLE_CHECK(e.t >= now_, "time ran backwards in the event queue");
    now_ = e.t;
    ++stats_.events;
    switch (e.kind) {
      case EventKind::kPairCheck: {
        PALPABLE_CHECK(e.owner < im.pairs.size() && im.pairs[e.owner].event == id &&
                           im.pairs[e.owner].a == e.a && im.pairs[e.owner].b == e.b,
                       "pair event without its pair");
        im.check_pair(e.owner, e.t, observer);
        break;
      }
      case EventKind::kHorizon:
        im.bodies[e.a.index].horizon_event = EventQueue::kNoEvent;
        im.commit(e.a, e.t);
        ++stats_.horizon_refreshes;
        im.refresh_body(e.a, e.t);
        break;
      case EventKind::kSample: {
        std::vector<BodyState> states(world_.bodies.size());
        for (std::uint32_t i = 0; i < states.size(); ++i) {
          states[i] = im.extrapolate(BodyId{i}, e.t);
          states[i].t = e.t;
        }
        ++stats_.samples;
        if (observer) observer->on_sample(e.t, states);
        ++im.next_sample;
        im.schedule_sample();
        break;
      }
    }
    if (progress && ++since_progress >= 4096) {
      since_progress = 0;
      progress(now_);
    }
  }
  now_ = std::max(now_, t_end);
}

}  // namespace palpable
