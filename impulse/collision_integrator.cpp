#include "impulse/collision_integrator.hpp"

#include "core/event_location.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace palpable {

std::string_view to_string(CollisionStatus status) {
  switch (status) {
    case CollisionStatus::kOk: return "ok";
    case CollisionStatus::kSeparating: return "separating";
    case CollisionStatus::kFailedNonFinite: return "failed: non-finite value";
    case CollisionStatus::kFailedNotPositive:
      return "failed: K not symmetric positive definite or material out of range";
    case CollisionStatus::kFailedStepLimit: return "failed: step limit exceeded";
    case CollisionStatus::kFailedStepUnderflow: return "failed: step size underflow";
    case CollisionStatus::kFailedNoCompressionEnd:
      return "failed: a constant-direction phase cannot end (K_z . zeta <= 0)";
  }
  return "unknown";
}

std::string_view to_string(PhaseKind kind) {
  switch (kind) {
    case PhaseKind::kFrictionless: return "frictionless";
    case PhaseKind::kSlid: return "slid";
    case PhaseKind::kStuckStably: return "stuck stably";
    case PhaseKind::kResumedSliding: return "resumed sliding";
    case PhaseKind::kReboundFloor: return "restitution extended to the rebound floor";
    case PhaseKind::kReversed: return "reversed";
    case PhaseKind::kDriftFreeTarget: return "drift-free target";
    case PhaseKind::kDriftFreeConeBoundary:
      return "drift-free target outside the cone: cone-boundary impulse";
    case PhaseKind::kMicroFallback: return "microcollision target outside the cone: integrated";
  }
  return "unknown";
}

std::string describe(const CollisionPhase& phase) {
  if (phase.kind != PhaseKind::kResumedSliding) return std::string(to_string(phase.kind));
  std::ostringstream os;
  os.precision(6);
  os << "resumed sliding in direction (" << phase.direction.x() << ", " << phase.direction.y()
     << ")";
  return os.str();
}

void CollisionResult::add_phase(PhaseKind kind, double p_z_begin, const Vec2& direction) {
  if (phase_count < static_cast<int>(phases.size())) {
    phases[phase_count++] = CollisionPhase{kind, p_z_begin, direction};
  }
}

CollisionParameters collision_parameters(const Material& material, const Settings& settings) {
  CollisionParameters params;
  params.friction = material.friction;
  params.restitution = material.restitution;
  params.law = settings.restitution_law;
  params.tolerance = settings.integration_tolerance;
  return params;
}

bool in_friction_cone(const Vec3& p_c, double friction, double relative_slack) {
  const double p_t = std::hypot(p_c.x(), p_c.y());
  return p_c.z() >= 0.0 && p_t <= friction * p_c.z() * (1.0 + relative_slack);
}

bool unstable_stick_direction(const Mat3& K_c, double friction, Vec2& direction) {
  // Stability (DESIGN.md §4): the impulse direction K^-1 e_z keeping u_t = 0 has tangential part
  // -K_t^-1 k (per unit normal impulse); stable iff |K_t^-1 k| <= mu.
  const Eigen::Matrix2d K_t = K_c.topLeftCorner<2, 2>();
  const Vec2 k = K_c.block<2, 1>(0, 2);
  const Vec2 stick_t = K_t.inverse() * k;
  if (stick_t.norm() <= friction) return false;
  // Unstable: t = (lambda 1 + mu K_t)^-1 k with |t| = 1, lambda > 0. In the eigenbasis of
  // mu K_t = Q diag(a) Q^T, f(lambda) = sum c_i^2 / (lambda + a_i)^2 - 1 (c = Q^T k) is convex and
  // strictly decreasing, so Newton's method from lambda = 0 (f > 0) rises monotonically to the
  // unique root; it replaces the thesis's quartic in tan(beta/2) (Mirtich 1996, §4.3).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(friction * K_t);
  const Vec2 a = eig.eigenvalues();
  const Vec2 c = eig.eigenvectors().transpose() * k;
  double lambda = 0.0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double q0 = c(0) / (lambda + a(0));
    const double q1 = c(1) / (lambda + a(1));
    const double f = q0 * q0 + q1 * q1 - 1.0;
    if (!(f > 0.0)) break;
    const double df = -2.0 * (q0 * q0 / (lambda + a(0)) + q1 * q1 / (lambda + a(1)));
    const double next = lambda - f / df;
    if (!(next > lambda)) break;
    const bool converged = next - lambda <= 1e-16 * next;
    lambda = next;
    if (converged) break;
  }
  const Vec2 t = eig.eigenvectors() * Vec2(c(0) / (lambda + a(0)), c(1) / (lambda + a(1)));
  direction = t / t.norm();
  return true;
}

