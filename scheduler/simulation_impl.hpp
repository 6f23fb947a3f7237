#pragma once
// The private state and operations of Simulation (scheduler/simulation.hpp), shared by the files
// that implement it:
//   simulation.cpp          the loop: the event queue, pairs and their bounds, samples
//   simulation_collide.cpp  collisions: a pair's check, riders, the contact model's resolution
//   simulation_hold.cpp     persistent contact: holding, islands, their events
// State has one owner: the world (bodies and committed states), the queue, the pairs and the
// statistics live here; the contact model (scheduler/contact.hpp) and the islands
// (scheduler/island.hpp) see values only. Not installed; no other module includes it.
#include "core/ballistic.hpp"
#include "distance/impact_instant.hpp"
#include "distance/toi_bound.hpp"
#include "impulse/microcollision.hpp"
#include "scheduler/contact.hpp"
#include "scheduler/island.hpp"
#include "scheduler/pair_set.hpp"
#include "scheduler/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <vector>

namespace palpable {

struct Simulation::Impl {
  World world;
  SimulationOptions options;
  SimulationStats stats;
  double now = 0.0;
  // The progress guard: events processed since the clock last moved past `stall_until` (a window
  // of kStallResolution of the time). Too many means the run can no longer advance (Zeno, or a
  // clock whose increments round away): it stops with an error naming the pair and the time.
  double stall_until = -1.0;
  std::uint64_t stall_events = 0;
  EventQueue queue;
  PairSet pairs;
  std::uint64_t next_sample = 0;
  SimulationObserver* observer = nullptr;  // of the step being processed

  // Persistent contact (scheduler/island.hpp): islands of held bodies, in slots.
  std::vector<Island> islands;
  std::vector<EventQueue::EventId> island_events;  // per slot
  std::vector<bool> island_live;                   // per slot
  std::vector<std::uint32_t> free_islands;
  std::vector<int> island_of;                    // per body: its island slot, or -1
  std::vector<const ShapeGeometry*> geometries;  // per body

  Impl(World w, SimulationOptions o)
      : world(std::move(w)), options(o), queue(o.queue), pairs(world, queue, stats) {}

  const Settings& settings() const { return world.settings; }
  Body& body(BodyId id) { return world.bodies[id.index]; }
  const Body& body(BodyId id) const { return world.bodies[id.index]; }

  bool persistent() const { return settings().contact_model == ContactModel::kPersistent; }
  const Island* island(BodyId id) const {
    const int i = island_of.empty() ? -1 : island_of[id.index];
    return i >= 0 ? &islands[static_cast<std::size_t>(i)] : nullptr;
  }
  // A dynamic body no island holds: it flies on its closed-form trajectory.
  bool in_free_flight(BodyId id) const { return body(id).is_dynamic() && !island(id); }

  // Is pair `index` one of the held links of its bodies' island?
  bool held_link(std::uint32_t index) const {
    const PairSet::Pair& p = pairs.pair(index);
    const Island* is = island(p.a) ? island(p.a) : island(p.b);
    return is && std::any_of(is->links.begin(), is->links.end(),
                             [&](const HeldLink& link) { return link.pair == index; });
  }

  // The island of a held body whose motion is planned, or null (free flight: not held, or held
  // at this instant and its plan pending).
  const Island* planned_island(BodyId id) const {
    const Island* is = island(id);
    return is && !is->plan_pending ? is : nullptr;
  }

