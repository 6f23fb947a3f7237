#pragma once
// `palpable compare` and the reference curves of `palpable plot`: a closed-form reference spec
// assembled from the command line (--reference, --param key=value, --reference-from SCENE.json),
// a trace (and optionally its events) read from CSV, the error figures, and optional thresholds.
#include "scenarios/trace.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace palpable::tools {

struct ReferenceOptions {
  std::string type;                 // --reference: "incline", "turntable", ...
  std::string scene_path;           // --reference-from: a scene whose "reference" object is used
  std::vector<std::string> params;  // --param key=value (value parsed as JSON, else a string)
};

// The reference spec: the scene's "reference" object (if given), then --reference as its "type",
// then each --param. Throws InputError naming the option or scene for bad input (a parameter
// without '=', a scene without a reference, no type at all).
nlohmann::json reference_spec(const ReferenceOptions& options);

struct CompareOptions {
  std::string trace_path;
  std::string events_path;  // empty: no events
  ReferenceOptions reference;
  std::vector<std::string> max;  // --max figure=value thresholds
};

struct CompareResult {
  nlohmann::json spec;
  nlohmann::json figures;
  std::vector<std::string> exceeded;  // "figure = value > max" for each threshold not met
};

// Reads the files, compares and checks the thresholds (|figure| <= max; for a list of numbers,
// every entry). Throws InputError for bad input, including a threshold on an unknown figure.
CompareResult compare_trace(const CompareOptions& options);

// The figures for people: one "name  value" line each, then the exceeded thresholds.
std::string compare_text(const CompareResult& result);

// Parses "key=value" (value as JSON, or a bare string); throws InputError naming `option`.
std::pair<std::string, nlohmann::json> parse_key_value(const std::string& text,
                                                       const std::string& option);

}  // namespace palpable::tools
