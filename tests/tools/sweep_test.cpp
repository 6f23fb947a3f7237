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
    // A clean run: no overlap, no retry-limit hit, no failed integration.
    CHECK(single.rows[r][column(single, "trouble")] == "0");
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
  other.columns[column(other, "/settings/envelope")] = "/settings/integration_tolerance";
  CHECK_THROWS_WITH(palpable::tools::merge_sweep_tables({a, other}, {"a.csv", "b.csv"}),
                    Catch::Contains("b.csv") && Catch::Contains("parameters differ"));
}

TEST_CASE("shards of different sweeps do not merge", "[tools][sweep]") {
  using palpable::tools::sweep_fingerprint;
  const SweepOptions base = small_sweep();
  const std::string print = sweep_fingerprint(base);
  CHECK(print.size() == 16);
  CHECK(print.find_first_not_of("0123456789abcdef") == std::string::npos);
  SweepOptions same = base;
  same.repeat = 3;
  same.jobs = 2;
  same.shard = {2, 3};
  CHECK(sweep_fingerprint(same) == print);
  // Each of these changes the meaning of the rows, so each changes the fingerprint.
  std::vector<SweepOptions> others(5, base);
  others[0].scene_path = scene("block_on_ramp_decelerating.json");
  others[1].overrides = {"/settings/envelope=1e-5"};
  others[2].end_time = 0.4;
  others[3].end_time.reset();
  others[4].parameters[0] = palpable::tools::parse_vary("/settings/envelope=1e-3,1e-5");
  for (std::size_t k = 0; k < others.size(); ++k) {
    CAPTURE(k);
    CHECK(sweep_fingerprint(others[k]) != print);
  }

  // Two sweeps of 2 x 2 combinations differing in one --vary value: their shards would fill
  // the table exactly, but they are not one sweep.
  SweepOptions a = base, b = others[4];
  a.shard = {1, 2};
  b.shard = {2, 2};
  const SweepTable part_a = palpable::tools::run_sweep(a);
  const SweepTable part_b = palpable::tools::run_sweep(b);
  CHECK(part_a.rows[0][2] == print);
  CHECK_THROWS_WITH(palpable::tools::merge_sweep_tables({part_a, part_b}, {"a.csv", "b.csv"}),
                    Catch::StartsWith("b.csv row 2") && Catch::Contains("another sweep"));
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
    // Named once, as the --vary option, not also as the --set it is applied like.
    CHECK_THROWS_WITH(palpable::tools::run_sweep(options), !Catch::Contains("--set"));
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

namespace {

// Writes `text` as it is (no newline translation) and returns the path.
std::string write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

const std::string kHeader =
    "combination,combinations,sweep,/settings/envelope,error,cpu_s,events,collisions,"
    "microcollisions,trouble,creep_m";

}  // namespace

TEST_CASE("malformed sweep tables are rejected naming the file and line", "[tools][sweep]") {
  using palpable::tools::read_sweep_csv;
  struct Case {
    std::string what, text, expected;
  };
  for (const Case& c :
       std::vector<Case>{{"empty file", "", "empty file"},
                         {"short row", kHeader + "\n0,2,f,1e-3,0.1,0.2,10,1,9,0,0\n\n1,2,f,1e-4\n",
                          "sweep_test_bad.csv line 4: 4 cells, the header has 11"},
                         {"long row", kHeader + "\n0,2,f,1e-3,0.1,0.2,10,1,9,0,0,7\n",
                          "sweep_test_bad.csv line 2: 12 cells"},
                         {"unterminated quote", kHeader + "\n0,2,f,\"1e-3,0.1,0.2,10,1,9,0,0\n",
                          "sweep_test_bad.csv line 2: unterminated quoted cell"},
                         {"not a sweep", "a,b,c\n1,2,3\n", "not a sweep table"}}) {
    CAPTURE(c.what);
    const std::string path = write_file("sweep_test_bad.csv", c.text);
    CHECK_THROWS_AS(read_sweep_csv(path), InputError);
    CHECK_THROWS_WITH(read_sweep_csv(path), Catch::Contains(c.expected));
    std::remove(path.c_str());
  }
}

TEST_CASE("CRLF shard files merge like LF ones, and a line break in a cell becomes a space",
          "[tools][sweep]") {
  const std::string rows[3] = {"0,3,f,1e-3,0.1,0.2,10,1,9,0,0.5", "1,3,f,1e-4,0.01,0.3,20,1,19,0,",
                               "2,3,f,\"a,b\",0.001,0.4,30,1,29,2,0.25"};
  const std::string lf = write_file(
      "sweep_test_lf.csv", kHeader + "\n" + rows[0] + "\n" + rows[1] + "\n" + rows[2] + "\n");
  const std::string crlf_a =
      write_file("sweep_test_crlf_a.csv", kHeader + "\r\n" + rows[0] + "\r\n" + rows[2] + "\r\n");
  const std::string crlf_b =
      write_file("sweep_test_crlf_b.csv", kHeader + "\r\n" + rows[1] + "\r\n");
  const SweepTable whole = palpable::tools::read_sweep_csv(lf);
  REQUIRE(whole.rows.size() == 3);
  CHECK(whole.columns.back() == "creep_m");
  CHECK(whole.rows[2][3] == "a,b");
  const SweepTable merged = palpable::tools::merge_sweep_tables(
      {palpable::tools::read_sweep_csv(crlf_a), palpable::tools::read_sweep_csv(crlf_b)},
      {crlf_a, crlf_b});
  CHECK(merged.columns == whole.columns);
  CHECK(merged.rows == whole.rows);
  for (const std::string& path : {lf, crlf_a, crlf_b}) std::remove(path.c_str());

  SweepTable broken = whole;
  broken.rows[0][10] = "two\nlines";
  const SweepTable back = through_file(broken, "sweep_test_newline.csv");
  REQUIRE(back.rows.size() == 3);
  CHECK(back.rows[0][10] == "two lines");
}

TEST_CASE("a combination that fails when run is named with its values", "[tools][sweep]") {
  // Each value is valid alone (validation passes), but in combination 0 the second assignment
  // points into the emptied array, so its run fails; combination 1 runs.
  for (int jobs : {1, 2}) {
    CAPTURE(jobs);
    SweepOptions options = small_sweep();
    options.jobs = jobs;
    options.parameters = {
        palpable::tools::parse_vary("/materials/pairs=[],[{\"bodies\": [\"block\", \"ramp\"], "
                                    "\"friction\": 0.3, \"restitution\": 0.0}]"),
        palpable::tools::parse_vary("/materials/pairs/0/friction=0.2")};
    REQUIRE(options.parameters[0].values.size() == 2);
    CHECK_THROWS_AS(palpable::tools::run_sweep(options), InputError);
    CHECK_THROWS_WITH(palpable::tools::run_sweep(options),
                      Catch::StartsWith("combination 0 (/materials/pairs=[], "
                                        "/materials/pairs/0/friction=0.2): ") &&
                          Catch::Contains("no such place"));
  }
}

TEST_CASE("a run's numerical trouble shows in its row", "[tools][sweep]") {
  // As in run_scene_test: the coins hit a retry limit of 1 (pairs colliding again at one
  // instant, and the corners skipped then overlap the table: two kinds), and run clean with the
  // default limit.
  SweepOptions options;
  options.scene_path = scene("coins.json");
  // The microcollision model's run: pinned, since the default may be the other (held, the coins'
  // skipped pairs leave no overlap).
  options.overrides = {"/settings/contact_model=microcollisions"};
  options.parameters = {palpable::tools::parse_vary("/settings/retry_limit=1,100")};
  const SweepTable table = palpable::tools::run_sweep(options);
  REQUIRE(table.rows.size() == 2);
  const std::size_t trouble = column(table, "trouble");
  CHECK(table.rows[0][trouble] == "2");
  CHECK(table.rows[1][trouble] == "0");
}

TEST_CASE("the Pareto front and its plot", "[tools][sweep][plot]") {
  using palpable::tools::ParetoPoint;
  const std::vector<ParetoPoint> points{{1.0, 1e-2, "a"},         {2.0, 1e-3, "b"},
                                        {2.5, 5e-3, "c"},         {4.0, 1e-6, "d"},
                                        {0.5, std::nan(""), "e"}, {8.0, 1e-6, "f"}};
  CHECK(palpable::tools::pareto_front(points) == std::vector<std::size_t>{0, 1, 3});

  SweepTable table;
  table.columns = {"combination", "combinations", "sweep",      "/settings/envelope", "error",
                   "cpu_s",       "events",       "collisions", "microcollisions",    "trouble"};
  table.rows = {{"0", "3", "f", "1e-3", "1e-2", "0.1", "10", "1", "9", "0"},
                {"1", "3", "f", "1e-4", "1e-4", "0.3", "30", "1", "29", "0"},
                {"2", "3", "f", "1e-5", "0", "0.9", "90", "1", "89", "1"}};
  std::vector<ParetoPoint> labelled = palpable::tools::sweep_points(table);
  REQUIRE(labelled.size() == 3);
  CHECK(labelled[1].label == "1e-4");
  CHECK(labelled[1].cpu_s == 0.3);
  CHECK(labelled[1].error == 1e-4);
  // A label gnuplot cannot quote, or too long a one: the combination index instead.
  SweepTable awkward = table;
  awkward.rows[0][3] = "say \"hi\"";
  awkward.rows[1][3] = std::string(25, 'x');
  labelled = palpable::tools::sweep_points(awkward);
  CHECK(labelled[0].label == "#0");
  CHECK(labelled[1].label == "#1");
  CHECK(labelled[2].label == "1e-5");

  const std::string png = "sweep_test_pareto.png";
  palpable::tools::plot_sweep(table, png, "test");
  std::ifstream in(png, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  CHECK(std::string(magic + 1, 3) == "PNG");
  std::remove(png.c_str());
}
