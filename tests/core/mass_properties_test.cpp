// Mass properties against closed forms: box, off-centre tetrahedra (products of inertia),
// regular prisms (exact, and converging to the cylinder), hulls of sphere points (converging to the
// ball), the sphere; recentring, principal frames, compounds (parallel-axis theorem), bad input.
// Run with -s to see the measured errors (CAPTURE).
#include "core/mass_properties.hpp"
#include "core_test_support.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <functional>
#include <iomanip>
#include <limits>
#include <random>

using namespace palpable;

namespace {

using palpable::test::input_error;

constexpr double kPi = 3.14159265358979323846;

double relative_error(const Mat3& a, const Mat3& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

// Independent closed form for a tetrahedron (v0..v3): the second-moment (covariance) matrix
// about the origin is C = (V/20) (sum v_i v_i^T + (sum v_i)(sum v_i)^T) (e.g. Tonon 2004).
struct TetIntegrals {
  double volume;
  Vec3 first;   // ∫ x dV
  Mat3 second;  // ∫ x x^T dV
};

TetIntegrals tetrahedron(const Vec3& v0, const Vec3& v1, const Vec3& v2, const Vec3& v3) {
  const double signed6 = (v1 - v0).dot((v2 - v0).cross(v3 - v0));
  const double V = signed6 / 6.0;
  const Vec3 sum = v0 + v1 + v2 + v3;
  Mat3 outer = sum * sum.transpose();
  for (const Vec3* v : {&v0, &v1, &v2, &v3}) outer += (*v) * v->transpose();
  return {V, V * sum / 4.0, V / 20.0 * outer};
}

// Central inertia from the integrals of a solid.
Mat3 central_inertia(double V, const Vec3& first, const Mat3& second) {
  const Vec3 c = first / V;
  const Mat3 C = second - V * c * c.transpose();
  return C.trace() * Mat3::Identity() - C;
}

// The oracle for any polyhedron: a fan of tetrahedra from a point, summed.
VolumeIntegrals tetrahedral_decomposition(const ConvexPolyhedron& p) {
  const Vec3 apex = p.vertices()[0];
  double V = 0.0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();
  for (const PolyFace& f : p.faces()) {
    const int h0 = f.half_edge;
    for (int h = p.half_edges()[h0].next; p.half_edges()[h].next != h0;
         h = p.half_edges()[h].next) {
      const TetIntegrals t = tetrahedron(apex, p.tail(h0), p.tail(h), p.head(h));
      V += t.volume;
      first += t.first;
      second += t.second;
    }
  }
  return {V, first / V, central_inertia(V, first, second)};
}

Quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Quat(g(rng), g(rng), g(rng), g(rng)).normalized();
}

// Errors printed in scientific notation (CAPTURE's fixed notation shows 1e-16 as 0.0).
#define CAPTURE_ERROR(x) INFO(#x " = " << std::scientific << std::setprecision(3) << (x))

// Exact regular n-gon prism (circumradius R, half-height h), unit density: area
// A = n R^2 sin(t) / 2, polar moment J = n R^4 sin(t) (2 + cos(t)) / 12 with t = 2 pi / n
// (a fan of n triangles, each ∫|x|² = A_t R² (2 + cos t) / 6), in-plane moments J / 2 each.
struct PrismExact {
  double volume, axial, transverse;
};
PrismExact prism_exact(double R, double h, int n) {
  const double t = 2.0 * kPi / n;
  const double A = n * R * R * std::sin(t) / 2.0;
  const double J = n * std::pow(R, 4) * std::sin(t) * (2.0 + std::cos(t)) / 12.0;
  const double H = 2.0 * h;
  return {A * H, J * H, J / 2.0 * H + A * H * H * H / 12.0};
}

}  // namespace