namespace {

// Dormand & Prince, "A family of embedded Runge-Kutta formulae", J. Comp. Appl. Math. 6, 1980:
// the 5(4) pair with first-same-as-last and Shampine's 4th-order dense output (the coefficients
// of Hairer's DOPRI5 / SciPy's RK45).
constexpr double kC2 = 1.0 / 5.0, kC3 = 3.0 / 10.0, kC4 = 4.0 / 5.0, kC5 = 8.0 / 9.0;
constexpr double kA21 = 1.0 / 5.0;
constexpr double kA31 = 3.0 / 40.0, kA32 = 9.0 / 40.0;
constexpr double kA41 = 44.0 / 45.0, kA42 = -56.0 / 15.0, kA43 = 32.0 / 9.0;
constexpr double kA51 = 19372.0 / 6561.0, kA52 = -25360.0 / 2187.0, kA53 = 64448.0 / 6561.0,
                 kA54 = -212.0 / 729.0;
constexpr double kA61 = 9017.0 / 3168.0, kA62 = -355.0 / 33.0, kA63 = 46732.0 / 5247.0,
                 kA64 = 49.0 / 176.0, kA65 = -5103.0 / 18656.0;
constexpr double kB1 = 35.0 / 384.0, kB3 = 500.0 / 1113.0, kB4 = 125.0 / 192.0,
                 kB5 = -2187.0 / 6784.0, kB6 = 11.0 / 84.0;
constexpr double kE1 = 71.0 / 57600.0, kE3 = -71.0 / 16695.0, kE4 = 71.0 / 1920.0,
                 kE5 = -17253.0 / 339200.0, kE6 = 22.0 / 525.0, kE7 = -1.0 / 40.0;
// Dense output: y(theta) = y0 + h sum_i k_i (P_i1 theta + P_i2 theta^2 + P_i3 theta^3 + ...).
constexpr double kP[7][4] = {
    {1.0, -8048581381.0 / 2820520608.0, 8663915743.0 / 2820520608.0,
     -12715105075.0 / 11282082432.0},
    {0.0, 0.0, 0.0, 0.0},
    {0.0, 131558114200.0 / 32700410799.0, -68118460800.0 / 10900136933.0,
     87487479700.0 / 32700410799.0},
    {0.0, -1754552775.0 / 470086768.0, 14199869525.0 / 1410260304.0, -10690763975.0 / 1880347072.0},
    {0.0, 127303824393.0 / 49829197408.0, -318862633887.0 / 49829197408.0,
     701980252875.0 / 199316789632.0},
    {0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0, -1453857185.0 / 822651844.0},
    {0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0}};

// Steps toward a predicted slip zero stop short by this fraction, so that no Runge-Kutta stage
// evaluates the friction direction at (or past) u_t = 0; each such step shrinks |u_t| by ~1e3.
constexpr double kSlipApproachShortfall = 1e-3;

// Where the collision is: compressing, restituting until the law's end, extending restitution
// to the rebound floor, done.
enum class Stage { kCompression, kRestitution, kFloor, kDone };

// y = (p_x, p_y, W_z): tangential impulse and the work of the normal impulse; p_z is the
// independent variable (DESIGN.md §4: dp/dp_z = zeta, dW_z/dp_z = u_z).
using State = Eigen::Vector3d;

enum class SlideEnd { kDone, kSlipZero, kFailed };

class Solver {
 public:
  Solver(const Mat3& K, const Vec3& u0, const CollisionParameters& params, CollisionResult& r)
      : K_(K), u0_(u0), params_(params), r_(r) {
    v_ref_ = std::max(u0.norm(), params.min_rebound_speed);
    p_ref_ = v_ref_ / K(2, 2);
    slip_tolerance_ = params.tolerance * v_ref_;
    stall_slip_ = std::sqrt(params.tolerance) * v_ref_;
    const Eigen::Matrix2d K_t = K.topLeftCorner<2, 2>();
    stable_stick_ = (K_t.inverse() * Vec2(K.block<2, 1>(0, 2))).norm() <= params.friction;
  }

