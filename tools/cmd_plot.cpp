// palpable plot: PNG pictures of a trace (gnuplot).
#include "tools/commands.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/plot.hpp"

#include <iostream>
#include <memory>

namespace {

palpable::tools::CommandRegistration registration{
    "plot", [](CLI::App& app) {
      auto options = std::make_shared<palpable::tools::PlotOptions>();
      auto kind = std::make_shared<std::string>("series");
      app.description(
          "Draw a trace CSV as a PNG with gnuplot (Debian package gnuplot-nox, installed by\n"
          "tools/setup). Kinds:\n"
          "  series     one body's position and velocity components against time (--body)\n"
          "  top        top view (x-y) of every moving body's path, one colour each, over the\n"
          "             fixed bodies near them (table, cushions, lane, pit, dish; needs --scene)\n"
          "  incline    along-slope position and velocity against the incline closed form\n"
          "  turntable  the ball's path against the closed-form circle (from the scene's launch\n"
          "             state), and its distance from the circle against time\n"
          "  line       bodies on one line (a chain of balls): position and velocity per body\n"
          "  tumble     bodies that bounce and turn over (coins): height, tilt and spin per body\n"
          "  auto       the scene's \"plot\" hint, else its reference's picture, else line when\n"
          "             every body stays on one line, else top\n"
          "incline and turntable take the reference like `palpable compare`: --reference-from\n"
          "SCENE.json (or --scene), or --reference and --param key=value. The PNG is written only\n"
          "when gnuplot succeeded (no partial file).\n\n"
          "Examples:\n"
          "  palpable plot ramp.csv --kind incline \\\n"
          "      --reference-from scenarios/block_on_ramp_decelerating.json --out ramp.png\n"
          "  palpable plot platter.csv --kind turntable --reference-from "
          "scenarios/ball_on_platter.json --out platter.png\n"
          "  palpable plot ramp.csv --kind series --body block --out block.png\n"
          "  palpable plot pool.csv --kind auto --scene scenarios/pool_break.json --out pool.png");
      app.add_option("trace", options->trace_path, "Trace CSV (t,body,x,y,z,qw,...)")->required();
      app.add_option("--kind", *kind,
                     "series | top | incline | turntable | line | tumble | auto (default series)");
      app.add_option("--out", options->out_path, "PNG file to write")->required();
      app.add_option("--scene", options->scene_path,
                     "The run's scene: fixed bodies in top views, the turntable's launch state, "
                     "the auto kind's choice");
      app.add_option("--body", options->body,
                     "Body to draw (series; may be omitted for a one-body trace)");
      app.add_option("--reference", options->reference.type,
                     "Closed form for incline/turntable plots");
      app.add_option("--reference-from", options->reference.scene_path,
                     "Scene file whose \"reference\" object is the spec");
      app.add_option("--param", options->reference.params,
                     "Reference parameter key=value (value parsed as JSON). Repeatable.");
      app.add_option("--gnuplot", options->gnuplot, "gnuplot program (default: gnuplot on PATH)");
      return std::function<int()>([options, kind] {
        options->kind = palpable::tools::parse_plot_kind(*kind);
        palpable::tools::plot_trace(*options);
        // With the PNG on standard output, the note goes to stderr.
        (palpable::tools::names_descriptor(options->out_path) == 1 ? std::cerr : std::cout)
            << "wrote " << options->out_path << "\n";
        return palpable::tools::kExitOk;
      });
    }};

}  // namespace
