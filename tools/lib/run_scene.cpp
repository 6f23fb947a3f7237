#include "tools/lib/run_scene.hpp"

#include "tools/version.hpp"

#include "core/check.hpp"
#include "scenarios/reference.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/fnv1a.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <initializer_list>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

namespace palpable::tools {
namespace {

void put_number(std::ostream& out, double x) {
  out << std::setprecision(17) << x;
}

// Streams samples into the trace CSV and keeps them in memory for the reference comparison;
// streams collisions into the events CSV. A fixed body is written once, in the first sample
// (read_trace_csv repeats it).
class RunObserver : public SimulationObserver {
 public:
  RunObserver(const World& world, AtomicFile* trace, AtomicFile* events, Trace* memory, bool keep,
              std::deque<EventRow>* kept_events)
      : trace_(trace), events_(events), memory_(memory), keep_(keep), kept_events_(kept_events) {
    for (const Body& b : world.bodies) {
      names_.push_back(b.name);
      fixed_.push_back(b.motion == MotionKind::kFixed);
    }
    memory_->body_names = names_;
    if (trace_) trace_->stream() << kTraceHeader << "\n";
    if (events_) events_->stream() << kEventsCsvHeader << "\n";
  }
  void on_sample(double t, const std::vector<BodyState>& states) override {
    for (const BodyState& s : states) {
      if (!s.x_W.allFinite() || !s.v_W.allFinite() || !s.w_W.allFinite() ||
          !s.q_WM.coeffs().allFinite()) {
        throw std::runtime_error("non-finite state at t = " + std::to_string(t) +
                                 " (no trace written)");
      }
    }
    if (trace_) {
      if (first_sample_) {
        write_trace_rows(trace_->stream(), t, names_, states);
        first_sample_ = false;
      } else {
        write_trace_rows(trace_->stream(), t, names_, states, &fixed_);
      }
    }
    if (!keep_) return;
    memory_->times.push_back(t);
    memory_->samples.push_back(states);
  }
  void on_collision(const CollisionRecord& r) override {
    if (keep_) {
      memory_->contacts.push_back(ContactEvent{r.t, r.a.index, r.b.index, r.p_W, r.n_W, r.impulse_W,
                                               r.kind == CollisionKind::kMicrocollision});
    }
    if (!events_ && !kept_events_) return;
    const EventRow row = event_row(r);
    if (events_) write_event_row(events_->stream(), row, names_);
    if (kept_events_) kept_events_->push_back(row);
  }
  // A held contact changing mode (persistent contact model): a row of its own kind, at the
  // contact's reference point, with no impulse.
  void on_mode_change(const ModeChange& m) override {
    if (!events_ && !kept_events_) return;
    const EventRow row = event_row(m);
    if (events_) write_event_row(events_->stream(), row, names_);
    if (kept_events_) kept_events_->push_back(row);
  }