TEST_CASE("Box: volume and inertia equal the closed form m (b^2 + c^2) / 3 (half extents)") {
  const Vec3 half(0.3, 0.5, 0.7);
  const auto box = ConvexPolyhedron::box(half);
  const VolumeIntegrals vi = volume_integrals(box);
  const double V = 8.0 * half.prod();
  const Vec3 h2 = half.cwiseProduct(half);
  const Mat3 exact =
      (V / 3.0 * Vec3(h2.y() + h2.z(), h2.x() + h2.z(), h2.x() + h2.y())).asDiagonal();
  const double volume_error = std::abs(vi.volume - V) / V;
  const double inertia_error = relative_error(vi.inertia_about_centroid, exact);
  CAPTURE_ERROR(volume_error);
  CAPTURE_ERROR(inertia_error);
  CHECK(volume_error < 1e-15);
  CHECK(inertia_error < 1e-15);
  CHECK(vi.centroid.norm() < 1e-16);
  const MassProperties mp = mass_properties_from_density(box, 2.0);
  CHECK(mp.mass == Approx(2.0 * V).epsilon(1e-15));
  CHECK(relative_error(mp.inertia_M, 2.0 * exact) < 1e-15);
  // Distinct moments, ascending: smallest about the longest axis (z), largest about x.
  CHECK(mp.principal_moments[0] == Approx(2.0 * exact(2, 2)).epsilon(1e-15));
  CHECK(mp.principal_moments[2] == Approx(2.0 * exact(0, 0)).epsilon(1e-15));
  const Mat3 R = mp.q_MB.toRotationMatrix();
  CHECK(std::abs(R.col(0).dot(Vec3::UnitZ())) == Approx(1.0).epsilon(1e-14));
  CHECK(std::abs(R.col(2).dot(Vec3::UnitX())) == Approx(1.0).epsilon(1e-14));
  CHECK(R.determinant() == Approx(1.0).epsilon(1e-14));
}

