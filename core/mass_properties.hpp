#pragma once
// Mass properties of a body about its centre of mass. Polyhedra: Mirtich, "Fast and Accurate
// Computation of Polyhedral Mass Properties", J. Graphics Tools 1(2), 1996. Spheres: closed form.
#include "core/shape.hpp"
#include "core/types.hpp"

namespace palpable {

struct MassProperties {
  // What advancing a free rotation reads comes first (see Body).
  Quat q_MB = Quat::Identity();  // principal frame B in modelling frame M: v_M = q_MB * v_B
  Vec3 principal_moments = Vec3::Zero();  // I_B = diag(I1, I2, I3) [kg m^2], ascending
  double mass = 0.0;                      // [kg]; +inf for fixed and kinematic bodies
  double inv_mass = 0.0;                  // [1/kg]; 0 for fixed and kinematic bodies
  Mat3 inertia_M = Mat3::Zero();          // [kg m^2] about the centre of mass, modelling frame

  bool is_infinite() const { return inv_mass == 0.0; }
  // Inverse inertia about the centre of mass in M [1/(kg m^2)]; zero for infinite mass.
  Mat3 inv_inertia_M() const {
    if (is_infinite()) return Mat3::Zero();
    const Mat3 R_MB = q_MB.toRotationMatrix();
    return R_MB * principal_moments.cwiseInverse().asDiagonal() * R_MB.transpose();
  }
};

// The volume integrals of a uniform solid of unit density, in the frame its geometry is given in
// (not necessarily about the centre of mass).
struct VolumeIntegrals {
  double volume = 0.0;                         // [m^3]
  Vec3 centroid = Vec3::Zero();                // [m]
  Mat3 inertia_about_centroid = Mat3::Zero();  // [m^5] (times density gives kg m^2)
};

VolumeIntegrals volume_integrals(const ConvexPolyhedron& polyhedron);

// From a bounded shape and either a density [kg/m^3] or a total mass [kg]. Throws InputError
// for non-positive or non-finite values and for unbounded shapes.
MassProperties mass_properties_from_density(const Shape& shape, double density);
MassProperties mass_properties_from_mass(const Shape& shape, double mass);
// The unit-density volume integrals of a bounded shape in its modelling frame: a sphere, ellipsoid,
// cylinder or capsule in closed form, a polyhedron by volume_integrals, a compound as the sum of
// its posed parts (parallel-axis theorem). Throws InputError for an unbounded shape and for a
// loaded ball (uniform density cannot put its centre of mass off its centre: use
// mass_properties_from_inertia with the ball's mass and inertia about its centre of mass, as a
// scene's "inertia" key does).
VolumeIntegrals shape_volume_integrals(const Shape& shape);
// Infinite mass (fixed and kinematic bodies): mass and principal moments +inf, inverses zero.
MassProperties infinite_mass_properties();
// From a mass and a symmetric positive-definite inertia tensor about the centre of mass in M:
// principal moments ascending and q_MB a proper rotation. Where moments are equal (within
// kEqualMomentTolerance) the principal axes are chosen by a fixed rule: all equal ->
// q_MB = identity; two equal -> the unique axis from the eigen-solver, the other two from the M
// axis least aligned with it. Throws InputError for a non-positive or non-finite mass or an
// inertia that is not symmetric positive definite or breaks the triangle inequality.
MassProperties mass_properties_from_inertia(double mass, const Mat3& inertia_M);

}  // namespace palpable