 private:
  std::vector<std::string> names_;
  std::vector<bool> fixed_;  // written in the first sample only
  bool first_sample_ = true;
  AtomicFile* trace_;
  AtomicFile* events_;
  Trace* memory_;
  bool keep_;  // samples and contacts kept in memory
  std::deque<EventRow>* kept_events_;
};

}  // namespace

const char* const kEventsCsvHeader =
    "t,kind,body_a,body_b,px,py,pz,nx,ny,nz,jx,jy,jz,approach_speed,energy_change,"
    "centre_of_pressure,phases,slip_before_x,slip_before_y,slip_before_z,slip_after_x,"
    "slip_after_y,slip_after_z,normal_impulse_compression,normal_impulse_restitution";

EventRow event_row(const CollisionRecord& r) {
  EventRow row;
  row.t = r.t;
  row.kind = r.kind == CollisionKind::kMicrocollision ? "microcollision" : "collision";
  row.a = r.a.index;
  row.b = r.b.index;
  row.p_W = r.p_W;
  row.n_W = r.n_W;
  row.impulse_W = r.impulse_W;
  row.approach_speed = r.approach_speed;
  row.energy_change = r.energy_change;
  row.centre_of_pressure = r.centre_of_pressure;
  row.group = r.group;
  row.detail = !r.group;
  row.phase_count = r.phase_count;
  for (int i = 0; i < r.phase_count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    row.phases[k] = static_cast<std::uint8_t>(r.phases[k]);
  }
  row.resumed_direction_W = r.resumed_direction_W;
  row.slip_before_W = r.slip_before_W;
  row.slip_after_W = r.slip_after_W;
  row.normal_impulse_compression = r.normal_impulse_compression;
  row.normal_impulse_restitution = r.normal_impulse_restitution;
  return row;
}

EventRow event_row(const ModeChange& m) {
  EventRow row;
  row.t = m.t;
  row.kind = m.kind;
  row.a = m.a.index;
  row.b = m.b.index;
  row.p_W = m.p_W;
  return row;
}

std::string phases_text(const EventRow& row) {
  if (row.group) return "group";
  std::ostringstream out;
  out << std::setprecision(6);
  for (int i = 0; i < row.phase_count; ++i) {
    if (i > 0) out << ';';
    switch (row.phase(i)) {
      case PhaseKind::kFrictionless: out << "frictionless"; break;
      case PhaseKind::kSlid: out << "slid"; break;
      case PhaseKind::kStuckStably: out << "stuck"; break;
      case PhaseKind::kResumedSliding: {
        const Vec3& d = row.resumed_direction_W;
        out << "resumed_sliding(" << d.x() << ' ' << d.y() << ' ' << d.z() << ')';
        break;
      }
      case PhaseKind::kReboundFloor: out << "rebound_floor"; break;
      case PhaseKind::kReversed: out << "reversed"; break;
      case PhaseKind::kDriftFreeTarget: out << "drift_free_target"; break;
      case PhaseKind::kDriftFreeConeBoundary: out << "drift_free_cone_boundary"; break;
      case PhaseKind::kMicroFallback: out << "micro_fallback"; break;
    }
  }
  return out.str();
}

void write_event_row(std::ostream& out, const EventRow& row,
                     const std::vector<std::string>& names) {
  auto number = [&out](double x) {
    out << ',';
    put_number(out, x);
  };
  auto vectors = [&number](std::initializer_list<const Vec3*> vs) {
    for (const Vec3* v : vs) {
      for (int i = 0; i < 3; ++i) number((*v)[i]);
    }
  };
  put_number(out, row.t);
  out << ',' << row.kind << ',' << names[row.a] << ',' << names[row.b];
  vectors({&row.p_W, &row.n_W, &row.impulse_W});
  number(row.approach_speed);
  number(row.energy_change);
  out << ',' << (row.centre_of_pressure ? 1 : 0) << ',' << phases_text(row);
  if (!row.detail) {
    out << ",,,,,,,,\n";  // no slips or normal impulses: a mode change, or a group's contact
    return;
  }
  vectors({&row.slip_before_W, &row.slip_after_W});
  number(row.normal_impulse_compression);
  number(row.normal_impulse_restitution);
  out << '\n';
}

namespace {

nlohmann::json provenance(const RunOptions& options, const Scene& scene,
                          const std::string& scene_text) {
  nlohmann::json p;
  p["palpable"] = {{"version", kVersion}, {"commit", kGitCommit}};
  p["scene_path"] = options.scene_path;
  p["scene_fnv1a64"] = fnv1a64_hex(scene_text);
  p["overrides"] = options.overrides;
  p["end_time_s"] = scene.end_time;
  if (options.cpu_limit_s) p["cpu_limit_s"] = *options.cpu_limit_s;
  p["output_interval_s"] = scene.output_interval;
  p["settings"] = settings_json(scene.world.settings, scene.world.gravity_W.norm());
  return p;
}

}  // namespace

RunResult run_scene(const RunOptions& options) {
  RunResult result;
  std::string scene_text;
  result.scene = load_scene(options.scene_path, options.overrides, &scene_text);
  if (options.end_time) {
    if (!(*options.end_time > 0.0) || !std::isfinite(*options.end_time)) {
      throw InputError("--end", "expected a positive number of seconds");
    }
    // The scene's own end_time is held to this in the loader; --end replaces it after.
    if (*options.end_time > kMaxEndTime) {
      throw InputError("--end", "at most 1e9 s (the event clock resolves 1e-12 of the time)");
    }
    if (result.scene.output_interval > 0.0 &&
        *options.end_time / result.scene.output_interval > kMaxSamples) {
      throw InputError("--end", "more than 1e9 samples at the scene's output interval");
    }
    result.scene.end_time = *options.end_time;
  }
  if (options.cpu_limit_s &&
      !(*options.cpu_limit_s >= 0.0 && std::isfinite(*options.cpu_limit_s))) {
    throw InputError("--cpu-limit", "expected a number of seconds >= 0");
  }
  const Scene& scene = result.scene;

  SimulationOptions sim_options;
  sim_options.output_interval = scene.output_interval;
  // The simulation's own errors (bodies overlapping at the start, a clock that stopped) name a
  // JSON pointer or the bodies: the scene's file goes in front.
  auto in_scene = [&scene](const InputError& e) {
    // The message is what() after "where: ", unless a "\u0000" in a name ended what() early.
    const std::string what = e.what();
    const std::size_t cut = e.where().empty() ? 0 : e.where().size() + 2;
    const std::string message = what.size() >= cut ? what.substr(cut) : what;
    if (e.where().empty()) return InputError(scene.source, message);
    return InputError(scene.source + (e.where()[0] == '/' ? ":" : ": ") + e.where(), message);
  };

  std::optional<Simulation> simulation_slot;
  try {
    simulation_slot.emplace(scene.world,
                            sim_options);  // validates (overlaps) before any file opens
  } catch (const InputError& e) {
    throw in_scene(e);
  }
  Simulation& simulation = *simulation_slot;

  std::unique_ptr<AtomicFile> trace_file, events_file;
  if (!options.trace_path.empty()) trace_file = std::make_unique<AtomicFile>(options.trace_path);
  if (!options.events_path.empty()) events_file = std::make_unique<AtomicFile>(options.events_path);
  // Opened before the run, so that an unwritable summary fails before anything runs.
  std::unique_ptr<AtomicFile> summary_file;
  if (!options.summary_path.empty()) {
    summary_file = std::make_unique<AtomicFile>(options.summary_path);
  }
  RunObserver observer(scene.world, trace_file.get(), events_file.get(), &result.trace,
                       options.keep_trace || !scene.reference.is_null(),
                       options.keep_events ? &result.events : nullptr);

  const auto wall_start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  auto last_report = wall_start;
  bool reported = false;
  std::function<bool(double)> progress;
  if (options.progress || options.cpu_limit_s) {
    progress = [&](double t) {
      if (options.cpu_limit_s &&
          static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC >= *options.cpu_limit_s) {
        result.stop = RunResult::Stop{t, *options.cpu_limit_s};
        return false;
      }
      if (!options.progress) return true;
      auto now = std::chrono::steady_clock::now();
      if (now - wall_start < std::chrono::seconds(1) ||
          now - last_report < std::chrono::milliseconds(250)) {
        return true;
      }
      last_report = now;
      reported = true;
      std::cerr << "\r" << scene.name << ": t = " << std::fixed << std::setprecision(3) << t
                << " / " << scene.end_time << " s (" << std::setprecision(0)
                << 100.0 * t / scene.end_time << " %)" << std::defaultfloat << std::flush;
      return true;
    };
  }
  {
    // The progress line is cleared however the run ends, so that what follows on stderr (the
    // summary, or an error thrown mid-run) starts at the beginning of a line.
    struct ClearProgress {
      const bool& reported;
      ~ClearProgress() {
        if (reported) std::cerr << "\r" << std::string(60, ' ') << "\r" << std::flush;
      }
    } clear_progress{reported};
    try {
      simulation.run_until(scene.end_time, &observer, progress);
    } catch (const InputError& e) {
      throw in_scene(e);
    }
  }
  result.cpu_time_s = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  result.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.stats = simulation.stats();

  if (!scene.reference.is_null() && result.stop) {
    // The closed form's figures (a stop instant, a final speed) are of the whole run.
    std::ostringstream why;
    why << "the run stopped at its CPU limit at t = " << result.stop->t_s
        << " s, before the end time";
    result.reference = {{"unavailable", why.str()}};
  } else if (!scene.reference.is_null() && !result.trace.times.empty()) {
    try {
      result.reference =
          compare_with_reference(scene.reference, result.trace, scene.source + ":/reference");
    } catch (const InputError& e) {
      // The run is sound; only its trace cannot be compared (too short, too coarse): say so.
      // Anything else (a bad reference object in the scene) stays an error.
      if (e.where() != "trace") throw;
      result.reference = {{"unavailable", e.what()}};
    }
  }
  if (options.strict) {
    const std::vector<std::string> trouble = numerical_trouble(result.stats);
    if (!trouble.empty()) {
      throw std::runtime_error(scene.source + ": --strict: " + trouble.front() +
                               " (no file written)");
    }
  }
  result.provenance = provenance(options, result.scene, scene_text);
  // The sidecar is opened before the outputs are committed, so that all or none appear.
  std::unique_ptr<AtomicFile> sidecar;
  if (trace_file && !trace_file->streaming()) {
    sidecar = std::make_unique<AtomicFile>(options.trace_path + ".json");
    sidecar->stream() << result.provenance.dump(2, ' ', false,
                                                nlohmann::json::error_handler_t::replace)
                      << "\n";
  }
  if (summary_file) {
    summary_file->stream() << summary_json(result).dump(2, ' ', false,
                                                        nlohmann::json::error_handler_t::replace)
                           << "\n";
  }
  // All or none: every output is written out and checked before the first is renamed into
  // place (a summary on a full disk left the trace committed and the run failed).
  const std::vector<AtomicFile*> outputs = {trace_file.get(), events_file.get(), sidecar.get(),
                                            summary_file.get()};
  for (AtomicFile* file : outputs) {
    if (file) file->finish();
  }
  for (AtomicFile* file : outputs) {
    if (file) file->commit();
  }
  return result;
}

std::vector<std::string> numerical_trouble(const SimulationStats& s) {
  std::vector<std::string> out;
  auto add = [&](std::uint64_t n, const std::string& what) {
    if (n > 0) out.push_back(std::to_string(n) + " " + what);
  };
  add(s.penetrations, "closest-feature queries found bodies overlapping");
  add(s.retry_limit_hits,
      "times a pair kept colliding at one instant past settings.retry_limit and was skipped");
  add(s.impulse_failures, "collisions whose impulse integration failed (frictionless fallback)");
  add(s.distance_failures, "closest-feature walks hit settings.distance_max_steps");
  return out;
}

nlohmann::json summary_json(const RunResult& r) {
  const SimulationStats& s = r.stats;
  nlohmann::json j;
  j["scene"] = r.scene.name;
  j["virtual_time_s"] = r.time_reached();
  if (r.stop) {
    j["stopped"] = {{"reason", "cpu_limit"},
                    {"cpu_limit_s", r.stop->cpu_limit_s},
                    {"end_time_s", r.scene.end_time}};
  }
  j["wall_time_s"] = r.wall_time_s;
  j["cpu_time_s"] = r.cpu_time_s;
  j["events"] = s.events;
  j["collisions"] = s.collisions;
  j["microcollisions"] = s.microcollisions;
  j["pair_checks"] = s.pair_checks;
  j["statistics"] = {{"bound_queries", s.bound_queries},
                     {"horizon_refreshes", s.horizon_refreshes},
                     {"samples", s.samples},
                     {"rescheduled", s.rescheduled},
                     {"retries", s.retries},
                     {"retry_limit_hits", s.retry_limit_hits},
                     {"floored_bounds", s.floored_bounds},
                     {"exact_bounds", s.exact_bounds},
                     {"approach_checks", s.approach_checks},
                     {"instant_refinements", s.instant_refinements},
                     {"instant_iterations", s.instant_iterations},
                     {"instant_unfound", s.instant_unfound},
                     {"penetrations", s.penetrations},
                     {"deepest_penetration_m", s.deepest_penetration_m},
                     {"distance_failures", s.distance_failures},
                     {"impulse_failures", s.impulse_failures},
                     {"centre_of_pressure", s.centre_of_pressure},
                     {"riders_carried", s.riders_carried},
                     {"groups", s.groups},
                     {"group_contacts", s.group_contacts},
                     {"group_unconverged", s.group_unconverged},
                     {"feature_steps", s.feature_steps},
                     {"integration_steps", s.integration_steps},
                     {"pairs_created", s.pairs_created},
                     {"max_pairs", s.max_pairs},
                     {"box_tests", s.box_tests},
                     {"holds", s.holds},
                     {"mode_changes", s.mode_changes},
                     {"island_plans", s.island_plans},
                     {"rests", s.rests},
                     {"rocking_ends", s.rocking_ends},
                     {"held_inconsistent", s.held_inconsistent},
                     {"stalled_islands", s.stalled_islands},
                     {"island_steps", s.island_steps},
                     {"island_rejected_steps", s.island_rejected_steps},
                     {"island_failed_motions", s.island_failed_motions},
                     {"island_chunks", s.island_chunks}};
  const Settings& st = r.scene.world.settings;
  j["palpable"] = {{"version", kVersion}, {"commit", kGitCommit}};
  j["scene_path"] = r.scene.source;
  j["provenance"] = r.provenance;
  j["settings"] = settings_json(st, r.scene.world.gravity_W.norm());
  if (!r.reference.is_null()) {
    j["reference"] = r.reference;
    j["reference_parameters"] = r.scene.reference;  // as given, and derived from the scene
  }
  return j;
}

std::string summary_text(const RunResult& r) {
  const SimulationStats& s = r.stats;
  std::ostringstream out;
  out << "scene            " << r.scene.name << "\n"
      << "virtual time     " << r.time_reached() << " s";
  if (r.stop) {
    out << " of " << r.scene.end_time << " s: stopped at the CPU limit (" << r.stop->cpu_limit_s
        << " s)";
  }
  out << "\n"
      << "wall time        " << std::setprecision(3) << r.wall_time_s << " s\n"
      << std::setprecision(6) << "events           " << s.events << "  (pair checks "
      << s.pair_checks << ", horizon refreshes " << s.horizon_refreshes << ", integration chunks "
      << s.island_chunks << ", samples " << s.samples << ")\n"
      << "collisions       " << s.collisions << "  microcollisions " << s.microcollisions
      << "  (centre of pressure " << s.centre_of_pressure << ")\n"
      << "numerical        retries " << s.retries << ", retry-limit hits " << s.retry_limit_hits
      << ", floored bounds " << s.floored_bounds << ", penetrations " << s.penetrations
      << ", distance failures " << s.distance_failures << ", impulse failures "
      << s.impulse_failures << "\n";
  const Settings& st = r.scene.world.settings;
  out << "settings         envelope " << st.envelope_m << " m, integration tolerance "
      << st.integration_tolerance << ", law " << to_string(st.restitution_law)
      << ", microcollision rule " << to_string(st.microcollision_rule) << ", contact model "
      << to_string(st.contact_model) << "\n";
  if (!r.reference.is_null()) {
    out << "reference        " << r.reference.value("reference", std::string("?")) << "\n";
    for (auto it = r.reference.begin(); it != r.reference.end(); ++it) {
      if (it.key() == "reference") continue;
      out << "  " << std::left << std::setw(30) << it.key() << " " << it.value().dump() << "\n";
    }
  }
  return out.str();
}

}  // namespace palpable::tools