TEST_CASE("Off-centre tetrahedra: volume, centroid and full inertia incl. products") {
  const std::uint64_t seed = 1996;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    CAPTURE(seed, trial);
    const Vec3 shift(3.0 * u(rng), 3.0 * u(rng), 3.0 * u(rng));
    std::vector<Vec3> v = {shift, shift + Vec3(0.5 + std::abs(u(rng)), 0, 0),
                           shift + Vec3(0, 0.5 + std::abs(u(rng)), 0),
                           shift + Vec3(0, 0, 0.5 + std::abs(u(rng)))};
    if (trial % 2 == 1) {  // a general (skew) tetrahedron, rotated
      const Quat q = random_rotation(rng);
      for (Vec3& p : v) p = shift + q * (p - shift + Vec3(0.3 * u(rng), 0.3 * u(rng), 0.0));
    }
    // The closed form evaluated about the vertex mean, so that the oracle itself does not lose
    // digits to the far origin.
    const Vec3 mean = (v[0] + v[1] + v[2] + v[3]) / 4.0;
    TetIntegrals t = tetrahedron(v[0] - mean, v[1] - mean, v[2] - mean, v[3] - mean);
    t.first += t.volume * mean;
    const double sign = t.volume > 0 ? 1.0 : -1.0;
    const double V = sign * t.volume;
    const Mat3 exact = sign * central_inertia(t.volume, t.first - t.volume * mean, t.second);
    // Built without recentring, so the integrals are about the given (far) origin.
    const std::vector<std::vector<int>> faces =
        sign > 0 ? std::vector<std::vector<int>>{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}
                 : std::vector<std::vector<int>>{{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    const auto tet = ConvexPolyhedron::from_faces(v, faces, 1e-12);
    const VolumeIntegrals vi = volume_integrals(tet);
    const double error = relative_error(vi.inertia_about_centroid, exact);
    worst = std::max(worst, error);
    CAPTURE_ERROR(error);
    CAPTURE(exact, vi.inertia_about_centroid);
    CHECK(std::abs(vi.volume - V) / V < 1e-14);
    CHECK((vi.centroid - t.first / t.volume).norm() < 1e-14);
    CHECK(error < 1e-14);
    // Products of inertia individually (where a transcription error would show).
    CHECK(std::abs(vi.inertia_about_centroid(0, 1) - exact(0, 1)) < 1e-14 * exact.norm());
    CHECK(std::abs(vi.inertia_about_centroid(1, 2) - exact(1, 2)) < 1e-14 * exact.norm());
    CHECK(std::abs(vi.inertia_about_centroid(0, 2) - exact(0, 2)) < 1e-14 * exact.norm());
    // from_points recentres on the centroid and gives the same central inertia.
    const auto hull = ConvexPolyhedron::from_points(v);
    CHECK((hull.com_shift_M() - t.first / t.volume).norm() < 1e-14);
    const MassProperties mp = mass_properties_from_density(hull, 1.0);
    CHECK(relative_error(mp.inertia_M, exact) < 1e-14);
  }
  CAPTURE_ERROR(worst);
  CHECK(worst < 1e-14);
}

TEST_CASE("The right tetrahedron has the textbook products of inertia") {
  // Vertices (0,0,0), (a,0,0), (0,b,0), (0,0,c): about the centroid I_xy = m a b / 80 (and
  // cyclic), I_xx = 3 m (b^2 + c^2) / 80 (Tonon 2004 specialised; products counted as -∫xy).
  const double a = 1.0, b = 2.0, c = 3.0;
  const auto tet =
      ConvexPolyhedron::from_faces({Vec3(0, 0, 0), Vec3(a, 0, 0), Vec3(0, b, 0), Vec3(0, 0, c)},
                                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, 1e-12);
  const VolumeIntegrals vi = volume_integrals(tet);
  const double m = a * b * c / 6.0;
  Mat3 exact;
  exact << 3 * m * (b * b + c * c) / 80, m * a * b / 80, m * a * c / 80,  //
      m * a * b / 80, 3 * m * (a * a + c * c) / 80, m * b * c / 80,       //
      m * a * c / 80, m * b * c / 80, 3 * m * (a * a + b * b) / 80;
  const double error = relative_error(vi.inertia_about_centroid, exact);
  CAPTURE_ERROR(error);
  CAPTURE(vi.inertia_about_centroid);
  CHECK(error < 1e-15);
  CHECK((vi.centroid - Vec3(a, b, c) / 4.0).norm() < 1e-15);
}

TEST_CASE("Random hulls agree with a tetrahedral decomposition") {
  const std::uint64_t seed = 5;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 30; ++trial) {
    CAPTURE(seed, trial);
    std::vector<Vec3> points;
    const Vec3 offset(10 * u(rng), 10 * u(rng), 10 * u(rng));
    for (int i = 0; i < 8 + 10 * trial; ++i) {
      points.push_back(offset + Vec3(u(rng), 0.5 * u(rng), 2.0 * u(rng)));
    }
    // A few merged polygon faces too: clip the cloud to a box.
    if (trial % 3 == 0) {
      for (Vec3& p : points) p = offset + (p - offset).cwiseMax(Vec3(-0.8, -0.4, -1.5));
    }
    const auto p = ConvexPolyhedron::from_points(points);
    const VolumeIntegrals vi = volume_integrals(p);
    const VolumeIntegrals oracle = tetrahedral_decomposition(p);
    const double error = relative_error(vi.inertia_about_centroid, oracle.inertia_about_centroid);
    worst = std::max(worst, error);
    CAPTURE_ERROR(error);
    CHECK(std::abs(vi.volume - oracle.volume) / oracle.volume < 1e-13);
    CHECK(vi.centroid.norm() < 1e-13);  // recentred by from_points
    CHECK((vi.centroid - oracle.centroid).norm() < 1e-13);
    CHECK(error < 1e-12);
  }
  CAPTURE_ERROR(worst);
  CHECK(worst < 1e-12);
}

