#pragma once
// Random simultaneous-impact groups and the properties every resolved group must keep (issue 15),
// shared by the property test (tests/tools/random_groups_test.cpp, 2,000 groups) and
// `palpable bench groups` (100,000 and more, outside the suite).
//
// A group: 1-4 dynamic bodies (masses over 4 decades, principal inertias over 2, random axes,
// random velocities and spins) and, for half the groups and always for a lone body, a fixed one;
// 2-8 contacts between random pairs of them at random points with random unit normals, friction
// mu in [0, 1.2) and Poisson's e in [0, 1). Every draw comes from one std::mt19937_64 stream in a
// fixed order, so a seed and a group's index reproduce it.
#include "impulse/group_impulse.hpp"

#include <cstdint>
#include <random>
#include <vector>

namespace palpable::tools {

struct RandomGroup {
  std::vector<GroupBody> bodies;
  std::vector<GroupContact> contacts;
  bool with_fixed = false;  // the last body is fixed (inv_mass 0): momentum is not conserved
};

class RandomGroups {
 public:
  explicit RandomGroups(std::uint64_t seed) : rng_(seed) {}
  // The next group of the stream. `contacts` > 0 fixes the number of contacts (the cost
  // benchmark); 0 draws it in [2, 8] as the property test does.
  RandomGroup next(int contacts = 0);

 private:
  double uniform();  // in [-1, 1)
  Vec3 uniform3();   // three draws, x first
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> U_{-1.0, 1.0};
};

// What one resolved group did, each figure relative to its scale, so that 0 is ideal and the
// bounds below are the same at every size of group.
struct GroupFigures {
  double energy_ratio = 0.0;     // E_after / E_before (<= 1: no energy created)
  double energy_excess = 0.0;    // E_after - E_before (1 + 1e-12) [J] (> 1e-15: created)
  double cone_excess = 0.0;      // max_i (|p_t| - mu p_n) / p_scale (> 0: outside its cone)
  double negative_normal = 0.0;  // max_i -p_n / p_scale (> 0: a contact pulls)
  double normal_deficit = 0.0;   // max_i (floor_i - u_n,i) / (1 + speed) [-] (> 0: approaching)
  double normal_mismatch = 0.0;  // max_i |u_n,i from the velocities - reported u_n,i| [m/s]
  double momentum_error = 0.0;   // |P_after - P_before| / (1 + |P_before| + p_scale), no fixed body
  bool converged = true;
};

// The bounds the property test asserts and the benchmark counts violations of (p_scale: the
// largest impulse of the group; speed: the largest |v| + |w| of its bodies before).
struct GroupBounds {
  double energy_excess = 1e-15;  // [J], after the relative 1e-12 above
  double cone_excess = 1e-9;
  double negative_normal = 1e-12;
  double normal_deficit = 1e-8;
  double normal_mismatch = 1e-9;  // [m/s]
  double momentum_error = 1e-12;
};

GroupFigures group_figures(const RandomGroup& group, const GroupResult& result);

// True if `figures` break any of `bounds` (convergence is not asked: see random_groups.cpp).
bool violates(const GroupFigures& figures, const GroupBounds& bounds = {});

}  // namespace palpable::tools
