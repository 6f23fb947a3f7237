#pragma once
// Contact that persists (DESIGN.md §8.1-8.3): dynamic bodies held in contact, and their motion
// between events.
//
// A held contact (HeldLink) is kept in the two bodies' own frames: the support owns the contact
// plane (a face, or a halfspace), the mover touches it with a face, an edge, a vertex or a sphere.
// The bodies it joins form an island with the contacts among them; fixed and kinematic bodies
// bound it. Between events an island moves as its contact problem (impulse/contact_dynamics.hpp)
// says, in closed form where one exists:
//  - at rest: bodies that are still on fixed supports, in equilibrium inside their friction cones,
//    stay exactly where they are and cost nothing;
//  - uniformly accelerated: every body either does not turn or is a sphere, every plane is fixed
//    (or translates uniformly) and every slip keeps its direction - a block sliding on a ramp, a
//    sphere sliding or rolling on a plane, a box on a sliding block: x = x0 + v0 t + a t^2 / 2,
//    w = w0 + alpha t, and every event (a slip that stops, a centre of pressure that reaches the
//    edge of the support's face) is a root of a polynomial;
//  - rolling on a turntable: a sphere rolling on a plane turning at Omega about its normal
//    circles at k Omega / (1 + k) (2 Omega / 7 for a solid ball), exactly;
//  - otherwise integrated (Dormand-Prince 5(4), tolerance Settings::integration_tolerance) with
//    dense output, events located on the interpolant.
// An event is a mode change at its exact instant: a slip that stops (then sticks, or slides on in
// the unstable direction), sticking friction that reaches its cone, a contact that lets go, a
// centre of pressure that reaches its patch boundary (the body tips, or slides off its support),
// another vertex of a held body reaching the plane (it lands: a collision).
#include "core/body.hpp"
#include "core/dormand_prince.hpp"
#include "core/settings.hpp"
#include "distance/closest_features.hpp"
#include "distance/feature_mesh.hpp"
#include "impulse/contact_dynamics.hpp"
#include "scheduler/world.hpp"

#include <optional>
#include <vector>

