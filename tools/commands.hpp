#pragma once
// Subcommands of the `palpable` command line register themselves here: each tools/cmd_*.cpp
// defines one static CommandRegistration, so adding a subcommand touches no other file.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace palpable::tools {

// Builds the subcommand under `app`; the returned callback runs it and returns the exit code.
struct Command {
  std::string name;
  std::function<std::function<int()>(CLI::App& app)> build;
};

std::vector<Command>& command_registry();

struct CommandRegistration {
  CommandRegistration(std::string name, std::function<std::function<int()>(CLI::App&)> build) {
    command_registry().push_back({std::move(name), std::move(build)});
  }
};

}  // namespace palpable::tools

// Example (tools/cmd_example.cpp):
//   namespace {
//   palpable::tools::CommandRegistration reg{"bench state", [](CLI::App& app) {
//     app.description("...");
//     auto repeats = std::make_shared<int>(5);
//     app.add_option("--repeats", *repeats, "...");
//     return std::function<int()>([repeats] { ...; return palpable::tools::kExitOk; });
//   }};
//   }
// A name with a space registers under a group ("bench state" is `palpable bench state`).
