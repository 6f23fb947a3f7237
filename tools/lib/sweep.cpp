#include "tools/lib/sweep.hpp"

#include "scenarios/reference.hpp"

#include "core/check.hpp"
#include "scenarios/scene.hpp"
#include "tools/lib/fnv1a.hpp"
#include "tools/lib/median.hpp"
#include "tools/lib/plot.hpp"

#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace palpable::tools {

using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The columns every table starts and ends its fixed part with.
const std::vector<std::string> kLeading{"combination", "combinations", "sweep"};
const std::vector<std::string> kMeasured{"error",      "cpu_s",           "events",
                                         "collisions", "microcollisions", "trouble"};

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

bool parse_size(const std::string& text, std::size_t* value) {
  if (text.empty() || text.size() > 9 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    return false;
  }
  *value = std::stoul(text);
  return true;
}

// The shortest text that reads back as the same double.
std::string number_text(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  return json(x).dump();
}

// A figure's cell: numbers at round-trip precision, strings as they are, null empty.
std::string cell_text(const json& value) {
  if (value.is_null()) return {};
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number_integer()) return value.dump();
  if (value.is_number()) return number_text(value.get<double>());
  return value.dump();
}

// Scalar figures by column name: arrays become name_0, name_1, ...; objects name.key.
void flatten(const std::string& name, const json& value, std::map<std::string, std::string>* out) {
  if (value.is_array()) {
    for (std::size_t i = 0; i < value.size(); ++i) {
      flatten(name + "_" + std::to_string(i), value[i], out);
    }
  } else if (value.is_object()) {
    for (auto it = value.begin(); it != value.end(); ++it) {
      flatten(name + "." + it.key(), it.value(), out);
    }
  } else {
    (*out)[name] = cell_text(value);
  }
}

// One combination's measurement, as JSON so that a forked worker can send it through a pipe and
// the in-process path reads exactly the same thing.
json run_combination(const SweepOptions& options, std::size_t index) {
  RunOptions run;
  run.scene_path = options.scene_path;
  run.overrides = options.overrides;
  const std::vector<std::size_t> digits = combination_digits(options.parameters, index);
  for (std::size_t p = 0; p < options.parameters.size(); ++p) {
    run.overrides.push_back(options.parameters[p].pointer + "=" +
                            options.parameters[p].values[digits[p]]);
  }
  run.end_time = options.end_time;
  std::vector<double> cpu;
  json first;
  for (int r = 0; r < options.repeat; ++r) {
    RunResult result = run_scene(run);
    cpu.push_back(result.cpu_time_s);
    json measured = {{"events", result.stats.events},
                     {"collisions", result.stats.collisions},
                     {"microcollisions", result.stats.microcollisions},
                     {"trouble", numerical_trouble(result.stats).size()},
                     {"reference", result.reference}};
    if (r == 0) {
      first = measured;
    } else if (measured.dump() != first.dump()) {
      // The simulation is deterministic: repeats may differ in their timings only. Compared as
      // text, since a NaN figure is unequal to itself as a number.
      throw std::runtime_error("repeat " + std::to_string(r + 1) + " differs from the first (" +
                               measured.dump() + " against " + first.dump() + ")");
    }
  }
  first["cpu_s"] = median(cpu);
  return first;
}

// A failure inside a worker, carried to the parent as JSON and rethrown there with its type.
json failure(const std::string& message, bool input) {
  return json{{"failed", message}, {"input_error", input}};
}

void rethrow_if_failed(const json& measured) {
  auto it = measured.find("failed");
  if (it == measured.end()) return;
  if (measured.value("input_error", false)) throw InputError("", it->get<std::string>());
  throw std::runtime_error(it->get<std::string>());
}

// "combination i (/p=v, ...)": what names a combination in an error.
std::string combination_name(const SweepOptions& options, std::size_t index) {
  const std::vector<std::size_t> digits = combination_digits(options.parameters, index);
  std::string values;
  for (std::size_t p = 0; p < options.parameters.size(); ++p) {
    values += (p ? ", " : "") + options.parameters[p].pointer + "=" +
              options.parameters[p].values[digits[p]];
  }
  return "combination " + std::to_string(index) + " (" + values + ")";
}