namespace palpable {

// The plane's resolution, relative to the bodies' reach: a vertex this close to a held contact's
// plane is on it (an island's landing events), and a fall from this height is a landing that
// settles (Simulation's quiet landings).
inline constexpr double kPlaneResolution = 1e-9;

// A held contact, in the bodies' own frames (modelling frames M; S for the support's).
struct HeldLink {
  std::uint32_t pair = 0;  // the pair's slot (PairSet)
  BodyId mover, support;
  int support_piece = 0;  // which piece of a compound support holds it
  // > 0: the mover is rounded by this radius about a core: a sphere centred at its origin (no
  // feature), or a cylinder or capsule lying on its side (its feature is then the core, the
  // piece's axis: the contact line is the axis moved by the radius against the normal).
  double sphere_radius = 0.0;
  // The mover's contact feature: a face (counter-clockwise about the mover's outward normal),
  // an edge (2 points) or a vertex (1); empty for a sphere; the axis of a rounded side.
  std::vector<Vec3> mover_feature_M;
  // The support's face (counter-clockwise about normal_S); empty for a halfspace (unbounded).
  std::vector<Vec3> support_face_S;
  Vec3 normal_S = Vec3::UnitZ();  // the contact plane's outward normal, toward the mover
  Vec3 point_S = Vec3::Zero();    // a point of the plane
  Vec3 t1_S = Vec3::UnitX();      // a tangent fixed in the support: slip directions refer to it
  double gap = 0.0;               // the gap held [m] (the mover's feature above the plane)
  // The mover touches the plane with a point of a curved surface (an ellipsoid, a cylinder's
  // rim, a capsule's end, a loaded ball): found afresh at every state as the support point of
  // this smooth shape (the mover's piece, posed at piece_p_M, piece_R_M in its frame) against the
  // plane's normal; mover_feature_M is empty, sphere_radius 0. The shape is the body's geometry,
  // which outlives the link.
  const Shape* curved_shape = nullptr;
  Vec3 piece_p_M = Vec3::Zero();
  Mat3 piece_R_M = Mat3::Identity();
  // A cylinder's or capsule's curved link: the end held, +1 or -1 along the piece's z (the rim or
  // end cap the point lies on, kept even where the body stands level and rounding would pick the
  // other); 0 for other shapes.
  double curved_end = 0.0;
  // A round side's piece (sphere_radius > 0 about its axis): where the line tips about one of its
  // ends, the link goes on as a curved point of that end (curved_shape).
  const Shape* side_shape = nullptr;
  // Neither side offers a plane (two spheres, a sphere or a vertex on an edge, an edge across an
  // edge): a point contact along the line between the two features' closest points. The
  // support's feature is then in support_face_S (1 point, or 2 for an edge; empty for a sphere of
  // radius support_sphere_radius about its origin), and the normal turns with the features.
  bool point_pair = false;
  double support_sphere_radius = 0.0;
  // A point pair of a sphere and a polyhedron's vertex or edge: that feature's Voronoi planes
  // (V-Clip), in the polyhedron's body frame, >= 0 inside. While the sphere's centre is inside
  // them the feature is the polyhedron's closest to it, so the gap held is the bodies' gap; when
  // it leaves them (a ball pushing a turning pin passes from an edge over a face) the link lets
  // go, and the pair's check finds the feature that touches now. Empty: not watched.
  std::vector<VoronoiPlane> feature_region;
  // An edge of a polyhedron held across an edge of another: feature_region is the mover's
  // edge's Voronoi region (in its frame), watched at the support's closest point, and this the
  // support's edge's (in the support's frame), watched at the mover's. While both closest points
  // stay inside, they are the two convex bodies' closest points (V-Clip's condition), so nothing
  // else of either body can touch the other. Empty otherwise.
  std::vector<VoronoiPlane> support_region;
  // Modes, carried from one plan to the next (see HeldContact).
  bool sticks = true;
  Vec2 slip_dir = Vec2::UnitX();
  bool spin_sticks = true;
  double spin_sign = 1.0;
  bool roll_sticks = true;
  Vec2 roll_dir = Vec2::UnitX();
};

// One side of a link at this instant.
struct LinkSide {
  const Body& body;
  const ShapeGeometry& geometry;
  const BodyState& state;
};

// The link of a pair to be held, from the query at its collision: which body owns the plane (a
// face or a halfspace facing the other body), and the other's contact feature; where neither side
// offers a plane, the two features of a point contact. nullopt for two parallel edges without a
// plane (held by neither rule: they stay collisions), and for a curved surface touching along a
// point or a line against anything but a plane (a smooth shape other than a cylinder's flat cap,
// a loaded ball): it stays a train of microcollisions. A curved point on a plane is held with
// the point found afresh from the shape (curved_shape); a cylinder's or capsule's side lying on a
// plane is held like a sphere about its axis (sphere_radius). `envelope` [m]: a rim within the
// landing level of its cap or its other rim is not held (see Island's landing events).
std::optional<HeldLink> make_held_link(std::uint32_t pair, BodyId a, BodyId b,
                                       const LinkSide& side_a, const LinkSide& side_b,
                                       const DistanceResult& closest,
                                       const ContactGeometry& geometry, double envelope);

// The plane and the patch of a link at the given states, in the world: the reference point c (the
// patch's centroid, on the mover's feature), the frame, and the patch (the mover's feature
// intersected with the support's face, projected on the plane). Empty `polygon` and kPoint for a
// single point. Returns false if the patch vanished (the mover left the support's face).
bool place_link(const HeldLink& link, const BodyState& mover, const BodyState& support,
                HeldContact& out);

// How far a polyhedral mover's held feature (mover_feature_M) is above the link's plane at the
// given states: its lowest point [m]; +inf for a link without one (a sphere, a curved point).
double held_feature_height(const HeldLink& link, const BodyState& mover, const BodyState& support);

// A support's edge watched against one of a held mover's edges (Island::integrate's landing
// event): their half-edges in the two pieces' meshes, their common normal when they were chosen
// (in the world, pointing out of the support), and the threshold their separation along it must
// stay above (edge_watch_candidates: the separation).
struct EdgeWatch {
  int support_edge, mover_edge;
  Vec3 axis_W;
  double threshold;
};

// The pairs of edges a held link watches besides its vertices, each with its present separation:
// an edge of the support and an edge of the mover (not one whose both ends are `held_vertex`,
// the feature held, whose leaving the patch the tip event watches) whose lines pass within
// `envelope` of each other at points inside both edges, at least 1e-3 rad from parallel, and
// whose common normal lies in both edges' normal cones (a Minkowski face: along it, the
// separation of the two edges is the two pieces' separation near there, negative where they
// cross). These are the crossings that no vertex watch sees: neither body's vertex enters the
// other. Both pieces are posed in the world (rotation and origin of the piece's frame).
std::vector<EdgeWatch> edge_watch_candidates(const ShapeGeometry::Piece& mover, const Mat3& R_mover,
                                             const Vec3& origin_mover,
                                             const std::vector<bool>& held_vertex,
                                             const ShapeGeometry::Piece& support,
                                             const Mat3& R_support, const Vec3& origin_support,
                                             double envelope);

// The separation of a watched pair of edges along their common normal now, oriented as the
// watch's axis (out of the support: negative where they cross; the cross product of the edges
// reverses where they turn through parallel, the axis does not); +inf where the normal has
// turned more than 60 degrees from the axis, or the edges are parallel (not the configuration
// chosen: the faces' and vertices' watches cover it). Both meshes posed in the world.
double edge_separation(const FeatureMesh& support, const Mat3& R_support,
                       const Vec3& origin_support, const FeatureMesh& mover, const Mat3& R_mover,
                       const Vec3& origin_mover, const EdgeWatch& watch);

// The edge of a link's support face (support_face_S, in the world at `support`) on which all
// `points` lie, measured within the link's plane (along its normal), to 1e-9 of the face's size;
// -1 if none (or the support offers no face). A reduced patch on such an edge tips the mover over
// the support's edge: the link's roles turn round.
int support_edge_under(const HeldLink& link, const BodyState& support,
                       const std::vector<Vec3>& points);

// At a plan made by a stop: every other sliding component (slip, spin about the normal, rolling)
// of `contacts` that decelerates so fast that, under the modes it has, it would stop within
// `resolution` seconds (the scheduler's progress floor) is marked stopped too (slip_stopped,
// spin_stopped, roll_stopped), so that its modes are chosen from rest together with the one
// that stopped. Components at rest, accelerating, or further from their stop are left alone.
void stop_imminent(const std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts,
                   double resolution);

// The event that ends an island's present motion.
struct IslandEvent {
  enum class Kind : std::uint8_t {
    kNone,
    kSlipStop,    // a sliding contact's slip reached zero
    kSpinStop,    // a spinning patch stopped turning about its normal
    kRollStop,    // a rolling contact with rolling resistance stopped rolling
    kSlipStart,   // sticking friction (or torsion, rolling resistance) reached its bound
    kLiftOff,     // a contact's normal force reached zero
    kTip,         // a centre of pressure reached its patch's boundary
    kLanding,     // another vertex of a held body reached the support plane
    kSegmentEnd,  // the integrated motion's segment ended (re-plan, re-bound)
    kChunkEnd,    // an integrated motion's chunk ended: it goes on (extend), re-bound
  };
  Kind kind = Kind::kNone;
  int link = -1;
};
const char* to_string(IslandEvent::Kind kind);

// Bodies held together and their motion from t0.
class Island {
 public:
  enum class Motion : std::uint8_t { kRest, kUniform, kTurntable, kIntegrated };

