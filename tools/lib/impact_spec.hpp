#pragma once
// The spec of `palpable impact`: one collision described either in the contact frame (K, u0) or
// by two bodies (mass, inertia, velocities, contact offsets) and a normal, plus the material.
// Parsing validates everything and throws palpable::InputError naming the JSON pointer, the value
// found and what was expected; resolving never throws (numerical trouble is the result's status).
#include "core/types.hpp"
#include "impulse/collision_integrator.hpp"
#include "impulse/collision_matrix.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <iosfwd>
#include <string>
#include <vector>

namespace palpable::tools {

struct ImpactSpec {
  bool from_bodies = false;
  std::array<ContactBody, 2> bodies;  // from_bodies: the two bodies (world frame)
  Mat3 R_WC = Mat3::Identity();       // from_bodies: contact frame [t1 t2 n]
  Mat3 K_c = Mat3::Identity();        // collision matrix in the contact frame
  Vec3 u0_c = Vec3::Zero();           // initial relative contact velocity, contact frame
  CollisionParameters params;
};

// The format, with an example (printed by `palpable impact --help`).
extern const char* const kImpactSpecHelp;

// Validates a parsed spec. Throws InputError("/bodies/0/mass", "got -1; expected ...").
ImpactSpec parse_impact_spec(const nlohmann::json& spec);

// Parses JSON text (`source` names it in errors) and validates it.
ImpactSpec parse_impact_spec_text(const std::string& text, const std::string& source);

// Resolves the collision and describes it: impulse, u_final, energy_change, phases, ...
// With `path`, also u(p_z) along the integration (ImpulsePathPoint, contact frame).
nlohmann::json resolve_impact(const ImpactSpec& spec,
                              std::vector<ImpulsePathPoint>* path = nullptr);

// The path as CSV: header p_z,p_x,p_y,u_x,u_y,u_z (contact frame, 17 significant digits).
void write_impulse_path_csv(std::ostream& out, const std::vector<ImpulsePathPoint>& path);

}  // namespace palpable::tools
