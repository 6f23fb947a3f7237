#include "impulse/group_impulse.hpp"

#include "impulse/collision_matrix.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace palpable {
namespace {

using VecX = Eigen::VectorXd;
using MatX = Eigen::MatrixXd;

// Projection onto the Coulomb cone {|l_t| <= mu l_n} of contact i's block (t1, t2, n).
void project_cone(VecX& l, int i, double mu) {
  const int k = 3 * i;
  const double n = l[k + 2];
  const double s = std::hypot(l[k], l[k + 1]);
  if (mu <= 0.0) {
    l[k] = l[k + 1] = 0.0;
    l[k + 2] = std::max(n, 0.0);
    return;
  }
  if (s <= mu * n) return;
  if (mu * s <= -n) {
    l[k] = l[k + 1] = l[k + 2] = 0.0;
    return;
  }
  const double n_new = (mu * s + n) / (mu * mu + 1.0);
  l[k] *= mu * n_new / s;
  l[k + 1] *= mu * n_new / s;
  l[k + 2] = n_new;
}

// Projection onto the disk |l_t| <= radius[i], the normal fixed at normal[i].
void project_disk(VecX& l, int i, double radius, double normal) {
  const int k = 3 * i;
  const double s = std::hypot(l[k], l[k + 1]);
  if (s > radius) {
    const double f = s > 0.0 ? radius / s : 0.0;
    l[k] *= f;
    l[k + 1] *= f;
  }
  l[k + 2] = normal;
}

// Accelerated projected gradient descent with adaptive restart on f(l) = l.b + l.A.l / 2 over a
// closed convex set given by `project` (in place). Returns the iterations used; `converged`
// reports whether the stationarity residual reached the tolerance.
template <class Project>
int apgd_scaled(const MatX& A, const VecX& b, double lipschitz, VecX& l, Project project,
                const GroupOptions& options, bool& converged) {
  const double step = 1.0 / lipschitz;
  project(l);
  VecX x_prev = l, y = l;
  // The iteration's vectors, allocated once (up to 20,000 iterations a problem).
  VecX g(l.size()), x(l.size()), r(l.size()), Ax(l.size());
  double theta = 1.0;
  // Scale of the impulses: the unconstrained frictionless size |b| / L, or the size of the
  // (projected) start if larger. An expansion's b is the velocity at the end of compression,
  // zero to rounding where the contacts stuck, while its impulses are the disks' normals: judged
  // against |b| / L alone (~1e-13 of them) the stationarity never reached the tolerance, and
  // such a problem ran its 20,000 iterations with its objective stationary to rounding (a cube
  // landing flat on a floor at 3 to 32 points: 2.5-49 ms a group; 118-122 iterations now).
  const double scale = std::max({b.norm() / lipschitz, l.norm(), 1e-300});
  for (int it = 1; it <= options.max_iterations; ++it) {
    g.noalias() = A * y + b;
    x = y - step * g;
    project(x);
    // Stationarity at x: the projected-gradient step's length.
    Ax.noalias() = A * x;
    r = x - step * (Ax + b);
    project(r);
    if ((x - r).norm() <= options.tolerance * scale) {
      l = x;
      return it;
    }
    const double theta_new = 0.5 * (-theta * theta + theta * std::sqrt(theta * theta + 4.0));
    const double beta = theta * (1.0 - theta) / (theta * theta + theta_new);
    if (g.dot(x - x_prev) > 0.0) {
      y = x;  // restart: momentum pointing uphill
      theta = 1.0;
    } else {
      y = x + beta * (x - x_prev);
      theta = theta_new;
    }
    x_prev = x;
  }
  l = x_prev;
  converged = false;
  return options.max_iterations;
}

// The group's operator scaled per contact: l = D m with D = diag(d_i I3), d_i = 1 / sqrt of the
// mean diagonal of contact i's block of A. A uniform scale of a contact's block maps its cone (or
// disk, with its radius and normal scaled alike) onto itself, so the projections are unchanged in
// form, while the scaled operator D A D is far better conditioned where masses and lever arms
// differ by orders of magnitude. Built once per group: every cone and disk problem of the group
// (compression, each round of the sliding shift, expansion) shares A.
struct ScaledOperator {
  VecX d;
  MatX As;
  double lipschitz = 1.0;  // the largest eigenvalue of D A D: APGD's step is its inverse

