// `palpable bench state`: the cost of one exact ballistic advance (core/ballistic.hpp) per kind
// of inertia. A benchmark, not a test: prints one JSON line per body with the median over repeats
// of a timed loop of chained advances, and the ratio to the sphere (the in-run baseline).
#include "core/ballistic.hpp"
#include "core/check.hpp"
#include "tools/commands.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/free_body.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace palpable::tools {
namespace {

struct BenchBody {
  const char* label;
  const char* inertia;
  Vec3 moments_M;  // [kg m^2], 1 kg bodies of unit density-like proportions
};

// Median nanoseconds per advance over `repeats` loops of `advances` chained advances of 1 ms.
double time_advances(const Body& body, int advances, int repeats, double& sink) {
  BodyState s0;
  s0.w_W = Vec3(0.3, 5.0, -0.7);  // a tumbling spin, not about a principal axis
  s0.v_W = Vec3(1.0, 0.0, 2.0);
  const Vec3 g_W(0.0, 0.0, -9.81);
  std::vector<double> ns;
  for (int r = 0; r < repeats; ++r) {
    BodyState s = s0;
    const auto start = std::chrono::steady_clock::now();
    for (int i = 1; i <= advances; ++i) s = advance(body, s, 1e-3 * i, g_W);
    const auto stop = std::chrono::steady_clock::now();
    sink += s.q_WM.w() + s.w_W.x() + s.x_W.z();  // keeps the loop observable
    ns.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / advances);
  }
  std::sort(ns.begin(), ns.end());
  return ns[ns.size() / 2];
}

CommandRegistration registration{
    "bench state", [](CLI::App& app) {
      app.description(
          "Time one exact ballistic advance (parabola + torque-free rotation) for a sphere\n"
          "(spherical inertia, closed form), a 1x1x2 box (axisymmetric, closed-form precession)\n"
          "and a 1x2x3 box (asymmetric: Jacobi elliptic functions and elliptic integrals).\n"
          "Prints one JSON line per body: median ns per advance over --repeats loops of\n"
          "--advances chained advances, and the ratio to the sphere.");
      auto advances = std::make_shared<int>(100000);
      auto repeats = std::make_shared<int>(7);
      app.add_option("--advances", *advances, "advances per timed loop (default 100000)");
      app.add_option("--repeats", *repeats, "timed loops per body, >= 5 (default 7)");
      return std::function<int()>([advances, repeats] {
        if (*advances < 1) throw InputError("--advances", "expected a positive count");
        if (*repeats < 5) throw InputError("--repeats", "expected at least 5 repeats");
        // Boxes of 1 kg: I = m (b^2 + c^2) / 12 about each axis.
        const auto box = [](double a, double b, double c) -> Vec3 {
          return Vec3(b * b + c * c, a * a + c * c, a * a + b * b) / 12.0;
        };
        const std::vector<BenchBody> bodies = {
            {"sphere", "spherical", Vec3::Constant(0.4 * 0.25)},
            {"box", "axisymmetric", box(1.0, 1.0, 2.0)},
            {"asymmetric", "asymmetric", box(1.0, 2.0, 3.0)},
        };
        double sink = 0.0;
        double sphere_ns = 0.0;
        for (const BenchBody& b : bodies) {
          const Body body = make_free_body(b.label, 1.0, b.moments_M);
          const double ns = time_advances(body, *advances, *repeats, sink);
          if (sphere_ns == 0.0) sphere_ns = ns;
          std::printf(
              "{\"bench\": \"state\", \"body\": \"%s\", \"inertia\": \"%s\", \"advance_ns\": %.1f, "
              "\"ratio_to_sphere\": %.2f, \"advances\": %d, \"repeats\": %d}\n",
              b.label, b.inertia, ns, ns / sphere_ns, *advances, *repeats);
        }
        volatile double keep = sink;  // the results feed a volatile store: the loops are kept
        (void)keep;
        return kExitOk;
      });
    }};

}  // namespace
}  // namespace palpable::tools
