// `palpable sweep`: a sweep run whole equals its shards merged, row for row (timings aside), in
// one process or several; bad options are rejected before anything runs, naming the option.
#include "tools/lib/sweep.hpp"

#include "core/check.hpp"
#include "tools/lib/plot.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

using nlohmann::json;
using palpable::InputError;
using palpable::tools::SweepOptions;
using palpable::tools::SweepTable;

namespace {

std::string scene(const std::string& name) {
  return std::string(PALPABLE_SOURCE_DIR) + "/scenarios/" + name;
}

// A cheap 2 x 2 sweep: the accelerating block for 0.3 s, two envelopes, two restitution laws.
SweepOptions small_sweep() {
  SweepOptions options;
  options.scene_path = scene("block_on_ramp_accelerating.json");
  options.end_time = 0.3;
  options.parameters = {palpable::tools::parse_vary("/settings/envelope=1e-3,1e-4"),
                        palpable::tools::parse_vary("/settings/restitution_law=stronge,poisson")};
  return options;
}

std::size_t column(const SweepTable& table, const std::string& name) {
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    if (table.columns[c] == name) return c;
  }
  FAIL("no column " << name);
  return 0;
}

// Every cell equal except the CPU time.
void require_same_rows(const SweepTable& a, const SweepTable& b) {
  REQUIRE(a.columns == b.columns);
  REQUIRE(a.rows.size() == b.rows.size());
  const std::size_t cpu = column(a, "cpu_s");
  for (std::size_t r = 0; r < a.rows.size(); ++r) {
    for (std::size_t c = 0; c < a.columns.size(); ++c) {
      if (c == cpu) continue;
      CAPTURE(r, a.columns[c]);
      CHECK(a.rows[r][c] == b.rows[r][c]);
    }
  }
}

SweepTable through_file(const SweepTable& table, const std::string& path) {
  {
    std::ofstream out(path);
    palpable::tools::write_sweep_csv(out, table);
  }
  SweepTable back = palpable::tools::read_sweep_csv(path);
  std::remove(path.c_str());
  return back;
}

}  // namespace

TEST_CASE("a sweep run whole equals its three shards merged, row for row", "[tools][sweep]") {
  SweepOptions whole = small_sweep();
  whole.jobs = 2;  // forked workers; the shards below run in process
  const SweepTable single = palpable::tools::run_sweep(whole);

  REQUIRE(single.rows.size() == 4);
  const std::size_t envelope = column(single, "/settings/envelope");
  const std::size_t law = column(single, "/settings/restitution_law");
  const char* expected[4][2] = {
      {"1e-3", "stronge"}, {"1e-3", "poisson"}, {"1e-4", "stronge"}, {"1e-4", "poisson"}};
  for (std::size_t r = 0; r < 4; ++r) {
    CAPTURE(r);
    CHECK(single.rows[r][0] == std::to_string(r));
    CHECK(single.rows[r][1] == "4");
    CHECK(single.rows[r][envelope] == expected[r][0]);
    CHECK(single.rows[r][law] == expected[r][1]);
    // The accelerating block's primary error is |acceleration_rel_error|.
    const double error = std::stod(single.rows[r][column(single, "error")]);
    const double rel = std::stod(single.rows[r][column(single, "acceleration_rel_error")]);
    CHECK(error == std::abs(rel));
    CHECK(error < 1e-2);
    CHECK(std::stol(single.rows[r][column(single, "events")]) > 0);
  }

  std::vector<SweepTable> parts;
  std::vector<std::string> names;
  for (std::size_t k = 1; k <= 3; ++k) {
    SweepOptions shard = small_sweep();
    shard.shard = {k, 3};
    names.push_back("sweep_test_shard" + std::to_string(k) + ".csv");
    parts.push_back(through_file(palpable::tools::run_sweep(shard), names.back()));
    // Shard k holds the combinations i with i mod 3 = k - 1.
    for (const auto& row : parts.back().rows) CHECK(std::stoul(row[0]) % 3 == k - 1);
  }
  // In any order.
  std::swap(parts[0], parts[2]);
  std::swap(names[0], names[2]);
  const SweepTable merged = palpable::tools::merge_sweep_tables(parts, names);
  require_same_rows(single, through_file(merged, "sweep_test_merged.csv"));
}