// A failure, its message prefixed by the combination it came from.
json run_combination_caught(const SweepOptions& options, std::size_t index) {
  try {
    return run_combination(options, index);
  } catch (const InputError& e) {
    return failure(combination_name(options, index) + ": " + e.what(), true);
  } catch (const std::exception& e) {
    return failure(combination_name(options, index) + ": " + e.what(), false);
  }
}

class Progress {
 public:
  Progress(bool enabled, std::size_t total) : enabled_(enabled), total_(total) {}
  void done() {
    ++done_;
    if (enabled_) {
      std::cerr << "\rsweep: " << done_ << " / " << total_ << " combinations" << std::flush;
    }
  }
  ~Progress() {
    if (enabled_ && done_ > 0) std::cerr << "\r" << std::string(50, ' ') << "\r" << std::flush;
  }

 private:
  bool enabled_;
  std::size_t total_;
  std::size_t done_ = 0;
};

// Runs `indices` in up to `jobs` forked processes at once; each writes its JSON result into a
// pipe the parent drains (poll) before reaping it. Results come back in the order of `indices`.
std::vector<json> run_forked(const SweepOptions& options, const std::vector<std::size_t>& indices,
                             Progress* progress) {
  struct Worker {
    std::size_t slot;
    int fd;
    std::string output;
  };
  std::vector<json> results(indices.size());
  std::map<pid_t, Worker> running;
  auto finish_one = [&] {
    while (true) {
      std::vector<pollfd> fds;
      std::vector<pid_t> pids;
      for (auto& [pid, w] : running) {
        fds.push_back(pollfd{w.fd, POLLIN, 0});
        pids.push_back(pid);
      }
      if (::poll(fds.data(), fds.size(), -1) < 0) {
        if (errno == EINTR) continue;
        throw std::runtime_error("sweep: poll failed");
      }
      for (std::size_t i = 0; i < fds.size(); ++i) {
        if (fds[i].revents == 0) continue;
        Worker& w = running.at(pids[i]);
        char buffer[4096];
        const ssize_t n = ::read(w.fd, buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n > 0) {
          w.output.append(buffer, static_cast<std::size_t>(n));
          continue;
        }
        ::close(w.fd);
        int status = 0;
        while (::waitpid(pids[i], &status, 0) < 0 && errno == EINTR) {
        }
        const std::size_t slot = w.slot;
        const std::string output = std::move(w.output);
        running.erase(pids[i]);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || output.empty()) {
          throw std::runtime_error("sweep: the worker for combination " +
                                   std::to_string(indices[slot]) + " died (status " +
                                   std::to_string(status) + ")");
        }
        results[slot] = json::parse(output);
        rethrow_if_failed(results[slot]);
        progress->done();
        return;
      }
    }
  };
  try {
    for (std::size_t slot = 0; slot < indices.size(); ++slot) {
      while (running.size() >= static_cast<std::size_t>(options.jobs)) finish_one();
      int fds[2];
      if (::pipe(fds) != 0) throw std::runtime_error("sweep: cannot create a pipe");
      std::cout.flush();
      std::cerr.flush();
      std::fflush(nullptr);
      const pid_t pid = ::fork();
      if (pid < 0) throw std::runtime_error("sweep: cannot fork a worker");
      if (pid == 0) {
        // The child never returns into the parent's code: whatever it throws (bad_alloc, a
        // JSON error) ends it with status 2, which the parent reports as a dead worker.
        try {
          // Stopped by the parent with SIGTERM: die, whatever handler the parent installed.
          ::signal(SIGTERM, SIG_DFL);
          ::signal(SIGINT, SIG_DFL);
          ::signal(SIGHUP, SIG_DFL);
          // A worker dies with its parent (killed, interrupted): it would otherwise run on.
          ::prctl(PR_SET_PDEATHSIG, SIGKILL);
          if (::getppid() == 1) ::_exit(3);  // the parent died before prctl took effect
          ::close(fds[0]);
          // Invalid UTF-8 in a message (a scene string) is replaced, not thrown.
          const std::string text = run_combination_caught(options, indices[slot])
                                       .dump(-1, ' ', false, json::error_handler_t::replace);
          std::size_t written = 0;
          while (written < text.size()) {
            const ssize_t n = ::write(fds[1], text.data() + written, text.size() - written);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) ::_exit(1);
            written += static_cast<std::size_t>(n);
          }
        } catch (...) {
          ::_exit(2);
        }
        ::_exit(0);
      }
      ::close(fds[1]);
      running.emplace(pid, Worker{slot, fds[0], {}});
    }
    while (!running.empty()) finish_one();
  } catch (...) {
    for (auto& [pid, w] : running) {
      ::kill(pid, SIGTERM);
      ::close(w.fd);
      int status = 0;
      ::waitpid(pid, &status, 0);
    }
    throw;
  }
  return results;
}