  BodyState extrapolate(BodyId id, double t) const {
    const Body& b = body(id);
    if (t <= b.state.t) return b.state;
    if (const Island* is = planned_island(id)) {
      return is->state_at(static_cast<std::size_t>(is->index_of(id)), t);
    }
    return advance(b, b.state, t, world.gravity_W, settings());
  }
  void commit(BodyId id, double t) {
    Body& b = body(id);
    if (t > b.state.t) b.state = extrapolate(id, t);
  }
  // The body as the contact model sees it. A held body carries its island's accelerations (one
  // lookup of it in the island, whose list is searched); free flight, none. A body held at this
  // instant whose island's plan is pending counts as held still (zero, without rotation): it was
  // just stopped along its contact, and what touches it now meets it (hold()).
  ContactSide side(BodyId id, const BodyState& s) const {
    static const Vec3 kStill = Vec3::Zero();
    ContactSide out{id, body(id), pairs.geometry(id), s};
    if (const Island* is = island(id)) {
      if (is->plan_pending) {
        out.acceleration_W = &kStill;
      } else {
        const std::size_t k = static_cast<std::size_t>(is->index_of(id));
        out.acceleration_W = &is->acceleration(k);
        out.angular_acceleration_W = &is->angular_acceleration(k);
      }
    }
    return out;
  }

  // ---------------------------------------------------------------- pairs and bounds

  void refresh_broad_phase(BodyId id, double t);

  // After a collision: the boxes and pairs of every dynamic body it moved (the pair's and the
  // riders it carried), then every pair of those bodies re-bounded once. A fixed body's box never
  // changes, and every dynamic body overlapping it was paired with it at that body's own last
  // refresh, so refreshing a fixed body would change nothing - but cost a scan of every dynamic
  // body for a halfspace, whose box is infinite: it is skipped. So for a kinematic body, whose
  // box follows only time (its horizon event keeps it current).
  void refresh_after_collision(const CollisionRecord& r, double t);
  // Bodies whose motion changed at t (a collision, a plan, an integrated motion's next chunk):
  // their swept boxes and every pair of theirs are bounded again.
  void refresh_moved(const std::vector<BodyId>& moved, double t);
  // What an island's present motion (or chunk of it) cost to integrate, into the statistics.
  void count_integration(const Island& is);

  void schedule_pair(std::uint32_t index, double t_next);

  // The least step a pair's next check may take at time t [s] (core/settings.hpp).
  double progress_floor(double t) const { return derived_progress_floor(settings(), t); }

  DistanceResult query(PairSet::Pair& p, const BodyState& s1, const BodyState& s2);

  // Is piece result r of pair p held (a compound's piece on which a link of p rests)? A pair
  // with a compound keeps its events for its other pieces (a ball held on the floor of a table
  // still meets its cushions); a plain held pair has none.
  bool held_piece(const PairSet::Pair& p, const DistanceResult& r) const;

  // The piece-pair result a collision would be resolved at: `dr` itself, or, for a pair with a
  // compound, the piece within the envelope approaching fastest (a ball in a crease touches two
  // pieces; the closest may be the one it is leaving), else the closest piece; held pieces
  // never.
  const DistanceResult& contact_result(const PairSet::Pair& p, const BodyState& s1,
                                       const BodyState& s2, const DistanceResult& dr) const;

  // A pair whose held contact let go at this very instant, not truly approaching (its contact
  // is only pressed by the gravity that no longer holds it: a ball leaving a table's edge).
  static bool lifting(const PairSet::Pair& p, const Contact& c, double t);

  // How a body moves over the coming interval, for a bound: free flight, or its island's motion.
  // A held body's motion bound from its island, its angular-speed bound taken to its broad-phase
  // horizon where the island's has no end.
  Island::MotionBound held_bound(const Island& is, BodyId id, const BodyState& s) const;
  ToiMotion motion_for(BodyId id, const BodyState& s, const BodyState& other,
                       BodyId other_id) const;

  // The conservative bound of a pair with a held body (never exact: no closed form follows a held
  // body's motion). `halve_gap`: within the envelope, moving apart or at rest against a fixed
  // body; aimed at half the gap it has left instead of half the envelope.
  ToiBound held_time_of_impact(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                               const DistanceResult& dr, bool halve_gap) const;
  // A polyhedral body of a planned island above a fixed halfspace: when one of its vertices can
  // first come within d_target of the plane (vertex_bound_above_plane, with the island's bounds
  // on the body's motion); -1 if the pair is not of this kind.
  double held_vertex_bound(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                           double d_target) const;
  // A pair whose closest features are a vertex and a face, of polyhedra, where the face's body
  // moves too: when a vertex of the one can first come within d_target of the other's face plane
  // (vertex_bound_above_face, each body's motion bounded by its island, as in free flight, or
  // not moving if fixed); -1 if the pair is not of this kind.
  double held_face_bound(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                         const DistanceResult& dr, double d_target) const;