TEST_CASE("Regular prisms: exact polygon-prism form, and convergence to the cylinder") {
  const double R = 0.4, h = 0.15;
  const double cyl_volume = kPi * R * R * 2 * h;
  const double cyl_axial = cyl_volume * R * R / 2.0;                          // m r^2 / 2
  const double cyl_transverse = cyl_volume * (3 * R * R + 4 * h * h) / 12.0;  // m (3r^2+4h^2)/12
  double previous_error = kInfinity;
  for (int n : {3, 4, 6, 12, 24, 48, 96, 192, 384}) {
    const auto prism = ConvexPolyhedron::prism(R, h, n);
    const VolumeIntegrals vi = volume_integrals(prism);
    const PrismExact exact = prism_exact(R, h, n);
    const Mat3 I = vi.inertia_about_centroid;
    const double exact_error = std::max(
        {std::abs(vi.volume - exact.volume) / exact.volume,
         std::abs(I(2, 2) - exact.axial) / exact.axial,
         std::abs(I(0, 0) - exact.transverse) / exact.transverse,
         std::abs(I(1, 1) - exact.transverse) / exact.transverse,
         std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))}) / exact.axial});
    // Against the cylinder the error is the polygon's: 1 - n sin(2 pi/n) / (2 pi) ~ (2 pi^2/3)/n^2
    // for the area.
    const double area_error = 1.0 - n * std::sin(2 * kPi / n) / (2 * kPi);
    const double cylinder_error = std::abs(I(2, 2) - cyl_axial) / cyl_axial;
    const double transverse_error = std::abs(I(0, 0) - cyl_transverse) / cyl_transverse;
    CAPTURE(n);
    CAPTURE_ERROR(exact_error);
    CAPTURE_ERROR(area_error);
    CAPTURE_ERROR(cylinder_error);
    CAPTURE_ERROR(transverse_error);
    CHECK(exact_error < 1e-14);
    // The axial moment's error is bounded by the polygon's area deficit (it is 1 - A J / (pi R^4 /
    // 2) and J's deficit is at most twice A's), and both shrink like 1/n^2.
    CHECK(cylinder_error <= 2.0 * area_error + 1e-15);
    CHECK(transverse_error <= 2.0 * area_error + 1e-15);
    CHECK(cylinder_error < previous_error);
    if (n >= 24) CHECK(cylinder_error * n * n == Approx(4 * kPi * kPi / 3).epsilon(0.02));
    previous_error = cylinder_error;
  }
  CHECK(previous_error < 1e-4);
}

TEST_CASE("Hulls of points on a sphere converge to the ball's 2/5 m r^2") {
  const std::uint64_t seed = 77;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  double previous = kInfinity;
  for (int n : {100, 1000, 10000}) {
    std::vector<Vec3> points;
    for (int i = 0; i < n; ++i) points.push_back(Vec3(g(rng), g(rng), g(rng)).normalized());
    const auto hull = ConvexPolyhedron::from_points(points);
    const MassProperties mp = mass_properties_from_mass(hull, 1.0);
    const double ratio = mp.principal_moments.mean();  // / (m r^2) with m = r = 1
    const double error = std::abs(ratio - 0.4) / 0.4;
    const double anisotropy = (mp.principal_moments[2] - mp.principal_moments[0]) / 0.4;
    CAPTURE(seed, n, ratio);
    CAPTURE_ERROR(error);
    CAPTURE_ERROR(anisotropy);
    CHECK(error < previous);
    CHECK(mp.mass == 1.0);
    previous = error;
  }
  CHECK(previous < 2e-3);
}

TEST_CASE("Sphere: closed form") {
  const MassProperties mp = mass_properties_from_density(make_sphere(0.25), 1000.0);
  const double m = 1000.0 * 4.0 / 3.0 * kPi * std::pow(0.25, 3);
  CHECK(mp.mass == Approx(m).epsilon(1e-15));
  CHECK(mp.inv_mass == Approx(1.0 / m).epsilon(1e-15));
  for (int i = 0; i < 3; ++i) {
    CHECK(mp.principal_moments[i] == Approx(0.4 * m * 0.0625).epsilon(1e-15));
  }
  CHECK(mp.q_MB.angularDistance(Quat::Identity()) == 0.0);
  const MassProperties by_mass = mass_properties_from_mass(make_sphere(0.25), 3.0);
  CHECK(by_mass.mass == Approx(3.0).epsilon(1e-15));
  CHECK(by_mass.principal_moments[0] == Approx(0.4 * 3.0 * 0.0625).epsilon(1e-15));
}