  Vec3 velocity() const { return u0_ + K_ * Vec3(y_(0), y_(1), p_z_); }
  Stage stage() const { return stage_; }
  double p_z() const { return p_z_; }

  // Moves through every stage whose end condition already holds at the current state.
  void advance_stage() {
    const double u_z = velocity().z();
    if (stage_ == Stage::kCompression) {
      if (u_z < 0.0) return;
      enter_restitution();
    }
    if (stage_ == Stage::kRestitution) {
      if (!law_reached(u_z)) return;
      stage_ = Stage::kFloor;
    }
    if (stage_ == Stage::kFloor) {
      if (params_.min_rebound_speed > 0.0 && u_z < params_.min_rebound_speed) {
        if (!floor_phase_recorded_) {
          r_.add_phase(PhaseKind::kReboundFloor, p_z_);
          floor_phase_recorded_ = true;
        }
        return;
      }
      stage_ = Stage::kDone;
    }
  }

  // Forces the transition out of the current stage (its event was located to tolerance, so the
  // end condition holds up to rounding), then moves on through any that already hold.
  void force_transition() {
    if (stage_ == Stage::kCompression) {
      enter_restitution();
    } else if (stage_ == Stage::kRestitution) {
      stage_ = Stage::kFloor;
    } else if (stage_ == Stage::kFloor) {
      stage_ = Stage::kDone;
    }
    advance_stage();
  }