  // The next event time of a pair from its closest features at time t.
  // `known`: the contact check_pair already made of this very query and found not approaching
  // (saves making it again); null to make it here.
  double next_check_time(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                         const DistanceResult& dr, double t, const Contact* known = nullptr);

  void rebound(std::uint32_t index, double t);

  // ---------------------------------------------------------------- collisions

  // The dynamic bodies riding on body `id` at time t: resting on it (within two envelopes, a
  // microcollision bounces a body up to 1.5; the normal within 60 degrees of the vertical;
  // at rest on it along the normal or settling onto it slower than the microcollision speed),
  // and those riding on them, up to kMaxRiderDepth levels. Appended to `riders` (no repeats),
  // each with the body it rests on appended to `supports`.
  void collect_riders(BodyId id, double t, int depth, std::vector<BodyId>& riders,
                      std::vector<BodyId>& supports);

  // Is body `id`'s rotation held at time t by a face of its own resting on a fixed or kinematic
  // support (a face-on-face contact within two envelopes - a microcollision train bounces a
  // body up to 1.5 - its normal within 60 degrees of the
  // vertical, not rocking), directly or through dynamic bodies stacked face on face below it, up
  // to kMaxRiderDepth levels? `above`: the body on top of it, not a support.
  bool seated(BodyId id, BodyId above, double t, int depth);
  // Sets a contact's rotation_held flags (a face on a face between two dynamic bodies).
  void mark_held_rotations(const PairSet::Pair& p, Contact& c, double t);

  // Resolves the collision of contact `c` (of pair `p`, states committed at t), commits the new
  // velocities and returns the record.
  CollisionRecord collide(const PairSet::Pair& p, Contact& c, double t,
                          const ResolveOptions& options = ResolveOptions{});

  // The touching gap of pair p [m]: kTouchingGap times the sum of its bodies' finite reaches.
  double touching_gap(const PairSet::Pair& p) const;

  // The instant pair p's gap closes, from states s1, s2 at the same time with closest features
  // dr (the query that filled `cache`): distance/impact_instant.hpp, counted in the statistics.
  ImpactInstant refine_instant(const PairSet::Pair& p, const BodyState& s1, const BodyState& s2,
                               const DistanceResult& dr, const PairCache& cache);

  // The time from t until the gap of an impact (an approach faster than v_micro) closes [s]:
  // exact for spheres against spheres and planes, followed along the trajectories otherwise
  // (refine_instant). 0: collide now (touching already, a microcollision, a held body, a
  // kinematic body, or kMaxApproachSteps spent). `dr`: the pair's query; `contact`: its piece
  // the collision would be resolved at (contact_result).
  double time_to_contact(PairSet::Pair& p, const Contact& c, const DistanceResult& dr,
                         const DistanceResult& contact, double t);

  // Two bodies in free flight left touching (within the touching gap) and parting slower than
  // the microcollision speed are parted at it by a frictionless impulse along the normal: a
  // microcollision, recorded as one (momentum kept, energy raised by at most the floor's
  // 1/2 m v_micro^2). Nothing else moves such a pair on: near contact the free-flight bound
  // aims at half the gap with the rotation's closing speed (|w| r ~ 0.1 m/s for a tumbling
  // hull), so a pair left 1e-13 m apart and parting at 4e-8 m/s was checked every 1e-12 s,
  // 1.8 million times (100 hulls, seed 1). So too a body in free flight and a body held by a
  // planned island (parted at the hand-over speed; the island is planned again from its body's
  // new velocity): a hull let go by a hull held on the floor, parting at 2e-5 m/s, hopped 5e-11 m
  // and was checked 750,000 times in 10 us (50 hulls, seed 4). Returns the record, or nullopt if
  // it does not apply.
  std::optional<CollisionRecord> part_free_pair(const PairSet::Pair& p, const Contact& c,
                                                const DistanceResult& contact, double t);
  // Holds pair `index`, touching a body held at this instant and neither approaching nor
  // parting, with that body's pending plan. Returns whether it did.
  bool join_pending_plan(std::uint32_t index, const Contact& c, const DistanceResult& contact,
                         double t);
  // A pair's event: collide if within the envelope and approaching — an impact at the instant
  // its gap closes —, else re-bound. Returns the collision, if any.
  std::optional<CollisionRecord> check_pair(std::uint32_t index, double t);

