#pragma once
// Contact that persists (DESIGN.md §8.1-8.3): dynamic bodies held in contact, and their motion
// between events.
//
// A held contact (HeldLink, scheduler/held_link.hpp) is kept in the two bodies' own frames: the
// support owns the contact plane (a face, or a halfspace), the mover touches it with a face, an
// edge, a vertex or a sphere.
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
#include "impulse/contact_dynamics.hpp"
#include "scheduler/held_link.hpp"
#include "scheduler/world.hpp"

#include <utility>
#include <vector>

namespace palpable {

// The plane's resolution, relative to the bodies' reach: a vertex this close to a held contact's
// plane is on it (an island's landing events), and a fall from this height is a landing that
// settles (Simulation's quiet landings).
inline constexpr double kPlaneResolution = 1e-9;

// At a plan: every sliding component (slip, spin about the normal, rolling) of `contacts` that
// decelerates under the modes it has, resisted against its present direction, and would stop
// within `resolution` seconds (at a plan made by a stop: the scheduler's progress floor) is
// marked stopped (slip_stopped, spin_stopped, roll_stopped), so that its modes are chosen from
// rest together with the rest of the island's; and so is every decelerating slip and rolling
// that moves no faster than `floor` (m/s at the contact; a rolling at its point's size): the slip
// floor of the motion the plan starts, below which that motion could not resolve it. (Not a
// spin: stopped at that floor too, at its island's size as its events judge it, 24 piles of 50
// hulls took 1.5 times the CPU.) Components at rest, accelerating, or further from their stop
// are left alone.
void stop_imminent(const std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts,
                   double resolution, double floor = 0.0);

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
  // Each body's links, with the body at each one's other end (-1: outside the island).
  using LinksByBody = std::vector<std::vector<std::pair<int, int>>>;
  // `touching`: links_by_body(), or empty until a face needs it (filled then).
  void find_uniform_event(const World& world, const std::vector<HeldContact>& contacts,
                          const HeldSolution& solution, LinksByBody& touching);
  LinksByBody links_by_body() const;
  // How the centre of pressure of links[i] moves over a uniform motion (in the plane; its
  // velocity and acceleration), and whether it rides on the mover: with the side of the link
  // that it alone holds (without it, joined to nothing fixed or kinematic), the mover's where
  // both are such (where neither is, it is taken to ride on the mover).
  struct PressureMotion {
    Vec3 v_W = Vec3::Zero();
    Vec3 a_W = Vec3::Zero();
    bool on_mover = true;
  };
  PressureMotion pressure_motion(const World& world, const std::vector<HeldContact>& contacts,
                                 const HeldSolution& solution, std::size_t i,
                                 const LinksByBody& touching) const;
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
