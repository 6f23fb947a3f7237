// `palpable bench idle`: what 10,000 idle bodies far from the action cost a scene. A benchmark,
// not a test: for each case, runs the scene without and with the idle bodies, alternately
// (so drifts of the machine's load hit both alike), and prints the medians of the event loop's
// wall time and of the construction's, their ratios, and both event counts (which must agree).
#include "core/check.hpp"
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"
#include "tools/commands.hpp"
#include "tools/lib/cli_checks.hpp"
#include "tools/lib/exit_codes.hpp"
#include "scenarios/gas.hpp"
#include "tools/lib/median.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace palpable::tools {
namespace {

struct Timed {
  double construct_s = 0.0;
  double run_s = 0.0;
  double run_cpu_s = 0.0;  // process CPU time of the event loop
  SimulationStats stats;
};

Timed run_world(World world, double t_end) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  Simulation sim(std::move(world), SimulationOptions{});
  const auto t1 = Clock::now();
  const std::clock_t c1 = std::clock();
  sim.run_until(t_end, nullptr);
  const std::clock_t c2 = std::clock();
  const auto t2 = Clock::now();
  return {std::chrono::duration<double>(t1 - t0).count(),
          std::chrono::duration<double>(t2 - t1).count(),
          static_cast<double>(c2 - c1) / CLOCKS_PER_SEC, sim.stats()};
}

// Prints the case's line; returns whether the event counts with and without the idle bodies
// agree (idle bodies far away must change nothing).
bool compare(const char* name, const World& base, const World& with_idle, double t_end, int repeats,
             int idle) {
  std::vector<double> base_run, idle_run, base_construct, idle_construct, base_cpu, idle_cpu;
  Timed b, i;
  for (int r = 0; r < repeats; ++r) {
    b = run_world(base, t_end);
    i = run_world(with_idle, t_end);
    base_run.push_back(b.run_s);
    idle_run.push_back(i.run_s);
    base_cpu.push_back(b.run_cpu_s);
    idle_cpu.push_back(i.run_cpu_s);
    base_construct.push_back(b.construct_s);
    idle_construct.push_back(i.construct_s);
  }
  const double br = median(base_run), ir = median(idle_run);
  const double bc = median(base_construct), ic = median(idle_construct);
  std::printf(
      "{\"bench\": \"idle\", \"case\": \"%s\", \"idle_bodies\": %d, \"virtual_s\": %g, "
      "\"events\": %llu, \"events_with_idle\": %llu, \"queries\": %llu, "
      "\"queries_with_idle\": %llu, \"run_s\": %.4f, \"run_s_with_idle\": %.4f, "
      "\"run_ratio\": %.3f, \"run_cpu_ratio\": %.3f, \"construct_s\": %.4f, "
      "\"construct_s_with_idle\": %.4f, "
      "\"total_ratio\": %.3f, \"repeats\": %d}\n",
      name, idle, t_end, static_cast<unsigned long long>(b.stats.events),
      static_cast<unsigned long long>(i.stats.events),
      static_cast<unsigned long long>(b.stats.pair_checks + b.stats.bound_queries),
      static_cast<unsigned long long>(i.stats.pair_checks + i.stats.bound_queries), br, ir, ir / br,
      median(idle_cpu) / median(base_cpu), bc, ic, (ic + ir) / (bc + br), repeats);
  std::fflush(stdout);
  if (b.stats.events != i.stats.events) {
    std::fprintf(stderr,
                 "palpable: error: %s: %llu events without the idle bodies, %llu with them "
                 "(idle bodies far away must change nothing)\n",
                 name, static_cast<unsigned long long>(b.stats.events),
                 static_cast<unsigned long long>(i.stats.events));
    return false;
  }
  return true;
}

CommandRegistration registration{
    "bench idle", [](CLI::App& app) {
      app.description(
          "Cost of --idle idle bodies far from the action. Cases: a zero-gravity gas of\n"
          "frictionless elastic spheres in a box of fixed slabs, plus resting spheres (idle:\n"
          "no gravity, nothing reaches them) or plus fixed cubes; and, with --scene, that scene\n"
          "plus fixed cubes 1 km away. Prints per case the medians over --repeats of the event\n"
          "loop's and the construction's wall time without and with the idle bodies, their\n"
          "ratios, and the event and closest-feature query counts of both. Exits with 1 if the\n"
          "event counts with and without the idle bodies differ (they must not).");
      auto idle = std::make_shared<int>(10000);
      auto repeats = std::make_shared<int>(5);
      auto spheres = std::make_shared<int>(200);
      auto gas_time = std::make_shared<double>(20.0);
      auto scene_path = std::make_shared<std::string>();
      const int most = std::numeric_limits<int>::max();
      app.add_option("--idle", *idle, "idle bodies to add (default 10000)")
          ->check(CLI::Range(1, most));
      app.add_option("--repeats", *repeats, "runs of each variant, >= 5 (default 5)")
          ->check(CLI::Range(5, most));
      app.add_option("--spheres", *spheres, "spheres of the gas (default 200)")
          ->check(CLI::Range(2, most));
      app.add_option("--gas-time", *gas_time, "virtual time of the gas runs [s] (default 20)")
          ->check(
              finite_range(std::numeric_limits<double>::min(), std::numeric_limits<double>::max()));
      app.add_option("--scene", *scene_path, "a scene file to run with fixed idle cubes too");
      return std::function<int()>([=] {
        GasOptions options;
        options.count = *spheres;
        options.walls = GasWalls::kSlabs;
        const World gas = make_sphere_gas(options);
        const double side = gas_container_side(options);
        const Vec3 far_W(3.0 * side + 100.0, 0.0, 0.0);  // beyond the slabs and any swept box
        World with_spheres = gas;
        add_idle_bodies(with_spheres, *idle, IdleKind::kRestingSpheres, far_W, 0.1);
        bool agree =
            compare("gas + resting spheres", gas, with_spheres, *gas_time, *repeats, *idle);
        World with_boxes = gas;
        add_idle_bodies(with_boxes, *idle, IdleKind::kFixedBoxes, far_W, 0.1);
        agree &= compare("gas + fixed cubes", gas, with_boxes, *gas_time, *repeats, *idle);
        if (!scene_path->empty()) {
          const Scene scene = scene_from_json(read_json_file(*scene_path), *scene_path);
          World with_cubes = scene.world;
          add_idle_bodies(with_cubes, *idle, IdleKind::kFixedBoxes, Vec3(1000.0, 1000.0, 1000.0),
                          0.1);
          agree &=
              compare(scene.name.c_str(), scene.world, with_cubes, scene.end_time, *repeats, *idle);
        }
        return agree ? kExitOk : kExitFailure;
      });
    }};

}  // namespace
}  // namespace palpable::tools