// A top-level comma splits values; commas inside [], {} or "" do not.
std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> values;
  std::string current;
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\' && i + 1 < text.size()) {
        current += c;
        current += text[++i];
        continue;
      }
      if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      ++depth;
    } else if (c == ']' || c == '}') {
      --depth;
    } else if (c == ',' && depth == 0) {
      values.push_back(trim(current));
      current.clear();
      continue;
    }
    current += c;
  }
  values.push_back(trim(current));
  return values;
}

std::vector<std::string> split_csv_line(const std::string& line, const std::string& where) {
  std::vector<std::string> cells;
  std::string current;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"') {
        if (i + 1 < line.size() && line[i + 1] == '"') {
          current += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        current += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.push_back(current);
      current.clear();
    } else {
      current += c;
    }
  }
  if (quoted) throw InputError(where, "unterminated quoted cell");
  cells.push_back(current);
  return cells;
}

// A cell as CSV: quoted if it holds a comma or a quote. A line break becomes a space, since the
// reader takes one line per row.
std::string csv_cell(const std::string& text) {
  std::string flat = text;
  std::replace(flat.begin(), flat.end(), '\n', ' ');
  std::replace(flat.begin(), flat.end(), '\r', ' ');
  if (flat.find_first_of(",\"") == std::string::npos) return flat;
  std::string out = "\"";
  for (char c : flat) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// Where the fixed columns are; throws InputError naming `where` if a table lacks them.
struct Layout {
  std::size_t error = 0;    // index of "error": parameters are [kLeading.size(), error)
  std::size_t figures = 0;  // index of the first figure column
};

Layout layout_of(const SweepTable& table, const std::string& where) {
  const auto& c = table.columns;
  if (c.size() < kLeading.size() + kMeasured.size() ||
      !std::equal(kLeading.begin(), kLeading.end(), c.begin())) {
    throw InputError(where,
                     "not a sweep table (expected the columns combination,combinations,sweep,"
                     "...,error,cpu_s,events,collisions,microcollisions,trouble,...)");
  }
  auto it = std::find(c.begin() + kLeading.size(), c.end(), kMeasured[0]);
  Layout layout;
  layout.error = static_cast<std::size_t>(it - c.begin());
  for (std::size_t k = 0; k < kMeasured.size(); ++k) {
    if (layout.error + k >= c.size() || c[layout.error + k] != kMeasured[k]) {
      throw InputError(where,
                       "not a sweep table (expected the columns error,cpu_s,events,"
                       "collisions,microcollisions,trouble after the parameters)");
    }
  }
  layout.figures = layout.error + kMeasured.size();
  return layout;
}

}  // namespace

SweepParameter parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  if (text.empty() || text[0] != '/' || eq == std::string::npos) {
    throw InputError("--vary " + text, "expected /json/pointer=v1,v2,... (RFC 6901 pointer)");
  }
  SweepParameter parameter;
  parameter.pointer = text.substr(0, eq);
  parameter.values = split_values(text.substr(eq + 1));
  for (const std::string& v : parameter.values) {
    if (v.empty()) throw InputError("--vary " + text, "an empty value (two commas in a row?)");
  }
  return parameter;
}

Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  Shard shard;
  if (slash == std::string::npos || !parse_size(text.substr(0, slash), &shard.index) ||
      !parse_size(text.substr(slash + 1), &shard.count) || shard.count == 0 || shard.index == 0 ||
      shard.index > shard.count) {
    throw InputError("--shard " + text, "expected K/N with 1 <= K <= N (the K-th of N slices)");
  }
  return shard;
}

