// `palpable bench experiments`: the paper's experiments timed on this machine — each shipped
// scene run through `palpable run`'s code path --repeats times per contact model (no files
// written): the median CPU time of the simulation, its event counts (identical in every repeat:
// the runs are deterministic, checked), the scene's primary error against its closed form, and
// Mirtich & Canny's real time on 1995 hardware with the ratio.
// A benchmark, not a test: it prints JSON lines (or, with --markdown, the README's table).
#include "scenarios/reference.hpp"
#include "tools/commands.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/median.hpp"
#include "tools/lib/run_scene.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Experiment {
  std::string scene;    // file name under the scenes folder
  double paper_real_s;  // Mirtich & Canny's real time (1995); 0: not reported
};

// Real times from the seed slides (the virtual times are the scenes').
const std::vector<Experiment>& experiments() {
  static const std::vector<Experiment> list = {
      {"block_on_ramp_decelerating.json", 0.0},
      {"block_on_ramp_accelerating.json", 0.0},
      {"sphere_slide_to_roll.json", 0.0},
      {"ball_on_platter.json", 129.0},
      {"pool_break.json", 95.0},
      {"chain_of_balls.json", 7.3},
      {"coins.json", 50.0},
      {"bowling.json", 167.0},
      {"balls_in_dish.json", 95.0},
  };
  return list;
}

std::string format(double x, const char* spec) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, spec, x);
  return buffer;
}

// Thousands separated by commas, as in the README's tables.
std::string grouped(std::uint64_t n) {
  std::string digits = std::to_string(n), out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

// Three significant digits, thousands grouped, times sign: 11,100×.
std::string ratio(double x) {
  if (x < 100.0) return format(x, "%.3g×");
  const double scale = std::pow(10.0, std::floor(std::log10(x)) - 2.0);
  return grouped(static_cast<std::uint64_t>(std::llround(x / scale) * scale)) + "×";
}

std::string duration(double seconds) {
  if (seconds < 1e-3) return format(seconds * 1e6, "%.0f µs");
  if (seconds < 1.0) return format(seconds * 1e3, "%.3g ms");
  return format(seconds, "%.3g s");
}

// The primary relative error against the scene's closed form, or a dash.
std::string error_text(const nlohmann::json& reference) {
  const double e = palpable::primary_error(reference);
  return std::isnan(e) ? "—" : format(e, "%.2g");
}

palpable::tools::CommandRegistration reg{
    "bench experiments", [](CLI::App& app) {
      app.description(
          "Times the paper's experiments: each shipped scene (ramps, slide to roll, platter, pool "
          "break, chain of balls, coins, bowling, balls in a dish) run --repeats times per contact "
          "model through the code path of `palpable run` without writing files. Prints one JSON "
          "line per scene and model: virtual time, median CPU and wall time of the simulation, "
          "events, collisions, microcollisions, the primary error against the scene's closed form "
          "(`error`, as `palpable sweep` reports it), and the real time Mirtich & Canny reported "
          "on 1995 hardware with the ratio (theirs / our CPU). With --markdown: the README's "
          "table, both models side by side. Exits 1 if two repeats of a scene disagree on any "
          "count (the runs must be deterministic).");
      auto repeats = std::make_shared<int>(5);
      auto folder = std::make_shared<std::string>("scenarios");
      auto markdown = std::make_shared<bool>(false);
      auto models = std::make_shared<std::vector<std::string>>(
          std::vector<std::string>{"microcollisions", "persistent"});
      app.add_option("--repeats", *repeats, "Runs per scene and model; the times are their median")
          ->check(CLI::Range(1, 1000));
      app.add_option("--scenes", *folder, "Folder holding the shipped scenes")
          ->check(CLI::ExistingDirectory);
      app.add_option("--models", *models, "Contact models to run, in column order")
          ->delimiter(',')
          ->check(CLI::IsMember({"microcollisions", "persistent"}));
      app.add_flag("--markdown", *markdown, "Print the README's table instead of JSON lines");
      return std::function<int()>([repeats, folder, markdown, models] {
        std::ostringstream table;
        table << "| scene | virtual |";
        for (const std::string& m : *models) {
          table << " " << m << ": events | CPU | error |";
        }
        table << " paper (1995) | paper / ours (" << models->front() << ") |\n|---|---|";
        for (std::size_t k = 0; k < models->size(); ++k) table << "---|---|---|";
        table << "---|---|\n";
        for (const Experiment& e : experiments()) {
          std::string name;
          double virtual_s = 0.0, first_cpu = 0.0;
          std::ostringstream cells;
          for (const std::string& model : *models) {
            palpable::tools::RunOptions options;
            options.scene_path = *folder + "/" + e.scene;
            options.overrides = {"/settings/contact_model=" + model};
            options.keep_trace = false;
            std::vector<double> walls, cpus;
            palpable::SimulationStats first;
            nlohmann::json reference;
            for (int k = 0; k < *repeats; ++k) {
              const palpable::tools::RunResult r = palpable::tools::run_scene(options);
              walls.push_back(r.wall_time_s);
              cpus.push_back(r.cpu_time_s);
              if (k == 0) {
                first = r.stats;
                name = r.scene.name;
                virtual_s = r.scene.end_time;
                reference = r.reference;
              } else if (r.stats.events != first.events ||
                         r.stats.collisions != first.collisions ||
                         r.stats.microcollisions != first.microcollisions) {
                std::cerr << "palpable: error: " << options.scene_path
                          << ": repeats disagree on the event counts (non-deterministic run)\n";
                return palpable::tools::kExitFailure;
              }
            }
            const double wall = palpable::tools::median(walls);
            const double cpu = palpable::tools::median(cpus);
            if (&model == &models->front()) first_cpu = cpu;
            nlohmann::json j = {{"scene", name},
                                {"contact_model", model},
                                {"virtual_s", virtual_s},
                                {"cpu_s", cpu},
                                {"wall_s", wall},
                                {"repeats", *repeats},
                                {"events", first.events},
                                {"collisions", first.collisions},
                                {"microcollisions", first.microcollisions}};
            const double error = palpable::primary_error(reference);
            if (!std::isnan(error)) j["error"] = error;
            if (e.paper_real_s > 0.0) {
              j["paper_real_s"] = e.paper_real_s;
              j["paper_over_ours"] = e.paper_real_s / cpu;
            }
            if (!*markdown) std::cout << j.dump() << std::endl;
            cells << " " << grouped(first.events) << " | " << duration(cpu) << " | "
                  << error_text(reference) << " |";
          }
          table << "| " << name << " | " << format(virtual_s, "%g s") << " |" << cells.str() << " "
                << (e.paper_real_s > 0.0 ? format(e.paper_real_s, "%g s") : "—") << " | "
                << (e.paper_real_s > 0.0 ? ratio(e.paper_real_s / first_cpu) : "—") << " |\n";
        }
        if (*markdown) std::cout << table.str();
        return palpable::tools::kExitOk;
      });
    }};

}  // namespace