TEST_CASE("repeats agree in everything but timing, and merging checks completeness",
          "[tools][sweep]") {
  SweepOptions options = small_sweep();
  options.parameters.pop_back();
  options.repeat = 3;
  const SweepTable table = palpable::tools::run_sweep(options);
  REQUIRE(table.rows.size() == 2);
  CHECK(std::stod(table.rows[0][column(table, "cpu_s")]) >= 0.0);

  SweepOptions first = options, second = options;
  first.repeat = second.repeat = 1;
  first.shard = {1, 2};
  second.shard = {2, 2};
  const SweepTable a = palpable::tools::run_sweep(first);
  const SweepTable b = palpable::tools::run_sweep(second);
  require_same_rows(table, palpable::tools::merge_sweep_tables({a, b}, {"a.csv", "b.csv"}));
  CHECK_THROWS_WITH(palpable::tools::merge_sweep_tables({a}, {"a.csv"}),
                    Catch::Contains("--merge") && Catch::Contains("1 of 2 combinations missing"));
  CHECK_THROWS_WITH(palpable::tools::merge_sweep_tables({a, b, a}, {"a.csv", "b.csv", "c.csv"}),
                    Catch::Contains("c.csv") && Catch::Contains("appears twice"));
  SweepTable other = b;
  other.columns[2] = "/settings/integration_tolerance";
  CHECK_THROWS_WITH(palpable::tools::merge_sweep_tables({a, other}, {"a.csv", "b.csv"}),
                    Catch::Contains("b.csv") && Catch::Contains("parameters differ"));
}

TEST_CASE("bad sweep options are rejected before anything runs, naming the option",
          "[tools][sweep]") {
  using palpable::tools::parse_shard;
  using palpable::tools::parse_vary;
  for (const char* text : {"settings/envelope=1", "/settings/envelope",
                           "/settings/envelope=", "/settings/envelope=1e-3,,1e-4", "=1"}) {
    CAPTURE(text);
    CHECK_THROWS_WITH(parse_vary(text), Catch::StartsWith("--vary"));
  }
  const auto gravity = parse_vary("/gravity=[0,0,-9.81], [0,0,-1.62]");
  CHECK(gravity.values == std::vector<std::string>{"[0,0,-9.81]", "[0,0,-1.62]"});
  CHECK(parse_vary("/name=\"a,b\",c").values.size() == 2);

  for (const char* text : {"0/3", "4/3", "1/0", "a/3", "3", "1/3/4", "-1/3", "/3"}) {
    CAPTURE(text);
    CHECK_THROWS_WITH(parse_shard(text), Catch::StartsWith("--shard"));
  }
  CHECK(parse_shard("3/3").index == 3);

  struct Case {
    std::string what, vary, expected;
  };
  for (const Case& c : std::vector<Case>{
           {"unknown key", "/settings/envelop=1e-3", "--vary /settings/envelop=1e-3"},
           {"bad value", "/settings/envelope=1e-3,-1", "--vary /settings/envelope=-1"},
           {"bad law", "/settings/restitution_law=stronge,hooke",
            "--vary /settings/restitution_law=hooke"},
           {"no such place", "/bodies/7/mass=1", "--vary /bodies/7/mass=1"}}) {
    CAPTURE(c.what);
    SweepOptions options = small_sweep();
    options.parameters = {parse_vary(c.vary)};
    CHECK_THROWS_AS(palpable::tools::run_sweep(options), InputError);
    CHECK_THROWS_WITH(palpable::tools::run_sweep(options), Catch::StartsWith(c.expected));
  }
  SweepOptions twice = small_sweep();
  twice.parameters.push_back(parse_vary("/settings/envelope=1e-5"));
  CHECK_THROWS_WITH(palpable::tools::run_sweep(twice), Catch::Contains("varied twice"));
  SweepOptions repeat = small_sweep();
  repeat.repeat = 0;
  CHECK_THROWS_WITH(palpable::tools::run_sweep(repeat), Catch::StartsWith("--repeat"));
  SweepOptions jobs = small_sweep();
  jobs.jobs = 0;
  CHECK_THROWS_WITH(palpable::tools::run_sweep(jobs), Catch::StartsWith("--jobs"));
  SweepOptions stdin_scene = small_sweep();
  stdin_scene.scene_path = "-";
  CHECK_THROWS_WITH(palpable::tools::run_sweep(stdin_scene), Catch::StartsWith("scene"));
  SweepOptions end = small_sweep();
  end.end_time = -1.0;
  CHECK_THROWS_WITH(palpable::tools::run_sweep(end), Catch::StartsWith("--end"));
}

