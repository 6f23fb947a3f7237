#pragma once
// The contact model (DESIGN.md §4): what two bodies touching within the envelope are to each
// other, and what a collision between them does. Values in, values out: the event loop finds the
// pair's closest features, builds a Contact here, asks whether it approaches, resolves it here,
// and commits the new velocities this returns. Nothing here reads or changes the simulation's
// state, so every rule can be tested with hand-built bodies and states.
//
// Where the impulse acts (Placement, chosen once per contact by make_contact):
//  - a point: the closest point, or over a patch the corner approaching fastest;
//  - a dynamic sphere: its contact point, with its slip taken at its centre's motion;
//  - a face on a face (a dynamic body on a fixed or kinematic one, touching over a polygon and
//    not rocking): the centre-of-pressure rule - the impulse's line of action passes through the
//    centre of mass, so a sliding block does not rock from corner to corner; where that line
//    leaves the patch the body really tips, about the patch boundary;
//  - an edge on a face (a segment patch): only the rotation about n x s is held, so a rod or a
//    coin on its rim still rolls and tips about the segment; so too a body turning about one
//    edge of a polygon patch onto the rest of it (a prism rolling onto its next face): it lands
//    along the opposite edge, the corner landing first and its neighbour, held as a segment
//    unless one leads the other by more than the microcollision speed;
//  - a face on a face between two dynamic bodies (a stack; DESIGN.md §4's last case): the patch
//    holds their relative rotation - the pressure carries the couple that keeps the faces
//    parallel - so both turn alike, by (I1 + I2)^-1 (x2 - x1) x p, whatever the point
//    (impulse/collision_matrix.hpp, held_rotation_response); a body whose own face rests on a
//    fixed or kinematic support (rotation_held, set by the event loop) turns neither. The
//    centre of pressure is where that couple puts the impulse; outside the patch the body tips
//    about its boundary, as over a fixed face.
//
// A collision is resolved in named stages (resolve): effective inertia (the rule's constraint on
// rotation) -> impulse (integration over p_z, or a microcollision) -> locate the pressure (at
// most one move: along a segment to where its torque vanishes, or to the tipping point) -> apply
// the impulse and the couples a point impulse cannot carry, and record.
//
// Frames: world (_W); the contact normal n_W points from body 2 to body 1; body 1 is the pair's
// lower id. Units SI.
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"
#include "distance/closest_features.hpp"
#include "impulse/collision_integrator.hpp"
#include "impulse/collision_matrix.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace palpable {

enum class CollisionKind : std::uint8_t { kCollision, kMicrocollision };

// One resolved collision, in the world frame.
struct CollisionRecord {
  double t = 0.0;
  CollisionKind kind = CollisionKind::kCollision;
  BodyId a;                       // body 1 of the pair (the lower id)
  BodyId b;                       // body 2
  Vec3 p_W = Vec3::Zero();        // contact point [m]
  Vec3 n_W = Vec3::UnitZ();       // contact normal, from b to a
  Vec3 impulse_W = Vec3::Zero();  // impulse on a [N s] (b receives the opposite)
  double approach_speed = 0.0;    // -u_n before the collision [m/s]
  double energy_change = 0.0;     // kinetic energy of the two bodies after minus before [J]
  bool centre_of_pressure = false;
  // What the impulse integration saw (impulse/collision_integrator.hpp), for the record only: its
  // phases in order (slid, stuck stably, resumed sliding, ...; at most one resumes sliding, in
  // the direction `resumed_direction_W`), the tangential relative contact velocity (the slip)
  // before and after, and the normal impulse of compression and of restitution (p_z at maximum
  // compression, and the rest). Over a patch these are of the point the impulse was resolved at,
  // with the centre-of-pressure rule's constrained inertia. A group's contacts (simultaneous
  // impacts) have none: `group` is set.
  bool group = false;
  std::uint8_t phase_count = 0;
  std::array<PhaseKind, 6> phases{};
  Vec3 resumed_direction_W = Vec3::Zero();  // the unit slip direction (world) sliding resumed in
  Vec3 slip_before_W = Vec3::Zero();
  Vec3 slip_after_W = Vec3::Zero();
  double normal_impulse_compression = 0.0;  // [N s]
  double normal_impulse_restitution = 0.0;  // [N s]
  // Bodies resting on the dynamic body of a microcollision with its support, carried along with
  // it (their velocity along n set to its); energy_change includes them. impulse_W is the
  // support's impulse on the whole stack; a rider settling onto the carrier also takes the
  // plastic impulse that matches its normal velocity to the carrier's, not recorded apart.
  std::vector<BodyId> carried;
};

