#pragma once
// Scene files (format "palpable-scene/1", documented in scenarios/README.md): parsing,
// validation with errors that name the JSON path, the value found and what was expected, and
// command-line overrides through RFC 6901 JSON pointers (`--set /settings/envelope=1e-5`).
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace palpable {

struct PairMaterial {
  BodyId a;
  BodyId b;
  Material material;
};

struct Scene {
  std::string name;
  std::string source;  // file name (or "-") the scene came from, for messages
  Vec3 gravity_W = Vec3(0.0, 0.0, -9.81);
  double end_time = 0.0;         // [s]
  double output_interval = 0.0;  // [s]; 0: no samples
  Settings settings;
  Material default_material;
  std::vector<PairMaterial> pair_materials;
  std::vector<Body> bodies;
  nlohmann::json reference;  // the closed-form reference the scene names, or null

  // The material of the pair (a, b), in either order.
  const Material& material(BodyId a, BodyId b) const;
  // Index of the body with this name, or an invalid id.
  BodyId find_body(const std::string& name) const;
};

// Parses and validates. Throws InputError whose where() is "<source>:<json pointer>".
Scene scene_from_json(const nlohmann::json& document, const std::string& source);

// Reads a JSON document from a file ("-": standard input). Throws InputError naming the file and,
// for a syntax error, the byte position.
nlohmann::json read_json_file(const std::string& path);

// Applies one "/json/pointer=value" override; value is parsed as JSON (a bare word that is not
// JSON is taken as a string). The parent of the pointer must exist. Throws InputError.
void apply_override(nlohmann::json& document, const std::string& assignment);

}  // namespace palpable
