#pragma once
// `palpable plot`: PNG pictures of a trace, drawn by gnuplot (Debian package gnuplot-nox, which
// tools/setup installs). The data and a gnuplot script go to a temporary directory; the PNG is
// written beside the target and renamed over it only when gnuplot succeeded, so a failed plot
// leaves no partial picture.
#include "tools/lib/compare.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace palpable::tools {

enum class PlotKind {
  kSeries,     // one body's position and velocity components against time
  kTop,        // top view (x-y) of every body's path
  kIncline,    // along-slope position and velocity against the incline closed form
  kTurntable,  // the ball's path against the closed-form circle
};

struct PlotOptions {
  std::string trace_path;
  PlotKind kind = PlotKind::kSeries;
  std::string body;                 // kSeries: required unless the trace has one body
  ReferenceOptions reference;       // kIncline, kTurntable
  std::string out_path;             // the PNG
  std::string gnuplot = "gnuplot";  // program name or path
};

// Parses "series", "top", "incline", "turntable"; throws InputError naming --kind otherwise.
PlotKind parse_plot_kind(const std::string& text);

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

// Draws error (log) against CPU time (log), one point per entry, the Pareto front joined as a
// staircase. Same atomicity and errors as plot_trace.
void plot_pareto(const std::vector<ParetoPoint>& points, const std::string& title,
                 const std::string& out_path, const std::string& gnuplot = "gnuplot");

}  // namespace palpable::tools