// Where a contact's impulse acts (see the header comment).
enum class Placement : std::uint8_t {
  kPoint,    // the closest point, or the patch corner approaching fastest
  kSphere,   // a dynamic sphere's contact point; its slip is its centre's motion
  kFace,     // centre-of-pressure rule over a polygon: line of action through the centre of mass
  kSegment,  // centre-of-pressure rule over a segment: rotation held about n x s only
};

// Which of the two bodies is dynamic.
enum class DynamicSide : std::uint8_t { kNeither, kFirst, kSecond, kBoth };

// One body of a pair as the contact model sees it: its constant data and its state at the
// contact instant (the loop's committed state, or an extrapolation).
struct ContactSide {
  BodyId id;
  const Body& body;
  const ShapeGeometry& geometry;
  const BodyState& state;
  // The body's acceleration if it is not that of free flight (gravity for a dynamic body, zero
  // for the others): a body held in contact (scheduler/island.hpp). Null: free flight.
  const Vec3* acceleration_W = nullptr;
  // With acceleration_W: the held body's angular acceleration (null: a body held at this
  // instant, whose plan is pending, counts as held still).
  const Vec3* angular_acceleration_W = nullptr;
};

// Everything the collision of a pair needs, in the world frame; body 1 = a, body 2 = b.
struct Contact {
  BodyId a, b;
  DynamicSide dynamic = DynamicSide::kNeither;
  Placement placement = Placement::kPoint;
  Vec3 point_W = Vec3::Zero();
  Vec3 n_W = Vec3::UnitZ();
  ContactBody body1, body2;
  Vec3 x1_W = Vec3::Zero(), x2_W = Vec3::Zero();  // the centres of mass
  double u_n = 0.0;                   // relative normal velocity (< 0 approaching) [m/s]
  double g_n = 0.0;                   // relative normal acceleration toward contact (>= 0) [m/s^2]
  bool held_acceleration = false;     // g_n is from a held body's true acceleration
  double v_micro = 0.0;               // microcollision speed of this contact [m/s]
  Vec3 a_rel_W = Vec3::Zero();        // slip acceleration at the moving contact location [m/s^2]
  Vec3 segment_dir_W = Vec3::Zero();  // kSegment: unit, along the segment patch
  // The gap between the bodies along n and a point of body 2's support plane: each body's
  // velocity is taken where the contact point, moved along n, meets its own surface.
  double gap = 0.0;
  Vec3 plane2_W = Vec3::Zero();
  std::vector<Vec3> patch;  // the contact patch (empty: a point), counter-clockwise about n
  // A face on a face between two dynamic bodies: whether each body's rotation is held by a face
  // of its own resting on a fixed or kinematic support, directly or through bodies stacked face
  // on face (set by the event loop, which sees the other pairs; make_contact leaves them false).
  // The patch then holds the other body's rotation too: both meet the impulse with their masses
  // alone, and the pressure acts below the free body's centre of mass.
  bool rotation_held1 = false, rotation_held2 = false;

  bool slip_at_centre() const {
    return placement == Placement::kSphere || placement == Placement::kFace ||
           placement == Placement::kSegment;
  }
  bool centre_of_pressure() const {
    return placement == Placement::kFace || placement == Placement::kSegment;
  }
  bool dynamic1() const { return dynamic == DynamicSide::kFirst || dynamic == DynamicSide::kBoth; }
  bool dynamic2() const { return dynamic == DynamicSide::kSecond || dynamic == DynamicSide::kBoth; }
  // The single dynamic body of a pair with one (body 1 if both are dynamic).
  const ContactBody& dynamic_body() const { return dynamic2() && !dynamic1() ? body2 : body1; }
  ContactBody& dynamic_body() { return dynamic2() && !dynamic1() ? body2 : body1; }
  const Vec3& dynamic_x_W() const { return dynamic2() && !dynamic1() ? x2_W : x1_W; }
};

// The contact of the pair (side1, side2) whose closest features are `closest` (states at the
// same time). `with_patch`: compute the contact patch and the placement over it (a collision);
// without it the contact is at the closest point (enough to ask whether it approaches).
Contact make_contact(const ContactSide& side1, const ContactSide& side2,
                     const DistanceResult& closest, const Settings& settings, const Vec3& gravity_W,
                     bool with_patch);

