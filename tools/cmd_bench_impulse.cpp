// `palpable bench impulse`: cost of one collision (median of repeated timings) for frictionless,
// sliding (constant and curving slip direction) and stick-then-slide contacts, and the error
// against a tight (1e-13) solution versus cost as the integration tolerance goes 1e-3 ... 1e-12.
// A benchmark, not a test: it prints JSON lines and asserts nothing.
#include "impulse/collision_integrator.hpp"
#include "impulse/collision_matrix.hpp"
#include "tools/commands.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/median.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

using palpable::CollisionParameters;
using palpable::CollisionResult;
using palpable::Mat3;
using palpable::Vec3;

struct BenchCase {
  std::string name;
  std::string what;
  Mat3 K;
  Vec3 u0;
  double friction;
  double restitution;
};

// A body touching at an offset off its principal axes: K couples all three directions, so the
// slip direction turns during the collision.
Mat3 coupled_K() {
  palpable::ContactBody body, ground;
  body.inv_mass = 1.0;
  body.inv_inertia_W = Vec3(12.0, 6.0, 3.0).asDiagonal();
  body.r_W = Vec3(-0.3, 0.2, -0.35);
  return palpable::collision_matrix_W(body, ground);
}

std::vector<BenchCase> bench_cases() {
  const Mat3 sphere = Vec3(3.5, 3.5, 1.0).asDiagonal();
  Mat3 rod;
  rod << 2.5, 0.0, -1.5, 0.0, 4.0, 0.0, -1.5, 0.0, 2.5;
  return {
      {"frictionless", "sphere on ground, mu = 0 (closed form; the baseline)", sphere,
       Vec3(3.0, 0.0, -2.0), 0.0, 0.6},
      {"sliding_constant", "sphere sliding throughout, slip direction constant", sphere,
       Vec3(3.0, 1.0, -2.0), 0.1, 0.6},
      {"sliding_curving", "3D contact sliding throughout, slip direction turns", coupled_K(),
       Vec3(1.0, 1.5, -1.0), 0.3, 0.7},
      {"stick_then_slide_2d", "leaning rod: slip stops, unstable stick, reversed sliding", rod,
       Vec3(0.5, 0.0, -1.0), 0.2, 0.5},
      {"stick_then_slide_3d", "3D drop without slip: unstable stick at p_z = 0, resumed sliding",
       coupled_K(), Vec3(0.0, 0.0, -1.0), 0.3, 0.5},
      {"slip_swings_past_zero_3d",
       "3D: sticking unstable, the slip curves close to zero and swings past it", coupled_K(),
       Vec3(0.05, -0.02, -1.0), 0.3, 0.5},
      {"spiral_to_stick_3d", "3D: slip spirals to zero, stable stick", coupled_K(),
       Vec3(0.3, -0.2, -1.0), 1.0, 0.5},
  };
}

CollisionParameters params_for(const BenchCase& c, double tolerance) {
  CollisionParameters params;
  params.friction = c.friction;
  params.restitution = c.restitution;
  params.law = palpable::RestitutionLaw::kStronge;
  params.tolerance = tolerance;
  return params;
}

// Median over `repeats` of the mean time per collision.
double median_ns(const BenchCase& c, const CollisionParameters& params, int repeats, double& sink) {
  return palpable::tools::median_ns_per_call(
      [&] { sink += palpable::integrate_collision(c.K, c.u0, params).p_c.z(); }, repeats, 1 << 24);
}

nlohmann::json phases_of(const CollisionResult& r) {
  nlohmann::json phases = nlohmann::json::array();
  for (int i = 0; i < r.phase_count; ++i) phases.push_back(palpable::describe(r.phases[i]));
  return phases;
}

palpable::tools::CommandRegistration registration{
    "bench impulse", [](CLI::App& app) {
      app.description(
          "Median cost of one collision (frictionless baseline, sliding, stick-then-slide) and the "
          "error against a 1e-13 solution versus cost for tolerances 1e-3 ... 1e-12; JSON lines");
      auto repeats = std::make_shared<int>(7);
      app.add_option("--repeats", *repeats, "timed repeats per figure (median), >= 5")
          ->check(CLI::Range(5, 1000));
      return std::function<int()>([repeats] {
        double sink = 0.0;
        const std::vector<BenchCase> cases = bench_cases();
        const double default_tolerance = palpable::Settings{}.integration_tolerance;
        const double baseline =
            median_ns(cases[0], params_for(cases[0], default_tolerance), *repeats, sink);
        for (const BenchCase& c : cases) {
          const CollisionParameters params = params_for(c, default_tolerance);
          const CollisionResult r = palpable::integrate_collision(c.K, c.u0, params);
          const double ns = median_ns(c, params, *repeats, sink);
          nlohmann::json line{{"bench", "impulse"},
                              {"case", c.name},
                              {"what", c.what},
                              {"tolerance", default_tolerance},
                              {"median_ns", ns},
                              {"ratio_to_frictionless", ns / baseline},
                              {"status", std::string(palpable::to_string(r.status))},
                              {"steps", r.steps},
                              {"rejected_steps", r.rejected_steps},
                              {"rhs_evaluations", r.rhs_evaluations},
                              {"phases", phases_of(r)},
                              {"repeats", *repeats}};
          std::cout << line.dump() << std::endl;
        }
        // Tolerance sweep: error of the impulse against the 1e-13 solution, relative to |p|.
        for (const BenchCase& c : cases) {
          if (c.friction == 0.0) continue;
          const Vec3 tight = palpable::integrate_collision(c.K, c.u0, params_for(c, 1e-13)).p_c;
          for (int exponent = 3; exponent <= 12; ++exponent) {
            const double tolerance = std::pow(10.0, -exponent);
            const CollisionParameters params = params_for(c, tolerance);
            const CollisionResult r = palpable::integrate_collision(c.K, c.u0, params);
            const double ns = median_ns(c, params, *repeats, sink);
            nlohmann::json line{{"bench", "impulse_tolerance"},
                                {"case", c.name},
                                {"tolerance", tolerance},
                                {"error_vs_tight", (r.p_c - tight).norm() / tight.norm()},
                                {"median_ns", ns},
                                {"ratio_to_frictionless", ns / baseline},
                                {"steps", r.steps},
                                {"rejected_steps", r.rejected_steps},
                                {"rhs_evaluations", r.rhs_evaluations}};
            std::cout << line.dump() << std::endl;
          }
        }
        if (sink == 0.1234567) std::cout << "";  // keeps the timed work observable
        return palpable::tools::kExitOk;
      });
    }};

}  // namespace