std::size_t combination_count(const std::vector<SweepParameter>& parameters) {
  std::size_t count = 1;
  for (const SweepParameter& p : parameters) {
    if (count > std::numeric_limits<std::size_t>::max() / p.values.size() ||
        count * p.values.size() > 100000000) {
      throw InputError("--vary", "more than 1e8 combinations");
    }
    count *= p.values.size();
  }
  return count;
}

std::vector<std::size_t> combination_digits(const std::vector<SweepParameter>& parameters,
                                            std::size_t index) {
  std::vector<std::size_t> digits(parameters.size());
  for (std::size_t p = parameters.size(); p-- > 0;) {
    digits[p] = index % parameters[p].values.size();
    index /= parameters[p].values.size();
  }
  return digits;
}

std::string sweep_fingerprint(const SweepOptions& options) {
  std::string text = "scene=" + options.scene_path + "\n";
  for (const std::string& assignment : options.overrides) text += "set=" + assignment + "\n";
  text += "end=" + (options.end_time ? number_text(*options.end_time) : std::string()) + "\n";
  for (const SweepParameter& p : options.parameters) {
    text += "vary=" + p.pointer + "\n";
    for (const std::string& value : p.values) text += "value=" + value + "\n";
  }
  return fnv1a64_hex(text);
}

SweepTable run_sweep(const SweepOptions& options) {
  if (options.scene_path == "-") {
    throw InputError("scene", "a sweep reads the scene once per run: give a file, not -");
  }
  if (options.repeat < 1) throw InputError("--repeat", "expected a whole number >= 1");
  if (options.jobs < 1) throw InputError("--jobs", "expected a whole number >= 1");
  if (options.end_time && !(*options.end_time > 0.0 && std::isfinite(*options.end_time))) {
    throw InputError("--end", "expected a positive number of seconds");
  }
  std::set<std::string> pointers;
  for (const SweepParameter& p : options.parameters) {
    if (!pointers.insert(p.pointer).second) {
      throw InputError("--vary " + p.pointer, "the same pointer is varied twice");
    }
  }
  const std::size_t total = combination_count(options.parameters);

  // Validate before anything runs: the fixed overrides, then every value of every parameter on
  // its own (a scene that rejects a value names it and the --vary option).
  json base = read_json_file(options.scene_path);
  for (const std::string& assignment : options.overrides) apply_override(base, assignment);
  scene_from_json(base, options.scene_path);
  for (const SweepParameter& p : options.parameters) {
    for (const std::string& value : p.values) {
      const std::string assignment = p.pointer + "=" + value;
      try {
        json document = base;
        apply_override(document, assignment);
        scene_from_json(document, options.scene_path);
      } catch (const InputError& e) {
        // apply_override names the assignment as "--set ...": say it once, as --vary.
        const std::string what = e.what();
        const std::string set = "--set " + assignment + ": ";
        throw InputError("--vary " + assignment,
                         what.compare(0, set.size(), set) == 0 ? what.substr(set.size()) : what);
      }
    }
  }

  // The shard comes from parse_shard (or is the default 1/1), which validated it.
  PALPABLE_CHECK(options.shard.index >= 1 && options.shard.index <= options.shard.count,
                 "a shard K/N with 1 <= K <= N");
  const std::string fingerprint = sweep_fingerprint(options);
  std::vector<std::size_t> indices;
  for (std::size_t i = options.shard.index - 1; i < total; i += options.shard.count) {
    indices.push_back(i);
  }
  Progress progress(options.progress, indices.size());
  std::vector<json> measured;
  if (options.jobs == 1 || indices.size() <= 1) {
    for (std::size_t i : indices) {
      measured.push_back(json::parse(
          run_combination_caught(options, i).dump(-1, ' ', false, json::error_handler_t::replace)));
      rethrow_if_failed(measured.back());
      progress.done();
    }
  } else {
    measured = run_forked(options, indices, &progress);
  }

  std::vector<std::map<std::string, std::string>> figures(measured.size());
  std::set<std::string> figure_names;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    const json& reference = measured[k]["reference"];
    if (reference.is_object()) {
      for (auto it = reference.begin(); it != reference.end(); ++it) {
        flatten(it.key(), it.value(), &figures[k]);
      }
    }
    for (const auto& [name, value] : figures[k]) figure_names.insert(name);
  }

  SweepTable table;
  table.columns = kLeading;
  for (const SweepParameter& p : options.parameters) table.columns.push_back(p.pointer);
  table.columns.insert(table.columns.end(), kMeasured.begin(), kMeasured.end());
  table.columns.insert(table.columns.end(), figure_names.begin(), figure_names.end());
  for (std::size_t k = 0; k < measured.size(); ++k) {
    const json& m = measured[k];
    std::vector<std::string> row{std::to_string(indices[k]), std::to_string(total), fingerprint};
    const std::vector<std::size_t> digits = combination_digits(options.parameters, indices[k]);
    for (std::size_t p = 0; p < options.parameters.size(); ++p) {
      row.push_back(options.parameters[p].values[digits[p]]);
    }
    row.push_back(number_text(primary_error(m["reference"])));
    row.push_back(number_text(m["cpu_s"].get<double>()));
    row.push_back(cell_text(m["events"]));
    row.push_back(cell_text(m["collisions"]));
    row.push_back(cell_text(m["microcollisions"]));
    row.push_back(cell_text(m["trouble"]));
    for (const std::string& name : figure_names) {
      auto it = figures[k].find(name);
      row.push_back(it == figures[k].end() ? std::string() : it->second);
    }
    table.rows.push_back(std::move(row));
  }
  return table;
}

