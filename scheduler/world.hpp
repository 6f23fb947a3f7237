#pragma once
// What a simulation starts from: the bodies, gravity, settings and contact materials. Built by
// scenarios/ from a scene file, or directly by tests and tools.
#include "core/body.hpp"
#include "core/settings.hpp"
#include "core/types.hpp"

#include <string>
#include <vector>

namespace palpable {

// The material of the pair (a, b); b invalid: a with every other body (a pair naming both bodies
// takes precedence).
struct PairMaterial {
  BodyId a;
  BodyId b;
  Material material;
};

struct World {
  std::vector<Body> bodies;
  Vec3 gravity_W = Vec3(0.0, 0.0, -9.81);  // [m/s^2], acts on dynamic bodies only
  Settings settings;
  Material default_material;
  std::vector<PairMaterial> pair_materials;

  // The material of the pair (a, b), in either order; the default if none is given.
  const Material& material(BodyId a, BodyId b) const;
  // Index of the body with this name, or an invalid id.
  BodyId find_body(const std::string& name) const;
  BodyId add(Body body);
};

}  // namespace palpable
