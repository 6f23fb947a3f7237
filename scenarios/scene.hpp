#pragma once
// Scene files (format "palpable-scene/1", documented in scenarios/README.md): parsing,
// validation with errors that name the JSON path, the value found and what was expected, and
// command-line overrides through RFC 6901 JSON pointers (`--set /settings/envelope=1e-5`).
#include "scheduler/world.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace palpable {

// The longest run a scene may ask for [s] (the event clock resolves 1e-12 of the time), and the
// most samples it may write.
inline constexpr double kMaxEndTime = 1e9;
inline constexpr double kMaxSamples = 1e9;

struct Scene {
  std::string name;
  std::string source;            // file name (or "-") the scene came from, for messages
  double end_time = 0.0;         // [s]
  double output_interval = 0.0;  // [s]; 0: no samples
  World world;
  nlohmann::json reference;  // the closed-form reference the scene names, or null
  std::string plot;          // the picture `palpable plot --kind auto` draws ("": its own choice)
};

// The values a scene's "plot" hint may take (`palpable plot`'s kinds, auto excepted).
inline const std::vector<std::string>& scene_plot_kinds() {
  static const std::vector<std::string> kinds = {"series",    "top",  "incline",
                                                 "turntable", "line", "tumble"};
  return kinds;
}

// Parses and validates. Throws InputError whose where() is "<source>:<json pointer>".
Scene scene_from_json(const nlohmann::json& document, const std::string& source);

// Reads a JSON document from a file ("-": standard input). Throws InputError naming the file and,
// for a syntax error, the byte position.
nlohmann::json read_json_file(const std::string& path);
// The bytes of a file ("-": standard input). Throws InputError naming the file.
std::string read_text_file(const std::string& path);

// A scene file read, overridden (--set assignments, in order) and parsed: what `palpable run`,
// the viewer and the Python module all start from. `text`, if given, receives the file's bytes.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {},
                 std::string* text = nullptr);

// Applies one "/json/pointer=value" override; value is parsed as JSON (a bare word that is not
// JSON is taken as a string). The parent of the pointer must exist. Throws InputError.
void apply_override(nlohmann::json& document, const std::string& assignment);

// Every setting in effect (core/settings.hpp's table, scene keys), with the derived tolerances
// under "derived" for a world whose gravity has magnitude gravity_mps2 [m/s^2].
nlohmann::json settings_json(const Settings& settings, double gravity_mps2);

}  // namespace palpable
