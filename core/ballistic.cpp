#include "core/ballistic.hpp"

#include "core/check.hpp"

#include <boost/math/special_functions/ellint_rf.hpp>
#include <boost/math/special_functions/ellint_rj.hpp>

#include <algorithm>
#include <cmath>

namespace palpable {
namespace {

// The asymmetric rotation is evaluated in extended precision (x87 long double, 64-bit mantissa)
// and rounded to double once at the end: a chained advance then adds little more than the
// rounding of the stored state, so 10,000 small advances stay close to one large one.
using Real = long double;
using Vec3L = Eigen::Matrix<Real, 3, 1>;
using Mat3L = Eigen::Matrix<Real, 3, 3>;
using QuatL = Eigen::Quaternion<Real>;

// Rotation of v by q / |q|: (q v q*) / |q|^2 written out, so that a quaternion normalised only to
// rounding (|q|^2 = 1 + O(eps)) neither scales v nor mixes in O(eps) of v itself (Eigen's q * v
// assumes |q| = 1 exactly). In double, the rounding of a rotated vector's length is measurably
// biased; accumulated over thousands of chained advances that bias drifts T and |L|, so rotations
// of angular velocities are done in extended precision.
template <typename S>
Eigen::Matrix<S, 3, 1> rotate(const Eigen::Quaternion<S>& q, const Eigen::Matrix<S, 3, 1>& v) {
  const Eigen::Matrix<S, 3, 1> u = q.vec();
  const S w = q.w();
  const S uu = u.squaredNorm();
  return ((w * w - uu) * v + (S(2) * u.dot(v)) * u + (S(2) * w) * u.cross(v)) / (w * w + uu);
}

// Unit quaternion of the rotation by the rotation vector `r` (angle |r| about r / |r|).
template <typename S>
Eigen::Quaternion<S> rotation_quat(const Eigen::Matrix<S, 3, 1>& r) {
  const S angle = r.norm();
  if (angle == S(0)) return Eigen::Quaternion<S>::Identity();
  const Eigen::Matrix<S, 3, 1> axis = r / angle;
  const S s = std::sin(S(0.5) * angle);
  return Eigen::Quaternion<S>(std::cos(S(0.5) * angle), s * axis.x(), s * axis.y(), s * axis.z());
}

// Jacobi elliptic functions sn, cn, dn for the parameter m = k^2, given k^2 and its complement
// k'^2 = 1 - k^2 separately (both computed without cancellation by the caller), by the descending
// Landen / arithmetic-geometric-mean scheme (Abramowitz & Stegun 16.4). Boost's jacobi_elliptic
// forms k' from k, which loses all precision near the separatrix (k -> 1). The AGM of (1, k')
// also gives the complete integral K = pi / (2 AGM) (A&S 17.6). Evaluated in double: measured,
// extended precision here changes chained advances by less than their rounding noise.
struct SnCnDn {
  Real sn, cn, dn;
};
class Jacobi {
 public:
  Jacobi(Real k2, Real kp2) : k2_(k2), kp2_(kp2) {
    a_[0] = 1.0;
    if (kp2 == 0) return;  // the separatrix: hyperbolic functions, no AGM
    c_[0] = std::sqrt(static_cast<double>(k2));
    double b = std::sqrt(static_cast<double>(kp2));
    while (std::fabs(c_[levels_]) > 4.0 * std::numeric_limits<double>::epsilon() * a_[levels_] &&
           levels_ < kMaxLevels) {
      a_[levels_ + 1] = 0.5 * (a_[levels_] + b);
      c_[levels_ + 1] = 0.5 * (a_[levels_] - b);
      b = std::sqrt(a_[levels_] * b);
      ++levels_;
    }
  }
  // K(k); requires k'^2 > 0.
  Real complete_K() const { return kHalfPi / a_[levels_]; }
  SnCnDn operator()(Real u) const {
    if (kp2_ == 0) {
      const Real sech = 1 / std::cosh(u);
      return {std::tanh(u), sech, sech};
    }
    // Near the poles u = +-K (sn = +-1) the amplitude below is found to an absolute 1e-16, and cn
    // = cos(amplitude) only to that, while cn there is as small as k' or smaller: near the
    // separatrix (k' << 1) its relative error 1e-16 / k' went into the phase and the precession
    // angle (a box turning about its intermediate axis, 1e-20 rad/s about the others, advanced
    // by 1e-6 s through 37 degrees). There the functions come from a point half a period away,
    // by the shift u = +-K + v (DLMF 22.4.3): sn = +-cd(v), cn = -+k' sd(v), dn = k' nd(v).
    const Real K = complete_K();
    if (std::fabs(u) > K / 2 && std::fabs(u) <= 3 * K / 2) {
      const Real s = u > 0 ? 1 : -1;
      const SnCnDn f = principal(u - s * K);
      const Real kp = std::sqrt(kp2_);
      return {s * f.cn / f.dn, -s * kp * f.sn / f.dn, kp / f.dn};
    }
    return principal(u);
  }

