#pragma once
// Scenes built in code for the cost benchmarks and tests ("paying only for what a scene
// needs"): a gas of spheres in zero gravity inside a cubic container, and idle bodies to add far
// from the action.
//
// Idle bodies: a fixed body never moves, so it schedules nothing and is never paired with another
// non-dynamic body; a dynamic body at rest in zero gravity cannot move until something reaches
// it, so its swept box is its own box for ever (no horizon event). Far from every moving body,
// neither enters a pair, an event or a closest-feature query: a scene should pay nothing for them.
#include "core/types.hpp"
#include "scheduler/world.hpp"

#include <cstdint>

namespace palpable {

enum class GasWalls {
  kHalfspaces,  // six fixed halfspaces (exact sphere-plane times of impact)
  kSlabs,       // six fixed box slabs (finite: bodies may be placed outside the container)
};

struct GasOptions {
  int count = 1000;              // spheres
  double radius_m = 0.05;        // [m]
  double volume_fraction = 0.1;  // sphere volume / container volume; sets the container side
  double speed_mps = 1.0;        // every sphere's initial speed, random direction [m/s]
  double friction = 0.0;         // mu of every pair
  double restitution = 1.0;      // e of every pair
  GasWalls walls = GasWalls::kHalfspaces;
  std::uint64_t seed = 1;  // directions (std::mt19937_64)
};

// Side [m] of the cubic container [0, L]^3 that holds `options.count` spheres at its volume
// fraction.
double gas_container_side(const GasOptions& options);

// Zero gravity; the spheres sit on a cubic lattice filling the container (the lattice spacing
// exceeds the diameter for volume fractions below pi / 6), each moving at speed_mps in a random
// direction. Throws InputError for counts < 1 or a volume fraction outside (0, pi / 6).
World make_sphere_gas(const GasOptions& options);

enum class IdleKind {
  kFixedBoxes,      // fixed cubes
  kRestingSpheres,  // dynamic spheres at rest (idle only in zero gravity)
};

// Appends `count` idle bodies of side / diameter `size_m`, on a cubic lattice of spacing
// 2 size_m whose first corner is `corner_W`. All share one shape.
void add_idle_bodies(World& world, int count, IdleKind kind, const Vec3& corner_W, double size_m);

}  // namespace palpable
