#pragma once
// Contact that persists (DESIGN.md §8.1-8.2): the contact problem of a set of bodies held in
// contact, at the acceleration level. Given the bodies' states, the contacts that are held and
// each contact's mode (sliding or sticking, for its friction, torsion and rolling), find the
// bodies' accelerations and the contact wrenches that keep every held contact touching and every
// sticking contact stuck (Baraff, "Analytical methods for dynamic simulation of non-penetrating
// rigid bodies", SIGGRAPH 1989; "Fast contact force computation for nonpenetrating rigid
// bodies", SIGGRAPH 1994). Plain numbers in, plain numbers out: no shapes, no queries.
//
// A contact is between a *mover* and a *support*: the support owns the contact plane (its normal
// n points from the support to the mover and turns with the support), the mover touches it with
// a point, a segment or a polygon of its own (material points of a polyhedron), or with a sphere
// (its contact point is its centre minus R n, not a material point). Either side may be a body of
// the problem (an unknown) or a body whose motion is known (fixed: at rest; kinematic: a
// prescribed rigid motion).
//
// The contact wrench, per contact, in the contact frame (t1, t2, n) at the reference point c:
//  - the normal force N >= 0;
//  - the pressure's moment about c, in the plane: two components over a polygon, one (about
//    n x s) over a segment, none at a point. The centre of pressure is c + n x M / N and must lie
//    in the patch (linear inequalities in N and M); where it would leave, the body tips;
//  - friction: sticking, a force F_t (two unknowns) with |F_t| <= mu N; sliding, -mu N s_hat at
//    the centre of pressure (so its moment about n follows the pressure: a linear function of N
//    and M);
//  - torsion about n over a segment or a polygon: sticking, an unknown torque with |tau| <= mu N
//    r_eff (r_eff the patch's mean distance from its centroid, the uniform-pressure arm, as in
//    impulse/contact_torque.hpp); spinning, -mu N r_eff sign(spin). At a point, the material's
//    spinning resistance s takes mu r_eff's place;
//  - rolling resistance at a point (a sphere), d the material's length: not rolling, an in-plane
//    torque with |tau| <= d N; rolling, -d N w_hat.
// Each held contact keeps its normal gap's second derivative at zero (with the velocity-product
// terms of a moving normal and of a sphere rolling over a turning plane), its rocking (over a
// polygon or a segment) and whatever sticks. The coupling with sliding friction makes the linear
// system non-symmetric; redundant constraints (a face held by four coplanar corners, a plank on
// two cubes) make it singular but consistent, and the solution taken is the one of least norm.
// The accelerations are unique either way.
//
// Numerical trouble (an inconsistent system: Painleve's paradox, or constraints that contradict
// each other) is a status, never a throw.
#include "core/types.hpp"

#include <optional>
#include <string_view>
#include <vector>

namespace palpable {

using Vec2 = Eigen::Vector2d;

// A body of the problem (an unknown), in the world frame.
struct HeldBody {
  double mass = 1.0;                  // [kg]
  Mat3 inertia_W = Mat3::Identity();  // [kg m^2]
  Mat3 inv_inertia_W = Mat3::Identity();
  Vec3 x_W = Vec3::Zero();      // centre of mass [m]
  Vec3 v_W = Vec3::Zero();      // [m/s]
  Vec3 w_W = Vec3::Zero();      // [rad/s]
  Vec3 force_W = Vec3::Zero();  // external force (gravity) [N]
};

// A body whose motion is prescribed: its reference point's position, velocity and acceleration,
// and its angular velocity and acceleration (all zero for a fixed body).
struct KnownMotion {
  Vec3 x_W = Vec3::Zero();
  Vec3 v_W = Vec3::Zero();
  Vec3 a_W = Vec3::Zero();
  Vec3 w_W = Vec3::Zero();
  Vec3 alpha_W = Vec3::Zero();
};

enum class PatchKind : std::uint8_t { kPoint, kSegment, kPolygon };

// One held contact. Frame: t1, t2, n orthonormal, n from the support to the mover.
struct HeldContact {
  int mover = -1;    // index of a HeldBody, or -1: `mover_known` moves it
  int support = -1;  // index of a HeldBody, or -1: `support_known` moves it
  KnownMotion mover_known, support_known;
  Vec3 c_W = Vec3::Zero();  // reference point, on the support's surface [m]
  Vec3 n_W = Vec3::UnitZ();
  Vec3 t1_W = Vec3::UnitX(), t2_W = Vec3::UnitY();
  // > 0: the mover is rounded, the surface at this distance from a core of its own: a sphere
  // (core: its centre) touching at c, or a cylinder or capsule lying on its side (core: its axis)
  // touching along the patch's segment. Its contact point is not a material point: it stays under
  // the core, c + R n, whichever way the body rolls.
  double sphere_radius = 0.0;
  // A rounded mover's core point above c, c + R n, from its centre of mass (zero for a sphere).
  Vec3 core_offset_W = Vec3::Zero();
  // A smooth mover touching with a point of its curved surface (an ellipsoid, a cylinder's rim, a
  // loaded ball), sphere_radius 0: c is that point, on the mover. Rolling moves it over the
  // surface at ds/dt = H (w_mover x n - dn/dt), H = curvature_W the derivative of the mover's
  // support point with respect to the direction at -n (its radii of curvature in the tangent
  // plane; core/shape.hpp smooth_support_derivative_M), which adds w_mover x ds/dt to the contact
  // point's acceleration (Montana, "The kinematics of contact and grasp", IJRR 1988, for the
  // contact point's motion over the surfaces). `curved_size` [m] stands for the sphere's radius
  // where turning is measured (a spin or rolling judged still).
  bool curved = false;
  Mat3 curvature_W = Mat3::Zero();
  double curved_size = 0.0;
  // The normal's rate when it does not simply turn with the support (two spheres, a sphere on an
  // edge, an edge across an edge: the normal follows the closest points of two features).
  bool has_n_dot = false;
  Vec3 n_dot_W = Vec3::Zero();
  // A point contact of a sphere and a polyhedron's vertex or edge: how far the sphere's centre is
  // inside that feature's Voronoi region [m] (there the feature is the closest); +inf otherwise.
  double feature_margin = kInfinity;
  // An edge of a polyhedron held across an edge of another (a point pair of two polyhedra).
  bool edge_on_edge = false;
  // A polyhedral mover's contact point that runs along its edge (a point contact of the edge and
  // a sphere: the edge's point closest to the sphere's centre), its velocity over the mover [m/s]:
  // d/dt of the mover's velocity there gains w_mover x mover_slide_W. Zero for a material point.
  Vec3 mover_slide_W = Vec3::Zero();
  PatchKind patch = PatchKind::kPoint;
  // kSegment: the segment runs from c + lo s to c + hi s (lo <= 0 <= hi) [m].
  Vec3 segment_W = Vec3::UnitX();
  double segment_lo = 0.0, segment_hi = 0.0;
  // kPolygon: its vertices relative to c in (t1, t2) coordinates, counter-clockwise about n; c
  // inside it.
  std::vector<Vec2> polygon;

