// palpable — the command line of the Palpable simulator. Subcommands register themselves
// (tools/commands.hpp); this file only parses and dispatches.
#include "core/check.hpp"
#include "tools/commands.hpp"
#include "tools/lib/atomic_file.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/heap.hpp"
#include "tools/version.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <iostream>
#include <string>

namespace palpable::tools {
std::vector<Command>& command_registry() {
  static std::vector<Command> registry;
  return registry;
}
}  // namespace palpable::tools

namespace {
std::string group_description(const std::string& group) {
  if (group == "bench") {
    return "Benchmarks (not tests): each prints medians of repeated timings as JSON lines";
  }
  return group;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace palpable::tools;
  // SIGINT, SIGTERM, SIGHUP, SIGPIPE: remove every temporary output file, exit 128 + signal.
  install_output_cleanup_on_signals();
  keep_freed_heap();
  CLI::App app{
      "Palpable: impulse-based, event-driven rigid-body simulation with exact ballistic flight,\n"
      "closest-feature collision detection and Coulomb friction integrated over the normal "
      "impulse\n"
      "(after Mirtich & Canny, 1995).\n\n"
      "Exit codes: 0 success; 1 the run failed; 2 bad input (command line, scene, spec), nothing\n"
      "run; 3 the run finished but a requested check did not hold; 4 a run stopped at its\n"
      "--cpu-limit before its end time (its outputs hold the run up to there).\n",
      "palpable"};
  app.set_version_flag("--version",
                       std::string("palpable ") + kVersion + " (git " + kGitCommit + ")");
  app.require_subcommand(1);
  app.set_help_all_flag("--help-all", "Print help for every subcommand");

  std::vector<std::pair<CLI::App*, std::function<int()>>> runners;
  auto& registry = command_registry();
  std::sort(registry.begin(), registry.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  // A name with a space ("bench distance") is a subcommand of a group ("bench"), created on
  // first use; the group itself requires one of its subcommands.
  for (const Command& command : registry) {
    CLI::App* parent = &app;
    std::string name = command.name;
    if (auto space = name.find(' '); space != std::string::npos) {
      std::string group = name.substr(0, space);
      name = name.substr(space + 1);
      try {
        parent = app.get_subcommand(group);
      } catch (const CLI::OptionNotFound&) {
        parent = app.add_subcommand(group, group_description(group));
        parent->require_subcommand(1);
      }
    }
    CLI::App* sub = parent->add_subcommand(name);
    runners.emplace_back(sub, command.build(*sub));
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  try {
    for (auto& [sub, run] : runners) {
      if (sub->parsed()) return run();
    }
  } catch (const palpable::InputError& e) {
    std::cerr << "palpable: error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "palpable: failed: " << e.what() << "\n";
    return kExitFailure;
  }
  return kExitFailure;
}
