#pragma once
// Running a scene file: the one code path behind `palpable run` (and later `sweep`): load,
// apply --set overrides, validate, simulate, write the trace and events atomically, compare
// with the scene's closed-form reference, summarise.
#include "scenarios/scene.hpp"
#include "scenarios/trace.hpp"
#include "scheduler/simulation.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <deque>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace palpable::tools {

// One row of the events table: a collision (or microcollision), or under the persistent contact
// model a held contact's change of mode. The events CSV writes these; the Python module keeps
// them (RunOptions::keep_events).
// Compact (216 bytes): the Python module keeps one per event.
struct EventRow {
  double t = 0.0;
  const char* kind = "";  // collision, microcollision, or a mode change: hold, stick, slip, ...
  std::uint32_t a = 0, b = 0;  // body indices
  Vec3 p_W = Vec3::Zero(), n_W = Vec3::Zero(), impulse_W = Vec3::Zero();
  double approach_speed = 0.0, energy_change = 0.0;
  bool centre_of_pressure = false;
  // A collision resolved by the impulse integration: its phases, slips and normal impulses
  // (CollisionRecord). False for mode changes and a group's contacts (kind "collision",
  // phases "group").
  bool detail = false;
  bool group = false;
  std::uint8_t phase_count = 0;
  std::array<std::uint8_t, 6> phases{};  // PhaseKind values
  Vec3 resumed_direction_W = Vec3::Zero();
  Vec3 slip_before_W = Vec3::Zero(), slip_after_W = Vec3::Zero();
  double normal_impulse_compression = 0.0, normal_impulse_restitution = 0.0;
  PhaseKind phase(int i) const {
    return static_cast<PhaseKind>(phases[static_cast<std::size_t>(i)]);
  }
};
EventRow event_row(const CollisionRecord& record);
EventRow event_row(const ModeChange& change);

// The phases as one CSV-safe word list, in order, separated by ';': frictionless, slid, stuck,
// resumed_sliding(dx dy dz) (the slip direction, world frame), rebound_floor, reversed,
// drift_free_target, drift_free_cone_boundary, micro_fallback; "group" for a group's contact.
std::string phases_text(const EventRow& row);

// The events CSV header and one row.
extern const char* const kEventsCsvHeader;
void write_event_row(std::ostream& out, const EventRow& row, const std::vector<std::string>& names);

struct RunOptions {
  std::string scene_path;              // "-": standard input
  std::vector<std::string> overrides;  // "/json/pointer=value"
  std::optional<double> end_time;      // replaces the scene's end_time
  std::string trace_path;              // empty: no trace file
  std::string events_path;             // empty: no events file
  std::string summary_path;            // empty: no summary JSON (summary_json) file
  bool progress = false;               // progress on stderr
  // A budget of CPU time [s] (>= 0): checked every 64 events, the run stops at the first check
  // past it, between two events, with its outputs holding the run up to there (RunResult::stop).
  std::optional<double> cpu_limit_s;
  // Numerical trouble (see numerical_trouble) fails the run: it throws and writes no file.
  bool strict = false;
  // Keep every sample and contact in RunResult::trace. Off, they are kept only when the scene's
  // reference needs them, so memory does not grow with simulated time (the command line).
  bool keep_trace = true;
  // Keep every event row in RunResult::events (the Python module).
  bool keep_events = false;
};

struct RunResult {
  Scene scene;
  SimulationStats stats;
  // Where a run stopped at its CPU budget (RunOptions::cpu_limit_s) before the end time: the
  // simulated time reached [s] and the budget. Empty for a run that reached its end time.
  struct Stop {
    double t_s = 0.0;
    double cpu_limit_s = 0.0;
  };
  std::optional<Stop> stop;
  // The simulated time the run reached [s]: its end time, or where it stopped.
  double time_reached() const { return stop ? stop->t_s : scene.end_time; }
  double wall_time_s = 0.0;
  double cpu_time_s = 0.0;
  Trace trace;  // the samples, in memory (see RunOptions::keep_trace)
  // Every event row (see RunOptions::keep_events); a deque: no copying as it grows, and its
  // blocks come from the heap, reused by the next run instead of faulted in afresh.
  std::deque<EventRow> events;
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
