// Mass properties. Polyhedra: B. Mirtich, "Fast and Accurate Computation of Polyhedral Mass
// Properties", J. Graphics Tools 1(2):31-50, 1996 — the volume integrals are reduced by the
// divergence theorem to face integrals (§3), each face integral to an integral over the face's
// projection on a coordinate plane (§4), and those by Green's theorem to sums over the edges (§5).
#include "core/mass_properties.hpp"

#include "core/check.hpp"
#include "core/settings.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <sstream>
#include <string>

namespace palpable {

namespace {

// Integrals over the projection R of a face on the (a, b) plane (Mirtich §5, eq. 20-22 in
// Green's-theorem form): P_{a^p b^q} = ∫_R a^p b^q da db, summed edge by edge over the
// counter-clockwise boundary.
struct ProjectionIntegrals {
  double P1 = 0, Pa = 0, Pb = 0, Paa = 0, Pab = 0, Pbb = 0, Paaa = 0, Paab = 0, Pabb = 0, Pbbb = 0;
};

ProjectionIntegrals projection_integrals(const std::vector<Vec3>& loop, int A, int B) {
  ProjectionIntegrals p;
  const std::size_t count = loop.size();
  for (std::size_t i = 0; i < count; ++i) {
    const double a0 = loop[i][A];
    const double b0 = loop[i][B];
    const double a1 = loop[(i + 1) % count][A];
    const double b1 = loop[(i + 1) % count][B];
    const double da = a1 - a0;
    const double db = b1 - b0;
    const double a0_2 = a0 * a0, a0_3 = a0_2 * a0, a0_4 = a0_3 * a0;
    const double b0_2 = b0 * b0, b0_3 = b0_2 * b0, b0_4 = b0_3 * b0;
    const double a1_2 = a1 * a1, a1_3 = a1_2 * a1;
    const double b1_2 = b1 * b1, b1_3 = b1_2 * b1;
    // Sums of the monomials of the edge's end points (Mirtich's C and K terms).
    const double C1 = a1 + a0;
    const double Ca = a1 * C1 + a0_2;
    const double Caa = a1 * Ca + a0_3;
    const double Caaa = a1 * Caa + a0_4;
    const double Cb = b1 * (b1 + b0) + b0_2;
    const double Cbb = b1 * Cb + b0_3;
    const double Cbbb = b1 * Cbb + b0_4;
    const double Cab = 3 * a1_2 + 2 * a1 * a0 + a0_2;
    const double Kab = a1_2 + 2 * a1 * a0 + 3 * a0_2;
    const double Caab = a0 * Cab + 4 * a1_3;
    const double Kaab = a1 * Kab + 4 * a0_3;
    const double Cabb = 4 * b1_3 + 3 * b1_2 * b0 + 2 * b1 * b0_2 + b0_3;
    const double Kabb = b1_3 + 2 * b1_2 * b0 + 3 * b1 * b0_2 + 4 * b0_3;
    p.P1 += db * C1;
    p.Pa += db * Ca;
    p.Paa += db * Caa;
    p.Paaa += db * Caaa;
    p.Pb += da * Cb;
    p.Pbb += da * Cbb;
    p.Pbbb += da * Cbbb;
    p.Pab += db * (b1 * Cab + b0 * Kab);
    p.Paab += db * (b1 * Caab + b0 * Kaab);
    p.Pabb += da * (a1 * Cabb + a0 * Kabb);
  }
  p.P1 /= 2.0;
  p.Pa /= 6.0;
  p.Paa /= 12.0;
  p.Paaa /= 20.0;
  p.Pb /= -6.0;
  p.Pbb /= -12.0;
  p.Pbbb /= -20.0;
  p.Pab /= 24.0;
  p.Paab /= 60.0;
  p.Pabb /= -60.0;
  return p;
}

std::string format_vec(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

void check_positive(const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    std::ostringstream os;
    os << "must be positive and finite, got " << value;
    throw InputError(name, os.str());
  }
}

Mat3 point_mass_inertia(double mass, const Vec3& d) {
  // Parallel-axis (Steiner) term: m (|d|^2 1 - d d^T).
  return mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
}

}  // namespace

VolumeIntegrals volume_integrals(const ConvexPolyhedron& polyhedron) {
  // Integrate about the vertex mean: the integrals about a far origin cancel catastrophically
  // when moved to the centroid.
  Vec3 reference = Vec3::Zero();
  for (const Vec3& v : polyhedron.vertices()) reference += v;
  reference /= static_cast<double>(polyhedron.vertices().size());

  // T0 = ∫ 1, T1 = ∫ (x, y, z), T2 = ∫ (x², y², z²), TP = ∫ (xy, yz, zx) over the solid.
  double T0 = 0.0;
  Vec3 T1 = Vec3::Zero();
  Vec3 T2 = Vec3::Zero();
  Vec3 TP = Vec3::Zero();
  std::vector<Vec3> loop;
  for (const PolyFace& face : polyhedron.faces()) {
    loop.clear();
    int h = face.half_edge;
    do {
      loop.push_back(polyhedron.tail(h) - reference);
      h = polyhedron.half_edges()[h].next;
    } while (h != face.half_edge);
    const Vec3& n = face.normal_M;
    double mean_offset = 0.0;
    for (const Vec3& q : loop) mean_offset += n.dot(q);
    const double w = -mean_offset / static_cast<double>(loop.size());  // plane n.x + w = 0

    // Project on the coordinate plane most nearly parallel to the face (Mirtich §4): gamma = C
    // is the coordinate of the normal's largest component, (A, B, C) a right-handed cycle.
    const Vec3 abs_n = n.cwiseAbs();
    int C = 2;
    if (abs_n.x() > abs_n.y() && abs_n.x() > abs_n.z()) {
      C = 0;
    } else if (abs_n.y() > abs_n.z()) {
      C = 1;
    }
    const int A = (C + 1) % 3;
    const int B = (A + 1) % 3;
    const ProjectionIntegrals p = projection_integrals(loop, A, B);

    // Face integrals F = ∫_F f dA from the projection integrals, with c = -(n_a a + n_b b + w)/n_c
    // on the face and dA = da db / |n_c| (Mirtich eq. 18-19).
    const double k1 = 1.0 / n[C], k2 = k1 * k1, k3 = k2 * k1, k4 = k3 * k1;
    const double na = n[A], nb = n[B];
    const double Fa = k1 * p.Pa;
    const double Fb = k1 * p.Pb;
    const double Fc = -k2 * (na * p.Pa + nb * p.Pb + w * p.P1);
    const double Faa = k1 * p.Paa;
    const double Fbb = k1 * p.Pbb;
    const double Fcc = k3 * (na * na * p.Paa + 2 * na * nb * p.Pab + nb * nb * p.Pbb +
                             w * (2 * (na * p.Pa + nb * p.Pb) + w * p.P1));
    const double Faaa = k1 * p.Paaa;
    const double Fbbb = k1 * p.Pbbb;
    const double Fccc = -k4 * (na * na * na * p.Paaa + 3 * na * na * nb * p.Paab +
                               3 * na * nb * nb * p.Pabb + nb * nb * nb * p.Pbbb +
                               3 * w * (na * na * p.Paa + 2 * na * nb * p.Pab + nb * nb * p.Pbb) +
                               w * w * (3 * (na * p.Pa + nb * p.Pb) + w * p.P1));
    const double Faab = k1 * p.Paab;
    const double Fbbc = -k2 * (na * p.Pabb + nb * p.Pbbb + w * p.Pbb);
    const double Fcca = k3 * (na * na * p.Paaa + 2 * na * nb * p.Paab + nb * nb * p.Pabb +
                              w * (2 * (na * p.Paa + nb * p.Pab) + w * p.Pa));

    // Divergence theorem (Mirtich eq. 7-12): e.g. ∫_V x dV = ½ ∮ n_x x² dA.
    const double F_of_x[3] = {Fa, Fb, Fc};  // ∫_F a, ∫_F b, ∫_F c
    int index_of[3];
    index_of[A] = 0;
    index_of[B] = 1;
    index_of[C] = 2;
    T0 += n.x() * F_of_x[index_of[0]];
    T1[A] += na * Faa;
    T1[B] += nb * Fbb;
    T1[C] += n[C] * Fcc;
    T2[A] += na * Faaa;
    T2[B] += nb * Fbbb;
    T2[C] += n[C] * Fccc;
    // TP[A] = ∫ a b, TP[B] = ∫ b c, TP[C] = ∫ c a: as (A, B, C) is a cyclic shift of (x, y, z),
    // TP[k] = ∫ x_k x_{k+1} in x, y, z too.
    TP[A] += na * Faab;
    TP[B] += nb * Fbbc;
    TP[C] += n[C] * Fcca;
  }
  T1 /= 2.0;
  T2 /= 3.0;
  TP /= 2.0;

  VolumeIntegrals out;
  out.volume = T0;
  const Vec3 r = T1 / T0;  // centroid relative to the reference point
  out.centroid = reference + r;
  // Second moments about the reference S_ij = ∫ x_i x_j; covariance about the centroid
  // C = S - V r r^T; inertia I = tr(C) 1 - C. Deriving the products of inertia through the
  // covariance keeps their sign right: I_xy = -∫(x - r_x)(y - r_y) = -(TP_x - V r_x r_y).
  Mat3 S;
  S << T2.x(), TP.x(), TP.z(), TP.x(), T2.y(), TP.y(), TP.z(), TP.y(), T2.z();
  const Mat3 covariance = S - T0 * r * r.transpose();
  out.inertia_about_centroid = covariance.trace() * Mat3::Identity() - covariance;
  return out;
}

VolumeIntegrals shape_volume_integrals(const Shape& shape) {
  if (const auto* sphere = std::get_if<Sphere>(&shape)) {
    const double kPi = 3.14159265358979323846;
    const double r = sphere->radius;
    VolumeIntegrals out;
    out.volume = 4.0 / 3.0 * kPi * r * r * r;
    out.inertia_about_centroid = (0.4 * out.volume * r * r) * Mat3::Identity();
    return out;
  }
  if (const auto* poly = std::get_if<ConvexPolyhedron>(&shape)) return volume_integrals(*poly);
  if (const auto* e = std::get_if<Ellipsoid>(&shape)) {
    if (e->com_offset != 0.0) {
      throw InputError("shape",
                       "an ellipsoid whose centre of mass is off its centre: a uniform density "
                       "cannot give its mass properties; give its mass and inertia");
    }
    // V = 4/3 pi abc; I_xx = V (b^2 + c^2) / 5 and cyclically.
    const double kPi = 3.14159265358979323846;
    const Vec3 sq = e->semi_axes_M.cwiseAbs2();
    VolumeIntegrals out;
    out.volume = 4.0 / 3.0 * kPi * e->semi_axes_M.prod();
    out.inertia_about_centroid =
        (out.volume / 5.0 * Vec3(sq.y() + sq.z(), sq.x() + sq.z(), sq.x() + sq.y())).asDiagonal();
    return out;
  }
  if (const auto* c = std::get_if<Cylinder>(&shape)) {
    // V = 2 pi r^2 h; I_zz = V r^2 / 2, I_xx = I_yy = V (r^2 / 4 + h^2 / 3) (length 2h).
    const double kPi = 3.14159265358979323846;
    const double r2 = c->radius * c->radius;
    const double h2 = c->half_height * c->half_height;
    VolumeIntegrals out;
    out.volume = 2.0 * kPi * r2 * c->half_height;
    const double transverse = out.volume * (r2 / 4.0 + h2 / 3.0);
    out.inertia_about_centroid = Vec3(transverse, transverse, out.volume * r2 / 2.0).asDiagonal();
    return out;
  }
  if (const auto* c = std::get_if<Capsule>(&shape)) {
    // A cylinder of length 2h and two hemispheres. Each hemisphere (volume V_s / 2) has moment
    // 2/5 (V_s / 2) r^2 about any axis through the centre of its flat face; its centroid is 3r/8
    // from that face, so about the capsule's centre (parallel axes twice) both together give
    // V_s (2/5 r^2 + h^2 + 3/4 h r) transversally and 2/5 V_s r^2 axially.
    const double kPi = 3.14159265358979323846;
    const double r = c->radius;
    const double h = c->half_length;
    const double v_cyl = 2.0 * kPi * r * r * h;
    const double v_sph = 4.0 / 3.0 * kPi * r * r * r;
    VolumeIntegrals out;
    out.volume = v_cyl + v_sph;
    const double transverse =
        v_cyl * (r * r / 4.0 + h * h / 3.0) + v_sph * (0.4 * r * r + h * h + 0.75 * h * r);
    const double axial = v_cyl * r * r / 2.0 + v_sph * 0.4 * r * r;
    out.inertia_about_centroid = Vec3(transverse, transverse, axial).asDiagonal();
    return out;
  }
  if (std::holds_alternative<LoadedBall>(shape)) {
    throw InputError("shape",
                     "a loaded ball's centre of mass is not its centroid: a uniform density "
                     "cannot give its mass properties; give its mass and inertia");
  }
  if (const auto* compound = std::get_if<Compound>(&shape)) {
    if (compound->parts.empty()) throw InputError("shape", "a compound needs at least one part");
    VolumeIntegrals out;
    std::vector<VolumeIntegrals> parts;
    std::vector<Vec3> centroids;
    for (const CompoundPart& part : compound->parts) {
      PALPABLE_CHECK(part.shape != nullptr, "compound part without a shape");
      parts.push_back(shape_volume_integrals(*part.shape));
      centroids.push_back(part.position_M + part.orientation_M * parts.back().centroid);
      out.volume += parts.back().volume;
      out.centroid += parts.back().volume * centroids.back();
    }
    out.centroid /= out.volume;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const Mat3 R = compound->parts[i].orientation_M.toRotationMatrix();
      out.inertia_about_centroid +=
          R * parts[i].inertia_about_centroid * R.transpose() +
          point_mass_inertia(parts[i].volume, centroids[i] - out.centroid);
    }
    return out;
  }
  throw InputError("shape",
                   "a halfspace is unbounded: it has no finite mass (use a fixed or "
                   "kinematic body)");
}

