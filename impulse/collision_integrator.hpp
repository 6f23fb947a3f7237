#pragma once
// Collision integration over the normal impulse p_z (DESIGN.md §4; Mirtich, PhD thesis 1996,
// ch. 4; Stronge, "Rigid body collisions with friction", Proc. R. Soc. A 439, 1992).
//
// Everything here is in the contact frame C = (t1, t2, n), n pointing from body 2 to body 1:
// u = u1 - u2 is the relative velocity of the contact point, p the impulse on body 1, and the
// collision matrix K_c (symmetric positive definite) maps impulse to change of velocity,
// du = K_c dp. The integrator takes plain numbers — no bodies, no shapes — and returns a
// CollisionResult; numerical trouble is a status in the result, never a throw.
//
// Guarantees: the normal impulse p_z grows monotonically; |p_t| <= mu p_z up to the integration
// tolerance; maximum compression (u_z = 0), the end of restitution and the slip zero (|u_t| -> 0)
// are located to the integration tolerance (root finding on the Dormand-Prince dense output, or
// closed form where the slip direction is constant); u_final = u0 + K_c p to rounding.
//
// Cost: frictionless contacts and slides whose direction does not turn (2D, spheres, stick at
// p_z = 0) are closed form, with no Runge-Kutta step. A 3D slip whose direction turns is
// integrated; near a slip zero the step shrinks in proportion to |u_t| (the tangential dynamics
// is self-similar there), so reaching it costs O(log 1/tol) steps. Where the friction direction
// is stiff near the slip zero (strongly anisotropic K_t), |u_t| can stall under an explicit
// step; the slip zero is then reached by an implicit landing step (counted in
// stalled_slip_landings). Over 100,000 random contacts the default tolerance stays within 1e-6
// (relative) of a 1e-13 solution, but that, not 1e-9, is the measured global accuracy there.
#include "core/settings.hpp"
#include "core/types.hpp"

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace palpable {

using Vec2 = Eigen::Vector2d;

enum class CollisionStatus {
  kOk,
  kSeparating,             // u_z0 > 0 and no rebound floor to reach: nothing to do, p = 0
  kFailedNonFinite,        // a NaN or infinity appeared in the input or the integration
  kFailedNotPositive,      // K_c is not symmetric positive definite (or mu, e out of range)
  kFailedStepLimit,        // the adaptive integrator exceeded its step budget
  kFailedStepUnderflow,    // the adaptive step became too small to make progress
  kFailedNoCompressionEnd  // a constant-direction phase cannot end its stage (K_z.zeta <= 0)
};
std::string_view to_string(CollisionStatus status);
inline bool succeeded(CollisionStatus s) {
  return s == CollisionStatus::kOk || s == CollisionStatus::kSeparating;
}

// What happened during a collision, in order.
enum class PhaseKind {
  kFrictionless,           // mu = 0: closed form along K e_z
  kSlid,                   // sliding with a (possibly turning) slip direction, integrated
  kStuckStably,            // |u_t| reached 0 and sticking is stable: u_t stays 0 (closed form)
  kResumedSliding,         // |u_t| reached 0, sticking unstable: slides on in a fixed `direction`
  kReboundFloor,           // restitution extended until u_z = the microcollision rebound floor
  kReversed,               // microcollision, Mirtich's reversal rule, inside the friction cone
  kDriftFreeTarget,        // microcollision, drift-free target inside the friction cone
  kDriftFreeConeBoundary,  // drift-free target outside the cone: cone-boundary impulse
  kMicroFallback,          // microcollision target outside the cone: ordinary integration
};
std::string_view to_string(PhaseKind kind);

struct CollisionPhase {
  PhaseKind kind = PhaseKind::kSlid;
  double p_z_begin = 0.0;         // [N s] normal impulse where the phase began
  Vec2 direction = Vec2::Zero();  // kResumedSliding: the unit slip direction (t1, t2)
};
// "slid", "stuck stably", "resumed sliding in direction (x, y)", ...
std::string describe(const CollisionPhase& phase);

struct CollisionResult {
  CollisionStatus status = CollisionStatus::kOk;
  Vec3 p_c = Vec3::Zero();        // impulse on body 1, contact frame [N s]
  Vec3 p_W = Vec3::Zero();        // the same in world (filled by the world-frame entry point)
  Vec3 u0_c = Vec3::Zero();       // initial relative contact velocity [m/s]
  Vec3 u_final_c = Vec3::Zero();  // final relative contact velocity, u0 + K_c p [m/s]
  double energy_change = 0.0;     // 1/2 (u0 + u_final) . p  [J]; <= 0 for Stronge
  double p_z_compression = 0.0;   // normal impulse at maximum compression [N s]
  double work_compression = 0.0;  // W_z at maximum compression (<= 0) [J]
  double work_normal = 0.0;       // W_z at the end [J]
  int steps = 0;                  // accepted Runge-Kutta steps
  int rejected_steps = 0;         // rejected Runge-Kutta steps
  int rhs_evaluations = 0;        // evaluations of dy/dp_z
  // Times |u_t| stalled near a stable slip zero (stiff friction direction) and the slip zero was
  // reached by an implicit landing step instead (accuracy there is O(|u_t| / |du_t/dp_z|)).
  int stalled_slip_landings = 0;
  std::array<CollisionPhase, 6> phases{};
  int phase_count = 0;

  void add_phase(PhaseKind kind, double p_z_begin, const Vec2& direction = Vec2::Zero());
};

// One point of the integration's path: the impulse so far and the relative contact velocity
// there (contact frame), u = u0 + K_c p. Recorded only on request (CollisionParameters).
struct ImpulsePathPoint {
  Vec3 p_c = Vec3::Zero();  // [N s]; p_c.z() is the normal impulse p_z, the integration variable
  Vec3 u_c = Vec3::Zero();  // [m/s]
};

// Everything the integrator needs besides K_c and u0.
struct CollisionParameters {
  double friction = 0.5;     // mu >= 0
  double restitution = 0.5;  // e in [0, 1]
  RestitutionLaw law = RestitutionLaw::kStronge;
  double tolerance = 1e-9;  // relative tolerance of the integration (Settings)
  // Restitution never ends below this normal speed [m/s] (the microcollision floor v_micro;
  // 0 for an ordinary collision). Restitution goes on past the law's end until u_z = floor.
  double min_rebound_speed = 0.0;
  int max_steps = 100000;  // step budget -> kFailedStepLimit
  // If set, receives u(p_z) along the integration (for hodographs; `palpable impact
  // --trajectory`): the start, the end of every closed-form segment (u is linear in p_z there),
  // and every accepted Runge-Kutta step with three points of its dense output inside. Recording
  // changes nothing in the result.
  std::vector<ImpulsePathPoint>* path = nullptr;
};

CollisionParameters collision_parameters(const Material& material, const Settings& settings);

// Resolves one collision: K_c symmetric positive definite, u0_c with u_z0 <= 0 (approaching;
// u_z0 = 0 is a resting contact). Never throws.
CollisionResult integrate_collision(const Mat3& K_c, const Vec3& u0_c,
                                    const CollisionParameters& params);

// The constant slip direction in which sliding resumes after an unstable stick (DESIGN.md §4):
// t = (lambda 1 + mu K_t)^-1 k with |t| = 1, k = (K_13, K_23). Returns false if sticking is
// stable (|K_t^-1 k| <= mu), in which case `direction` is untouched.
bool unstable_stick_direction(const Mat3& K_c, double friction, Vec2& direction);

// True if the impulse p_c lies in the friction cone |p_t| <= mu p_z, with relative slack.
bool in_friction_cone(const Vec3& p_c, double friction, double relative_slack);

}  // namespace palpable