  // Closed form with constant dp/dp_z = zeta (zeta_z = 1): frictionless, stable sticking,
  // sliding resumed in a fixed direction, or sliding whose direction does not turn (2D, spheres).
  // du/dp_z = K zeta is constant and W_z quadratic. With `stop_at_slip_zero`, the segment also
  // ends where |u_t| reaches 0 (returning kSlipZero), if that comes first.
  SlideEnd linear(const Vec3& zeta, bool stop_at_slip_zero, CollisionStatus& status) {
    const Vec3 d = K_ * zeta;
    while (stage_ != Stage::kDone) {
      const Vec3 u = velocity();
      double delta = 0.0;
      switch (stage_) {
        case Stage::kCompression:
          // K_z . zeta <= 0: u_z does not rise in this direction; only a slip zero can end the
          // segment (checked below).
          delta = d.z() > 0.0 ? -u.z() / d.z() : kInfinity;
          break;
        case Stage::kRestitution:
          if (params_.law == RestitutionLaw::kStronge) {
            // W + u_z delta + d_z delta^2 / 2 = W_end: the first root delta >= 0, in a form that
            // does not cancel; none (W never gets there in this direction) -> infinity.
            const double dW = std::max(stronge_remaining(y_(2)), 0.0);
            const double discriminant = u.z() * u.z() + 2.0 * d.z() * dW;
            const double denominator = discriminant >= 0.0 ? u.z() + std::sqrt(discriminant) : -1.0;
            delta = dW == 0.0 ? 0.0 : denominator > 0.0 ? 2.0 * dW / denominator : kInfinity;
          } else if (params_.law == RestitutionLaw::kPoisson) {
            delta = p_z_end_ - p_z_;
          } else {
            delta = time_to_normal_speed(u_z_end_, u.z(), d.z());
          }
          break;
        case Stage::kFloor:
          delta = time_to_normal_speed(params_.min_rebound_speed, u.z(), d.z());
          break;
        case Stage::kDone: break;
      }
      if (std::isnan(delta)) {
        status = CollisionStatus::kFailedNonFinite;
        return SlideEnd::kFailed;
      }
      delta = std::max(delta, 0.0);
      bool slip_zero = false;
      if (stop_at_slip_zero) {
        const Vec2 u_t = u.head<2>();
        const double slip = u_t.norm();
        const double ds = slip > 0.0 ? u_t.dot(d.head<2>()) / slip : 0.0;
        if (ds < 0.0 && slip / -ds <= delta) {
          delta = slip / -ds;
          slip_zero = true;
        }
      }
      if (!std::isfinite(delta)) {
        status = CollisionStatus::kFailedNoCompressionEnd;
        return SlideEnd::kFailed;
      }
      y_(0) += zeta.x() * delta;
      y_(1) += zeta.y() * delta;
      y_(2) += u.z() * delta + 0.5 * d.z() * delta * delta;
      p_z_ += delta;
      record();
      if (slip_zero) {
        advance_stage();
        return SlideEnd::kSlipZero;
      }
      force_transition();
    }
    return SlideEnd::kDone;
  }

  // Normal impulse until u_z reaches `target` at the constant rate d_z (infinity if never).
  static double time_to_normal_speed(double target, double u_z, double d_z) {
    if (u_z >= target) return 0.0;
    return d_z > 0.0 ? (target - u_z) / d_z : kInfinity;
  }