namespace {

MassProperties from_unit_density(const Shape& shape, double density) {
  const VolumeIntegrals integrals = shape_volume_integrals(shape);
  // The modelling frame's origin must be the centre of mass (DESIGN.md §2).
  const double radius = max_radius(shape);
  if (!(integrals.centroid.norm() <= 1e-9 * radius)) {
    throw InputError("shape", "the centre of mass is at " + format_vec(integrals.centroid) +
                                  ", not at the modelling-frame origin; shift the shape by "
                                  "minus that (from_points does this itself)");
  }
  return mass_properties_from_inertia(density * integrals.volume,
                                      density * integrals.inertia_about_centroid);
}

}  // namespace

MassProperties mass_properties_from_density(const Shape& shape, double density) {
  check_positive("density", density);
  return from_unit_density(shape, density);
}

MassProperties mass_properties_from_mass(const Shape& shape, double mass) {
  check_positive("mass", mass);
  const double volume = shape_volume_integrals(shape).volume;
  return from_unit_density(shape, mass / volume);
}

MassProperties infinite_mass_properties() {
  MassProperties out;
  out.mass = kInfinity;
  out.inv_mass = 0.0;
  out.inertia_M = kInfinity * Mat3::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) out.inertia_M(i, j) = 0.0;
    }
  }
  out.principal_moments = Vec3::Constant(kInfinity);
  out.q_MB = Quat::Identity();
  return out;
}