  double friction = 0.0;             // mu
  double spinning_resistance = 0.0;  // [m] s: the torsion bound s N at a point
  double rolling_resistance = 0.0;   // [m] d: the rolling bound d N at a point
  // The torsion bound over N [m]: mu r_eff over a patch, s at a point (set_torsion_arm).
  double torsion_arm = 0.0;
  bool active = true;  // false: let go (ignored by the solver)
  // Its slip (spin, rolling) has just stopped at an event, to the integration's accuracy: it
  // counts as still whatever remains (choose_held_modes, project_held_velocities).
  bool slip_stopped = false, spin_stopped = false, roll_stopped = false;

  // Modes. Sliding directions are unit vectors in (t1, t2).
  bool sticks = true;  // friction force: sticking (else sliding along slip_dir)
  Vec2 slip_dir = Vec2::UnitX();
  bool spin_sticks = true;  // torsion: not spinning (else spinning with sign spin_sign)
  double spin_sign = 1.0;
  bool roll_sticks = true;  // rolling resistance: not rolling (else rolling along roll_dir)
  Vec2 roll_dir = Vec2::UnitX();
};

// The length over which a point contact's relative turning is measured: a sphere's radius, a
// curved mover's size (0 for a polyhedron's vertex).
inline double point_size(const HeldContact& c) {
  return c.sphere_radius > 0.0 ? c.sphere_radius : (c.curved ? c.curved_size : 0.0);
}

// What each contact carries.
struct HeldContactForces {
  double normal = 0.0;                     // N [N]
  Vec2 moment = Vec2::Zero();              // pressure moment about c in (t1, t2) [N m]
  Vec2 friction = Vec2::Zero();            // friction force in (t1, t2) [N]
  double torsion = 0.0;                    // torque about n [N m]
  Vec2 rolling = Vec2::Zero();             // rolling-resistance torque in (t1, t2) [N m]
  Vec2 centre_of_pressure = Vec2::Zero();  // relative to c in (t1, t2) [m]
};

// The relative motion at a contact (mover minus support), world frame.
struct HeldContactMotion {
  Vec3 slip_W = Vec3::Zero();       // s: relative velocity at the contact point (normal: gap rate)
  Vec3 slip_rate_W = Vec3::Zero();  // ds/dt, following the contact point
  Vec3 dw_W = Vec3::Zero();         // relative angular velocity
  Vec3 dalpha_W = Vec3::Zero();     // relative angular acceleration
  // d/dt of the rolling, dw's part in the tangent plane, as the normal turns: dalpha - (dw . n)
  // dn/dt (its part in that plane). Where the normal turns (a ball on a ball), the spin about it
  // turns into rolling: not dalpha's part alone.
  Vec3 roll_rate_W = Vec3::Zero();
};

enum class HeldStatus : std::uint8_t {
  kOk,
  kInconsistent,  // no accelerations satisfy the held constraints (Painleve, contradiction)
  kNonFinite,
};
std::string_view to_string(HeldStatus status);

struct HeldSolution {
  HeldStatus status = HeldStatus::kOk;
  std::vector<Vec3> a_W, alpha_W;  // per HeldBody
  std::vector<HeldContactForces> forces;
  std::vector<HeldContactMotion> motion;
  double residual = 0.0;  // of the linear system, relative
};

// The accelerations and wrenches for the given modes. `feasible_forces`: where the held
// constraints are redundant and the least-norm wrenches break an inequality of worst_violation,
// the wrenches that meet them all if any do (a linear programme over the redundancy; the
// accelerations are the same).
HeldSolution solve_held(const std::vector<HeldBody>& bodies,
                        const std::vector<HeldContact>& contacts, bool feasible_forces = false);

// The relative motion (s, dw) at every contact, without accelerations (for choosing modes).
std::vector<HeldContactMotion> held_velocities(const std::vector<HeldBody>& bodies,
                                               const std::vector<HeldContact>& contacts);

// Makes the held contacts hold at the velocity level: the smallest impulses (least squares in
// the bodies' kinetic metric) along each active contact's normal and rocking, and along whatever
// of it is still (friction, torsion, rolling relative motion below `still`), that zero those
// relative velocities. A contact handed over from a collision arrives with |u_n| below the
// microcollision speed; the projection takes out that remainder and the rocking (the plastic
// slap of the centre-of-pressure rule). A contact separating faster than `separation` (an impact
// on its body sent it apart) is left out: its index goes into `separating`. Changes the bodies'
// v_W and w_W; returns the kinetic energy change [J] (<= 0).
double project_held_velocities(std::vector<HeldBody>& bodies,
                               const std::vector<HeldContact>& contacts, double still,
                               double separation = kInfinity,
                               std::vector<int>* separating = nullptr);

// What a solution breaks, if anything: the worst violation, to be mended by changing a mode.
struct HeldViolation {
  enum class Kind : std::uint8_t {
    kNone,
    kLiftOff,  // N < 0: the contact cannot hold
    kTip,      // the centre of pressure leaves the patch across `edge` (polygon: edge from
               // vertex edge to edge + 1; segment: 0 the lo end, 1 the hi end)
    kSlip,     // sticking friction beyond mu N: sliding starts
    kSpin,     // sticking torsion beyond its bound: spinning starts
    kRoll,     // rolling resistance beyond d N: rolling starts
  };
  Kind kind = Kind::kNone;
  int contact = -1;
  int edge = -1;
  double amount = 0.0;  // how far beyond, relative to the contact's N scale
};
HeldViolation worst_violation(const std::vector<HeldContact>& contacts, const HeldSolution& s,
                              double tolerance);

// Chooses the modes (DESIGN.md §8.1): friction, torsion and rolling stick where their relative
// motion is below `still` (m/s at the contact; rad/s times the patch size for turning), slide
// otherwise; then, while the solution breaks a condition, the worst is mended - a contact that
// must pull lets go (made inactive), a centre of pressure that leaves its patch makes the patch
// its boundary (tipping: a polygon becomes the edge it crosses, a segment its end; a sliding one
// is then resisted against its slip there), a sticking group beyond its bound slides in the
// direction its sliding acceleration points (the same unique direction as the impulse
// integrator's unstable stick, at the acceleration level). Contacts that start to slide together
// have their directions chosen again, one at a time, until each slip grows along its own
// direction (to 1e-3 rad) under the modes of all.
// Returns the final solution; `changes` counts the mendings.
struct HeldModes {
  HeldSolution solution;
  std::vector<int> released;  // contacts that let go (now inactive)
  int changes = 0;
  bool converged = true;  // false: the mendings did not settle within their budget
};
HeldModes choose_held_modes(const std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts,
                            double still, double tolerance);

// The direction contact i slides in at this state while its slip is too small to follow (below
// an integrated motion's slip floor): d with its slip rate lambda d, lambda > 0, under the others'
// modes - the acceleration-level Coulomb law, as for a slip that starts from rest. A slip that
// small turns towards d at a rate of order mu g / |slip| (DESIGN.md §4), a stiff mode no explicit
// step follows; resisted along d it is taken as turned already. Nullopt, contacts[i] unchanged,
// where the contact could stick (its sticking friction within the cone: the slip stops), where
// there is no such d, or where the search does not settle; else contacts[i].slip_dir = d.
std::optional<Vec2> vanishing_slip_direction(const std::vector<HeldBody>& bodies,
                                             std::vector<HeldContact>& contacts, std::size_t i);

// Sets c.torsion_arm from its patch: mu times the mean distance of the patch from c under uniform
// pressure (a disc of radius R about its centre: 2R/3; a segment about its middle: L/4), or the
// spinning resistance at a point.
void set_torsion_arm(HeldContact& c);

// Reduces a polygon patch to its edge `edge`, or a segment to its end `edge` (0 lo, 1 hi): the
// contact a tipping body keeps (its reference point moves to the edge's middle, or the end).
void reduce_patch(HeldContact& c, int edge);

}  // namespace palpable