TEST_CASE("Rotated box: same principal moments and q_MB maps principal axes onto the box axes") {
  const std::uint64_t seed = 11;
  std::mt19937_64 rng(seed);
  const Vec3 half(0.3, 0.5, 0.7);
  const MassProperties reference = mass_properties_from_density(ConvexPolyhedron::box(half), 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    CAPTURE(seed, trial);
    const Quat q = random_rotation(rng);
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i) {
      corners.push_back(Vec3(1, 2, 3) + q * Vec3((i & 1) ? half.x() : -half.x(),
                                                 (i & 2) ? half.y() : -half.y(),
                                                 (i & 4) ? half.z() : -half.z()));
    }
    const MassProperties mp =
        mass_properties_from_density(ConvexPolyhedron::from_points(corners), 1.0);
    const double error = (mp.principal_moments - reference.principal_moments).norm() /
                         reference.principal_moments.norm();
    CAPTURE_ERROR(error);
    CHECK(error < 1e-14);
    const Mat3 R_MB = mp.q_MB.toRotationMatrix();
    CHECK(R_MB.determinant() == Approx(1.0).epsilon(1e-14));
    // Ascending moments: about the box's z (longest), y, then x axis.
    CHECK(std::abs(R_MB.col(0).dot(q * Vec3::UnitZ())) == Approx(1.0).epsilon(1e-13));
    CHECK(std::abs(R_MB.col(1).dot(q * Vec3::UnitY())) == Approx(1.0).epsilon(1e-13));
    CHECK(std::abs(R_MB.col(2).dot(q * Vec3::UnitX())) == Approx(1.0).epsilon(1e-13));
    // I_M = R diag(I_B) R^T.
    const Mat3 rebuilt = R_MB * mp.principal_moments.asDiagonal() * R_MB.transpose();
    CHECK(relative_error(rebuilt, mp.inertia_M) < 1e-14);
    CHECK(relative_error(mp.inv_inertia_M() * mp.inertia_M, Mat3::Identity()) < 1e-14);
  }
}