namespace {

// Flip v so that its largest-magnitude component (the first, on ties) is positive.
Vec3 canonical_sign(const Vec3& v) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(v[i]) > std::abs(v[k])) k = i;
  }
  return v[k] < 0.0 ? Vec3(-v) : v;
}

}  // namespace

MassProperties mass_properties_from_inertia(double mass, const Mat3& inertia_M) {
  check_positive("mass", mass);
  if (!inertia_M.allFinite()) throw InputError("inertia", "must be finite");
  const double scale = inertia_M.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) throw InputError("inertia", "must be positive definite, got zero");
  if ((inertia_M - inertia_M.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) {
    throw InputError("inertia", "must be symmetric");
  }
  const Mat3 I = 0.5 * (inertia_M + inertia_M.transpose());
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(I);
  PALPABLE_CHECK(solver.info() == Eigen::Success, "eigen-decomposition of the inertia failed");
  const Vec3 moments = solver.eigenvalues();  // ascending
  if (!(moments[0] > 0.0)) throw InputError("inertia", "must be positive definite");
  // A rigid body's principal moments obey I1 + I2 >= I3 (the covariance is positive
  // semi-definite); the slack allows the rounding of a flat body's tensor.
  if (moments[0] + moments[1] < moments[2] * (1.0 - 1e-9)) {
    throw InputError("inertia", "breaks the triangle inequality I1 + I2 >= I3 of a rigid body");
  }
  const double equal = kEqualMomentTolerance * moments[2];
  const Mat3 V = solver.eigenvectors();
  Mat3 R;  // columns: the principal axes in M
  const bool low_pair = moments[1] - moments[0] <= equal;
  const bool high_pair = moments[2] - moments[1] <= equal;
  if (low_pair && high_pair) {
    R = Mat3::Identity();
  } else if (low_pair || high_pair) {
    const int unique = low_pair ? 2 : 0;
    const Vec3 a = canonical_sign(V.col(unique));
    int least = 0;
    for (int i = 1; i < 3; ++i) {
      if (std::abs(a[i]) < std::abs(a[least])) least = i;
    }
    const Vec3 b = (Vec3::Unit(least) - a[least] * a).normalized();
    R.col(unique) = a;
    R.col((unique + 1) % 3) = b;
    R.col((unique + 2) % 3) = a.cross(b);
  } else {
    R.col(0) = canonical_sign(V.col(0));
    R.col(1) = canonical_sign(V.col(1));
    R.col(2) = R.col(0).cross(R.col(1));
  }
  MassProperties out;
  out.mass = mass;
  out.inv_mass = 1.0 / mass;
  out.inertia_M = I;
  out.principal_moments = moments;
  out.q_MB = Quat(R).normalized();
  return out;
}

}  // namespace palpable
