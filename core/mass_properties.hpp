#pragma once
// Mass properties of a body about its centre of mass. Polyhedra: Mirtich, "Fast and Accurate
// Computation of Polyhedral Mass Properties", J. Graphics Tools 1(2), 1996. Spheres: closed form.
#include "core/shape.hpp"
#include "core/types.hpp"

namespace palpable {

struct MassProperties {
  double mass = 0.0;                     // [kg]; +inf for fixed and kinematic bodies
  double inv_mass = 0.0;                 // [1/kg]; 0 for fixed and kinematic bodies
  Mat3 inertia_M = Mat3::Zero();         // [kg m^2] about the centre of mass, modelling frame
  Vec3 principal_moments = Vec3::Zero(); // I_B = diag(I1, I2, I3) [kg m^2], ascending
  Quat q_MB = Quat::Identity();          // principal frame B in modelling frame M: v_M = q_MB * v_B

  bool is_infinite() const { return inv_mass == 0.0; }
};

// The volume integrals of a uniform solid of unit density, in the frame its geometry is given in
// (not necessarily about the centre of mass).
struct VolumeIntegrals {
  double volume = 0.0;           // [m^3]
  Vec3 centroid = Vec3::Zero();  // [m]
  Mat3 inertia_about_centroid = Mat3::Zero();  // [m^5] (times density gives kg m^2)
};

VolumeIntegrals volume_integrals(const ConvexPolyhedron& polyhedron);

// From a bounded shape and either a density [kg/m^3] or a total mass [kg]. Throws InputError
// for non-positive or non-finite values and for unbounded shapes.
MassProperties mass_properties_from_density(const Shape& shape, double density);
MassProperties mass_properties_from_mass(const Shape& shape, double mass);
// Infinite mass (fixed and kinematic bodies).
MassProperties infinite_mass_properties();
// From a principal decomposition of a symmetric positive-definite inertia tensor.
MassProperties mass_properties_from_inertia(double mass, const Mat3& inertia_M);

}  // namespace palpable
