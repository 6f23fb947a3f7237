#pragma once
// `palpable sweep`: run a scene over the cartesian product of varied values, each combination
// through run_scene (the code path of `palpable run`, the values applied like --set overrides),
// and tabulate one row per combination: the values, the scene's primary relative error and every
// scalar reference figure, the median CPU time of the repeats and the event counts. Sharding
// splits the combinations into disjoint slices that merge back into the single-machine table.
#include "tools/lib/plot.hpp"
#include "tools/lib/run_scene.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace palpable::tools {

// One --vary option: a JSON pointer and the values it takes (as written, parsed like --set); from
// parse_vary, so at least one value, none empty.
struct SweepParameter {
  std::string pointer;
  std::vector<std::string> values;
};

// The K-th (1-based) of N slices: combination i belongs to shard (i mod N) + 1.
struct Shard {
  std::size_t index = 1;
  std::size_t count = 1;
};

struct SweepOptions {
  std::string scene_path;
  std::vector<SweepParameter> parameters;  // the first varies slowest
  std::vector<std::string> overrides;      // fixed --set overrides, applied before the varied ones
  std::optional<double> end_time;          // replaces the scene's end_time
  int repeat = 1;                          // runs per combination; cpu_s is their median
  int jobs = 1;                            // combinations run at once (forked processes)
  Shard shard;                             // from parse_shard, or the default 1/1
  bool progress = false;                   // progress on stderr
};

// Parses "/json/pointer=v1,v2,..." (a value holding commas, such as a JSON array, is written in
// brackets or quotes: /gravity=[0,0,-9.81],[0,0,-1.62]). Throws InputError naming --vary.
SweepParameter parse_vary(const std::string& text);
// Parses "K/N" with 1 <= K <= N. Throws InputError naming --shard.
Shard parse_shard(const std::string& text);

// The number of combinations (the product of the value counts; 1 with no parameters).
std::size_t combination_count(const std::vector<SweepParameter>& parameters);
// The value index of each parameter in combination `index` (mixed radix, the last parameter
// varying fastest).
std::vector<std::size_t> combination_digits(const std::vector<SweepParameter>& parameters,
                                            std::size_t index);



// The table a sweep writes: a header and rows of CSV cells (text as written).
struct SweepTable {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
};

// What identifies a sweep, so that only shards of one sweep merge: 16 hex digits, the 64-bit
// FNV-1a hash of the text naming the scene path, the fixed overrides, the end time and every
// --vary pointer with its value list (not --repeat, --jobs or --shard, which leave the rows'
// meaning unchanged).
std::string sweep_fingerprint(const SweepOptions& options);

// Runs the combinations of options.shard (validating every value first: bad input throws
// InputError naming the --vary option before anything runs) and returns their rows in
// combination order. Columns: combination, combinations (the total), sweep (the fingerprint),
// one per parameter (named by its pointer), error, cpu_s, events, collisions, microcollisions,
// trouble, then the scalar reference figures in name order (array figures as name_0, name_1,
// ...; missing ones empty).
SweepTable run_sweep(const SweepOptions& options);

// Merges shard tables into one: checks every row holds the same sweep fingerprint, the parameter
// columns agree, every combination of the total appears exactly once, and returns the rows in
// combination order (figure columns are the union, in name order). Throws InputError naming the
// file (`where`) for a bad or missing part.
SweepTable merge_sweep_tables(const std::vector<SweepTable>& parts,
                              const std::vector<std::string>& where);

void write_sweep_csv(std::ostream& out, const SweepTable& table);
// Throws InputError naming the path for an unreadable or malformed file.
SweepTable read_sweep_csv(const std::string& path);

// The points of a sweep table's Pareto plot, one per row: error, cpu_s (NaN if not numbers) and
// the label, the row's parameter values joined by commas, or "#combination" when that is empty,
// longer than 24 characters or holds a '"' (gnuplot reads labels as quoted strings).
std::vector<ParetoPoint> sweep_points(const SweepTable& table);

// The Pareto plot of a sweep table: error against cpu_s, both logarithmic, the front drawn.
void plot_sweep(const SweepTable& table, const std::string& png_path, const std::string& title);

}  // namespace palpable::tools
