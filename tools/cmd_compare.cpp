// palpable compare: error figures of a trace against a closed-form reference.
#include "tools/commands.hpp"
#include "tools/lib/compare.hpp"
#include "tools/lib/exit_codes.hpp"

#include <iostream>
#include <memory>

namespace {

palpable::tools::CommandRegistration registration{
    "compare", [](CLI::App& app) {
      auto options = std::make_shared<palpable::tools::CompareOptions>();
      auto as_json = std::make_shared<bool>(false);
      app.description(
          "Compare a trace CSV (from `palpable run --trace`) with a closed-form reference and\n"
          "print the error figures. The reference is a JSON object with \"type\" and parameters\n"
          "(scenarios/README.md): take a scene's own with --reference-from, or give --reference\n"
          "and --param key=value (values parsed as JSON; --param overrides the scene's).\n"
          "References: incline, turntable, slide_to_roll, bouncing_ball, impact_1d.\n"
          "Times are measured from the trace's first sample.\n\n"
          "Exit codes: 0 compared; 2 bad input; 3 a --max threshold was exceeded.\n\n"
          "Examples:\n"
          "  palpable compare ramp.csv --reference-from scenarios/block_on_ramp_decelerating.json"
          " \\\n"
          "      --events ramp_events.csv --max stop_time_error_s=1e-3\n"
          "  palpable compare ball.csv --reference slide_to_roll --param body=ball \\\n"
          "      --param friction=0.2 --param gravity=9.81 --param radius=0.1 --json");
      app.add_option("trace", options->trace_path, "Trace CSV (t,body,x,y,z,qw,...)")->required();
      app.add_option("--events", options->events_path,
                     "Events CSV (t,kind,body_a,body_b,px,py,pz,...): contact points and impact "
                     "times for the references that use them");
      app.add_option("--reference", options->reference.type,
                     "Closed form: incline, turntable, slide_to_roll, bouncing_ball, impact_1d");
      app.add_option("--reference-from", options->reference.scene_path,
                     "Scene file whose \"reference\" object is the spec");
      app.add_option("--param", options->reference.params,
                     "Reference parameter key=value (value parsed as JSON, a bare word is a "
                     "string). Repeatable.");
      app.add_option("--max", options->max,
                     "Threshold figure=limit: exit 3 if |figure| (every entry of a list) exceeds "
                     "it. Repeatable.");
      app.add_flag("--json", *as_json, "Print {\"reference\": spec, \"figures\": {...}} as JSON");
      return std::function<int()>([options, as_json] {
        palpable::tools::CompareResult result = palpable::tools::compare_trace(*options);
        if (*as_json) {
          nlohmann::json out{{"reference", result.spec},
                             {"figures", result.figures},
                             {"exceeded", result.exceeded}};
          std::cout << out.dump(2) << "\n";
        } else {
          std::cout << palpable::tools::compare_text(result);
        }
        return result.exceeded.empty() ? palpable::tools::kExitOk
                                       : palpable::tools::kExitCheckFailed;
      });
    }};

}  // namespace
