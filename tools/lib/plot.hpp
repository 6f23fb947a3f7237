#pragma once
// `palpable plot`: PNG pictures of a trace, drawn by gnuplot (Debian package gnuplot-nox, which
// tools/setup installs). The data and a gnuplot script go to a temporary directory; the PNG is
// written beside the target and renamed over it only when gnuplot succeeded, so a failed plot
// leaves no partial picture.
#include "tools/lib/compare.hpp"

#include "scenarios/scene.hpp"
#include "scenarios/trace.hpp"

#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace palpable::tools {

enum class PlotKind {
  kSeries,     // one body's position and velocity components against time
  kTop,        // top view (x-y) of every body's path, the fixed bodies drawn (with a scene)
  kIncline,    // along-slope position and velocity against the incline closed form
  kTurntable,  // the ball's path against the closed-form circle, and its distance from it
  kLine,       // bodies moving on one line (a chain of balls): position and velocity per body
  kTumble,     // bodies that bounce and turn over (coins): height, tilt and spin per body
  kAuto,       // chosen by the scene and the trace (choose_plot_kind)
};

struct PlotOptions {
  std::string trace_path;
  PlotKind kind = PlotKind::kSeries;
  std::string body;                 // kSeries: required unless the trace has one body
  ReferenceOptions reference;       // kIncline, kTurntable
  std::string scene_path;           // the run's scene (else reference.scene_path): fixed bodies,
                                    // the turntable's launch state, kAuto's choice
  std::string out_path;             // the PNG
  std::string gnuplot = "gnuplot";  // program name or path
};

// Parses "series", "top", "incline", "turntable", "line", "tumble", "auto"; throws InputError
// naming --kind otherwise.
PlotKind parse_plot_kind(const std::string& text);

// kAuto's choice: the scene's "plot" hint if it has one; else its reference's picture (incline,
// turntable); else kLine when every moving body stays on one line (within 2% of the longest
// path); else kTop. `scene` may be null (only the trace decides).
PlotKind choose_plot_kind(const Trace& trace, const Scene* scene);

// The i-th colour of a palette that does not repeat: golden-angle hues, "#rrggbb".
std::string palette_colour(std::size_t i);

// The program's full path if it is found (a path, or on PATH), else empty.
std::string find_program(const std::string& name);
// The same, but throws std::runtime_error naming the program and the Debian package to install
// (gnuplot-nox) if it is not found.
std::string require_gnuplot(const std::string& name = "gnuplot");

// Draws the plot. Throws InputError for bad input, std::runtime_error if gnuplot is missing or
// fails (its messages included).
void plot_trace(const PlotOptions& options);

// One point of a cost/accuracy plot.
struct ParetoPoint {
  double cpu_s = 0.0;
  double error = 0.0;
  std::string label;  // drawn beside the point (a combination index)
};

// The indices of the points on the Pareto front (no other point has both a lower CPU time and a
// lower error), in order of increasing CPU time; non-finite points are never on it.
std::vector<std::size_t> pareto_front(const std::vector<ParetoPoint>& points);

// Where a point's label goes in a cost/accuracy plot whose axes span 10^x_lo..10^x_hi and
// 10^y_lo..10^y_hi: beside its point, overlapping no other label and no point, the Pareto front's
// labels placed first; a label with no free place is left out (shown false). Sizes are those of
// the 1100x800 picture's plot area (about 900x650 pixels) with an 8-point font.
struct LabelPlace {
  bool shown = false;
  double x = 0.0, y = 0.0;                // the anchor: left end, vertical middle (graph units)
  std::array<double, 4> box{0, 0, 0, 0};  // left, bottom, right, top (graph units)
};
std::vector<LabelPlace> place_labels(const std::vector<ParetoPoint>& points, double x_lo,
                                     double x_hi, double y_lo, double y_hi);

// Draws error (log) against CPU time (log), one point per entry, the Pareto front joined as a
// staircase. Same atomicity and errors as plot_trace.
void plot_pareto(const std::vector<ParetoPoint>& points, const std::string& title,
                 const std::string& out_path, const std::string& gnuplot = "gnuplot");

}  // namespace palpable::tools