 private:
  SnCnDn principal(Real u) const {
    double phi = std::ldexp(a_[levels_] * static_cast<double>(u), levels_);
    for (int j = levels_; j > 0; --j) phi = 0.5 * (phi + std::asin(c_[j] * std::sin(phi) / a_[j]));
    const Real cn = std::cos(phi);
    return {std::sin(phi), cn, std::sqrt(kp2_ + k2_ * cn * cn)};
  }

  static constexpr int kMaxLevels = 40;
  static constexpr Real kHalfPi = 1.570796326794896619231321691639751442L;
  Real k2_, kp2_;
  double a_[kMaxLevels + 1] = {};
  double c_[kMaxLevels + 1] = {};
  int levels_ = 0;
};

// Carlson's symmetric integrals R_F and R_J (Boost.Math; DLMF 19.16.1-2), evaluated in double
// without Boost's default promotion to long double. Their results enter the phase and the
// precession angle with absolute error ~1e-16 * K per advance, below the rounding of the stored
// state; the extended precision is kept where it matters (rotations, Jacobi functions).
using CarlsonPolicy = boost::math::policies::policy<boost::math::policies::promote_double<false>>;
Real carlson_rf(Real x, Real y, Real z) {
  return boost::math::ellint_rf(static_cast<double>(x), static_cast<double>(y),
                                static_cast<double>(z), CarlsonPolicy());
}
Real carlson_rj(Real x, Real y, Real z, Real p) {
  return boost::math::ellint_rj(static_cast<double>(x), static_cast<double>(y),
                                static_cast<double>(z), static_cast<double>(p), CarlsonPolicy());
}

// Incomplete integrals of the first and third kind at the amplitude phi with sin(phi) = s,
// cos(phi) = c >= 0 (|phi| <= pi/2), in Carlson's symmetric form (DLMF 19.25.5, 19.25.14):
//   F(phi, k)    = s R_F(c^2, D, 1),
//   Pi(n; phi, k) = F + (n / 3) s^3 R_J(c^2, D, 1, 1 - n s^2),   D = 1 - k^2 s^2 = c^2 + k'^2 s^2,
// with Pi the integral of 1 / ((1 - n sin^2) sqrt(1 - k^2 sin^2)).
struct FirstAndThird {
  Real F, Pi;
};
FirstAndThird incomplete_integrals(Real s, Real c, Real kp2, Real n) {
  const Real c2 = c * c;
  const Real D = c2 + kp2 * s * s;
  const Real F = s * carlson_rf(c2, D, 1);
  if (n == 0 || s == 0) return {F, F};
  return {F, F + n / 3 * s * s * s * carlson_rj(c2, D, 1, 1 - n * s * s)};
}

// The ZXZ frame G(l) of the pole frame P: the rotation whose third column is l / |l| (in P
// coordinates, l = (la, lb, lp)); G = Rz(-phi) Rx(-theta) with l = |l| (sin th sin ph, sin th cos
// ph, cos th). Requires la^2 + lb^2 > 0.
Mat3L pole_frame(const Vec3L& l_P) {
  const Real sxy = std::sqrt(l_P.x() * l_P.x() + l_P.y() * l_P.y());  // O(1) values
  const Real len = l_P.norm();
  const Real ct = l_P.z() / len, st = sxy / len;
  const Real sp = l_P.x() / sxy, cp = l_P.y() / sxy;
  Mat3L g;
  g << cp, sp * ct, sp * st, -sp, cp * ct, cp * st, 0, -st, ct;
  return g;
}

FreeRotation steady_rotation(const Quat& q_WB, const Vec3& w_W, double dt) {
  return {(rotation_quat<double>(w_W * dt) * q_WB).normalized(), w_W};
}

// Regular precession of an axisymmetric body with symmetric axis `axis` (0 or 2) of moment I_s,
// transverse moment I_t: w = L / I_t + w_s (1 - I_s / I_t) e_s, hence
// R(t) = exp([L_W dt / I_t]x) R0 exp([e_s w_s (1 - I_s / I_t) dt]x).
FreeRotation axisymmetric_rotation(double I_s, double I_t, int axis, const Quat& q_WB,
                                   const Vec3& w_W, double dt) {
  const QuatL q0 = q_WB.cast<Real>();
  const Vec3L w0 = w_W.cast<Real>();
  const Vec3L e_s_B = Vec3L::Unit(axis);
  const Vec3L e_s_W = rotate(q0, e_s_B);
  const Real w_s = e_s_W.dot(w0);
  const Vec3L L_W = Real(I_t) * w0 + Real(I_s - I_t) * w_s * e_s_W;
  const Real body_rate = w_s * (1 - Real(I_s) / Real(I_t));
  const QuatL q = (rotation_quat<Real>(L_W * (Real(dt) / Real(I_t))) * q0 *
                   rotation_quat<Real>(e_s_B * (body_rate * Real(dt))))
                      .normalized();
  const Vec3L w1 = L_W / Real(I_t) + body_rate * rotate(q, e_s_B);
  return {q.cast<double>().normalized(), w1.cast<double>()};
}

// The general (asymmetric) torque-free rotation; see the header for the construction.
FreeRotation asymmetric_rotation(const Vec3& I, const Quat& q_WB, const Vec3& w_W, double dt) {
  const QuatL q0 = q_WB.cast<Real>();
  const Vec3L w_B = rotate(q0.conjugate(), Vec3L(w_W.cast<Real>()));
  const Real w_max = w_B.cwiseAbs().maxCoeff();
  if (w_max == 0.0 || !std::isfinite(w_max)) return {q_WB, w_W};
  // Everything below is homogeneous in |w|: work with e = w_B / spin, spin the power of two
  // nearest above max |w_i| (an exact scaling: no overflow or underflow of T and L for huge or
  // tiny spins, and a state exactly on the separatrix stays exactly on it), and scale rates by
  // `spin`.
  int exponent = 0;
  std::frexp(w_max, &exponent);
  const Real spin = std::ldexp(Real(1), exponent);
  const Vec3L e = w_B / spin;
  const Real I1 = I.x(), I2 = I.y(), I3 = I.z();
  const Real e1s = e.x() * e.x(), e2s = e.y() * e.y(), e3s = e.z() * e.z();
  // D_j = L^2 - 2 T I_j = sum_i I_i (I_i - I_j) e_i^2, formed without cancellation.
  const Real D1 = I2 * (I2 - I1) * e2s + I3 * (I3 - I1) * e3s;  // >= 0
  const Real D3 = I1 * (I3 - I1) * e1s + I2 * (I3 - I2) * e2s;  // 2 T I3 - L^2 >= 0
  const Real D2 = I1 * (I1 - I2) * e1s + I3 * (I3 - I2) * e3s;  // signed
  const bool high = D2 >= 0.0;  // L^2 >= 2 T I2: L_B circulates around e3; else around e1
  // Axis with cn (the pole), axis with dn; axis 2 always carries sn (Landau & Lifshitz §37).
  const int c_axis = high ? 0 : 2;
  const int d_axis = high ? 2 : 0;
  if ((high ? D3 : D1) == 0.0) return steady_rotation(q_WB, w_W, dt);  // about a principal axis
  Real Ac2, A22, Ad2, lambda2, k2, kp2, n, C, I_p;
  if (high) {
    Ac2 = D3 / (I1 * (I3 - I1));
    A22 = D3 / (I2 * (I3 - I2));
    Ad2 = D1 / (I3 * (I3 - I1));
    lambda2 = (I3 - I2) * D1 / (I1 * I2 * I3);
    k2 = (I2 - I1) * D3 / ((I3 - I2) * D1);
    kp2 = (I3 - I1) * D2 / ((I3 - I2) * D1);
    n = -I1 * D3 / (I3 * D1);
    C = -(I3 - I1) / I3;
    I_p = I1;
  } else {
    Ac2 = D1 / (I3 * (I3 - I1));
    A22 = D1 / (I2 * (I2 - I1));
    Ad2 = D3 / (I1 * (I3 - I1));
    lambda2 = (I2 - I1) * D3 / (I1 * I2 * I3);
    k2 = (I3 - I2) * D1 / ((I2 - I1) * D3);
    kp2 = -(I3 - I1) * D2 / ((I2 - I1) * D3);
    n = -I3 * D1 / (I1 * D3);
    C = (I3 - I1) / I1;
    I_p = I3;
  }
  k2 = std::min(k2, Real(1));
  const Real Ac = std::sqrt(Ac2), A2 = std::sqrt(A22), Ad = std::sqrt(Ad2);
  const Real lambda = std::sqrt(lambda2);  // rate of the elliptic argument per unit |w|
  const Real L = std::sqrt(I1 * I1 * e1s + I2 * I2 * e2s + I3 * I3 * e3s);  // per unit |w|

  // Signs: w_c = s_c Ac cn, w_2 = s_2 A2 sn, w_d = s_d Ad dn solve Euler's equations iff
  // s_c s_2 s_d = 1; choosing s_c = sign(w_c) puts the initial amplitude in [-pi/2, pi/2].
  const Real s_c = e[c_axis] >= 0 ? 1 : -1;
  const Real s_d = e[d_axis] >= 0 ? 1 : -1;
  const Real s_2 = s_c * s_d;
  Real sn0 = s_2 * e.y() / A2;
  Real cn0 = s_c * e[c_axis] / Ac;
  const Real h = std::sqrt(sn0 * sn0 + cn0 * cn0);  // O(1) values
  sn0 /= h;
  cn0 /= h;

  const Real u_rate = spin * lambda;
  Real u0, J0, u1, J1;
  SnCnDn f1;
  if (kp2 > 0) {
    const FirstAndThird i0 = incomplete_integrals(sn0, cn0, kp2, n);
    // Not finite only at the equilibrium on e2 with k'^2 underflowing: a steady rotation.
    if (!std::isfinite(i0.Pi)) return steady_rotation(q_WB, w_W, dt);
    u0 = i0.F;
    J0 = i0.Pi;
    u1 = u0 + u_rate * dt;
    // Reduce u1 to r in [-K, K]: sn, cn change sign with every half period 2K, dn does not, and
    // the third-kind integral gains the complete Pi(n, k) per half period.
    const Jacobi jacobi(k2, kp2);
    const Real K = jacobi.complete_K();
    const Real m = std::nearbyint(static_cast<double>(u1 / (2 * K)));
    const Real r = u1 - 2 * K * m;
    f1 = jacobi(r);
    const FirstAndThird i1 = incomplete_integrals(f1.sn, std::fabs(f1.cn), kp2, n);
    J1 = i1.Pi;
    if (m != 0) J1 += 2 * m * (n == 0 ? K : K + n / 3 * carlson_rj(0, kp2, 1, 1 - n));
    if (std::fmod(m, Real(2)) != 0) {
      f1.sn = -f1.sn;
      f1.cn = -f1.cn;
    }
  } else {
    // The separatrix, k = 1: sn = tanh, cn = dn = sech, F = atanh(sin phi), and
    // int du / (1 + mu tanh^2 u) = (u + sqrt(mu) atan(sqrt(mu) tanh u)) / (1 + mu), mu = -n.
    if (cn0 == 0) return steady_rotation(q_WB, w_W, dt);  // the unstable equilibrium on e2
    const Real sqrt_mu = std::sqrt(-n);
    const auto J = [&](Real u) {
      return (u + sqrt_mu * std::atan(sqrt_mu * std::tanh(u))) / (1 - n);
    };
    u0 = std::asinh(sn0 / cn0);
    u1 = u0 + u_rate * dt;
    J0 = J(u0);
    J1 = J(u1);
    f1 = Jacobi(1, 0)(u1);
  }

  Vec3L e1;  // omega_B(t) per unit |w|
  e1[c_axis] = s_c * Ac * f1.cn;
  e1.y() = s_2 * A2 * f1.sn;
  e1[d_axis] = s_d * Ad * f1.dn;

  // Precession angle about L_W: psi' = (|L| / I_p) (1 + C / (1 - n sn^2)), so
  // dpsi = (|L| / I_p) (dt + C (J1 - J0) / rate of u).
  const Real dpsi = spin * L / I_p * dt + L * C / (I_p * lambda) * (J1 - J0);

  // Pole frame P: coordinates (a, b, p) a cyclic permutation of the body axes with the pole last.
  Mat3L P_from_B;
  if (high) {
    P_from_B << 0, 1, 0, 0, 0, 1, 1, 0, 0;  // (e2, e3, e1)
  } else {
    P_from_B.setIdentity();
  }
  const Vec3L IL = I.cast<Real>();
  const Vec3L l0_P = P_from_B * IL.cwiseProduct(e);
  const Vec3L l1_P = P_from_B * IL.cwiseProduct(e1);
  const QuatL q_B_G0(Mat3L(P_from_B.transpose() * pole_frame(l0_P)));
  const QuatL q_B_G1(Mat3L(P_from_B.transpose() * pole_frame(l1_P)));
  const QuatL q_psi(std::cos(dpsi / 2), 0, 0, std::sin(dpsi / 2));
  const QuatL q = (q0 * q_B_G0 * q_psi * q_B_G1.conjugate()).normalized();
  return {q.cast<double>().normalized(), rotate(q, Vec3L(spin * e1)).cast<double>()};
}

}  // namespace

InertiaSymmetry classify_inertia(const Vec3& I_B, double relative_tolerance) {
  const double scale = relative_tolerance * I_B.z();
  if (I_B.z() - I_B.x() <= scale) return InertiaSymmetry::kSpherical;
  if (I_B.y() - I_B.x() <= scale || I_B.z() - I_B.y() <= scale) {
    return InertiaSymmetry::kAxisymmetric;
  }
  return InertiaSymmetry::kAsymmetric;
}

FreeRotation advance_free_rotation(const Vec3& I_B, const Quat& q_WB, const Vec3& w_W, double dt,
                                   double symmetry_tolerance) {
  PALPABLE_CHECK(I_B.x() > 0.0 && I_B.x() <= I_B.y() && I_B.y() <= I_B.z(),
                 "principal moments must be positive and ascending");
  if (dt == 0.0) return {q_WB, w_W};
  switch (classify_inertia(I_B, symmetry_tolerance)) {
    case InertiaSymmetry::kSpherical: return steady_rotation(q_WB, w_W, dt);
    case InertiaSymmetry::kAxisymmetric: {
      const double scale = symmetry_tolerance * I_B.z();
      if (I_B.y() - I_B.x() <= scale) {  // symmetric axis e3 (largest moment)
        return axisymmetric_rotation(I_B.z(), 0.5 * (I_B.x() + I_B.y()), 2, q_WB, w_W, dt);
      }
      return axisymmetric_rotation(I_B.x(), 0.5 * (I_B.y() + I_B.z()), 0, q_WB, w_W, dt);
    }
    case InertiaSymmetry::kAsymmetric: return asymmetric_rotation(I_B, q_WB, w_W, dt);
  }
  return {q_WB, w_W};
}

BodyState advance(const Body& body, const BodyState& from, double t, const Vec3& gravity_W,
                  const Settings& settings) {
  PALPABLE_CHECK(t >= from.t, "advance goes forward in time");
  const double dt = t - from.t;
  BodyState to = from;
  to.t = t;
  switch (body.motion) {
    case MotionKind::kFixed: return to;
    case MotionKind::kKinematic: {
      const KinematicMotion& k = body.kinematic;
      const Quat turn = rotation_quat<double>(k.angular_velocity_W * dt);
      const Vec3 c0_W = k.point_W + k.velocity_W * from.t;
      const Vec3 c1_W = k.point_W + k.velocity_W * t;
      to.x_W = c1_W + turn * (from.x_W - c0_W);
      to.q_WM = (turn * from.q_WM).normalized();
      to.w_W = k.angular_velocity_W;
      to.v_W = k.velocity_W + k.angular_velocity_W.cross(to.x_W - c1_W);
      return to;
    }
    case MotionKind::kDynamic: break;
  }
  to.x_W = from.x_W + from.v_W * dt + 0.5 * gravity_W * (dt * dt);
  to.v_W = from.v_W + gravity_W * dt;
  const Quat& q_MB = body.mass.q_MB;
  const FreeRotation r = advance_free_rotation(body.mass.principal_moments, from.q_WM * q_MB,
                                               from.w_W, dt, settings.inertia_symmetry_tolerance);
  to.q_WM = (r.q_WB * q_MB.conjugate()).normalized();
  to.w_W = r.w_W;
  return to;
}

double angular_speed_bound(const Body& body, const BodyState& state, const Settings& settings) {
  switch (body.motion) {
    case MotionKind::kFixed: return 0.0;
    case MotionKind::kKinematic: return body.kinematic.angular_velocity_W.norm();
    case MotionKind::kDynamic: break;
  }
  const Vec3& I = body.mass.principal_moments;
  if (classify_inertia(I, settings.inertia_symmetry_tolerance) != InertiaSymmetry::kAsymmetric) {
    return state.w_W.norm();
  }
  const Vec3 w_B = (state.q_WM * body.mass.q_MB).conjugate() * state.w_W;
  const double spin = w_B.norm();
  if (spin == 0.0) return 0.0;
  const Vec3 e = w_B / spin;
  const double L = I.cwiseProduct(e).norm();
  const double two_T = e.dot(I.cwiseProduct(e));
  return spin * std::min(L / I.x(), std::sqrt(two_T / I.x()));
}

Quat principal_orientation_W(const MassProperties& mass, const Quat& q_WM) {
  return (q_WM * mass.q_MB).normalized();
}

Mat3 inverse_inertia_W(const Body& body, const Quat& q_WM) {
  if (body.mass.is_infinite()) return Mat3::Zero();
  const Mat3 R_WB = principal_orientation_W(body.mass, q_WM).toRotationMatrix();
  return R_WB * body.mass.principal_moments.cwiseInverse().asDiagonal() * R_WB.transpose();
}

Vec3 point_velocity_W(const BodyState& state, const Vec3& p_W) {
  return state.v_W + state.w_W.cross(p_W - state.x_W);
}

double rotational_energy(const MassProperties& mass, const BodyState& state) {
  const Vec3 w_B = principal_orientation_W(mass, state.q_WM).conjugate() * state.w_W;
  return 0.5 * w_B.dot(mass.principal_moments.cwiseProduct(w_B));
}

double kinetic_energy(const Body& body, const BodyState& state) {
  return 0.5 * body.mass.mass * state.v_W.squaredNorm() + rotational_energy(body.mass, state);
}

Vec3 angular_momentum_W(const MassProperties& mass, const BodyState& state) {
  const Quat q_WB = principal_orientation_W(mass, state.q_WM);
  return q_WB * mass.principal_moments.cwiseProduct(q_WB.conjugate() * state.w_W);
}

double polhode_period(const Vec3& I_B, const Vec3& w_B) {
  const double spin = w_B.norm();
  if (spin == 0.0 || !(I_B.x() < I_B.y() && I_B.y() < I_B.z())) return kInfinity;
  const Vec3 e = w_B / spin;
  const double I1 = I_B.x(), I2 = I_B.y(), I3 = I_B.z();
  const double e1s = e.x() * e.x(), e2s = e.y() * e.y(), e3s = e.z() * e.z();
  const double D1 = I2 * (I2 - I1) * e2s + I3 * (I3 - I1) * e3s;
  const double D3 = I1 * (I3 - I1) * e1s + I2 * (I3 - I2) * e2s;
  const double D2 = I1 * (I1 - I2) * e1s + I3 * (I3 - I2) * e3s;
  const bool high = D2 >= 0.0;
  const double lambda2 = high ? (I3 - I2) * D1 / (I1 * I2 * I3) : (I2 - I1) * D3 / (I1 * I2 * I3);
  const double kp2 = high ? (I3 - I1) * D2 / ((I3 - I2) * D1) : -(I3 - I1) * D2 / ((I2 - I1) * D3);
  if (kp2 <= 0.0 || lambda2 <= 0.0) return kInfinity;
  const double K = boost::math::ellint_rf(0.0, kp2, 1.0);
  return 4.0 * K / (spin * std::sqrt(lambda2));
}

}  // namespace palpable