TEST_CASE("the primary error of each reference type", "[tools][sweep]") {
  using palpable::tools::primary_error;
  CHECK(primary_error(json{{"reference", "incline"},
                           {"mode", "slide_then_stop"},
                           {"stop_time_error_s", -2e-3},
                           {"stop_time_closed_form_s", 2.0},
                           {"creep_m", 4e-3},
                           {"stop_distance_closed_form_m", 2.0}}) == Approx(2e-3));
  CHECK(primary_error(json{{"reference", "incline"},
                           {"mode", "accelerating"},
                           {"acceleration_rel_error", -3e-5}}) == Approx(3e-5));
  CHECK(primary_error(json{{"reference", "turntable"},
                           {"rate_rel_error", 1e-4},
                           {"circle_deviation_max_m", 1e-3},
                           {"radius_closed_form_m", 0.5}}) == Approx(2e-3));
  CHECK(primary_error(json{{"reference", "slide_to_roll"},
                           {"roll_time_error_s", 1e-3},
                           {"roll_time_closed_form_s", 0.25},
                           {"final_speed_rel_error", -1e-3}}) == Approx(4e-3));
  CHECK(primary_error(json{{"reference", "bouncing_ball"}, {"apex_height_rel_error_max", -0.1}}) ==
        Approx(0.1));
  CHECK(primary_error(json{{"reference", "impact_1d"},
                           {"velocity_a_rel_error", 1e-9},
                           {"velocity_b_rel_error", -2e-9}}) == Approx(2e-9));
  // A figure the error needs is missing (the block never stopped): not a number.
  CHECK(std::isnan(primary_error(json{{"reference", "incline"},
                                      {"mode", "slide_then_stop"},
                                      {"creep_m", 0.0},
                                      {"stop_distance_closed_form_m", 2.0}})));
  CHECK(std::isnan(primary_error(json())));
}

TEST_CASE("the Pareto front and its plot", "[tools][sweep][plot]") {
  using palpable::tools::ParetoPoint;
  const std::vector<ParetoPoint> points{{1.0, 1e-2, "a"},         {2.0, 1e-3, "b"},
                                        {2.5, 5e-3, "c"},         {4.0, 1e-6, "d"},
                                        {0.5, std::nan(""), "e"}, {8.0, 1e-6, "f"}};
  CHECK(palpable::tools::pareto_front(points) == std::vector<std::size_t>{0, 1, 3});

  SweepTable table;
  table.columns = {"combination", "combinations", "/settings/envelope", "error",
                   "cpu_s",       "events",       "collisions",         "microcollisions"};
  table.rows = {{"0", "3", "1e-3", "1e-2", "0.1", "10", "1", "9"},
                {"1", "3", "1e-4", "1e-4", "0.3", "30", "1", "29"},
                {"2", "3", "1e-5", "0", "0.9", "90", "1", "89"}};
  const std::string png = "sweep_test_pareto.png";
  palpable::tools::plot_sweep(table, png, "test");
  std::ifstream in(png, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  CHECK(std::string(magic + 1, 3) == "PNG");
  std::remove(png.c_str());
}
