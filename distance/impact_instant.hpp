#pragma once
// The instant an impact's gap closes (DESIGN.md §8.5) for pairs whose time of impact has no
// closed form: polyhedra against planes, polyhedra and spheres, and compounds of them.
//
// From a pair inside the envelope at time t0 (states given, nothing committed), the gap g(t) —
// the distance between the closest features, re-queried with V-Clip at each iterate along the
// bodies' exact ballistic trajectories (core/ballistic.hpp) — is followed to the first instant it
// falls below a touching gap at rounding level. Each step is Newton's step on a lower model of the
// gap that is certified, so no root is ever stepped over, however the bodies turn:
//
//   along the fixed direction n0 of the iterate's closest features (from body 2 to body 1, per
//   piece pair of a compound), the slab between the pieces lower-bounds their distance, and every
//   vertex v of body 1 and w of body 2 keeps
//     n0 . (x_v - x_w)(t + s) >= (h_v - h_w) + (hdot_v - hdot_w) s - A_vw s^2 / 2,
//     A_vw = -n0 . (g1 - g2) + |r_v| (w1^2 + a1) + |r_w| (w2^2 + a2),
//   with h and hdot each vertex's height along n0 and its rate (exact, v + w x r), w_i the body's
//   angular-speed bound and a_i = w_i^2 (I_max - I_min) / I_min a bound on |w'| in torque-free
//   flight (|w x I w| <= |w|^2 (I_max - I_min)); a sphere piece is its centre, offset by its
//   radius, and a halfspace its plane. The earliest root over the vertex pairs (DESIGN.md §3's
//   branches) is a step during which the pieces cannot touch.
//
// The model's first derivative is exact at the closest vertices, so near a transversal root the
// gap shrinks quadratically (g_(k+1) <= A g_k^2 / u_n^2): three or four queries from half an
// envelope for a box landing at a metre per second. A gap that stops closing is reported as such
// (receding) rather than followed; a stalled clock (the step rounds away) stops where it is.
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"
#include "distance/closest_features.hpp"

#include <cstdint>

namespace palpable {

enum class InstantStatus : std::uint8_t {
  kFound,          // the gap is at most the touching gap at dt
  kReceding,       // the gap opened past the envelope, or no contact is possible in this phase
  kStalled,        // the certified step no longer advances the clock (dt is where it stopped)
  kNotConverged,   // max_iterations spent (dt: how far the certified steps got)
  kNotApplicable,  // a kinematic body, or a query that was not separated or touching
};

const char* to_string(InstantStatus status);

struct ImpactInstant {
  InstantStatus status = InstantStatus::kNotApplicable;
  double dt = 0.0;     // [s] from t0: no contact before it (every status but kNotApplicable)
  double gap_m = 0.0;  // the gap at dt
  int iterations = 0;  // closest-feature queries made (each one a certified step)
};

// Follows the pair (body 1, body 2), in states state1 and state2 at the same time t0 with closest
// features `closest` (the query that filled `cache`), to the first instant its gap is at most
// `touching_gap_m`. The cache is copied: the pair's own is left as it was.
ImpactInstant impact_instant(const Body& body1, const BodyState& state1,
                             const ShapeGeometry& geometry1, const Body& body2,
                             const BodyState& state2, const ShapeGeometry& geometry2,
                             const DistanceResult& closest, const PairCache& cache,
                             const Vec3& gravity_W, const Settings& settings, double touching_gap_m,
                             int max_iterations);

// One certified step [s]: from states at the same time with closest features `closest` (and, for
// a compound in the pair, the piece results in `cache`), the pair's gap stays above target_m
// (>= 0, below the present gap) for this long;
// +inf if no contact is possible in this ballistic phase, 0 if the model does not apply (a
// kinematic body, a piece pair overlapping or failed).
double certified_step(const Body& body1, const BodyState& state1, const ShapeGeometry& geometry1,
                      const Body& body2, const BodyState& state2, const ShapeGeometry& geometry2,
                      const DistanceResult& closest, const PairCache& cache, const Vec3& gravity_W,
                      const Settings& settings, double target_m);

}  // namespace palpable
