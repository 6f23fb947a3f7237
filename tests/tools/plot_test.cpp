// `palpable plot`: every kind draws a PNG from a small synthetic trace with the real gnuplot
// (tools/setup installs gnuplot-nox; a machine without it fails here rather than skipping), and a
// failing gnuplot leaves no file behind.
#include "tools/lib/plot.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

using palpable::BodyState;
using palpable::Vec3;
using palpable::tools::PlotKind;
using palpable::tools::PlotOptions;

namespace {
constexpr double kPi = 3.14159265358979323846;

// A block sliding down a 30 degree slope from rest (mu = 0.3), and a second body at rest.
void write_incline_trace(const std::string& path) {
  const double theta = kPi / 6.0, a = 9.81 * (std::sin(theta) - 0.3 * std::cos(theta));
  const Vec3 down(std::cos(theta), 0.0, -std::sin(theta));
  std::ofstream out(path);
  out << palpable::kTraceHeader << "\n";
  for (int k = 0; k <= 50; ++k) {
    const double t = 0.02 * k;
    BodyState block, ramp;
    block.x_W = Vec3(0.0, 0.0, 1.0) + down * 0.5 * a * t * t;
    block.v_W = down * a * t;
    palpable::write_trace_rows(out, t, {"ramp", "block"}, {ramp, block});
  }
}

bool is_png(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  return in.gcount() == 8 && std::string(magic, 8) == std::string("\x89PNG\r\n\x1a\n", 8);
}
}  // namespace

TEST_CASE("plot: every kind writes a PNG", "[tools][plot]") {
  if (palpable::tools::find_program("gnuplot").empty()) {
    FAIL("gnuplot is not on PATH: install the Debian package gnuplot-nox (tools/setup does)");
  }
  const std::string trace = "plot_test_incline.csv";
  write_incline_trace(trace);
  const std::string incline_params[] = {
      "body=block",   "angle_deg=30",      "friction=0.3",
      "gravity=9.81", "initial_speed=0.0", "down_slope=[0.8660254037844386,0,-0.5]",
      "normal=[0.5,0,0.8660254037844386]"};
  struct Case {
    PlotKind kind;
    std::string name;
  };
  for (const Case& c :
       {Case{PlotKind::kSeries, "series"}, Case{PlotKind::kTop, "top"},
        Case{PlotKind::kIncline, "incline"}, Case{PlotKind::kTurntable, "turntable"}}) {
    CAPTURE(c.name);
    PlotOptions options;
    options.trace_path = trace;
    options.kind = c.kind;
    options.body = "block";
    options.out_path = "plot_test_" + c.name + ".png";
    std::remove(options.out_path.c_str());
    if (c.kind == PlotKind::kIncline) {
      options.reference.type = "incline";
      options.reference.params.assign(std::begin(incline_params), std::end(incline_params));
    } else if (c.kind == PlotKind::kTurntable) {
      options.reference.type = "turntable";
      options.reference.params = {"body=block", "omega=6.283185307179586"};
    }
    palpable::tools::plot_trace(options);
    CHECK(is_png(options.out_path));
    std::remove(options.out_path.c_str());
  }
  std::remove(trace.c_str());
}

TEST_CASE("plot: bad input and a failing gnuplot leave no file", "[tools][plot]") {
  const std::string trace = "plot_test_bad.csv";
  write_incline_trace(trace);
  PlotOptions options;
  options.trace_path = trace;
  options.out_path = "plot_test_bad.png";
  std::remove(options.out_path.c_str());
  // Two bodies: series needs --body.
  CHECK_THROWS_WITH(palpable::tools::plot_trace(options), Catch::Contains("--body"));
  options.kind = PlotKind::kIncline;
  options.reference.type = "turntable";
  CHECK_THROWS_WITH(palpable::tools::plot_trace(options), Catch::Contains("--reference"));
  CHECK_THROWS_WITH(palpable::tools::parse_plot_kind("pie"), Catch::Contains("--kind"));
  // A "gnuplot" that fails without drawing anything.
  options.kind = PlotKind::kTop;
  options.gnuplot = "/bin/false";
  CHECK_THROWS_WITH(palpable::tools::plot_trace(options), Catch::Contains("gnuplot failed"));
  options.gnuplot = "no-such-gnuplot-program";
  CHECK_THROWS_WITH(palpable::tools::plot_trace(options), Catch::Contains("gnuplot-nox"));
  CHECK_FALSE(std::filesystem::exists(options.out_path));
  std::remove(trace.c_str());
}