  // Sliding with the slip direction integrated (Dormand-Prince 5(4)), until the collision ends
  // or |u_t| reaches 0 (to the tolerance). Events are located on the dense output.
  SlideEnd slide(CollisionStatus& status) {
    State k[7];
    k[0] = rhs(p_z_, y_);
    double h = p_ref_ * std::min(1.0, 10.0 * std::pow(params_.tolerance, 0.2));
    double best_slip = kInfinity;
    int since_progress = 0;
    while (stage_ != Stage::kDone) {
      if (r_.steps + r_.rejected_steps >= params_.max_steps) {
        status = CollisionStatus::kFailedStepLimit;
        return SlideEnd::kFailed;
      }
      const Vec3 u = velocity();
      const Vec2 u_t = u.head<2>();
      const double s = u_t.norm();
      const Vec2 zeta_t(k[0](0), k[0](1));
      // du_t/dp_z, its part along the slip (d|u_t|/dp_z, which predicts the slip zero) and across
      // it (which turns the slip direction at the rate |perp| / |u_t| per unit p_z).
      const Vec2 d_t = K_.topLeftCorner<2, 2>() * zeta_t + K_.block<2, 1>(0, 2);
      const double ds = s > 0.0 ? u_t.dot(d_t) / s : 0.0;
      const double turn_rate = s > 0.0 ? (d_t - ds * u_t / s).norm() / s : 0.0;
      // Freezing the direction over the rest of the slide (up to the predicted slip zero, or the
      // collision's scale) errs in p_t by about mu turn_rate L^2 / 2. When that is well inside the
      // tolerance — at once if the direction does not turn (2D, spheres), and on the final
      // approach of a 3D slip spiralling into the origin — finish the slide in closed form,
      // which locates the slip zero exactly instead of letting the step size collapse near it.
      const double p_scale = p_ref_ + p_z_;
      const double span = ds < 0.0 ? std::min(s / -ds, p_scale) : p_scale;
      const bool frozen_is_accurate =
          10.0 * params_.friction * turn_rate * span * span <= params_.tolerance * p_scale;
      // Near the zero of a slip that can stick stably, the friction direction is stiff (it snaps
      // within a vanishing p_z), and an explicit step can cycle without reducing |u_t| while
      // passing its error test. If |u_t| stalls there, land on the slip zero implicitly.
      const bool stalled = since_progress >= 8 && s <= stall_slip_;
      if (s <= slip_tolerance_ || stalled) {
        // The slip zero, to tolerance: land on it (exactly, when sticking is stable) and let the
        // caller test the stick. If even the landing direction would not reduce |u_t| (an
        // unstable stick approached to within the tolerance), the residual slip is dropped.
        if (stalled) ++r_.stalled_slip_landings;
        const Vec3 zeta = landing_zeta(u_t, zeta_t);
        const Vec2 d_land = (K_ * zeta).head<2>();
        if (u_t.dot(d_land) < 0.0) return linear(zeta, true, status);
        return SlideEnd::kSlipZero;
      }
      if (frozen_is_accurate) return linear(Vec3(zeta_t.x(), zeta_t.y(), 1.0), true, status);
      if (ds < 0.0 && stable_stick_) {
        // A slip that can stick stably, heading into the origin: the implicit landing direction
        // (the constant one that reaches u_t = 0) differs from the integrated one by |dt|; using
        // it for the rest of the approach errs by about mu |dt| |u_t| / |d|u_t|/dp_z|.
        const Vec3 zeta = landing_zeta(u_t, zeta_t);
        const double dt = (zeta.head<2>() - zeta_t).norm();
        if (10.0 * dt * (s / -ds) <= params_.tolerance * p_scale) {
          return linear(zeta, true, status);
        }
      }
      if (ds < 0.0) {
        // Stop short of the predicted slip zero so that no stage evaluates the direction there.
        // If the direction still turns (by more than a milliradian per e-fold of |u_t|, as in a
        // 3D spiral), a step across several e-folds would be rejected: halve |u_t| instead.
        const double turn_per_efold = turn_rate * s / -ds;
        const double fraction = turn_per_efold <= 1e-3 ? 1.0 - kSlipApproachShortfall : 0.5;
        h = std::min(h, fraction * s / -ds);
      }
      bool lands_on_poisson_end = false;
      if (stage_ == Stage::kRestitution && params_.law == RestitutionLaw::kPoisson &&
          p_z_ + h >= p_z_end_) {
        h = p_z_end_ - p_z_;
        lands_on_poisson_end = true;
      }
      if (!(h > 1e-15 * (p_z_ + p_ref_))) {
        if (lands_on_poisson_end) {
          force_transition();
          k[0] = rhs(p_z_, y_);
          continue;
        }
        status = CollisionStatus::kFailedStepUnderflow;
        return SlideEnd::kFailed;
      }
      // One Dormand-Prince step.
      k[1] = rhs(p_z_ + kC2 * h, y_ + h * (kA21 * k[0]));
      k[2] = rhs(p_z_ + kC3 * h, y_ + h * (kA31 * k[0] + kA32 * k[1]));
      k[3] = rhs(p_z_ + kC4 * h, y_ + h * (kA41 * k[0] + kA42 * k[1] + kA43 * k[2]));
      k[4] = rhs(p_z_ + kC5 * h, y_ + h * (kA51 * k[0] + kA52 * k[1] + kA53 * k[2] + kA54 * k[3]));
      k[5] = rhs(p_z_ + h,
                 y_ + h * (kA61 * k[0] + kA62 * k[1] + kA63 * k[2] + kA64 * k[3] + kA65 * k[4]));
      const State y_new = y_ + h * (kB1 * k[0] + kB3 * k[2] + kB4 * k[3] + kB5 * k[4] + kB6 * k[5]);
      k[6] = rhs(p_z_ + h, y_new);
      const State error =
          h * (kE1 * k[0] + kE3 * k[2] + kE4 * k[3] + kE5 * k[4] + kE6 * k[5] + kE7 * k[6]);
      const double tol = params_.tolerance;
      const double p_step_scale = p_ref_ + std::max(p_z_ + h, 0.0);
      const double e0 = error(0) / (tol * p_step_scale);
      const double e1 = error(1) / (tol * p_step_scale);
      const double e2 =
          error(2) / (tol * (p_ref_ * v_ref_ + std::max(std::abs(y_(2)), std::abs(y_new(2)))));
      const double err = std::sqrt((e0 * e0 + e1 * e1 + e2 * e2) / 3.0);
      if (!std::isfinite(err) || !y_new.allFinite()) {
        status = CollisionStatus::kFailedNonFinite;
        return SlideEnd::kFailed;
      }
      const double grow = err == 0.0 ? 5.0 : std::clamp(0.9 * std::pow(err, -0.2), 0.2, 5.0);
      if (err > 1.0) {
        ++r_.rejected_steps;
        h *= grow;
        continue;
      }
      ++r_.steps;
      const double theta = locate_event(k, h, y_new);
      if (params_.path) {
        for (double f : {0.25, 0.5, 0.75}) record(p_z_ + f * theta * h, dense(k, h, f * theta));
      }
      if (theta < 1.0) {
        y_ = dense(k, h, theta);
        p_z_ += theta * h;
        force_transition();
        k[0] = rhs(p_z_, y_);
      } else {
        y_ = y_new;
        p_z_ += h;
        k[0] = k[6];
        if (lands_on_poisson_end) force_transition();
      }
      record();
      h *= grow;
      // The tangential dynamics du_t/dp_z depends on the slip direction only, so near the slip
      // zero the motion is self-similar and the natural step scales with |u_t|: shrink the next
      // step with it, rather than letting the controller find that out by rejections.
      const double s_new = velocity().head<2>().norm();
      if (s_new < s) h *= s_new / s;
      if (s_new < 0.99 * best_slip) {
        best_slip = s_new;
        since_progress = 0;
      } else {
        ++since_progress;
      }
    }
    return SlideEnd::kDone;
  }