SweepTable merge_sweep_tables(const std::vector<SweepTable>& parts,
                              const std::vector<std::string>& where) {
  if (parts.empty()) throw InputError("--merge", "expected at least one sweep table");
  const std::ptrdiff_t first_parameter = static_cast<std::ptrdiff_t>(kLeading.size());
  std::vector<Layout> layouts;
  for (std::size_t k = 0; k < parts.size(); ++k) layouts.push_back(layout_of(parts[k], where[k]));
  const std::vector<std::string> parameters(parts[0].columns.begin() + first_parameter,
                                            parts[0].columns.begin() + layouts[0].error);
  std::set<std::string> figure_names;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const std::vector<std::string> mine(parts[k].columns.begin() + first_parameter,
                                        parts[k].columns.begin() + layouts[k].error);
    if (mine != parameters) {
      throw InputError(where[k], "its varied parameters differ from those of " + where[0]);
    }
    figure_names.insert(parts[k].columns.begin() + layouts[k].figures, parts[k].columns.end());
  }
  SweepTable merged;
  merged.columns = kLeading;
  merged.columns.insert(merged.columns.end(), parameters.begin(), parameters.end());
  merged.columns.insert(merged.columns.end(), kMeasured.begin(), kMeasured.end());
  merged.columns.insert(merged.columns.end(), figure_names.begin(), figure_names.end());

  std::optional<std::size_t> total;
  std::optional<std::pair<std::string, std::string>> fingerprint;  // the value, where first seen
  std::map<std::size_t, std::pair<std::vector<std::string>, std::string>> rows;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const SweepTable& part = parts[k];
    std::map<std::string, std::size_t> figure_column;
    for (std::size_t c = layouts[k].figures; c < part.columns.size(); ++c) {
      figure_column[part.columns[c]] = c;
    }
    for (std::size_t r = 0; r < part.rows.size(); ++r) {
      const std::vector<std::string>& row = part.rows[r];
      const std::string here = where[k] + " row " + std::to_string(r + 2);
      std::size_t index = 0, count = 0;
      if (row.size() != part.columns.size() || !parse_size(row[0], &index) ||
          !parse_size(row[1], &count)) {
        throw InputError(here, "expected " + std::to_string(part.columns.size()) +
                                   " cells starting with the combination and the total");
      }
      if (!fingerprint) {
        fingerprint = std::make_pair(row[2], here);
      } else if (fingerprint->first != row[2]) {
        throw InputError(here, "from another sweep (fingerprint " + row[2] + ", " +
                                   fingerprint->second + " has " + fingerprint->first +
                                   "): a different scene, --set, --end or --vary values");
      }
      if (total && *total != count) {
        throw InputError(here, "a sweep of " + std::to_string(count) + " combinations, the " +
                                   "others have " + std::to_string(*total));
      }
      total = count;
      if (index >= count) {
        throw InputError(here, "combination " + row[0] + " is past the total " + row[1]);
      }
      std::vector<std::string> aligned(row.begin(), row.begin() + layouts[k].figures);
      for (const std::string& name : figure_names) {
        auto it = figure_column.find(name);
        aligned.push_back(it == figure_column.end() ? std::string() : row[it->second]);
      }
      auto [it, inserted] = rows.emplace(index, std::make_pair(aligned, here));
      if (!inserted) {
        throw InputError(
            here, "combination " + row[0] + " appears twice (also at " + it->second.second + ")");
      }
    }
  }
  if (!total) throw InputError("--merge", "the tables hold no rows");
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < *total; ++i) {
    if (rows.count(i) == 0) missing.push_back(i);
  }
  if (!missing.empty()) {
    std::string list;
    for (std::size_t k = 0; k < missing.size() && k < 10; ++k) {
      list += (k ? ", " : "") + std::to_string(missing[k]);
    }
    if (missing.size() > 10) list += ", ...";
    throw InputError("--merge", std::to_string(missing.size()) + " of " + std::to_string(*total) +
                                    " combinations missing (a shard not given?): " + list);
  }
  for (auto& [index, row] : rows) merged.rows.push_back(std::move(row.first));
  return merged;
}

