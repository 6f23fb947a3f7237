#pragma once
// Simultaneous impact: the contacts that meet at one instant resolved as one problem (issue 15;
// DESIGN.md §8.4).
//
// The model, in three phases over the group's Delassus operator A = J M^-1 J^T (J maps the
// bodies' velocities to the contacts' relative velocities in their frames [t1 t2 n]):
//  1. Compression: the plastic frictional impulse lambda_c, the minimiser of the kinetic-energy
//     change f(lambda) = lambda.u0 + lambda.A.lambda / 2 over the Coulomb cones (|lambda_t| <=
//     mu lambda_n) - the cone-complementarity problem of Anitescu & Tasora (2010). Its KKT
//     conditions leave every contact separating or at rest (u_n >= mu |u_t| >= 0), friction
//     maximally dissipative, and f <= f(0) = 0: compression never adds energy. A sliding contact
//     would separate at mu |u_t|; a fixed point on that shift (solving again with b_n + mu |u_t|)
//     gives Coulomb's u_n = 0 there, each round kept only if it adds no energy.
//  2. Expansion, by the scene's law per contact. Poisson: the normal impulse e_i lambda_c,n,i.
//     Stronge: the normal impulses p_i for which each contact's normal impulse does the work
//     e_i^2 W_c,i that its compression absorbed, the works taken along straight impulse paths
//     (W = p (u_n,start + u_n,end) / 2, exact for a path on which u_n is linear): W_c,i =
//     lambda_c,n,i u0_n,i / 2 at a contact brought to rest. One contact without friction: both
//     laws give e lambda_c,n. Coupled contacts: Stronge's per-contact works sum to the
//     e^2-weighted compression loss, Poisson's need not. Either with the friction that minimises
//     f over the disks |lambda_t| <= mu p_n (for Stronge, alternated with Newton's method on the
//     works until the normals settle).
//     If the expansion would end with more kinetic energy than the group had before impact, it
//     is scaled down (the largest factor in [0, 1] that does not): the energy bound is kept.
//  3. If anything still approaches (the expansion drove a contact into approach, or the cone
//     solver stopped at its tolerance), the frictionless plastic impulse on the normals, an LCP
//     solved as a convex programme by an active set with proximal rounds (any number of
//     contacts, singular A included): it only removes energy and adds normal impulse.
// Both cone problems are solved by accelerated projected gradient descent with restart (APGD,
// Mazhar, Heyn, Negrut & Tasora 2015): every step treats all contacts at once, so a mirror-
// symmetric group gets a mirror-symmetric answer (a Gauss-Seidel sweep would not), and the
// impulses on the two bodies of a contact are equal and opposite (momentum is conserved).
//
// What it keeps (Smith et al. 2012 show no model keeps all): momentum, the energy bound (no
// kinetic energy created, for every e in [0, 1]), symmetry, non-penetration (u_n >= 0 after),
// impulses inside their cones. What it does not: Newton's cradle with touching balls as one group
// gives a spread-out answer, not the textbook one - which is why the scheduler groups only
// contacts that approach at the instant (a cradle's touching balls do not: they stay sequential).
#include "core/settings.hpp"
#include "core/types.hpp"

#include <vector>

namespace palpable {

// One body of a group. A fixed or kinematic body has inv_mass 0 and a zero inverse inertia; its
// velocity is still that of its surface.
struct GroupBody {
  double inv_mass = 0.0;
  Mat3 inv_inertia_W = Mat3::Zero();
  Vec3 x_W = Vec3::Zero();  // centre of mass [m]
  Vec3 v_W = Vec3::Zero();
  Vec3 w_W = Vec3::Zero();
};

// One contact of a group: between bodies[body1] and bodies[body2], the normal pointing from
// body 2 to body 1 (body 1 is pushed along +n).
struct GroupContact {
  int body1 = 0;
  int body2 = 0;
  Vec3 point_W = Vec3::Zero();
  Vec3 n_W = Vec3::UnitZ();
  double friction = 0.0;     // mu
  double restitution = 0.0;  // Poisson's e, in [0, 1]
  // The least normal velocity after [m/s]: a microcollision's rebound floor v_micro (0: none).
  // Met by the last phase's frictionless push, which then adds the energy the floor needs.
  double min_separation = 0.0;
};

struct GroupOptions {
  double tolerance = 1e-14;  // stationarity of the cone problems, relative to the impulse scale
  int max_iterations = 20000;
  int max_shift_rounds = 50;  // fixed-point rounds on the sliding contacts' normal shift
  // The expansion's law: Stronge (energetic, per contact) or Poisson (kinetic, per contact);
  // Newton's kinematic law is not offered to groups and is resolved as Poisson's.
  RestitutionLaw law = RestitutionLaw::kPoisson;
  int max_stronge_rounds = 20;  // rounds between Stronge's normals and the friction they allow
};

struct GroupResult {
  std::vector<Vec3> impulse_W;  // per contact: the total impulse on body 1 (body 2: the opposite)
  std::vector<Vec3> v_W, w_W;   // per body, after (unchanged for fixed and kinematic bodies)
  std::vector<double> normal_velocity;  // per contact, after [m/s] (>= 0 up to the tolerance)
  double energy_before = 0.0;           // kinetic energy of the dynamic bodies [J]
  double energy_after = 0.0;
  double restitution_scale = 1.0;  // < 1: the expansion was scaled down to keep the energy bound
  int iterations = 0;              // APGD iterations over all phases
  bool converged = true;
  bool final_push = false;  // phase 3 acted: something still approached after the expansion
  int shift_rounds = 0;     // fixed-point rounds taken on the sliding contacts' normal shift
  int stronge_rounds = 0;   // rounds taken between Stronge's normals and their friction
};

// Resolves the group; throws std::invalid_argument on a body index out of range or a non-unit
// normal.
GroupResult resolve_group(const std::vector<GroupBody>& bodies,
                          const std::vector<GroupContact>& contacts,
                          const GroupOptions& options = {});

// The linear momentum of the dynamic bodies (inv_mass > 0) moving at the velocities v_W [kg m/s]:
// what a group conserves when no body is fixed.
Vec3 linear_momentum(const std::vector<GroupBody>& bodies, const std::vector<Vec3>& v_W);

}  // namespace palpable