  // The constant dp/dp_z that brings the slip u_t exactly to zero (an implicit step onto the
  // slip zero): zeta_t = -mu t with u_t + delta (-mu K_t t + k) = 0, |t| = 1, delta > 0. With
  // A = (mu K_t)^-1 and lambda = 1 / delta, |A (lambda u_t + k)|^2 = 1 is a quadratic in lambda
  // with exactly one positive root when sticking is stable (|A k| <= 1). Otherwise (or if
  // degenerate) the current direction is kept.
  Vec3 landing_zeta(const Vec2& u_t, const Vec2& zeta_t) const {
    const Eigen::Matrix2d A = (params_.friction * K_.topLeftCorner<2, 2>()).inverse();
    const Vec2 Au = A * u_t, Ak = A * Vec2(K_.block<2, 1>(0, 2));
    const double a = Au.squaredNorm(), b = Au.dot(Ak), c = Ak.squaredNorm() - 1.0;
    if (!(c <= 0.0) || !(a > 0.0)) return Vec3(zeta_t.x(), zeta_t.y(), 1.0);
    const double lambda = (-b + std::sqrt(std::max(b * b - a * c, 0.0))) / a;
    if (!(lambda > 0.0)) return Vec3(zeta_t.x(), zeta_t.y(), 1.0);
    const Vec2 t = A * (lambda * u_t + Vec2(K_.block<2, 1>(0, 2)));
    const Vec2 zeta = -params_.friction * t / t.norm();
    return Vec3(zeta.x(), zeta.y(), 1.0);
  }