TEST_CASE("Repeated moments get a deterministic principal frame") {
  // Cube: all moments equal, q_MB = identity.
  const MassProperties cube =
      mass_properties_from_density(ConvexPolyhedron::box(Vec3(1, 1, 1)), 1.0);
  CHECK(cube.q_MB.angularDistance(Quat::Identity()) == 0.0);
  // Prism along z: the axis is unique; the rule then gives the identity as well.
  for (int n : {3, 5, 8, 33}) {
    CAPTURE(n);
    const MassProperties p =
        mass_properties_from_density(ConvexPolyhedron::prism(0.5, 0.1, n), 1.0);
    CHECK(p.q_MB.angularDistance(Quat::Identity()) < 1e-12);
    CHECK(p.principal_moments[2] == Approx(prism_exact(0.5, 0.1, n).axial).epsilon(1e-14));
  }
  // A rotated cube from points: still the identity (equal moments within tolerance).
  const Quat q(Eigen::AngleAxisd(0.3, Vec3(1, 1, 0).normalized()));
  std::vector<Vec3> corners;
  for (int i = 0; i < 8; ++i) {
    corners.push_back(q * Vec3((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1));
  }
  const MassProperties rotated_cube =
      mass_properties_from_density(ConvexPolyhedron::from_points(corners), 1.0);
  CHECK(rotated_cube.q_MB.angularDistance(Quat::Identity()) == 0.0);
  // A tall rotated prism from points: the unique (largest... here smallest) axis is q * z.
  std::vector<Vec3> points;
  for (int k = 0; k < 7; ++k) {
    const double a = 2 * kPi * k / 7;
    points.push_back(q * Vec3(0.2 * std::cos(a), 0.2 * std::sin(a), -1.0));
    points.push_back(q * Vec3(0.2 * std::cos(a), 0.2 * std::sin(a), 1.0));
  }
  const MassProperties tall =
      mass_properties_from_density(ConvexPolyhedron::from_points(points), 1.0);
  const Mat3 R = tall.q_MB.toRotationMatrix();
  CHECK(std::abs(R.col(0).dot(q * Vec3::UnitZ())) == Approx(1.0).epsilon(1e-12));
  CHECK(R.determinant() == Approx(1.0).epsilon(1e-14));
  // Same input, same frame.
  const MassProperties again =
      mass_properties_from_density(ConvexPolyhedron::from_points(points), 1.0);
  CHECK(again.q_MB.coeffs() == tall.q_MB.coeffs());
}

TEST_CASE("Compound: parts rotated and shifted sum by the parallel-axis theorem") {
  // Two boxes stacked along z, the lower one given rotated by 90 degrees about z, fill the box of
  // half extents (1, 2, 1) exactly; the compound's inertia must be that box's.
  auto upper = std::make_shared<const Shape>(ConvexPolyhedron::box(Vec3(1, 2, 0.25)));
  auto lower = std::make_shared<const Shape>(ConvexPolyhedron::box(Vec3(2, 1, 0.75)));
  const Quat quarter(Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()));
  const Shape compound = make_compound(
      {{upper, Vec3(0, 0, 0.75), Quat::Identity()}, {lower, Vec3(0, 0, -0.25), quarter}});
  const MassProperties whole =
      mass_properties_from_density(ConvexPolyhedron::box(Vec3(1, 2, 1)), 3.0);
  const MassProperties sum = mass_properties_from_density(compound, 3.0);
  const double error = relative_error(sum.inertia_M, whole.inertia_M);
  CAPTURE_ERROR(error);
  CHECK(sum.mass == Approx(whole.mass).epsilon(1e-15));
  CHECK(error < 1e-15);
  // Unequal spheres balanced about the origin: m1 a = m2 b; I_xx = sum 2/5 m r^2,
  // I_yy = I_zz = that + m1 a^2 + m2 b^2.
  const double r1 = 0.3, r2 = 0.5, a = 2.0;
  const double m1 = std::pow(r1, 3), m2 = std::pow(r2, 3);  // proportional to the masses
  const double b = m1 * a / m2;
  const Shape spheres = make_compound(
      {{std::make_shared<const Shape>(make_sphere(r1)), Vec3(a, 0, 0), Quat::Identity()},
       {std::make_shared<const Shape>(make_sphere(r2)), Vec3(-b, 0, 0), Quat::Identity()}});
  const double rho = 1.0;
  const double M1 = rho * 4.0 / 3.0 * kPi * m1, M2 = rho * 4.0 / 3.0 * kPi * m2;
  const double spin = 0.4 * (M1 * r1 * r1 + M2 * r2 * r2);
  const MassProperties two = mass_properties_from_density(spheres, rho);
  CHECK(two.inertia_M(0, 0) == Approx(spin).epsilon(1e-14));
  CHECK(two.inertia_M(1, 1) == Approx(spin + M1 * a * a + M2 * b * b).epsilon(1e-14));
  CHECK(two.inertia_M(2, 2) == Approx(spin + M1 * a * a + M2 * b * b).epsilon(1e-14));
  // A compound whose centre of mass is off the origin is refused, with the offset.
  const Shape off = make_compound(
      {{std::make_shared<const Shape>(make_sphere(r1)), Vec3(a, 0, 0), Quat::Identity()}});
  CHECK_THAT(input_error([&] { mass_properties_from_density(off, 1.0); }),
             Catch::Matchers::Contains("centre of mass"));
}

