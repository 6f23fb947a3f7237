#pragma once
// Closed-form references a trace is compared with (DESIGN.md §6). Each takes a JSON spec of its
// parameters (from a scene's "reference" object, or the command line of `palpable compare`) and
// a sampled trace, and returns named error figures as JSON.
//
//   incline:   {"type": "incline", "body": "block", "angle_deg": 30, "friction": 0.7,
//               "gravity": 9.81, "initial_speed": 2.0, "down_slope": [x, y, z], "normal": [x, y,
//               z]}
//   turntable: {"type": "turntable", "body": "ball", "omega": 6.283185307179586,
//               "axis": [0, 0, 1], "k": 0.4}      (k: I = k m r^2; 2/5 for a solid ball)
//   slide_to_roll: {"type": "slide_to_roll", "body": "ball", "friction": 0.2, "gravity": 9.81,
//               "radius": 0.1, "k": 0.4, "normal": [0, 0, 1]}   (sphere sliding on a plane;
//               optional "velocity", "angular_velocity": the launch state, default the first
//               sample's — which, for a ball starting on the plane, already holds the impulses
//               of the collisions at t = 0)
//   bouncing_ball: {"type": "bouncing_ball", "body": "ball", "restitution": 0.8,
//               "gravity": 9.81, "radius": 0.1, "ground": 0, "normal": [0, 0, 1], "apexes": 3}
//               (height = normal . x - ground - radius)
//   impact_1d: {"type": "impact_1d", "body_a": "a", "body_b": "b", "restitution": 0.5,
//               "mass_a": 1, "mass_b": 2, "axis": [1, 0, 0]}   (first sample before, last after)
//
// Times in the figures are measured from the trace's first sample, where the closed forms start.
//
// Stop times are measured by a least-squares fit of the position (never from a sampled
// velocity, which jitters by about a_t tau / 2 during microcollision contact; DESIGN.md §4).
#include "core/types.hpp"
#include "scenarios/trace.hpp"
#include "scheduler/world.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace palpable {

// Checks a reference object before anything runs: a known "type", only that type's keys, each
// of the expected kind, and (when `body_names` is not empty) body names that are bodies of the
// scene. Throws InputError naming `where` + the key.
void validate_reference(const nlohmann::json& spec, const std::string& where,
                        const std::vector<std::string>& body_names = {}, bool require_all = true);

// A scene's reference with every parameter it omits derived from the scene, so that the closed
// form follows the scene (`--set` of a friction, a start, a spin): given "support" (the body the
// reference body rests on), the incline's normal, angle, down-slope direction, friction, gravity
// and launch speed; the turntable's Ω, axis, k and launch state; slide-to-roll's friction,
// gravity, radius, k, normal and launch state. Parameters the spec gives are kept. Throws
// InputError naming `where` for a support the body does not rest on.
nlohmann::json complete_reference(const nlohmann::json& spec, const std::string& where,
                                  const World& world);

// The figure a sweep reports as "error" for a reference's figures (compare_with_reference's
// result): the worst relative error of what the closed form predicts — stop time and creep for a
// block that stops, acceleration for one that accelerates, creep for one that sticks, rate and
// circle for the turntable, roll time and final speed for slide-to-roll, apex heights for the
// bouncing ball, velocities after a 1-D impact. NaN when the figures do not hold it.
double primary_error(const nlohmann::json& figures);

// Throws InputError naming `where` + the spec key for a bad spec (validate_reference).
nlohmann::json compare_with_reference(const nlohmann::json& spec, const Trace& trace,
                                      const std::string& where);

// The closed forms the figures are measured against, for pictures and users (`palpable plot`
// draws these, never a second copy). `spec` must pass validate_reference.

// A block on an incline (DESIGN.md §6): along-slope acceleration a = g (sin θ − μ cos θ) while it
// slides; launched down the slope at v0 it stops at t* = v0 / −a when a < 0; launched at rest with
// a <= 0 it sticks (acceleration 0).
struct InclineMotion {
  double sliding_acceleration = 0.0;  // g (sin θ − μ cos θ) [m/s^2]
  double acceleration = 0.0;          // sliding_acceleration, or 0 if it sticks [m/s^2]
  double initial_speed = 0.0;         // v0, down the slope [m/s]
  double stop_time = 0.0;             // t* [s] from the first sample; infinite if it never stops
  Vec3 down_slope = Vec3::UnitX();    // unit
  // Along-slope distance and speed at time t after the first sample.
  double distance(double t) const;
  double speed(double t) const;
};
InclineMotion incline_motion(const nlohmann::json& spec, const std::string& where);

// A ball rolling on a turntable spinning at Ω about `axis` (DESIGN.md §6): its centre circles at
// rate k Ω / (1 + k) about x0 + axis × v0 / rate, with radius |v0| / rate (v0: the launch velocity
// in the platter's plane).
struct TurntableCircle {
  double rate = 0.0;  // [rad/s]
  Vec3 axis = Vec3::UnitZ();
  Vec3 centre = Vec3::Zero();
  double radius = 0.0;  // [m]
};
TurntableCircle turntable_circle(const nlohmann::json& spec, const std::string& where,
                                 const Vec3& x0, const Vec3& v0_W);

// Least-squares polynomial fit y ~ sum_k c_k t^k (k = 0..degree), conditioned by centring and
// scaling t. Returns the coefficients in the unscaled variable t. Throws InputError ("trace")
// with no more samples than the degree.
std::vector<double> polynomial_fit(const std::vector<double>& t, const std::vector<double>& y,
                                   int degree);

}  // namespace palpable