  // Appends the current point (or a given one) to the requested path.
  void record() const { record(p_z_, y_); }
  void record(double p_z, const State& y) const {
    if (!params_.path) return;
    const Vec3 p(y(0), y(1), p_z);
    params_.path->push_back(ImpulsePathPoint{p, u0_ + K_ * p});
  }

  void finish(CollisionStatus status) {
    r_.status = status;
    r_.p_c = Vec3(y_(0), y_(1), p_z_);
    r_.u_final_c = u0_ + K_ * r_.p_c;
    r_.energy_change = 0.5 * (u0_ + r_.u_final_c).dot(r_.p_c);
    r_.work_normal = y_(2);
  }

 private:
  State rhs(double p_z, const State& y) {
    ++r_.rhs_evaluations;
    const Vec3 u = u0_ + K_ * Vec3(y(0), y(1), p_z);
    const double s = std::hypot(u.x(), u.y());
    if (s > 0.0) direction_ = Vec2(u.x(), u.y()) / s;
    return State(-params_.friction * direction_.x(), -params_.friction * direction_.y(), u.z());
  }

  State dense(const State* k, double h, double theta) const {
    const double t1 = theta, t2 = t1 * theta, t3 = t2 * theta, t4 = t3 * theta;
    State sum = State::Zero();
    for (int i = 0; i < 7; ++i) {
      sum += (kP[i][0] * t1 + kP[i][1] * t2 + kP[i][2] * t3 + kP[i][3] * t4) * k[i];
    }
    return y_ + h * sum;
  }

  // The current stage's event function: negative before its end, >= 0 at and after.
  double event(double p_z, const State& y) const {
    const double u_z = u0_.z() + K_.row(2).dot(Vec3(y(0), y(1), p_z));
    switch (stage_) {
      case Stage::kCompression: return u_z;
      case Stage::kRestitution:
        if (params_.law == RestitutionLaw::kStronge) return -stronge_remaining(y(2));
        if (params_.law == RestitutionLaw::kNewton) return u_z - u_z_end_;
        return -1.0;  // Poisson: the step lands on p_z_end exactly
      case Stage::kFloor: return u_z - params_.min_rebound_speed;
      case Stage::kDone: break;
    }
    return 0.0;
  }

  // The fraction theta in (0, 1] of the step at which the stage's event occurs (1: none inside),
  // found on the dense output by the Illinois variant of regula falsi to full precision.
  double locate_event(const State* k, double h, const State& y_new) const {
    const double g1 = event(p_z_ + h, y_new);
    if (g1 < 0.0) return 1.0;
    const double g0 = event(p_z_, y_);
    if (g0 >= 0.0) return 0.0;
    return locate_crossing([&](double m) { return event(p_z_ + m * h, dense(k, h, m)); }, 0.0, g0,
                           1.0, g1, 1e-15, 200);
  }

  void enter_restitution() {
    stage_ = Stage::kRestitution;
    r_.p_z_compression = p_z_;
    r_.work_compression = y_(2);
    const double e = params_.restitution;
    p_z_end_ = (1.0 + e) * p_z_;
    u_z_end_ = -e * u0_.z();
    // e = 0: every law ends at maximum compression; no empty restitution phase is integrated.
    if (e == 0.0) stage_ = Stage::kFloor;
  }

  // Stronge's law ends at W_z = (1 - e^2) W_c; the work still to do, (W_c - W) - e^2 W_c, written
  // so that it is exact at maximum compression and does not cancel for small e.
  double stronge_remaining(double W) const {
    const double e = params_.restitution;
    return (r_.work_compression - W) - e * e * r_.work_compression;
  }

  bool law_reached(double u_z) const {
    switch (params_.law) {
      case RestitutionLaw::kStronge: return stronge_remaining(y_(2)) <= 0.0;
      case RestitutionLaw::kPoisson: return p_z_ >= p_z_end_;
      case RestitutionLaw::kNewton: return u_z >= u_z_end_;
    }
    return true;
  }