  // Simultaneous impact (issue 15, impulse/group_impulse.hpp): the contacts that meet pair
  // `index`'s collision at instant t with an impact's approach (faster than the microcollision
  // speed) - the corners of a face landing on a dynamic face, and the contacts of every pair of
  // the collision's dynamic bodies within the envelope - resolved as one group when there are
  // two or more. Returns nothing (and changes nothing) for a single contact, or under the
  // microcollision model when a body is held: the pair's own collision path then resolves it.
  // `dr` is the pair's contact query. Under the persistent model the held contacts of the
  // struck bodies on fixed supports are members too (plastic, at each point of their patch, not
  // held again), and the group's other contacts go on as a lone collision's would
  // (collide_or_hold): held if they leave slowly, else their islands planned again.
  std::optional<CollisionRecord> collide_group(std::uint32_t index, const Contact& c,
                                               const DistanceResult& dr, double t);

  // ---------------------------------------------------------------- persistent contact

  void report(const char* kind, BodyId a, BodyId b, const Vec3& p_W, double t);

  // Under the persistent contact model (DESIGN.md §8.1): the collision is integrated with the
  // material's restitution and no rebound floor (plastic if it arrives slower than the
  // microcollision speed: what would have started a microcollision train); if the contact then
  // separates slower than the microcollision speed, it is held. A contact whose features offer no
  // plane (two spheres, a sphere on an edge) cannot be held: it stays a microcollision train, as
  // under Mirtich's model. Nothing (no collision) where the touch is held without an impulse.
  std::optional<CollisionRecord> collide_or_hold(std::uint32_t index, Contact& c,
                                                 const DistanceResult& dr, double t);

  // The collide_or_hold round of pair `p` at instant t: how many times it collided there before.
  static int collision_round(const PairSet::Pair& p, double t) {
    return t == p.last_collision_t ? p.collisions_at_t : 0;
  }
  // The round its collision at t counts as for holding it: its collision round, or how many of
  // its collisions in a row were its held face landing back on the plane slower than
  // settle_speed, whichever is more. A bowling pin's hull, held on a facet tilted within the
  // envelope, tipped about an edge of it clear of the lane and landed back every 1.06e-6 s at
  // 3e-8 m/s, each round 2e-12 of its size lower (the landing event's tolerance), until it
  // overlapped the lane; from the fourth such round it is a microcollision, whose rebound floor
  // lifts it clear, as a train at one instant. Holds that let go at once (or within the progress
  // floor of their collision) count the same way: a coin struck where its gap closed, held and
  // let go at that instant (its plan lifting what the next check finds approaching at g times a
  // clock tick) went round 488,000 times in 10 s of CPU, at last a clock tick (1e-12 t) apart.
  static int hold_round(const PairSet::Pair& p, double t) {
    return std::max({collision_round(p, t), static_cast<int>(p.quiet_landings),
                     static_cast<int>(p.quick_releases)});
  }
  // The speed of a fall from the plane's resolution (kPlaneResolution of the larger dynamic
  // body's reach, the height at which an island's landing events take a vertex as on the plane).
  double settle_speed(const PairSet::Pair& p) const;
  // The dynamic bodies of pair `p` whose collision at t ends a rocking train (collide_or_hold):
  // from its fourth quiet landing in a row, before its eighth, not at a quick round - the one
  // on a fixed support, or both of two dynamic bodies. None otherwise (a kinematic support).
  std::vector<BodyId> zeno_end_bodies(const PairSet::Pair& p, double t) const;
  // The larger reach of the pair's dynamic bodies [m] (0 if neither is dynamic).
  double dynamic_reach(const PairSet::Pair& p) const;
  // The hand-over speed of a contact: the microcollision speed of the bodies' weight along the
  // normal (a held body's acceleration may be zero, its weight is not). A collision that leaves
  // the contact slower is held.
  double hand_over_speed(const Contact& c) const {
    return std::max(c.v_micro,
                    microcollision_speed(settings(), std::abs(world.gravity_W.dot(c.n_W))));
  }

