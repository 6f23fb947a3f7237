#pragma once
// Running a scene file: the one code path behind `palpable run` (and later `sweep`): load,
// apply --set overrides, validate, simulate, write the trace and events atomically, compare
// with the scene's closed-form reference, summarise.
#include "scenarios/scene.hpp"
#include "scenarios/trace.hpp"
#include "scheduler/simulation.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace palpable::tools {

struct RunOptions {
  std::string scene_path;              // "-": standard input
  std::vector<std::string> overrides;  // "/json/pointer=value"
  std::optional<double> end_time;      // replaces the scene's end_time
  std::string trace_path;              // empty: no trace file
  std::string events_path;             // empty: no events file
  bool progress = false;               // progress on stderr
};

struct RunResult {
  Scene scene;
  SimulationStats stats;
  double wall_time_s = 0.0;
  double cpu_time_s = 0.0;
  Trace trace;               // the samples, in memory
  nlohmann::json reference;  // error figures against the scene's reference (null if none)
};

// Throws InputError for bad input (before anything runs; no file is written).
RunResult run_scene(const RunOptions& options);

// The summary as JSON: scene, virtual and wall time, statistics, reference figures.
nlohmann::json summary_json(const RunResult& result);
// The same for people.
std::string summary_text(const RunResult& result);

}  // namespace palpable::tools
