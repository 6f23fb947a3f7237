// palpable sweep: run a scene over a grid of settings, tabulate error and cost per combination.
#include "core/check.hpp"
#include "tools/commands.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/plot.hpp"
#include "tools/lib/sweep.hpp"

#include <iostream>
#include <memory>

#include <unistd.h>

namespace {

struct SweepCommand {
  palpable::tools::SweepOptions options;
  std::string scene;
  std::vector<std::string> vary;
  std::string shard;
  std::vector<std::string> merge;
  std::string out_path;
  std::string plot_path;
  double end = 0.0;
  CLI::Option* end_option = nullptr;
};

int run(SweepCommand& c) {
  using namespace palpable::tools;
  if (c.merge.empty() && c.scene.empty()) {
    throw palpable::InputError("scene", "required: the scene file to sweep (or --merge)");
  }
  check_distinct_outputs({{"--out", c.out_path}, {"--plot", c.plot_path}});
  // Before the sweep runs, not after: a missing gnuplot costs nothing.
  if (!c.plot_path.empty()) require_gnuplot();
  SweepTable table;
  std::string title;
  if (!c.merge.empty()) {
    std::vector<SweepTable> parts;
    for (const std::string& path : c.merge) parts.push_back(read_sweep_csv(path));
    table = merge_sweep_tables(parts, c.merge);
    title = "merged sweep";
  } else {
    c.options.scene_path = c.scene;
    for (const std::string& text : c.vary) c.options.parameters.push_back(parse_vary(text));
    if (!c.shard.empty()) c.options.shard = parse_shard(c.shard);
    if (c.end_option->count() > 0) c.options.end_time = c.end;
    c.options.progress = ::isatty(2) != 0;
    table = run_sweep(c.options);
    title = c.scene.substr(c.scene.find_last_of('/') + 1);
    for (const auto& p : c.options.parameters) title += " " + p.pointer;
  }
  if (c.out_path.empty()) {
    write_sweep_csv(std::cout, table);
  } else {
    AtomicFile out(c.out_path);
    write_sweep_csv(out.stream(), table);
    out.commit();
  }
  if (!c.plot_path.empty()) plot_sweep(table, c.plot_path, title + ": error against CPU time");
  return kExitOk;
}

palpable::tools::CommandRegistration registration{
    "sweep", [](CLI::App& app) {
      auto c = std::make_shared<SweepCommand>();
      app.description(
          "Run a scene for every combination of the varied values (cartesian product), each\n"
          "through the code path of `palpable run` (the values are applied like --set), and write\n"
          "one CSV row per combination:\n"
          "  combination      index in the fixed enumeration order (the first --vary varies\n"
          "                   slowest, the last fastest), combinations (the total),\n"
          "  sweep            the sweep's fingerprint (hash of the scene path, --set, --end and\n"
          "                   every --vary): --merge joins only tables of one sweep,\n"
          "  /json/pointer    one column per --vary, the value as given,\n"
          "  error            the scene's primary relative error against its closed form:\n"
          "                     incline (stopping): max(|t_stop error| / t*, creep / stop "
          "distance)\n"
          "                     incline (accelerating): |acceleration relative error|\n"
          "                     turntable: max(|orbit rate rel. error|, circle deviation / "
          "radius)\n"
          "                     slide_to_roll: max(|roll time error| / t_roll, |final speed rel.\n"
          "                       error|)\n"
          "                     bouncing_ball: largest apex height relative error\n"
          "                     impact_1d: largest velocity error / approach speed\n"
          "                   (nan: the run did not show the motion the reference measures),\n"
          "  cpu_s            CPU time of one run, median of the --repeat runs (only timings may\n"
          "                   differ between repeats: any other difference fails the sweep),\n"
          "  events, collisions, microcollisions,\n"
          "  trouble          kinds of numerical trouble the run met (overlapping bodies, a pair\n"
          "                   past the collision retry limit, failed impulse integrations or\n"
          "                   closest-feature walks: `palpable run`'s warnings); 0 when clean, a\n"
          "                   row with trouble > 0 may be wrong,\n"
          "  then every scalar reference figure (as `palpable run` prints them; arrays as\n"
          "  name_0, name_1, ...).\n"
          "Every value is checked before anything runs; nothing is written if the sweep fails.\n\n"
          "Spreading a sweep over machines: --shard K/N runs the combinations i with\n"
          "i mod N = K - 1 (rows keep their global index); --merge joins the shard tables,\n"
          "checking that every combination appears exactly once.\n\n"
          "Examples:\n"
          "  palpable sweep scenarios/block_on_ramp_accelerating.json \\\n"
          "      --vary /settings/envelope=1e-3,1e-4,1e-5 \\\n"
          "      --vary /settings/restitution_law=stronge,poisson --repeat 3 --jobs 2 \\\n"
          "      --out ramp.csv --plot ramp.png\n"
          "  for k in 1 2 3; do palpable sweep SCENE --vary ... --shard $k/3 --out part$k.csv; "
          "done\n"
          "  palpable sweep --merge part1.csv part2.csv part3.csv --out all.csv --plot all.png");
      CLI::Option* scene = app.add_option("scene", c->scene, "Scene file (JSON)");
      CLI::Option* vary = app.add_option(
          "--vary", c->vary,
          "/json/pointer=v1,v2,...: the values one scene value takes (each parsed as\n"
          "JSON, a bare word is a string; a value holding commas goes in brackets or\n"
          "quotes). Repeatable: the sweep runs the cartesian product.");
      CLI::Option* set = app.add_option(
          "--set", c->options.overrides,
          "/json/pointer=value: a fixed override for every combination. Repeatable.");
      c->end_option =
          app.add_option("--end", c->end, "End time [s], replacing the scene's end_time");
      CLI::Option* repeat = app.add_option(
          "--repeat", c->options.repeat, "Runs per combination; cpu_s is their median (default 1)");
      CLI::Option* jobs =
          app.add_option("--jobs", c->options.jobs,
                         "Combinations run at once, each in its own process (default 1). The rows\n"
                         "come out in combination order whatever the number.");
      CLI::Option* shard =
          app.add_option("--shard", c->shard,
                         "K/N: run only the K-th of N disjoint slices (combination i is in slice\n"
                         "(i mod N) + 1)");
      CLI::Option* merge = app.add_option(
          "--merge", c->merge,
          "Merge these sweep tables (the shards' outputs) instead of running; fails\n"
          "on a missing or duplicated combination or on tables of different sweeps.\n"
          "Takes no scene and no run option (--vary, --set, --end, --repeat, --jobs,\n"
          "--shard): those are the shards'.");
      // Every run option is meaningless with --merge: CLI11 rejects the pair, naming both.
      for (CLI::Option* run_option : {scene, vary, set, c->end_option, repeat, jobs, shard}) {
        merge->excludes(run_option);
      }
      app.add_option("--out", c->out_path, "Write the CSV here (atomically); default stdout");
      app.add_option("--plot", c->plot_path,
                     "Draw error (log) against CPU time (log) with the Pareto front into this PNG "
                     "(gnuplot)");
      return std::function<int()>([c] { return run(*c); });
    }};

}  // namespace
