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
  double theta = 1.0;
  // Scale of the impulses: the unconstrained frictionless size |b| / L.
  const double scale = std::max(b.norm() / lipschitz, 1e-300);
  for (int it = 1; it <= options.max_iterations; ++it) {
    const VecX g = A * y + b;
    VecX x = y - step * g;
    project(x);
    // Stationarity at x: the projected-gradient step's length.
    VecX r = x - step * (A * x + b);
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

// APGD on the problem scaled per contact: l = D m with D = diag(d_i I3), d_i = 1 / sqrt of the
// mean diagonal of contact i's block of A. A uniform scale of a contact's block maps its cone (or
// disk, with its radius and normal scaled alike) onto itself, so the projections are unchanged in
// form, while the scaled operator D A D is far better conditioned where masses and lever arms
// differ by orders of magnitude. `project_scaled(m, d)` projects in the scaled variables.
template <class Project>
int apgd(const MatX& A, const VecX& b, VecX& l, Project project_scaled,
         const GroupOptions& options, bool& converged) {
  const int k = static_cast<int>(b.size() / 3);
  VecX d(3 * k);
  for (int i = 0; i < k; ++i) {
    const double mean = A.block<3, 3>(3 * i, 3 * i).trace() / 3.0;
    d.segment<3>(3 * i).setConstant(mean > 0.0 ? 1.0 / std::sqrt(mean) : 1.0);
  }
  const MatX As = d.asDiagonal() * A * d.asDiagonal();
  const VecX bs = d.cwiseProduct(b);
  const double lipschitz = std::max(
      Eigen::SelfAdjointEigenSolver<MatX>(As, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff(),
      1e-300);
  VecX m = l.cwiseQuotient(d);
  const int iterations = apgd_scaled(
      As, bs, lipschitz, m, [&](VecX& x) { project_scaled(x, d); }, options, converged);
  l = d.cwiseProduct(m);
  return iterations;
}

// The frictionless plastic LCP on the normals: l_n >= 0, u_n = (A l + b)_n >= 0, l_n u_n = 0,
// by enumerating active sets, smallest first (the velocities are unique; A may be singular).
// Returns false (l untouched) if nothing approaches by more than `slack`.
bool normal_lcp(const MatX& A, const VecX& b, double slack, VecX& l) {
  const int k = static_cast<int>(b.size() / 3);
  std::vector<int> approaching;
  for (int i = 0; i < k; ++i) {
    if (b[3 * i + 2] < -slack) approaching.push_back(i);
  }
  if (approaching.empty()) return false;
  MatX An(k, k);
  VecX bn(k);
  for (int i = 0; i < k; ++i) {
    bn[i] = b[3 * i + 2];
    for (int j = 0; j < k; ++j) An(i, j) = A(3 * i + 2, 3 * j + 2);
  }
  const double scale = std::max(bn.cwiseAbs().maxCoeff(), 1e-300);
  VecX best = VecX::Zero(k);
  double best_violation = kInfinity;
  const int subsets = k <= 16 ? (1 << k) : 0;
  for (int size = 1; size <= k && best_violation > 0.0; ++size) {
    for (int mask = 1; mask < subsets; ++mask) {
      if (__builtin_popcount(static_cast<unsigned>(mask)) != size) continue;
      std::vector<int> act;
      for (int i = 0; i < k; ++i) {
        if (mask & (1 << i)) act.push_back(i);
      }
      const int m = static_cast<int>(act.size());
      MatX Aa(m, m);
      VecX ba(m);
      for (int x = 0; x < m; ++x) {
        ba[x] = bn[act[x]];
        for (int y = 0; y < m; ++y) Aa(x, y) = An(act[x], act[y]);
      }
      const VecX la = Aa.completeOrthogonalDecomposition().solve(-ba);
      VecX ln = VecX::Zero(k);
      for (int x = 0; x < m; ++x) ln[act[x]] = la[x];
      const VecX u = An * ln + bn;
      const double violation = std::max({0.0, -ln.minCoeff() * 1e-3, -u.minCoeff() / scale});
      if (violation < best_violation) {
        best_violation = violation;
        best = ln;
      }
      if (violation <= 1e-12) {
        best_violation = 0.0;
        break;
      }
    }
  }
  for (int i = 0; i < k; ++i) l[3 * i + 2] += std::max(best[i], 0.0);
  return true;
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

  // 1. Compression.
  const VecX u0 = J * q;
  VecX l_c = VecX::Zero(3 * k);
  out.iterations += apgd(A, u0, l_c, cones, options, out.converged);
  // The cone problem's conditions leave a sliding contact separating at mu |u_t| (Anitescu's
  // relaxation): a ball sliding on the cloth would leave it. Coulomb's law wants u_n = 0 there.
  // Fixed point on the shift s_i = mu_i |u_t,i|: the cone problem with b_n + s_i leaves
  // u_n + s_i >= mu_i |u_t,i| = s_i, so u_n >= 0, complementary to lambda_n (De Saxce's
  // bipotential). Each round starts from the last impulse; a round that would gain energy is not
  // taken (the relaxed answer never gains).
  {
    double speed = 0.0;
    for (int i = 0; i < k; ++i) speed = std::max(speed, u0.segment<3>(3 * i).norm());
    VecX shift = VecX::Zero(3 * k);
    const double ke0 = out.energy_before;
    for (int round = 0; round < options.max_shift_rounds; ++round) {
      const VecX u = A * l_c + u0;
      VecX next = VecX::Zero(3 * k);
      for (int i = 0; i < k; ++i) {
        next[3 * i + 2] = contacts[i].friction * u.segment<2>(3 * i).norm();
      }
      if ((next - shift).lpNorm<Eigen::Infinity>() <= options.tolerance * 1e2 * speed) break;
      shift = next;
      VecX l_try = l_c;
      bool ok = true;
      const int used = apgd(A, u0 + shift, l_try, cones, options, ok);
      out.iterations += used;
      if (kinetic(bodies, q + MinvJt * l_try) > ke0) break;
      out.shift_rounds = round + 1;
      l_c = l_try;
      out.converged = out.converged && ok;
    }
  }
  VecX q_c = q + MinvJt * l_c;

  // 2. Expansion (Poisson): the normal impulses e lambda_c,n; friction within their disks.
  VecX l_e = VecX::Zero(3 * k);
  bool any_restitution = false;
  for (int i = 0; i < k; ++i) {
    l_e[3 * i + 2] = contacts[i].restitution * l_c[3 * i + 2];
    any_restitution = any_restitution || l_e[3 * i + 2] > 0.0;
  }
  VecX q_e = q_c;
  if (any_restitution) {
    auto disks = [&](VecX& l, const VecX& d) {
      for (int i = 0; i < k; ++i) {
        const double pn = contacts[i].restitution * l_c[3 * i + 2] / d[3 * i];
        project_disk(l, i, contacts[i].friction * pn, pn);
      }
    };
    out.iterations += apgd(A, J * q_c, l_e, disks, options, out.converged);
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
