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
#include <set>

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
  const std::string incline_params[] = {"body=block",
                                        "angle_deg=30",
                                        "friction=0.3",
                                        "gravity=9.81",
                                        "initial_speed=0.0",
                                        "down_slope=[0.8660254037844386,0,-0.5]",
                                        "normal=[0.5,0,0.8660254037844386]"};
  struct Case {
    PlotKind kind;
    std::string name;
  };
  for (const Case& c :
       {Case{PlotKind::kSeries, "series"}, Case{PlotKind::kTop, "top"},
        Case{PlotKind::kIncline, "incline"}, Case{PlotKind::kTurntable, "turntable"},
        Case{PlotKind::kLine, "line"}, Case{PlotKind::kTumble, "tumble"}}) {
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

namespace {
// Bodies on a line: a striker and two balls moving along x only.
void write_line_trace(const std::string& path) {
  std::ofstream out(path);
  out << palpable::kTraceHeader << "\n";
  for (int k = 0; k <= 50; ++k) {
    BodyState table, a, b;
    a.x_W = Vec3(0.02 * k, 0.0, 0.03);
    b.x_W = Vec3(1.0 + 0.01 * k, 0.0, 0.03);
    palpable::write_trace_rows(out, 0.02 * k, {"table", "a", "b"}, {table, a, b});
  }
}

palpable::Scene scene_of(const std::string& json_text) {
  return palpable::scene_from_json(nlohmann::json::parse(json_text), "test.json");
}
}  // namespace

TEST_CASE("plot: line and tumble draw, auto chooses by scene and trace", "[tools][plot]") {
  const std::string line = "plot_test_kinds_line.csv", incline = "plot_test_kinds_incline.csv";
  write_line_trace(line);
  write_incline_trace(incline);
  for (PlotKind kind : {PlotKind::kLine, PlotKind::kTumble, PlotKind::kAuto}) {
    PlotOptions options;
    options.trace_path = line;
    options.kind = kind;
    options.out_path = "plot_test_kinds.png";
    palpable::tools::plot_trace(options);
    CHECK(is_png(options.out_path));
    std::remove(options.out_path.c_str());
  }
  const palpable::Trace on_line = palpable::read_trace_csv(line);
  const palpable::Trace sloped = palpable::read_trace_csv(incline);
  CHECK(palpable::tools::choose_plot_kind(on_line, nullptr) == PlotKind::kLine);
  CHECK(palpable::tools::choose_plot_kind(sloped, nullptr) == PlotKind::kTop);
  const std::string bodies =
      R"("bodies": [{"name": "table", "motion": "fixed", "shape": {"type": "halfspace", "normal": [0, 0, 1], "offset": 0}},
                    {"name": "a", "mass": 1, "shape": {"type": "sphere", "radius": 0.03}},
                    {"name": "b", "mass": 1, "shape": {"type": "sphere", "radius": 0.03}}])";
  const palpable::Scene hinted = scene_of(
      R"({"format": "palpable-scene/1", "end_time": 1, "plot": "tumble", )" + bodies + "}");
  CHECK(palpable::tools::choose_plot_kind(on_line, &hinted) == PlotKind::kTumble);
  const palpable::Scene plain =
      scene_of(R"({"format": "palpable-scene/1", "end_time": 1, )" + bodies + "}");
  CHECK(palpable::tools::choose_plot_kind(on_line, &plain) == PlotKind::kLine);
  std::remove(line.c_str());
  std::remove(incline.c_str());
}

TEST_CASE("plot: the palette does not repeat within a scene", "[tools][plot]") {
  std::set<std::string> colours;
  for (std::size_t i = 0; i < 24; ++i) {
    const std::string c = palpable::tools::palette_colour(i);
    CAPTURE(i, c);
    CHECK(c.size() == 7);
    CHECK(c[0] == '#');
    colours.insert(c);
  }
  CHECK(colours.size() == 24);
}

TEST_CASE("plot: Pareto labels do not print over each other", "[tools][plot]") {
  // Forty points in a tight cloud: most labels would overlap; the ones placed must not.
  std::vector<palpable::tools::ParetoPoint> points;
  for (int i = 0; i < 40; ++i) {
    points.push_back({1e-3 * (1.0 + 0.01 * (i % 7)), 1e-4 * (1.0 + 0.013 * i), std::to_string(i)});
  }
  points.push_back({1e-1, 1e-8, "far"});
  const auto places = palpable::tools::place_labels(points, -3.2, -0.8, -8.2, -3.6);
  std::size_t shown = 0;
  for (std::size_t i = 0; i < places.size(); ++i) {
    if (!places[i].shown) continue;
    ++shown;
    for (std::size_t j = 0; j < i; ++j) {
      if (!places[j].shown) continue;
      const auto &a = places[i].box, &b = places[j].box;
      CAPTURE(i, j);
      CHECK_FALSE((a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]));
    }
  }
  CHECK(places.back().shown);  // a point alone keeps its label
  CHECK(shown > 3);
  CHECK(shown < points.size());  // the cloud cannot label every point
}