  explicit ScaledOperator(const MatX& A) {
    const int k = static_cast<int>(A.rows() / 3);
    d.resize(3 * k);
    for (int i = 0; i < k; ++i) {
      const double mean = A.block<3, 3>(3 * i, 3 * i).trace() / 3.0;
      d.segment<3>(3 * i).setConstant(mean > 0.0 ? 1.0 / std::sqrt(mean) : 1.0);
    }
    As = d.asDiagonal() * A * d.asDiagonal();
    lipschitz = std::max(
        Eigen::SelfAdjointEigenSolver<MatX>(As, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff(),
        1e-300);
  }
};

// APGD on the scaled problem; `project_scaled(m, d)` projects in the scaled variables.
template <class Project>
int apgd(const ScaledOperator& op, const VecX& b, VecX& l, Project project_scaled,
         const GroupOptions& options, bool& converged) {
  const VecX bs = op.d.cwiseProduct(b);
  VecX m = l.cwiseQuotient(op.d);
  const int iterations = apgd_scaled(
      op.As, bs, op.lipschitz, m, [&](VecX& x) { project_scaled(x, op.d); }, options, converged);
  l = op.d.cwiseProduct(m);
  return iterations;
}

// min x.H.x / 2 + c.x over x >= 0 for a symmetric positive definite H: Lawson & Hanson's active
// set ("Solving least squares problems", 1974, ch. 23), written for a quadratic form rather than
// a least-squares matrix. Finite in exact arithmetic: each outer step frees the bound with the
// steepest descent, each inner step moves to the free set's minimiser or to the first bound on the
// way. Returns false if it hit the iteration cap (x is then feasible, not optimal).
bool nonnegative_qp(const MatX& H, const VecX& c, double tolerance, VecX& x) {
  const int k = static_cast<int>(c.size());
  x = VecX::Zero(k);
  std::vector<char> free(k, 0);
  const int cap = 10 * k + 100;
  int it = 0;
  while (it++ < cap) {
    const VecX w = -(H * x + c);  // > 0: descent by raising x_i from its bound
    int j = -1;
    for (int i = 0; i < k; ++i) {
      if (!free[i] && w[i] > tolerance && (j < 0 || w[i] > w[j])) j = i;
    }
    if (j < 0) return true;
    free[j] = 1;
    while (it++ < cap) {
      std::vector<int> set;
      for (int i = 0; i < k; ++i) {
        if (free[i]) set.push_back(i);
      }
      const int m = static_cast<int>(set.size());
      MatX Hs(m, m);
      VecX cs(m);
      for (int a = 0; a < m; ++a) {
        cs[a] = c[set[a]];
        for (int b = 0; b < m; ++b) Hs(a, b) = H(set[a], set[b]);
      }
      const VecX z = Hs.ldlt().solve(-cs);
      // The longest step towards z that keeps every free variable >= 0, and what stops it.
      double alpha = 1.0;
      int stop = -1;
      for (int a = 0; a < m; ++a) {
        if (z[a] > 0.0) continue;
        const double x_a = x[set[a]];
        const double to_bound = x_a > 0.0 ? x_a / (x_a - z[a]) : 0.0;
        if (to_bound < alpha || stop < 0) {
          alpha = std::min(alpha, to_bound);
          stop = a;
        }
      }
      if (stop < 0) {
        for (int a = 0; a < m; ++a) x[set[a]] = z[a];
        break;
      }
      // Exactly, the variable just freed rises (Lawson & Hanson, lemma 23.17); if rounding says
      // otherwise at once, x is optimal to rounding.
      if (alpha <= 0.0 && set[stop] == j) {
        free[j] = 0;
        return true;
      }
      for (int a = 0; a < m; ++a) x[set[a]] += alpha * (z[a] - x[set[a]]);
      x[set[stop]] = 0.0;
      for (int a = 0; a < m; ++a) {
        if (x[set[a]] <= 0.0) {
          x[set[a]] = 0.0;
          free[set[a]] = 0;
        }
      }
    }
  }
  return false;
}

// The normal components (every third, from 2) of a group vector in the contacts' frames, and
// the normal-normal block of the group's operator.
VecX normal_part(const VecX& v) {
  return Eigen::Map<const VecX, 0, Eigen::InnerStride<3>>(v.data() + 2, v.size() / 3);
}

MatX normal_block(const MatX& A) {
  const Eigen::Index k = A.rows() / 3;
  MatX An(k, k);
  for (Eigen::Index i = 0; i < k; ++i) {
    for (Eigen::Index j = 0; j < k; ++j) An(i, j) = A(3 * i + 2, 3 * j + 2);
  }
  return An;
}

// The frictionless plastic LCP on the normals: l_n >= 0, u_n = (A l + b)_n >= 0, l_n u_n = 0, as
// the convex programme min l.A.l / 2 + b.l over l_n >= 0 (A is positive semidefinite). A may be
// singular (seven contacts on one body, of six freedoms): the impulses are then not unique, the
// velocities are. Solved by proximal point: each round the strictly convex problem with
// delta |l - l_last|^2 / 2 added (delta 1e-12 of A's largest diagonal), by the active set above;
// the rounds converge to a solution of the LCP whenever one exists (Rockafellar 1976), and each
// leaves u_n short of complementarity by at most delta |l - l_last|. Any number of contacts.
// Returns false (l untouched) if nothing approaches by more than `slack`.
bool normal_lcp(const MatX& A, const VecX& b, double slack, VecX& l) {
  const int k = static_cast<int>(b.size() / 3);
  bool approaching = false;
  for (int i = 0; i < k; ++i) approaching = approaching || b[3 * i + 2] < -slack;
  if (!approaching) return false;
  const MatX An = normal_block(A);
  const VecX bn = normal_part(b);
  const double diag = std::max(An.diagonal().maxCoeff(), 1e-300);
  const double delta = 1e-12 * diag;
  const MatX H = An + delta * MatX::Identity(k, k);
  VecX x = VecX::Zero(k), next(k);
  for (int round = 0; round < 50; ++round) {
    nonnegative_qp(H, bn - delta * x, 1e-15 * std::max(bn.cwiseAbs().maxCoeff(), slack), next);
    const double moved = (next - x).lpNorm<Eigen::Infinity>();
    x = next;
    // The round's proximal term shifts u_n by at most delta * moved: stop once that is rounding.
    if (delta * moved <= 1e-15 * std::max(bn.cwiseAbs().maxCoeff(), slack)) break;
  }
  for (int i = 0; i < k; ++i) l[3 * i + 2] += std::max(x[i], 0.0);
  return true;
}

// Stronge's law for a group's expansion: normal impulses p >= 0 such that each contact's normal
// impulse, applied along the straight path from the end of compression, does the work
// W_i(p) = p_i (start_i + end_i(p)) / 2 = target_i, where start is the normal velocity at the end
// of compression and end(p) = base + A_nn p the one at the end of expansion (base: the friction's
// share, held). Newton's method from `guess` (Poisson's answer), halving a step that would make an
// impulse negative or not reduce the residual. A contact with no target gets no impulse.
VecX stronge_normals(const MatX& A, const VecX& u_start, const VecX& u_base, const VecX& target,
                     const VecX& guess) {
  const int k = static_cast<int>(target.size());
  const MatX Ann = normal_block(A);
  const VecX start = normal_part(u_start), base = normal_part(u_base);
  std::vector<char> on(k);
  for (int i = 0; i < k; ++i) on[i] = target[i] > 0.0;
  auto residual = [&](const VecX& p) {
    VecX F = VecX::Zero(k);
    const VecX end = base + Ann * p;
    for (int i = 0; i < k; ++i) {
      if (on[i]) F[i] = 0.5 * p[i] * (start[i] + end[i]) - target[i];
    }
    return F;
  };
  // Each contact's work, the others' impulses held, is a parabola in its own impulse through 0
  // with a single nonnegative root: A_ii p^2 + B p - 2 target = 0, B = start + base + the
  // others' share. Jacobi rounds on those roots (all contacts at once: a mirror-symmetric group
  // stays symmetric), half-damped, bring p onto the branch where every contact separates; Newton's
  // method then polishes (from Poisson's guess it could converge to p_i = 0 on the wrong branch,
  // a contact driven into approach by the others' expansion).
  VecX p = guess;
  for (int i = 0; i < k; ++i) {
    if (!on[i]) p[i] = 0.0;
  }
  for (int round = 0; round < 200; ++round) {
    const VecX share = Ann * p;
    VecX next = p;
    for (int i = 0; i < k; ++i) {
      if (!on[i]) continue;
      const double a = Ann(i, i);
      const double B = start[i] + base[i] + share[i] - a * p[i];
      // The root, without cancellation: 4 target / (B + sqrt(...)) when B > 0.
      const double sq = std::sqrt(B * B + 8.0 * a * target[i]);
      next[i] = B > 0.0 ? 4.0 * target[i] / (B + sq) : a > 0.0 ? (sq - B) / (2.0 * a) : 0.0;
    }
    const double change = (next - p).lpNorm<Eigen::Infinity>();
    p = 0.5 * (p + next);
    if (change <= 1e-12 * std::max(p.lpNorm<Eigen::Infinity>(), 1e-300)) break;
  }
  VecX F = residual(p);
  const double scale = std::max(target.lpNorm<Eigen::Infinity>(), 1e-300);
  for (int it = 0; it < 100 && F.lpNorm<Eigen::Infinity>() > 1e-15 * scale; ++it) {
    const VecX end = base + Ann * p;
    MatX Jac = MatX::Identity(k, k);
    for (int i = 0; i < k; ++i) {
      if (!on[i]) continue;
      Jac.row(i) = 0.5 * p[i] * Ann.row(i);
      Jac(i, i) += 0.5 * (start[i] + end[i]);
    }
    VecX step = -Jac.colPivHouseholderQr().solve(F);
    for (int i = 0; i < k; ++i) {
      if (!on[i]) step[i] = 0.0;
    }
    double t = 1.0;
    VecX trial = p + step;
    VecX F_trial = residual(trial);
    while (t > 1e-6 && (trial.minCoeff() < 0.0 || F_trial.norm() >= F.norm())) {
      t *= 0.5;
      trial = p + t * step;
      F_trial = residual(trial);
    }
    if (t <= 1e-6) break;  // no progress: keep the last iterate
    p = trial;
    F = F_trial;
  }
  return p;
}

double kinetic(const std::vector<GroupBody>& bodies, const VecX& q) {
  double e = 0.0;
  for (std::size_t j = 0; j < bodies.size(); ++j) {
    const GroupBody& b = bodies[j];
    if (!(b.inv_mass > 0.0)) continue;
    const Vec3 v = q.segment<3>(6 * j), w = q.segment<3>(6 * j + 3);
    e += 0.5 * v.squaredNorm() / b.inv_mass;
    // I w from I^-1: solve rather than invert (I^-1 is symmetric positive definite).
    e += 0.5 * w.dot(b.inv_inertia_W.ldlt().solve(w));
  }
  return e;
}

}  // namespace

GroupResult resolve_group(const std::vector<GroupBody>& bodies,
                          const std::vector<GroupContact>& contacts, const GroupOptions& options) {
  const int nb = static_cast<int>(bodies.size());
  const int k = static_cast<int>(contacts.size());
  for (const GroupContact& c : contacts) {
    if (c.body1 < 0 || c.body1 >= nb || c.body2 < 0 || c.body2 >= nb || c.body1 == c.body2) {
      throw std::invalid_argument("resolve_group: a contact's bodies are out of range or equal");
    }
    if (!(std::abs(c.n_W.norm() - 1.0) <= 1e-9)) {
      throw std::invalid_argument("resolve_group: a contact normal is not a unit vector");
    }
  }
  // Generalised velocities q = (v_0, w_0, v_1, w_1, ...), M^-1 and J.
  VecX q(6 * nb);
  MatX Minv = MatX::Zero(6 * nb, 6 * nb);
  for (int j = 0; j < nb; ++j) {
    q.segment<3>(6 * j) = bodies[j].v_W;
    q.segment<3>(6 * j + 3) = bodies[j].w_W;
    Minv.block<3, 3>(6 * j, 6 * j) = Mat3::Identity() * bodies[j].inv_mass;
    Minv.block<3, 3>(6 * j + 3, 6 * j + 3) = bodies[j].inv_inertia_W;
  }
  MatX J = MatX::Zero(3 * k, 6 * nb);
  for (int i = 0; i < k; ++i) {
    const GroupContact& c = contacts[i];
    const Mat3 R = contact_frame_W(c.n_W);
    auto add = [&](int j, double sign) {
      const Vec3 r = c.point_W - bodies[j].x_W;
      // u = R^T (v + w x r) = R^T v - R^T [r]x w
      J.block<3, 3>(3 * i, 6 * j) += sign * R.transpose();
      Mat3 rx;
      rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
      J.block<3, 3>(3 * i, 6 * j + 3) += -sign * R.transpose() * rx;
    };
    add(c.body1, 1.0);
    add(c.body2, -1.0);
  }
  const MatX MinvJt = Minv * J.transpose();
  MatX A = J * MinvJt;
  A = 0.5 * (A + A.transpose());

  GroupResult out;
  out.energy_before = kinetic(bodies, q);
  auto cones = [&](VecX& l, const VecX&) {
    for (int i = 0; i < k; ++i) project_cone(l, i, contacts[i].friction);
  };

  const ScaledOperator op(A);

  // 1. Compression.
  const VecX u0 = J * q;
  VecX l_c = VecX::Zero(3 * k);
  out.iterations += apgd(op, u0, l_c, cones, options, out.converged);
  // The cone problem's conditions leave a sliding contact separating at mu |u_t| (Anitescu's
  // relaxation): a ball sliding on the cloth would leave it. Coulomb's law wants u_n = 0 there.
  // Fixed point on the shift s_i = mu_i |u_t,i|: the cone problem with b_n + s_i leaves
  // u_n + s_i >= mu_i |u_t,i| = s_i, so u_n >= 0, complementary to lambda_n (De Saxce's
  // bipotential). Each round starts from the last impulse; a round that would gain energy is not
  // taken (the relaxed answer never gains). The plain iteration contracts linearly (by about 1/2
  // a round in piles of balls: 30-40 rounds to 1e-12), so each round is extrapolated by
  // Anderson's method of depth 1 (the secant step on the residual G(s) - s; Walker & Ni 2011),
  // the shift kept >= 0; an extrapolated round that would gain energy is taken plainly instead.
  {
    double speed = 0.0;
    for (int i = 0; i < k; ++i) speed = std::max(speed, u0.segment<3>(3 * i).norm());
    VecX shift = VecX::Zero(3 * k), last_shift, last_next;
    const double ke0 = out.energy_before;
    for (int round = 0; round < options.max_shift_rounds; ++round) {
      const VecX u = A * l_c + u0;
      VecX next = VecX::Zero(3 * k);
      for (int i = 0; i < k; ++i) {
        next[3 * i + 2] = contacts[i].friction * u.segment<2>(3 * i).norm();
      }
      const VecX residual = next - shift;
      if (residual.lpNorm<Eigen::Infinity>() <= options.tolerance * 1e2 * speed) break;
      VecX extrapolated = next;
      if (round > 0) {
        const VecX change = residual - (last_next - last_shift);
        const double squared = change.squaredNorm();
        if (squared > 0.0) {
          extrapolated =
              (next - (residual.dot(change) / squared) * (next - last_next)).cwiseMax(0.0);
        }
      }
      last_shift = shift;
      last_next = next;
      // A round from the shift `to`, taken unless it would gain energy.
      auto take = [&](const VecX& to) {
        VecX l_try = l_c;
        bool ok = true;
        out.iterations += apgd(op, u0 + to, l_try, cones, options, ok);
        if (kinetic(bodies, q + MinvJt * l_try) > ke0) return false;
        shift = to;
        l_c = l_try;
        out.converged = out.converged && ok;
        return true;
      };
      if (!take(extrapolated) && (extrapolated == next || !take(next))) break;
      out.shift_rounds = round + 1;
    }
  }
  VecX q_c = q + MinvJt * l_c;

  // 2. Expansion: the normal impulses the law asks; friction within their disks.
  VecX l_e = VecX::Zero(3 * k);
  bool any_restitution = false;
  for (int i = 0; i < k; ++i) {
    l_e[3 * i + 2] = contacts[i].restitution * l_c[3 * i + 2];
    any_restitution = any_restitution || l_e[3 * i + 2] > 0.0;
  }
  VecX q_e = q_c;
  if (any_restitution) {
    // Poisson: p_e,n = e p_c,n. Stronge: p_e,n such that each contact's normal force does
    // e^2 times the work it absorbed in compression (see stronge_normals).
    VecX pn(k);
    for (int i = 0; i < k; ++i) pn[i] = l_e[3 * i + 2];
    auto disks = [&](VecX& l, const VecX& d) {
      for (int i = 0; i < k; ++i) {
        const double n = pn[i] / d[3 * i];
        project_disk(l, i, contacts[i].friction * n, n);
      }
    };
    const VecX u_c = J * q_c;
    out.iterations += apgd(op, u_c, l_e, disks, options, out.converged);
    if (options.law == RestitutionLaw::kStronge) {
      VecX target(k);
      for (int i = 0; i < k; ++i) {
        // Along the straight impulse path 0 -> l_c the normal velocity is linear in the path
        // parameter: the work is the impulse times the mean of the end velocities.
        const double w_c = 0.5 * l_c[3 * i + 2] * (u0[3 * i + 2] + u_c[3 * i + 2]);
        const double e = contacts[i].restitution;
        target[i] = e * e * std::max(-w_c, 0.0);
      }
      for (int round = 0; round < options.max_stronge_rounds; ++round) {
        // The friction impulses held, the normal impulses that meet the targets.
        VecX tangential = l_e;
        for (int i = 0; i < k; ++i) tangential[3 * i + 2] = 0.0;
        const VecX end_without_normals = u_c + A * tangential;
        const VecX next = stronge_normals(A, u_c, end_without_normals, target, pn);
        const double change = (next - pn).lpNorm<Eigen::Infinity>();
        pn = next;
        for (int i = 0; i < k; ++i) l_e[3 * i + 2] = pn[i];
        out.iterations += apgd(op, u_c, l_e, disks, options, out.converged);
        ++out.stronge_rounds;
        if (change <= 1e-13 * std::max(pn.lpNorm<Eigen::Infinity>(), 1e-300)) break;
      }
    }
    // The energy bound: KE(s) = KE_c + s l_e.J q_c + s^2 l_e.A.l_e / 2 <= KE_before.
    const double ke_c = kinetic(bodies, q_c);
    const double lin = l_e.dot(J * q_c), quad = 0.5 * l_e.dot(A * l_e);
    auto ke = [&](double s) { return ke_c + s * lin + s * s * quad; };
    // A moving fixed-path (kinematic) body does work on the group: no bound to keep then.
    bool driven = false;
    for (const GroupBody& b : bodies) {
      driven = driven || (!(b.inv_mass > 0.0) && (b.v_W.squaredNorm() + b.w_W.squaredNorm() > 0.0));
    }
    double s = 1.0;
    if (!driven && ke(1.0) > out.energy_before) {
      // The larger root of quad s^2 + lin s + (ke_c - E0) = 0 in [0, 1].
      const double c0 = ke_c - out.energy_before;
      const double disc = lin * lin - 4.0 * quad * c0;
      s = quad > 0.0 && disc >= 0.0 ? (-lin + std::sqrt(disc)) / (2.0 * quad) : 0.0;
      s = std::clamp(s, 0.0, 1.0);
      while (s > 0.0 && ke(s) > out.energy_before) s = std::nextafter(s, 0.0) * (1.0 - 1e-15);
    }
    out.restitution_scale = s;
    l_e *= s;
    q_e = q_c + MinvJt * l_e;
  }

  // 3. No contact left approaching: the frictionless plastic impulse on what still approaches
  // (the cone problems stop at a tolerance; ill-conditioned groups may leave a residual approach).
  VecX l_p = VecX::Zero(3 * k);
  // A contact's floor (a microcollision's rebound speed) is met here too: the LCP on u_n - floor.
  VecX u_e = J * q_e;
  double speed = 0.0;
  for (int i = 0; i < k; ++i) {
    speed = std::max(speed, u_e.segment<3>(3 * i).norm());
    u_e[3 * i + 2] -= contacts[i].min_separation;
  }
  if (normal_lcp(A, u_e, 1e-13 * speed, l_p)) out.final_push = true;
  const VecX l = l_c + l_e + l_p;
  const VecX q_after = q + MinvJt * l;
  const VecX u_after = J * q_after;
  out.normal_velocity.resize(k);
  for (int i = 0; i < k; ++i) out.normal_velocity[i] = u_after[3 * i + 2];

  out.impulse_W.resize(k);
  for (int i = 0; i < k; ++i) {
    out.impulse_W[i] = contact_frame_W(contacts[i].n_W) * Vec3(l.segment<3>(3 * i));
  }
  out.v_W.resize(nb);
  out.w_W.resize(nb);
  for (int j = 0; j < nb; ++j) {
    const bool dynamic = bodies[j].inv_mass > 0.0;
    out.v_W[j] = dynamic ? Vec3(q_after.segment<3>(6 * j)) : bodies[j].v_W;
    out.w_W[j] = dynamic ? Vec3(q_after.segment<3>(6 * j + 3)) : bodies[j].w_W;
  }
  out.energy_after = kinetic(bodies, q_after);
  return out;
}

Vec3 linear_momentum(const std::vector<GroupBody>& bodies, const std::vector<Vec3>& v_W) {
  Vec3 p = Vec3::Zero();
  for (std::size_t j = 0; j < bodies.size(); ++j) {
    if (bodies[j].inv_mass > 0.0) p += v_W[j] / bodies[j].inv_mass;
  }
  return p;
}

}  // namespace palpable