  const Mat3& K_;
  const Vec3 u0_;
  const CollisionParameters& params_;
  CollisionResult& r_;
  double v_ref_ = 0.0, p_ref_ = 0.0, slip_tolerance_ = 0.0, stall_slip_ = 0.0;
  double p_z_ = 0.0;
  State y_ = State::Zero();
  Stage stage_ = Stage::kCompression;
  double p_z_end_ = 0.0, u_z_end_ = 0.0;
  bool floor_phase_recorded_ = false;
  bool stable_stick_ = false;  // |K_t^-1 k| <= mu (DESIGN.md §4)
  Vec2 direction_ = Vec2::Zero();
};

bool valid_input(const Mat3& K, const CollisionParameters& params) {
  const double scale = K.cwiseAbs().maxCoeff();
  if (!((K - K.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale)) return false;
  // Sylvester's criterion on the leading minors.
  const double m1 = K(0, 0);
  const double m2 = K(0, 0) * K(1, 1) - K(0, 1) * K(1, 0);
  const double m3 = K.determinant();
  return m1 > 0.0 && m2 > 0.0 && m3 > 0.0 && K(2, 2) > 0.0 && params.friction >= 0.0 &&
         params.restitution >= 0.0 && params.restitution <= 1.0 && params.tolerance > 0.0 &&
         params.min_rebound_speed >= 0.0;
}

}  // namespace

CollisionResult integrate_collision(const Mat3& K_c, const Vec3& u0_c,
                                    const CollisionParameters& params) {
  CollisionResult result;
  result.u0_c = u0_c;
  result.u_final_c = u0_c;
  if (!K_c.allFinite() || !u0_c.allFinite() || !std::isfinite(params.friction) ||
      !std::isfinite(params.restitution) || !std::isfinite(params.tolerance) ||
      !std::isfinite(params.min_rebound_speed)) {
    result.status = CollisionStatus::kFailedNonFinite;
    return result;
  }
  if (!valid_input(K_c, params)) {
    result.status = CollisionStatus::kFailedNotPositive;
    return result;
  }
  Solver solver(K_c, u0_c, params, result);
  solver.record();
  solver.advance_stage();
  if (solver.stage() == Stage::kDone) {
    solver.finish(u0_c.z() > 0.0 ? CollisionStatus::kSeparating : CollisionStatus::kOk);
    return result;
  }
  CollisionStatus status = CollisionStatus::kOk;
  if (params.friction == 0.0) {
    result.add_phase(PhaseKind::kFrictionless, 0.0);
    solver.linear(Vec3::UnitZ(), false, status);
    solver.finish(status);
    return result;
  }
  const double slip_tolerance = params.tolerance * std::max(u0_c.norm(), params.min_rebound_speed);
  if (u0_c.head<2>().norm() > slip_tolerance) {
    result.add_phase(PhaseKind::kSlid, 0.0);
    const SlideEnd end = solver.slide(status);
    if (end != SlideEnd::kSlipZero) {
      solver.finish(status);
      return result;
    }
    if (solver.stage() == Stage::kDone) {
      solver.finish(status);
      return result;
    }
  }
  // Slip zero (or no slip at the start): stable sticking or sliding resumed in a fixed direction.
  Vec2 direction;
  if (unstable_stick_direction(K_c, params.friction, direction)) {
    result.add_phase(PhaseKind::kResumedSliding, solver.p_z(), direction);
    solver.linear(Vec3(-params.friction * direction.x(), -params.friction * direction.y(), 1.0),
                  false, status);
  } else {
    result.add_phase(PhaseKind::kStuckStably, solver.p_z());
    const Vec2 zeta_t = -K_c.topLeftCorner<2, 2>().inverse() * Vec2(K_c.block<2, 1>(0, 2));
    solver.linear(Vec3(zeta_t.x(), zeta_t.y(), 1.0), false, status);
  }
  solver.finish(status);
  return result;
}

}  // namespace palpable
