#pragma once
// Shared by the scheduler tests.
#include "core/body.hpp"
#include "core/mass_properties.hpp"
#include "core/shape.hpp"

#include <memory>
#include <string>

namespace palpable::test {

// A fixed horizontal ground, the halfspace z <= 0.
inline Body fixed_ground(const std::string& name = "ground") {
  Body b;
  b.name = name;
  b.motion = MotionKind::kFixed;
  b.shape = std::make_shared<const Shape>(make_halfspace(Vec3::UnitZ(), 0.0));
  b.mass = infinite_mass_properties();
  return b;
}

}  // namespace palpable::test