TEST_CASE("Mass properties reject bad input") {
  using Catch::Matchers::Contains;
  const Shape box = ConvexPolyhedron::box(Vec3(1, 1, 1));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THAT(input_error([&] { mass_properties_from_density(box, 0.0); }), Contains("density"));
  CHECK_THAT(input_error([&] { mass_properties_from_density(box, -1.0); }), Contains("density"));
  CHECK_THAT(input_error([&] { mass_properties_from_density(box, nan); }), Contains("density"));
  CHECK_THAT(input_error([&] { mass_properties_from_mass(box, kInfinity); }), Contains("mass"));
  CHECK_THAT(
      input_error([&] { mass_properties_from_density(make_halfspace(Vec3::UnitZ(), 0.0), 1.0); }),
      Contains("unbounded"));
  Mat3 skew_inertia = Mat3::Identity();
  skew_inertia(0, 1) = 0.1;
  CHECK_THAT(input_error([&] { mass_properties_from_inertia(1.0, skew_inertia); }),
             Contains("symmetric"));
  CHECK_THAT(input_error([&] { mass_properties_from_inertia(1.0, Vec3(1, -1, 1).asDiagonal()); }),
             Contains("positive definite"));
  CHECK_THAT(input_error([&] { mass_properties_from_inertia(1.0, Vec3(1, 1, 3).asDiagonal()); }),
             Contains("triangle"));
  CHECK_THAT(input_error([&] { mass_properties_from_inertia(0.0, Mat3::Identity()); }),
             Contains("mass"));
  // A polyhedron not centred on its centre of mass (from_faces does not recentre).
  const Shape tet =
      ConvexPolyhedron::from_faces({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)},
                                   {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, 1e-12);
  CHECK_THAT(input_error([&] { mass_properties_from_density(tet, 1.0); }),
             Contains("centre of mass"));
  const MassProperties fixed = infinite_mass_properties();
  CHECK(fixed.is_infinite());
  CHECK(fixed.mass == kInfinity);
  CHECK(fixed.inv_inertia_M() == Mat3::Zero());
}

namespace {

// Points on the surface of a smooth shape on a latitude-longitude grid: `rings` latitudes of
// `per_ring` points each on the unit sphere, mapped by `map` (a point of the unit sphere to the
// shape's surface). Their hull is inscribed in the (convex) shape.
std::vector<Vec3> surface_grid(int rings, int per_ring,
                               const std::function<Vec3(const Vec3&)>& map) {
  std::vector<Vec3> points{map(Vec3::UnitZ()), map(-Vec3::UnitZ())};
  for (int i = 1; i < rings; ++i) {
    const double theta = kPi * i / rings;
    for (int j = 0; j < per_ring; ++j) {
      const double phi = 2.0 * kPi * (j + 0.5 * (i % 2)) / per_ring;
      points.push_back(map(
          Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta))));
    }
  }
  return points;
}

// The closed form against the hull of a dense grid of surface points. The hull is inscribed, so
// its volume and its moments about the (common, by symmetry) centre are below the closed form's,
// and they converge to it as the grid refines: the closed form must lie in [hull, hull (1 + gap)].
void check_against_inscribed_hull(const Shape& shape, const std::vector<Vec3>& points, double gap) {
  const VolumeIntegrals exact = shape_volume_integrals(shape);
  const VolumeIntegrals hull = volume_integrals(ConvexPolyhedron::from_points(points, 0.0));
  CAPTURE(exact.volume, hull.volume);
  CHECK(exact.centroid.norm() == 0.0);
  CHECK(hull.volume <= exact.volume);
  CHECK(exact.volume <= hull.volume * (1.0 + gap));
  for (int i = 0; i < 3; ++i) {
    CAPTURE(i, exact.inertia_about_centroid(i, i), hull.inertia_about_centroid(i, i));
    CHECK(hull.inertia_about_centroid(i, i) <= exact.inertia_about_centroid(i, i));
    CHECK(exact.inertia_about_centroid(i, i) <= hull.inertia_about_centroid(i, i) * (1.0 + gap));
    for (int j = 0; j < 3; ++j) {
      if (j != i) CHECK(exact.inertia_about_centroid(i, j) == 0.0);
    }
  }
}

}  // namespace