// The placement over a patch of at least two points (DESIGN.md §4's centre-of-pressure rule; see
// the header comment): kFace or kSegment where the rule applies, else the corner landing first.
// Returns the placement and sets c.point_W (and c.segment_dir_W; a polygon landing along one of
// its edges has c.patch replaced by that edge). `foot_W`: the foot of the
// dynamic body's centre of mass on the contact plane.
Placement place_over_patch(Contact& c, const BodyState& s1, const BodyState& s2, const Vec3& foot_W,
                           const Settings& settings);

// The relative normal speed at the contact that is within rounding of the bodies' speeds there
// (kVelocityRounding of their sum): slower than that, a contact neither approaches nor separates.
double rounding_speed(const Contact& c);

// True if the pair collides now: it approaches, or rests with gravity pressing it together
// (a body left at rest in contact by an e = 0 collision must collide again, DESIGN.md §4).
bool approaching(const Contact& c);

// True if any point of the contact's patch approaches (a corner of a face landing while the
// centre of pressure, where approaching() looks, does not).
bool patch_approaching(const Contact& c, const BodyState& s1, const BodyState& s2);

// Puts the contact at `point_W` (between the bodies, on the normal's line through it): each body's
// contact offset is to where that line meets its own surface.
void place(Contact& c, const Vec3& point_W);

// The relative normal velocity of the contact in the contact frame, u0_c.z(), as the resolution
// computes it: its sign and size decide between a collision and a microcollision.
double initial_normal_velocity(const Contact& c);

// True if a collision of `c` carries the bodies resting on its dynamic body (riders): a
// microcollision of a face resting on an upward-facing support.
bool carries_riders(const Contact& c, const Settings& settings, const Vec3& gravity_W);

// A body resting on the dynamic body of the contact, carried along by its microcollision.
struct Rider {
  BodyId id;
  const Body& body;
  const BodyState& state;  // at the contact instant
  double friction = 0.0;   // mu between the rider and the body it rests on
};

// How the resolution ended (DESIGN.md §4's centre-of-pressure rule).
enum class PressureOutcome : std::uint8_t {
  kAtPoint,         // a point impulse (no rule)
  kWithinPatch,     // the rule's line of action met the patch: resolved there
  kMovedOnSegment,  // over a segment, moved once to where the impulse's torque vanishes
  kTipped,          // the line left the patch: resolved at the tipping point (or the corner
                    // landing first, if that point already separates)
};

// What a collision does: the new velocities of the two bodies and the riders, and its record.
struct Resolution {
  CollisionRecord record;
  Vec3 v1_W = Vec3::Zero(), w1_W = Vec3::Zero();  // body 1 after (unchanged if not dynamic)
  Vec3 v2_W = Vec3::Zero(), w2_W = Vec3::Zero();
  std::vector<Vec3> rider_v_W;  // each rider's velocity after (in the order given)
  PressureOutcome outcome = PressureOutcome::kAtPoint;
  // The most kinetic energy this collision may create [J] (DESIGN.md §5 step 6): the integration
  // tolerance times its energy scale |p| |u_n|, plus, when gravity presses the contact, what the
  // microcollision rebound floor lends - the larger of (1/2) |p| v_micro (the normal floor's
  // extra work) and (1/2) m_red |u'|^2 (an impulse aimed at a target relative velocity u', the
  // drift-free rule: p = K^-1 (u' - u0) changes the energy by at most that, as K >= 1 / m_red).
  // A checked build (PALPABLE_CHECKED) fails on a collision under Stronge or Poisson that
  // exceeds it; Newton's law can create energy (Kane's paradox) and a kinematic body does work
  // on what it hits (a platter, a paddle): neither is checked.
  double energy_allowance = 0.0;
  int integration_steps = 0;  // Runge-Kutta steps of every pass
  int impulse_failures = 0;   // passes whose integration failed (the frictionless impulse stood in)
};

// How a collision may end.
struct ResolveOptions {
  // A collision slower than the microcollision speed is a microcollision (Mirtich's contact
  // model). Under the persistent contact model every collision is integrated with the material's
  // restitution and no rebound floor, and a slow one hands its contact to the hold.
  bool microcollisions = true;
  // >= 0: the restitution to use instead of the material's (0: a plastic collision, the hand-over
  // of a contact arriving slower than the microcollision speed).
  double restitution = -1.0;
};

// Resolves the collision of `c` (a contact with its patch, made from side1 and side2) at time t.
// `riders`: the bodies it carries (non-empty only if carries_riders(c)).
Resolution resolve(Contact c, const ContactSide& side1, const ContactSide& side2,
                   const Material& material, const Settings& settings,
                   const std::vector<Rider>& riders, double t,
                   const ResolveOptions& options = ResolveOptions{});

}  // namespace palpable
