// palpable run: simulate a scene file.
#include "core/check.hpp"
#include "tools/commands.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/run_scene.hpp"

#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <unistd.h>

namespace {

palpable::tools::CommandRegistration registration{
    "run", [](CLI::App& app) {
      auto options = std::make_shared<palpable::tools::RunOptions>();
      auto end = std::make_shared<double>(0.0);
      app.description(
          "Simulate a scene file (format palpable-scene/1, see scenarios/README.md) and print a\n"
          "summary: virtual and wall time, events by kind and, when the scene names a closed-form\n"
          "reference, the error figures against it. Output files are written atomically: a run\n"
          "that fails leaves none behind.\n\n"
          "Example:\n"
          "  palpable run scenarios/block_on_ramp_decelerating.json --trace block.csv \\\n"
          "      --set /settings/envelope=1e-5 --set /materials/pairs/0/friction=0.6");
      app.add_option("scene", options->scene_path, "Scene file (JSON), or - for standard input")
          ->required();
      app.add_option("--set", options->overrides,
                     "Override a scene value: /json/pointer=value (RFC 6901 pointer; the value is\n"
                     "parsed as JSON, a bare word is a string). Repeatable.");
      app.add_option(
          "--trace", options->trace_path,
          "Write the trace CSV (t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz; world frame)");
      app.add_option(
          "--events", options->events_path,
          "Write the collision events CSV (t,kind,body_a,body_b,px,py,pz,nx,ny,nz,jx,jy,jz,"
          "approach_speed,...)");
      app.add_flag("--strict", options->strict,
                   "Fail (exit 1, no file written) if the run met numerical trouble: bodies\n"
                   "overlapping, the retry limit hit, a failed impulse or distance query.\n"
                   "Without it such a run warns on stderr and exits 0.");
      auto* end_option =
          app.add_option("--end", *end, "End time [s], replacing the scene's end_time");
      app.add_option("--summary-json", options->summary_path,
                     "Write the summary (statistics, wall time, reference figures) as JSON");
      auto cpu_limit = std::make_shared<double>(0.0);
      auto* cpu_limit_option = app.add_option(
          "--cpu-limit", *cpu_limit,
          "Stop the run once it has used this much CPU time [s], checked every 64 events: its\n"
          "outputs are written and hold the run up to the event it stopped after, the summary\n"
          "says where (virtual_time_s, and \"stopped\" in --summary-json), and it exits 4.\n"
          "For budgets over batches of runs (a run to its end exits 0 as usual).");
      auto progress = std::make_shared<bool>(false);
      app.add_flag("--progress", *progress,
                   "Report the simulated time reached on stderr even when it is not a terminal\n"
                   "(by default only on a terminal): at most 4 times a second, after the first\n"
                   "second of wall time, each report starting with a carriage return.");
      return std::function<int()>([options, end, end_option, cpu_limit, cpu_limit_option,
                                   progress] {
        if (end_option->count() > 0) options->end_time = *end;
        if (cpu_limit_option->count() > 0) options->cpu_limit_s = *cpu_limit;
        options->progress = *progress || ::isatty(2) != 0;
        options->keep_trace = false;  // memory flat in simulated time: stream, keep no history
        std::vector<std::pair<std::string, std::string>> outputs = {
            {"--trace", options->trace_path},
            {"--events", options->events_path},
            {"--summary-json", options->summary_path}};
        // A trace written to a file gets a sidecar, TRACE.json: a fourth output.
        if (!options->trace_path.empty() && !palpable::tools::writes_through(options->trace_path)) {
          outputs.push_back({"the --trace sidecar", options->trace_path + ".json"});
        }
        palpable::tools::check_distinct_outputs(outputs);
        palpable::tools::RunResult result = palpable::tools::run_scene(*options);
        // With an output streamed to standard output, the summary goes to stderr.
        auto stdout_named = [](const std::string& path) {
          return palpable::tools::names_descriptor(path) == 1;
        };
        const bool stdout_taken = stdout_named(options->trace_path) ||
                                  stdout_named(options->events_path) ||
                                  stdout_named(options->summary_path);
        (stdout_taken ? std::cerr : std::cout) << palpable::tools::summary_text(result);
        for (const std::string& trouble : palpable::tools::numerical_trouble(result.stats)) {
          std::cerr << "palpable: warning: " << options->scene_path << ": " << trouble
                    << ": the trace may be wrong\n";
        }
        return result.stop ? palpable::tools::kExitStopped : palpable::tools::kExitOk;
      });
    }};

}  // namespace