  std::vector<BodyId> bodies;
  std::vector<HeldLink> links;

  // The motion from t0 and when it ends.
  double t0 = 0.0;
  Motion motion = Motion::kRest;
  double t_end = kInfinity;  // the next event's time
  IslandEvent event;
  double last_event_t = -kInfinity;  // when its last event was (no progress: counted)
  // The event that makes the next plan (set by the loop when the motion reaches `event`; plan()
  // reads and clears it). A plan after a collision or a hold has none.
  IslandEvent trigger;
  // Its motions that ended within 1e-3 of the progress floor of the one before, in a row, and the
  // pairs whose links' events ended them (Simulation: past 50, those contacts let go).
  int stalls = 0;
  std::vector<std::uint32_t> stall_pairs;
  // Held contacts joined it at this instant and it has not been planned since: its plan waits
  // for an island event at that instant, after the instant's pair checks (so contacts that meet
  // together, a stack placed touching, are planned together, not one by one).
  bool plan_pending = false;

  // What plan() found.
  struct PlanResult {
    std::vector<std::uint32_t> released;  // pairs of the links that let go (removed from links)
    double projection_energy = 0.0;       // kinetic energy the velocity projection took out [J]
    bool inconsistent = false;            // the contact problem had no solution (counted)
  };

  // Plans the motion from time t: the bodies' states are read from the world (committed at t);
  // their velocities are projected onto the held constraints and written back; the modes are
  // chosen; links that let go are removed; the motion and its next event are found.
  PlanResult plan(World& world, const std::vector<const ShapeGeometry*>& geometry, double t);

  // Goes on with the integrated motion whose chunk ended at time t (IslandEvent::kChunkEnd) from
  // the bodies' states there, read from the world (committed at t), with the same links and
  // modes: nothing is projected and no mode is chosen again - the motion is the one the plan
  // found, integrated a chunk at a time.
  void extend(const World& world, const std::vector<const ShapeGeometry*>& geometry, double t);

