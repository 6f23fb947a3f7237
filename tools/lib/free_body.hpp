#pragma once
// A free rigid body given by its moments of inertia about the axes of its modelling frame, for the
// command-line tools that exercise ballistic motion (`palpable spin`, `palpable bench state`)
// before scene files exist. Mass properties are built directly (no shape): the principal frame is
// the modelling frame with its axes reordered so that the moments ascend (DESIGN.md §2).
#include "core/body.hpp"
#include "core/types.hpp"

#include <string>

namespace palpable::tools {

// Throws InputError naming `where` unless the moments are finite, positive and satisfy the
// triangle inequality of a real body (each moment <= the sum of the other two, to 1e-12 relative).
void check_moments_of_inertia(const Vec3& moments_M, const std::string& where);

// A dynamic body of mass `mass` [kg] whose inertia tensor in its modelling frame is
// diag(moments_M) [kg m^2]; no shape.
Body make_free_body(const std::string& name, double mass, const Vec3& moments_M);

}  // namespace palpable::tools