TEST_CASE("Smooth shapes: closed-form mass properties against inscribed hulls") {
  // A 120 x 240 grid: the hull's deficit is about (pi / 120)^2 / 2 ~ 3.4e-4 of the volume.
  const int rings = 120, per_ring = 240;
  const double gap = 1.5e-3;
  SECTION("ellipsoid") {
    const Vec3 a(0.3, 0.5, 0.7);
    const Shape e = make_ellipsoid(a);
    check_against_inscribed_hull(
        e, surface_grid(rings, per_ring, [&](const Vec3& u) { return Vec3(a.cwiseProduct(u)); }),
        gap);
    // The sphere as an ellipsoid with equal semi-axes: to rounding.
    const VolumeIntegrals round =
        shape_volume_integrals(Shape(make_ellipsoid(Vec3::Constant(0.4))));
    const VolumeIntegrals sphere = shape_volume_integrals(Shape(make_sphere(0.4)));
    CHECK(round.volume == Approx(sphere.volume).epsilon(1e-15));
    CHECK(relative_error(round.inertia_about_centroid, sphere.inertia_about_centroid) < 1e-15);
  }
  SECTION("cylinder") {
    const double r = 0.4, h = 0.15;
    std::vector<Vec3> points;
    for (int j = 0; j < 4 * per_ring; ++j) {
      const double phi = 2.0 * kPi * j / (4 * per_ring);
      points.emplace_back(r * std::cos(phi), r * std::sin(phi), h);
      points.emplace_back(r * std::cos(phi), r * std::sin(phi), -h);
    }
    check_against_inscribed_hull(Shape(make_cylinder(r, h)), points, 1e-4);
    // And the exact regular prism of 4096 sides: with t = 2 pi / n its volume falls short of the
    // cylinder's by t^2/6 and its axial moment by t^2/3 (series of n sin t (2 + cos t) / (6 pi)),
    // to O(t^4); the transverse moment mixes the two.
    const int n = 4096;
    const double t = 2 * kPi / n;
    const PrismExact prism = prism_exact(r, h, n);
    const VolumeIntegrals c = shape_volume_integrals(Shape(make_cylinder(r, h)));
    CHECK((c.volume - prism.volume) / c.volume / (t * t / 6) == Approx(1.0).epsilon(1e-5));
    CHECK((c.inertia_about_centroid(2, 2) - prism.axial) / c.inertia_about_centroid(2, 2) /
              (t * t / 3) ==
          Approx(1.0).epsilon(1e-5));
    const double transverse_deficit =
        (c.inertia_about_centroid(0, 0) - prism.transverse) / c.inertia_about_centroid(0, 0);
    CHECK(transverse_deficit >= t * t / 6 * (1 - 1e-5));
    CHECK(transverse_deficit <= t * t / 3 * (1 + 1e-5));
  }
  SECTION("capsule") {
    const double r = 0.2, h = 0.35;
    // Each hemisphere's grid, shifted to its end of the segment; the equator rings bound the
    // cylinder.
    auto map = [&](const Vec3& u) { return Vec3(r * u + Vec3(0, 0, u.z() >= 0 ? h : -h)); };
    std::vector<Vec3> points = surface_grid(rings, per_ring, map);
    for (int j = 0; j < per_ring; ++j) {
      const double phi = 2.0 * kPi * j / per_ring;
      points.emplace_back(r * std::cos(phi), r * std::sin(phi), h);
      points.emplace_back(r * std::cos(phi), r * std::sin(phi), -h);
    }
    check_against_inscribed_hull(Shape(make_capsule(r, h)), points, gap);
  }
  SECTION("a loaded ball has no uniform-density mass properties") {
    const Shape ball = make_loaded_ball(0.1, 0.02);
    CHECK_THAT(input_error([&] { mass_properties_from_density(ball, 1000.0); }),
               Catch::Contains("loaded ball"));
    CHECK_THAT(input_error([&] { mass_properties_from_mass(ball, 1.0); }),
               Catch::Contains("loaded ball"));
    // Given explicitly (the scene's "mass" and "inertia"), it is an ordinary rigid body.
    const MassProperties m =
        mass_properties_from_inertia(1.0, Vec3(0.004, 0.004, 0.0035).asDiagonal());
    CHECK(m.principal_moments.x() == 0.0035);
  }
  SECTION("nor has an ellipsoid whose centre of mass is off its centre") {
    const Shape e = make_ellipsoid(Vec3(0.2, 0.03, 0.02), -0.01);
    CHECK_THAT(input_error([&] { mass_properties_from_density(e, 1000.0); }),
               Catch::Contains("centre of mass is off its centre"));
    CHECK_THAT(input_error([&] { mass_properties_from_mass(e, 1.0); }),
               Catch::Contains("centre of mass is off its centre"));
  }
}