  // The link that would hold pair `index`'s contact (closest features `dr`, states at t).
  std::optional<HeldLink> link_of(std::uint32_t index, const DistanceResult& dr) const;

  // A collision changed the velocities of these bodies: islands re-plan, free bodies re-bound.
  void after_collision(const CollisionRecord& record, double t);

  // Holds the contact of pair `index` (states committed at t): its link joins the island of its
  // dynamic bodies. A contact `struck` (held after an impact, not a gentle landing) is lifted to
  // the plane's resolution first (raise_to_resolution).
  void hold(std::uint32_t index, HeldLink link, const DistanceResult& dr, double t,
            bool struck = false);
  // A polyhedron on a fixed or kinematic support (held, or just let go) `gap` above its plane,
  // within the plane's resolution of it above or below, is moved along the normal to that
  // resolution above it (see the definition). Returns the gap it leaves.
  double raise_to_resolution(const HeldLink& link, double gap);

  // The island holding all of `ids` (dynamic bodies): theirs merged, or a new one.
  std::uint32_t join(const std::vector<BodyId>& ids, double t);

  std::uint32_t new_slot();

  void release_slot(std::uint32_t i);

  // Plans island i's motion from time t (after a collision, a hold or one of its events), then
  // splits it where its links no longer connect it, frees bodies held by nothing, queues its next
  // event and refreshes its bodies' boxes and bounds.
  void replan(std::uint32_t i, double t);
  // Pair `index`'s held contact let go at t (a plan released it, or its island stalled): it is
  // lifted, counted as a quick release if it came within the progress floor of its collision,
  // and reported. Its link is already out of its island; part_released follows the plan.
  void note_release(std::uint32_t index, double t);
  // After a release: a pair let go overlapping by its held motion's drift is parted.
  void part_released(std::uint32_t index, double t);

  // Splits island k into the components its links connect; bodies no link holds leave it (free
  // flight from their state at t). Returns the new islands (to be planned); island k keeps the
  // component of its first link.
  std::vector<std::uint32_t> split(std::uint32_t k, double t, bool& changed);

  void schedule_island(std::uint32_t i, double t);
  // Plans island i by an island event at t, after the pair checks at t (Island::plan_pending).
  void defer_plan(std::uint32_t i, double t);
  // Island i's event at time t (pushed, or moved there).
  void put_island_event(std::uint32_t i, double t);

  // Island i's motion reached its next event at time t: a mode change.
  void island_event(std::uint32_t i, double t);

  // ---------------------------------------------------------------- the loop

  void schedule_sample();

  void sample(double t, SimulationObserver* observer);

  // Bodies may start touching (the racked pool balls sit inside each other's envelopes) but never
  // overlapping, and only with finite states.
  void validate_start();

  void start();

  StepResult step(double t_end, SimulationObserver* step_observer);
  // Throws InputError "t = <time> s": the clock stopped advancing, naming the last event's bodies.
  [[noreturn]] void report_stall(const Event& e) const;

  // The progress guard's window, relative to the time (1e-12 is some 4,500 ulps of the clock),
  // and how many events it may hold: a valid run moves past it long before.
  static constexpr double kStallResolution = 1e-12;
  static constexpr std::uint64_t kStallEvents = 1000000;
  static constexpr std::uint64_t kStallEventsPerBody = 1000;
};

}  // namespace palpable
