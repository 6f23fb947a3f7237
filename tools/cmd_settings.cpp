// `palpable settings`: every setting of a scene's "settings" object — scene key, unit, default,
// accepted values and meaning — from the one table in core/settings.hpp, with the derived
// tolerances and the named constants. `--markdown` prints the README's table (a test keeps the
// README equal to it).
#include "core/settings.hpp"
#include "tools/commands.hpp"
#include "tools/lib/exit_codes.hpp"

#include <iostream>
#include <memory>
#include <string>

namespace palpable::tools {
namespace {

void print_markdown(std::ostream& out) {
  const Settings defaults;
  out << "| key | unit | default | accepted | meaning |\n|---|---|---|---|---|\n";
  for (const SettingInfo& info : settings_table()) {
    out << "| `" << info.key << "` | " << (info.unit.empty() ? "" : info.unit) << " | `"
        << format_setting(info.get(defaults)) << "` | " << info.check << " | " << info.meaning
        << " |\n";
  }
  out << "\nDerived (at the defaults, g = 9.81 m/s²; computed in `core/settings.hpp` only):\n\n"
      << "| name | unit | value | meaning |\n|---|---|---|---|\n";
  for (const DerivedSetting& d : derived_settings(defaults, 9.81)) {
    out << "| " << d.name << " | " << d.unit << " | "
        << format_setting(SettingValue(d.value)) << " | " << d.meaning << " |\n";
  }
}

void print_text(std::ostream& out) {
  const Settings defaults;
  for (const SettingInfo& info : settings_table()) {
    std::string head = "/settings/" + std::string(info.key);
    out << head << std::string(head.size() < 38 ? 38 - head.size() : 1, ' ')
        << format_setting(info.get(defaults)) << (info.unit.empty() ? "" : " ")
        << (info.unit == "-" ? "" : info.unit) << "\n    " << info.meaning << "\n    accepts "
        << info.check << "\n";
  }
  out << "derived (g = 9.81 m/s^2):\n";
  for (const DerivedSetting& d : derived_settings(defaults, 9.81)) {
    out << "  " << d.name << " = " << format_setting(SettingValue(d.value)) << " " << d.unit
        << ": " << d.meaning << "\n";
  }
}

CommandRegistration reg{"settings", [](CLI::App& app) {
  app.description(
      "Print every setting a scene can give under \"settings\" (or `run --set "
      "/settings/KEY=VALUE`): scene key, default, unit, accepted values and meaning, and the "
      "tolerances derived from them. Each run's summary prints the values in effect.");
  auto markdown = std::make_shared<bool>(false);
  app.add_flag("--markdown", *markdown, "print the README's Markdown table");
  return std::function<int()>([markdown] {
    if (*markdown) {
      print_markdown(std::cout);
    } else {
      print_text(std::cout);
    }
    return kExitOk;
  });
}};

}  // namespace
}  // namespace palpable::tools