  // What the present motion's integration cost (Motion::kIntegrated; zero otherwise):
  // Dormand-Prince steps accepted and rejected, and whether the contact problem broke down along
  // the way (the motion then ends early, where it last held).
  struct IntegrationCount {
    std::uint64_t steps = 0, rejected = 0;
    bool failed = false;
  };
  IntegrationCount integration;

  // A body's state at time t >= t0 (index into `bodies`).
  BodyState state_at(std::size_t k, double t) const;
  // Index of `id` in `bodies`, or -1.
  int index_of(BodyId id) const;
  // The body's acceleration over the present motion, as a bound for time-of-impact bounds:
  // nominal acceleration and the most the true one can differ from it [m/s^2], and a bound on
  // |w| [rad/s].
  struct MotionBound {
    Vec3 a_W = Vec3::Zero();
    Vec3 alpha_W = Vec3::Zero();  // the angular acceleration now [rad/s^2]
    double a_slack = 0.0;
    double w_bound = 0.0;
    // How far the angular acceleration may depart from alpha_W over the motion [rad/s^2]: 0
    // where it is constant; an integrated motion's, from its stages as a_slack.
    double alpha_slack = 0.0;
  };
  MotionBound bound(std::size_t k) const;
  // The body's acceleration now (the nominal of bound()).
  const Vec3& acceleration(std::size_t k) const { return bounds_[k].a_W; }
  const Vec3& angular_acceleration(std::size_t k) const { return bounds_[k].alpha_W; }

 private:
  void classify(const World& world, const std::vector<const ShapeGeometry*>& geometry,
                const std::vector<HeldContact>& contacts, const HeldSolution& solution);
  void find_uniform_event(const World& world, const std::vector<HeldContact>& contacts,
                          const HeldSolution& solution);
  // From anchor_ at t0; `extending`: a chunk of the motion planned before (extend()), which keeps
  // its speed scale and slip floor.
  void integrate(const World& world, const std::vector<const ShapeGeometry*>& geometry,
                 bool extending = false);
  Quat orientation_at(std::size_t k, double t) const;
  Vec3 angular_velocity_at(std::size_t k, double t) const;

  std::vector<BodyState> anchor_;  // states at t0
  std::vector<Vec3> a_, alpha_;    // kUniform
  // kTurntable: the sphere's centre circles c + R(rate t) (x0 - c) in the plane.
  Vec3 turn_axis_ = Vec3::UnitZ();
  Vec3 turn_centre_ = Vec3::Zero();
  double turn_rate_ = 0.0;
  Vec3 turn_w_ = Vec3::Zero();  // the platter's angular velocity
  Vec3 turn_point_ = Vec3::Zero();
  double radius_ = 0.0;
  // kIntegrated: the accepted steps of the segment.
  std::vector<dopri5::Step> steps_;
  // A clocked step's last component is the time since its start times this speed [m/s].
  double clock_scale_ = 1.0;
  // The step the controller proposed after the island's last accepted step [s] (0: none yet):
  // where the next integrated motion starts. (From 1 ms each time, the piles' motions spent 4.6
  // rejected steps a motion finding their scale again: 12,628 of 28,546 rejections.)
  double step_hint_ = 0.0;
  // The integrated motion's slip floor [m/s] (Island::integrate): below it a slip, spin or
  // rolling is at rest to what the motion resolves.
  double slip_floor_ = 0.0;
  double speed_scale_ = 1.0;  // the integrated motion's speed scale [m/s] (Island::integrate)
  // Steps the integrated motion rejected since its plan, over all its chunks: past 1000 it breaks
  // down and is planned again. (Counted per chunk, a motion chattering in steps of 3e-9 s, two
  // rejected to one taken, went on for ever, 600 rejections a chunk: 50 hulls, seed 14.)
  std::uint64_t motion_rejected_ = 0;
  // When the present motion was planned (plan(); extend() keeps it): its integration ends, to be
  // planned again, a broad-phase horizon after that.
  double planned_t_ = 0.0;
  std::vector<MotionBound> bounds_;
  std::vector<bool> turning_;  // kUniform: w0 and alpha not parallel (orientation integrated)
  // Orientation of a sphere whose angular velocity turns (kUniform with w0 not parallel to alpha,
  // kTurntable): integrated on demand and cached at the last time asked for.
  mutable std::vector<std::pair<double, Quat>> orientation_cache_;
};

}  // namespace palpable