void write_sweep_csv(std::ostream& out, const SweepTable& table) {
  auto line = [&out](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << csv_cell(cells[i]);
    out << '\n';
  };
  line(table.columns);
  for (const auto& row : table.rows) line(row);
}

SweepTable read_sweep_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open the sweep table");
  SweepTable table;
  std::string text;
  // A file written on (or through) Windows ends its lines with CR LF: the CR is not a cell's.
  auto next_line = [&in, &text] {
    if (!std::getline(in, text)) return false;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    return true;
  };
  if (!next_line() || text.empty()) {
    throw InputError(path, "empty file, expected a sweep table (a header line first)");
  }
  table.columns = split_csv_line(text, path + " line 1");
  std::size_t number = 1;
  while (next_line()) {
    ++number;
    if (text.empty()) continue;
    const std::string here = path + " line " + std::to_string(number);
    table.rows.push_back(split_csv_line(text, here));
    if (table.rows.back().size() != table.columns.size()) {
      throw InputError(here, std::to_string(table.rows.back().size()) + " cells, the header has " +
                                 std::to_string(table.columns.size()));
    }
  }
  layout_of(table, path);
  return table;
}

std::vector<ParetoPoint> sweep_points(const SweepTable& table) {
  const Layout layout = layout_of(table, "--plot");
  std::vector<ParetoPoint> points;
  for (const auto& row : table.rows) {
    ParetoPoint p;
    auto number = [](const std::string& text) {
      try {
        return text.empty() ? kNaN : std::stod(text);
      } catch (const std::exception&) {
        return kNaN;
      }
    };
    p.error = number(row[layout.error]);
    p.cpu_s = number(row[layout.error + 1]);
    std::string values;
    for (std::size_t c = kLeading.size(); c < layout.error; ++c) {
      values += (values.empty() ? "" : ",") + row[c];
    }
    // gnuplot reads the label as a quoted string: one holding a quote falls back to the index.
    const bool unquotable = values.find('"') != std::string::npos;
    p.label = values.empty() || values.size() > 24 || unquotable ? "#" + row[0] : values;
    points.push_back(p);
  }
  return points;
}

void plot_sweep(const SweepTable& table, const std::string& png_path, const std::string& title) {
  plot_pareto(sweep_points(table), title, png_path);
}

}  // namespace palpable::tools
