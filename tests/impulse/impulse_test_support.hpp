#pragma once
// Shared by the impulse tests.
#include "impulse/collision_integrator.hpp"

namespace palpable::test {

inline CollisionParameters params_for(double mu, double e, RestitutionLaw law,
                                      double tolerance = 1e-9) {
  CollisionParameters params;
  params.friction = mu;
  params.restitution = e;
  params.law = law;
  params.tolerance = tolerance;
  return params;
}

}  // namespace palpable::test
