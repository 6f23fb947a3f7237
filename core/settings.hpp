#pragma once
// Every tolerance and knob of the simulator in one place (STYLE.md, after Jolt's PhysicsSettings):
// unit, default and what changing it does. Scenes override these under "settings"; the command
// line prints the values in effect. Derived tolerances are computed from these in one place
// (derived_*) — no module keeps a private epsilon.
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace palpable {

// How a collision's restitution phase ends (DESIGN.md §4).
enum class RestitutionLaw {
  kStronge,  // energetic: W_z(end) = (1 - e^2) W_z(max compression); never creates energy
  kPoisson,  // kinetic: p_z(end) = (1 + e) p_z(max compression)
  kNewton,   // kinematic: u_z' = -e u_z0; for comparison only, can create energy (Kane's paradox)
};

// What a microcollision aims at (DESIGN.md §4, "Continuous contact").
enum class MicrocollisionRule {
  kDriftFree,  // default: tangential target -a_t tau / 2, zero mean slip over the next flight
  kReversal,   // Mirtich's rule: reverse the relative velocity (u' = -u0, with the rebound floor)
};

// How contact that persists is simulated (DESIGN.md §8).
enum class ContactModel {
  kPersistent,       // held as a constraint between events (scheduler/island.hpp); impacts stay
                     // collisions, and an impact ending slower than the microcollision speed hands
                     // its contact over to the hold
  kMicrocollisions,  // Mirtich's trains of microcollisions (DESIGN.md §4), kept for comparison
};

std::string_view to_string(RestitutionLaw law);
std::string_view to_string(MicrocollisionRule rule);
std::string_view to_string(ContactModel model);

// Contact material of a pair of bodies.
struct Material {
  double friction = 0.5;     // Coulomb coefficient mu, >= 0
  double restitution = 0.5;  // coefficient e in [0, 1] (meaning depends on RestitutionLaw)
  // Rolling resistance d [m]: the couple d N against relative rolling (impulse/contact_torque.hpp).
  // 0 (default): a rolling ball rolls forever; a solid sphere decelerates at 5 d g / (7 r).
  double rolling_resistance = 0.0;
  // Spinning resistance [m]: the couple s N against relative spin about the normal at a point
  // contact (a face or edge on a face uses mu over its patch instead). 0 (default): a ball
  // spinning about the vertical spins forever; a solid sphere's spin decays at 5 s g / (2 r^2).
  double spinning_resistance = 0.0;
};

struct Settings {
  // Collision envelope epsilon [m]. A pair closer than this and approaching collides. The main
  // accuracy knob of contact: resting/rolling error scales with it, event count with 1/sqrt(eps).
  double envelope_m = 1e-4;

  // Approach speed below which a collision is a microcollision [m/s]. Unset (the default):
  // derived per contact as sqrt(2 g_n envelope), the speed of a fall through the envelope under
  // the normal component g_n of gravity (derived_microcollision_speed).
  std::optional<double> microcollision_speed_mps;

  // Relative slack of the microcollision test: approach speed <= v_micro (1 + slack) [-]. A
  // resting body returns at exactly v_micro, which must still count as a microcollision.
  double microcollision_speed_slack = 1e-6;

  // Relative tolerance of the adaptive Runge-Kutta integration of a collision over p_z [-].
  // Smaller is more accurate and costs more integration steps.
  double integration_tolerance = 1e-9;

  RestitutionLaw restitution_law = RestitutionLaw::kStronge;
  MicrocollisionRule microcollision_rule = MicrocollisionRule::kDriftFree;

  // Contact that persists: held between events (the default since 2026-11-27), or trains of
  // microcollisions (Mirtich's method; the default before).
  ContactModel contact_model = ContactModel::kPersistent;

  // Relative speed below which a held contact counts as still [m/s]: its friction sticks (or is
  // tested for sticking), and an island of still bodies on fixed supports in equilibrium is at
  // rest. Slip that stops at an event is zero to rounding; this only absorbs that rounding.
  double still_speed_mps = 1e-9;

  // Relative difference of principal moments below which they count as equal [-] (ballistic
  // motion, core/ballistic.hpp): equal moments select the closed-form spherical or axisymmetric
  // rotation. A body whose moments differ by delta (relative) below this moves as if symmetric,
  // with an orientation error ~ delta * |omega| * t; larger is never needed for accuracy.
  double inertia_symmetry_tolerance = 1e-12;

  // The centre-of-pressure rule for face-on-face contacts (DESIGN.md §4): the impulse's line of
  // action through the centre of mass while it meets the contact patch, so a sliding block does
  // not rock from corner to corner. false: the single patch point approaching fastest (for
  // comparison; a flat block then pitches and creeps).
  bool centre_of_pressure = true;

  // Broad-phase horizon [s]: each moving body's swept box covers this much of its future
  // ballistic flight, and is refreshed (an event of its own) when it runs out or the body
  // collides. Longer horizons mean fewer refreshes but bigger boxes, so more pairs bounded.
  double broad_phase_horizon_s = 0.25;
  // The farthest a dynamic body travels at its current speed within one horizon, in multiples
  // of its reach (its largest distance from its centre of mass to its surface) [-]: a faster
  // body's horizon is shortened to reach x this / speed, so that its swept box, and with it the
  // number of pairs it is bounded against, stays a few times its own size. A large value keeps
  // every horizon at broad_phase_horizon_s. Applied only to a body whose short box meets another
  // moving body's (see Simulation). Measured on sphere gases (README, "Cost follows
  // interaction"): against no limit, 2 costs 1.8x less per collision at 100 spheres, 2.1x less
  // at 10,000.
  double broad_phase_max_sweep = 2.0;

  // Events processed at one instant for one pair before the scheduler reports a rounding loop
  // and moves on (counted in the statistics, never silent).
  int retry_limit = 100;

  // Closest-feature walk (V-Clip, distance module): feature updates allowed in one query before
  // it reports status `failed` (counted). V-Clip provably terminates; this only guards against
  // rounding loops. A cold query on a 1280-face hull takes tens of steps.
  int distance_max_steps = 10000;

  // Minimum progress of a time-of-impact bound [s] (DESIGN.md §3, "Progress"): a conservative
  // bound below this floor is raised to it and the raise is counted (ToiBound::floored), so a
  // pair inside the envelope that closes only through rotation cannot stall the scheduler. 0
  // disables the floor (bounds are then strictly conservative); larger values mean fewer
  // re-checks. The floor is capped so that it never carries a pair through contact (at most
  // half an envelope deep when the pair is already inside half an envelope).
  double toi_min_progress_s = 1e-6;
};

// ---------------------------------------------------------------- derived tolerances
// Computed here and nowhere else; the run summary prints them with the settings.

// The gap a conservative time-of-impact bound aims at [m]: half the envelope, so that the pair is
// checked again, inside the envelope, before it can touch (distance/toi_bound.cpp).
inline double derived_target_gap(const Settings& s) { return 0.5 * s.envelope_m; }

// How far apart a body may rest on another and still ride along when the lower one is hit by a
// microcollision [m]: two envelopes (a microcollision bounces a body up to 1.5 envelopes).
inline double derived_rider_distance(const Settings& s) { return 2.0 * s.envelope_m; }

// The microcollision speed of a contact pressed by gravity g_n [m/s^2] along its normal [m/s]:
// the setting when given, else sqrt(2 g_n envelope) (a fall through the envelope).
inline double derived_microcollision_speed(const Settings& s, double g_n) {
  if (s.microcollision_speed_mps) return *s.microcollision_speed_mps;
  return std::sqrt(2.0 * std::max(g_n, 0.0) * s.envelope_m);
}

// The least step a pair's next check may take at time t [s]: toi_min_progress_s, and never less
// than 1e-12 t, so that t + step > t however long the run.
inline double derived_progress_floor(const Settings& s, double t) {
  return std::max(s.toi_min_progress_s, 1e-12 * std::max(1.0, t));
}

// ---------------------------------------------------------------- named constants
// Fixed numbers of the contact rules, named with their units; not settings because no scene has
// a reason to change them (each is a rounding guard or a geometric convention).

// A contact normal counts as support when within 60 degrees of "up" (against gravity): its
// cosine with up exceeds this [-].
inline constexpr double kSupportCosine = 0.5;
// Riders are collected through at most this many levels of bodies resting on bodies [-].
inline constexpr int kMaxRiderDepth = 64;
// A contact pressed by gravity is approaching (collides) while u_n <= this x v_micro [-]: what an
// e = 0 collision leaves is rounding, and must collide again.
inline constexpr double kRestingApproachSlack = 1e-9;
// Relative rounding of a relative normal velocity [-], times the bodies' contact-point speeds:
// u_n below -this x scale is approaching, above is not.
inline constexpr double kVelocityRounding = 1e-12;
// Two bodies closer than this, times the sum of their reaches, touch [-]: an impact is applied
// there (the instant its gap closes), not sought closer.
inline constexpr double kTouchingGap = 1e-12;
// Checks of one impact's approach to the instant of contact, by conservative advancement, before
// it is applied where it is (each closes the gap by the ratio of the true closing speed to its
// bound; an exact bound needs one).
inline constexpr int kMaxApproachSteps = 64;
// Closest-feature queries one search for an impact's instant of contact may make
// (distance/impact_instant.hpp; each step is certified and, near a transversal root, closes the
// gap quadratically: three to five suffice from half an envelope). Beyond it the pair is checked
// again where the steps got.
inline constexpr int kMaxInstantIterations = 32;
// Hulls built from points: relative coplanarity tolerance [-], times the diagonal of the points'
// bounding box (facets whose planes agree within it become one face; thinner point sets are
// rejected as coplanar). A scene's hull sets its own with "coplanar_tolerance".
inline constexpr double kHullCoplanarTolerance = 1e-9;
// Principal moments within this of each other, relative to the largest, count as equal [-]: the
// principal axes are then chosen by a fixed rule (DESIGN.md §2), so the same shape always gets
// the same body frame.
inline constexpr double kEqualMomentTolerance = 1e-10;

// ---------------------------------------------------------------- the table
// Every setting once: scene key (under "/settings"), Settings member, unit, default, check and
// meaning. The scene parser reads settings through it, the run summary prints every setting in
// effect through it, and `palpable settings --markdown` prints the README's table from it.

// A setting's value: a flag, an integer, a number, or a word (a choice, or "auto").
using SettingValue = std::variant<bool, long long, double, std::string>;

struct SettingInfo {
  std::string_view key;      // scene key under /settings
  std::string_view member;   // Settings member
  std::string_view unit;     // SI unit, "-" for dimensionless, "" for flags and choices
  std::string_view check;    // the accepted values, as an error message says "expected ..."
  std::string_view meaning;  // one line
  SettingValue (*get)(const Settings&);
  // Sets the value if it passes the check; false (and `s` unchanged) otherwise.
  bool (*set)(Settings& s, const SettingValue& value);
};

const std::vector<SettingInfo>& settings_table();

// The value as it is written in a scene (numbers with 17 significant digits, shortest form).
std::string format_setting(const SettingValue& value);

// The derived tolerances in effect for a world whose gravity has magnitude g [m/s^2]: name,
// unit, value, meaning.
struct DerivedSetting {
  std::string_view name;
  std::string_view unit;
  double value;
  std::string_view meaning;
};
std::vector<DerivedSetting> derived_settings(const Settings& s, double gravity_mps2);

}  // namespace palpable
