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
#include "scenarios/trace.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace palpable {

// Throws InputError naming `where` + the spec key for a bad spec.
nlohmann::json compare_with_reference(const nlohmann::json& spec, const Trace& trace,
                                      const std::string& where);

// Least-squares polynomial fit y ~ sum_k c_k t^k (k = 0..degree), conditioned by centring and
// scaling t. Returns the coefficients in the unscaled variable t. Throws InputError ("trace")
// with no more samples than the degree.
std::vector<double> polynomial_fit(const std::vector<double>& t, const std::vector<double>& y,
                                   int degree);

}  // namespace palpable
