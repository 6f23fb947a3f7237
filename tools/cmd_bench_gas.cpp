// `palpable bench gas`: events per second for gases of frictionless elastic spheres in zero
// gravity, inside six fixed halfspaces, at a fixed volume fraction, from 100 to 10,000 spheres.
// A benchmark, not a test: one JSON line per count with the median wall time of the event loop
// (construction excluded) over repeats of a run of at least --events events, then one line
// comparing the growth of the cost per event with the growth of log n.
#include "core/check.hpp"
#include "scheduler/simulation.hpp"
#include "tools/commands.hpp"
#include "tools/lib/cli_checks.hpp"
#include "tools/lib/exit_codes.hpp"
#include "scenarios/gas.hpp"
#include "tools/lib/median.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <memory>
#include <vector>

namespace palpable::tools {
namespace {

struct GasRun {
  double wall_s = 0.0;
  double cpu_s = 0.0;      // process CPU time: what a loaded machine does not inflate
  double virtual_s = 0.0;  // timed virtual time [s]
  std::uint64_t events = 0, collisions = 0, horizon_refreshes = 0, pair_checks = 0,
                bound_queries = 0, box_tests = 0, max_pairs = 0;
};

// One run: construct and warm up to `warmup_s` of virtual time (untimed: the lattice start relaxes
// toward a Maxwell distribution of speeds in a few collisions per sphere), then advance in slices
// of virtual time until `events` more events. Counters are those of the timed part.
GasRun run_gas(const GasOptions& options, double horizon_s, double max_sweep, double warmup_s,
               std::uint64_t events, double slice_s) {
  World world = make_sphere_gas(options);
  if (horizon_s > 0.0) world.settings.broad_phase_horizon_s = horizon_s;
  if (max_sweep > 0.0) world.settings.broad_phase_max_sweep = max_sweep;
  Simulation sim(std::move(world), SimulationOptions{});
  sim.run_until(warmup_s, nullptr);
  const SimulationStats before = sim.stats();
  GasRun run;
  double t = warmup_s;
  const std::clock_t cpu_start = std::clock();
  const auto start = std::chrono::steady_clock::now();
  while (sim.stats().events - before.events < events) {
    t += slice_s;
    sim.run_until(t, nullptr);
  }
  const auto stop = std::chrono::steady_clock::now();
  run.cpu_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  run.wall_s = std::chrono::duration<double>(stop - start).count();
  run.virtual_s = t - warmup_s;
  const SimulationStats& after = sim.stats();
  run.events = after.events - before.events;
  run.collisions = after.collisions - before.collisions;
  run.horizon_refreshes = after.horizon_refreshes - before.horizon_refreshes;
  run.pair_checks = after.pair_checks - before.pair_checks;
  run.bound_queries = after.bound_queries - before.bound_queries;
  run.box_tests = after.box_tests - before.box_tests;
  run.max_pairs = after.max_pairs;
  return run;
}

CommandRegistration registration{
    "bench gas", [](CLI::App& app) {
      app.description(
          "Events per second for gases of frictionless elastic spheres (r = 5 cm, 1 kg, 1 m/s in\n"
          "random directions, zero gravity) in a cube of six fixed halfspaces at a fixed volume\n"
          "fraction. Per count: after an untimed --warmup, median wall (and CPU) time of the\n"
          "event loop over --repeats runs of at least --events events (3 repeats from 10,000\n"
          "spheres), events/s, us per event, us per event / log2 n, and the work per event.\n"
          "Last line: the growth of us/event against that of log n.");
      const double kLargest = std::numeric_limits<double>::max();
      auto counts =
          std::make_shared<std::vector<int>>(std::vector<int>{100, 300, 1000, 3000, 10000});
      auto events = std::make_shared<std::uint64_t>(100000);
      auto repeats = std::make_shared<int>(5);
      auto fraction = std::make_shared<double>(0.1);
      auto horizon = std::make_shared<double>(0.0);
      auto max_sweep = std::make_shared<double>(0.0);
      auto warmup = std::make_shared<double>(1.0);
      app.add_option("--counts", *counts, "sphere counts (default 100,300,1000,3000,10000)")
          ->delimiter(',');
      app.add_option("--events", *events, "events per run, at least (default 100000)")
          ->check(CLI::Range(std::uint64_t{1}, std::numeric_limits<std::uint64_t>::max()));
      app.add_option("--repeats", *repeats, "runs per count, >= 5 (3 from 10,000) (default 5)")
          ->check(CLI::Range(5, std::numeric_limits<int>::max()));
      // The open interval (0, pi / 6) make_sphere_gas accepts: the smallest positive double to
      // just below pi / 6 (a cubic packing of touching spheres).
      app.add_option("--volume-fraction", *fraction, "sphere volume / box volume (default 0.1)")
          ->check(finite_range(std::numeric_limits<double>::min(),
                               std::nextafter(std::acos(-1.0) / 6.0, 0.0)));
      app.add_option("--horizon", *horizon,
                     "broad-phase horizon [s] (default: Settings::broad_phase_horizon_s)")
          ->check(finite_range(std::numeric_limits<double>::min(), kLargest));
      app.add_option("--max-sweep", *max_sweep,
                     "farthest travel per horizon, in sphere radii (default: "
                     "Settings::broad_phase_max_sweep; 1e9 for no limit)")
          ->check(finite_range(std::numeric_limits<double>::min(), kLargest));
      app.add_option("--warmup", *warmup, "untimed virtual time before timing [s] (default 1)")
          ->check(finite_range(0.0, kLargest));
      return std::function<int()>([counts, events, repeats, fraction, horizon, max_sweep, warmup] {
        if (counts->empty()) throw InputError("--counts", "expected at least one count");
        double first_us = 0.0, last_us = 0.0, first_cpu_us = 0.0, last_cpu_us = 0.0;
        int first_n = 0, last_n = 0;
        for (int n : *counts) {
          if (n < 2) throw InputError("--counts", "expected counts >= 2");
          GasOptions options;
          options.count = n;
          options.volume_fraction = *fraction;
          // About ten collisions and horizons per sphere per second: a slice holds ~n / 10
          // events, so the run overshoots --events by little.
          const double slice_s = 0.01;
          const int runs = n >= 10000 ? 3 : *repeats;
          std::vector<double> walls, cpus;
          GasRun run;
          for (int r = 0; r < runs; ++r) {
            run = run_gas(options, *horizon, *max_sweep, *warmup, *events, slice_s);
            walls.push_back(run.wall_s);
            cpus.push_back(run.cpu_s);
          }
          const double wall = median(walls);
          const double cpu = median(cpus);
          const double ev = static_cast<double>(run.events);
          const double us = 1e6 * wall / ev;
          const double cpu_us = 1e6 * cpu / ev;
          std::printf(
              "{\"bench\": \"gas\", \"n\": %d, \"events\": %llu, \"collisions\": %llu, "
              "\"horizon_refreshes\": %llu, \"pair_checks\": %llu, \"bound_queries_per_event\": "
              "%.2f, \"box_tests_per_event\": %.1f, \"max_pairs\": %llu, \"virtual_s\": %.3f, "
              "\"wall_s\": %.4f, \"cpu_s\": %.4f, \"repeats\": %d, \"events_per_s\": %.0f, "
              "\"us_per_event\": %.3f, \"cpu_us_per_event\": %.3f, "
              "\"us_per_event_per_log2n\": %.4f}\n",
              n, static_cast<unsigned long long>(run.events),
              static_cast<unsigned long long>(run.collisions),
              static_cast<unsigned long long>(run.horizon_refreshes),
              static_cast<unsigned long long>(run.pair_checks),
              static_cast<double>(run.bound_queries) / ev, static_cast<double>(run.box_tests) / ev,
              static_cast<unsigned long long>(run.max_pairs), run.virtual_s, wall, cpu, runs,
              ev / wall, us, cpu_us, us / std::log2(n));
          std::fflush(stdout);
          if (first_n == 0) {
            first_n = n;
            first_us = us;
            first_cpu_us = cpu_us;
          }
          last_n = n;
          last_us = us;
          last_cpu_us = cpu_us;
        }
        std::printf(
            "{\"bench\": \"gas\", \"summary\": true, \"n_from\": %d, \"n_to\": %d, "
            "\"us_per_event_ratio\": %.3f, \"cpu_us_per_event_ratio\": %.3f, "
            "\"log_n_ratio\": %.3f, \"n_ratio\": %.1f}\n",
            first_n, last_n, last_us / first_us, last_cpu_us / first_cpu_us,
            std::log(last_n) / std::log(first_n), static_cast<double>(last_n) / first_n);
        return kExitOk;
      });
    }};

}  // namespace
}  // namespace palpable::tools
