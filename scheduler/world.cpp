#include "scheduler/world.hpp"

namespace palpable {

const Material& World::material(BodyId a, BodyId b) const {
  for (const PairMaterial& p : pair_materials) {
    if ((p.a == a && p.b == b) || (p.a == b && p.b == a)) return p.material;
  }
  // A pair with one body and "any other" (an invalid id) comes second.
  for (const PairMaterial& p : pair_materials) {
    if (!p.b.valid() && (p.a == a || p.a == b)) return p.material;
  }
  return default_material;
}

BodyId World::find_body(const std::string& name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].name == name) return BodyId{static_cast<std::uint32_t>(i)};
  }
  return BodyId{};
}

BodyId World::add(Body body) {
  bodies.push_back(std::move(body));
  return BodyId{static_cast<std::uint32_t>(bodies.size() - 1)};
}

}  // namespace palpable
