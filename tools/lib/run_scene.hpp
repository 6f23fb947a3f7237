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
  // Numerical trouble (see numerical_trouble) fails the run: it throws and writes no file.
  bool strict = false;
  // Keep every sample and contact in RunResult::trace. Off, they are kept only when the scene's
  // reference needs them, so memory does not grow with simulated time (the command line).
  bool keep_trace = true;
};

struct RunResult {
  Scene scene;
  SimulationStats stats;
  double wall_time_s = 0.0;
  double cpu_time_s = 0.0;
  Trace trace;               // the samples, in memory (see RunOptions::keep_trace)
  nlohmann::json reference;  // error figures against the scene's reference (null if none)
  // How the run was made: palpable version and commit, scene path and the FNV-1a hash of its
  // text, every override, the end time, and every setting in effect (derived ones included).
  // In the summary JSON, and in a sidecar TRACE.json next to a trace file.
  nlohmann::json provenance;
};

// Throws InputError for bad input (before anything runs; no file is written).
RunResult run_scene(const RunOptions& options);

// What in a run's statistics means its trace may be wrong, one sentence each: overlapping bodies,
// a pair stuck colliding at one instant past the retry limit, failed impulse integrations or
// closest-feature walks. Empty for a clean run.
std::vector<std::string> numerical_trouble(const SimulationStats& stats);

// The summary as JSON: scene, virtual and wall time, statistics, reference figures.
nlohmann::json summary_json(const RunResult& result);
// The same for people.
std::string summary_text(const RunResult& result);

}  // namespace palpable::tools
