#include "tools/lib/compare.hpp"

#include "scenarios/json_reader.hpp"
#include "scenarios/scene.hpp"

#include "core/check.hpp"
#include "scenarios/reference.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace palpable::tools {

using nlohmann::json;

std::pair<std::string, json> parse_key_value(const std::string& text, const std::string& option) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw InputError(option + " " + text, "expected key=value");
  }
  std::string key = text.substr(0, eq), raw = text.substr(eq + 1);
  return {key, parse_command_line_value(raw, option + " " + text)};
}

json reference_spec(const ReferenceOptions& options) {
  json spec = json::object();
  if (!options.scene_path.empty()) {
    // Through the scene loader: the reference is validated and completed from the scene (its
    // derived parameters follow the scene's bodies and materials).
    const Scene scene = load_scene(options.scene_path);
    if (scene.reference.is_null()) {
      throw InputError(options.scene_path + ":/reference",
                       "the scene has no \"reference\" object (give --reference and --param)");
    }
    spec = scene.reference;
  }
  if (!options.type.empty()) spec["type"] = options.type;
  for (const std::string& p : options.params) {
    auto [key, value] = parse_key_value(p, "--param");
    spec[key] = value;
  }
  if (!spec.contains("type")) {
    throw InputError("--reference",
                     "missing: name a closed form (incline, turntable, "
                     "slide_to_roll, bouncing_ball, impact_1d) or --reference-from");
  }
  return spec;
}

namespace {
// The largest magnitude of a number or a list of numbers; NaN if the figure is not numeric.
double magnitude(const json& figure) {
  if (figure.is_number()) return std::abs(figure.get<double>());
  if (figure.is_array() && !figure.empty()) {
    double worst = 0.0;
    for (const json& x : figure) {
      if (!x.is_number()) return std::nan("");
      worst = std::max(worst, std::abs(x.get<double>()));
    }
    return worst;
  }
  return std::nan("");
}
}  // namespace

CompareResult compare_trace(const CompareOptions& options) {
  CompareResult result;
  result.spec = reference_spec(options.reference);
  std::vector<std::pair<std::string, double>> limits;
  for (const std::string& m : options.max) {
    auto [key, value] = parse_key_value(m, "--max");
    if (!value.is_number() || !(value.get<double>() >= 0.0)) {
      throw InputError("--max " + m, "expected figure=limit with a limit >= 0");
    }
    limits.emplace_back(key, value.get<double>());
  }
  Trace trace = read_trace_csv(options.trace_path);
  if (!options.events_path.empty()) read_events_csv(options.events_path, trace);
  const std::string where = options.reference.scene_path.empty()
                                ? std::string("--param")
                                : options.reference.scene_path + ":/reference";
  result.figures = compare_with_reference(result.spec, trace, where);
  for (const auto& [key, limit] : limits) {
    auto it = result.figures.find(key);
    if (it != result.figures.end() && it->is_null()) {
      // Its closed form does not apply (the premise failed): never a pass.
      result.exceeded.push_back(key + " is null: " +
                                result.figures.value("premise_failed", std::string("no value")));
      continue;
    }
    const double value = it == result.figures.end() ? std::nan("") : magnitude(*it);
    if (std::isnan(value)) {
      std::string known;
      for (const auto& [name, figure] : result.figures.items()) {
        if (!std::isnan(magnitude(figure))) known += (known.empty() ? "" : ", ") + name;
      }
      throw InputError("--max " + key, "no numeric figure of that name (figures: " + known + ")");
    }
    if (value > limit) {
      std::ostringstream line;
      line << std::setprecision(6) << key << " = " << value << " > " << limit;
      result.exceeded.push_back(line.str());
    }
  }
  return result;
}

std::string compare_text(const CompareResult& result) {
  std::ostringstream out;
  out << "reference        " << result.spec.dump() << "\n";
  std::size_t width = 0;
  for (const auto& item : result.figures.items()) width = std::max(width, item.key().size());
  for (const auto& [name, figure] : result.figures.items()) {
    if (name == "reference") continue;
    out << std::left << std::setw(static_cast<int>(width) + 2) << name;
    if (figure.is_number_float()) {
      out << std::setprecision(8) << figure.get<double>() << "\n";
    } else {
      out << figure.dump() << "\n";
    }
  }
  for (const std::string& e : result.exceeded) out << "EXCEEDED  " << e << "\n";
  return out.str();
}

}  // namespace palpable::tools
