#include "impulse/contact_dynamics.hpp"

#include "impulse/contact_torque.hpp"
#include "impulse/lcp.hpp"

#include "core/convex_polygon.hpp"

#include <glpk.h>
#include <Eigen/Dense>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

namespace palpable {

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using MatX = Eigen::MatrixXd;
using VecX = Eigen::VectorXd;

// The motion of one side of a contact at this instant: velocities, and for a known body its
// accelerations (an unknown body's are what the problem solves for).
struct Side {
  int body = -1;  // index of a HeldBody, -1: known
  Vec3 x = Vec3::Zero(), v = Vec3::Zero(), w = Vec3::Zero();
  Vec3 a = Vec3::Zero(), alpha = Vec3::Zero();  // known sides only
};

Side mover_side(const HeldContact& c, const std::vector<HeldBody>& bodies) {
  Side s;
  s.body = c.mover;
  if (c.mover >= 0) {
    const HeldBody& b = bodies[static_cast<std::size_t>(c.mover)];
    s.x = b.x_W, s.v = b.v_W, s.w = b.w_W;
  } else {
    s.x = c.mover_known.x_W, s.v = c.mover_known.v_W, s.w = c.mover_known.w_W;
    s.a = c.mover_known.a_W, s.alpha = c.mover_known.alpha_W;
  }
  return s;
}

Side support_side(const HeldContact& c, const std::vector<HeldBody>& bodies) {
  Side s;
  s.body = c.support;
  if (c.support >= 0) {
    const HeldBody& b = bodies[static_cast<std::size_t>(c.support)];
    s.x = b.x_W, s.v = b.v_W, s.w = b.w_W;
  } else {
    s.x = c.support_known.x_W, s.v = c.support_known.v_W, s.w = c.support_known.w_W;
    s.a = c.support_known.a_W, s.alpha = c.support_known.alpha_W;
  }
  return s;
}

// One row of the problem: a scalar relative acceleration that must vanish, as J . acc + bias,
// and the wrench its multiplier applies. Up to two bodies (mover, support) take part.
struct Row {
  int contact = 0;
  int body[2] = {-1, -1};
  Vec6 J[2] = {Vec6::Zero(), Vec6::Zero()};   // on (a, alpha) of body[k]
  Vec6 W[2] = {Vec6::Zero(), Vec6::Zero()};   // (force, torque) per unit multiplier
  Vec6 MW[2] = {Vec6::Zero(), Vec6::Zero()};  // the accelerations W gives body[k] (M^-1 W)
  double bias = 0.0;
};

Vec6 wrench(const Vec3& f, const Vec3& tau) {
  Vec6 w;
  w << f, tau;
  return w;
}

// The velocity of the point at r (from the side's centre) moving with that side.
Vec3 point_velocity(const Side& side, const Vec3& r) {
  return side.v + side.w.cross(r);
}

// The kinematics of a contact at this instant.
struct Kinematics {
  Side m, s;
  Vec3 r_m, r_s;  // contact point from each centre
  Vec3 slip;      // s = u_mover - u_support at the contact
  Vec3 n_dot;     // dn/dt = w_support x n
  // ds/dt = Jm (a_m, alpha_m) + Js (a_s, alpha_s) + bias (3 x 6 each).
  Eigen::Matrix<double, 3, 6> Jm, Js;
  Vec3 slip_bias;
  Vec3 dw;  // relative angular velocity
};

Kinematics kinematics(const HeldContact& c, const std::vector<HeldBody>& bodies) {
  Kinematics k;
  k.m = mover_side(c, bodies);
  k.s = support_side(c, bodies);
  k.r_m = c.c_W - k.m.x;
  k.r_s = c.c_W - k.s.x;
  const Vec3 u_m = point_velocity(k.m, k.r_m);
  const Vec3 u_s = point_velocity(k.s, k.r_s);
  k.slip = u_m - u_s;
  k.n_dot = c.has_n_dot ? c.n_dot_W : Vec3(k.s.w.cross(c.n_W));
  k.dw = k.m.w - k.s.w;
  const Mat3 I = Mat3::Identity();
  // The mover's contact point: a material point of a polyhedron, whose acceleration is
  // a + alpha x r + w x (w x r); or a rounded body's point c = q - R n under its core point q
  // (q - x = r_q material: a sphere's centre, r_q = 0; a point of a lying cylinder's axis), which
  // rolls over its surface: d/dt (v + w x (r_q - R n)) = a + alpha x (r_q - R n) + w x (w x r_q)
  // - R w x dn/dt.
  Vec3 p_dot;  // velocity of the contact point itself
  k.Jm.leftCols<3>() = I;
  if (c.sphere_radius > 0.0) {
    const Vec3& r_q = c.core_offset_W;
    k.Jm.rightCols<3>() = c.sphere_radius * skew(c.n_W) - skew(r_q);
    k.slip_bias = k.m.w.cross(k.m.w.cross(r_q)) - c.sphere_radius * k.m.w.cross(k.n_dot);
    p_dot = k.m.v + k.m.w.cross(r_q) - c.sphere_radius * k.n_dot;
  } else if (c.curved) {
    // A point of a curved surface moving over it at s_dot: d/dt (v + w x r) along the moving
    // point is a + alpha x r + w x (w x r) + w x s_dot.
    const Vec3 s_dot = c.curvature_W * (k.m.w.cross(c.n_W) - k.n_dot);
    k.Jm.rightCols<3>() = -skew(k.r_m);
    k.slip_bias = k.m.w.cross(k.m.w.cross(k.r_m)) + k.m.w.cross(s_dot);
    p_dot = u_m + s_dot;
  } else {
    // A material point, or one running along the mover's edge at mover_slide_W: d/dt (v + w x r)
    // along it is a + alpha x r + w x (w x r) + w x slide.
    k.Jm.rightCols<3>() = -skew(k.r_m);
    k.slip_bias = k.m.w.cross(k.m.w.cross(k.r_m)) + k.m.w.cross(c.mover_slide_W);
    p_dot = u_m + c.mover_slide_W;
  }
  // The support's surface point under the moving contact point: its material acceleration, plus
  // w_s x (p_dot - u_s) for the point moving over a turning surface.
  k.Js.leftCols<3>() = -I;
  k.Js.rightCols<3>() = skew(k.r_s);
  k.slip_bias -= k.s.w.cross(k.s.w.cross(k.r_s)) + k.s.w.cross(p_dot - u_s);
  // Known sides: their accelerations go into the bias.
  if (k.m.body < 0) k.slip_bias += k.Jm.leftCols<3>() * k.m.a + k.Jm.rightCols<3>() * k.m.alpha;
  if (k.s.body < 0) k.slip_bias += k.Js.leftCols<3>() * k.s.a + k.Js.rightCols<3>() * k.s.alpha;
  return k;
}

Vec3 in_plane(const HeldContact& c, const Vec2& v) {
  return v.x() * c.t1_W + v.y() * c.t2_W;
}
Vec2 plane_coords(const HeldContact& c, const Vec3& v) {
  return Vec2(v.dot(c.t1_W), v.dot(c.t2_W));
}

// The centre of pressure c + n x M / N on the inner side of edge e of a polygon patch, as a
// linear inequality a . (N, M1, M2) >= 0, unit in the edge's inward normal (with N d = (-M2, M1):
// inward . (N d - N p0) >= 0). False for a zero-length edge (a repeated vertex), which bounds
// nothing.
bool polygon_edge_inequality(const HeldContact& c, std::size_t e, Vec3& a) {
  const Vec2& p0 = c.polygon[e];
  const Vec2 edge = c.polygon[(e + 1) % c.polygon.size()] - p0;
  const double length = edge.norm();
  if (!(length > 0.0)) return false;
  const Vec2 inward = Vec2(-edge.y(), edge.x()) / length;
  a = Vec3(-inward.dot(p0), inward.y(), -inward.x());
  return true;
}

// The length over which a contact's relative spin about n is measured: the patch's mean radius
// (r_eff), a segment's length, a sphere's radius.
double turning_size(const HeldContact& c) {
  switch (c.patch) {
    case PatchKind::kPolygon: return c.friction > 0.0 ? c.torsion_arm / c.friction : 0.0;
    case PatchKind::kSegment: return c.segment_hi - c.segment_lo;
    case PatchKind::kPoint: return point_size(c);
  }
  return 0.0;
}

// The axis of a segment's held rocking, m = n x s, and its rate.
Vec3 segment_axis(const HeldContact& c) {
  return c.n_W.cross(c.segment_W);
}
Vec3 segment_axis_rate(const HeldContact& c, const Kinematics& k) {
  return k.n_dot.cross(c.segment_W) + c.n_W.cross(k.m.w.cross(c.segment_W));
}

class Assembly {
 public:
  Assembly(const std::vector<HeldBody>& bodies, const std::vector<HeldContact>& contacts,
           bool velocity_level = false)
      : bodies_(bodies), contacts_(contacts), velocity_level_(velocity_level) {
    kinematics_.resize(contacts.size());
    rows_.reserve(6 * contacts.size());
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      if (contacts[i].active) add_contact(static_cast<int>(i));
    }
  }

  // The velocity-level problem: rows for each active contact's normal and rocking, and for its
  // friction, torsion and rolling where they are still; impulses of least norm that zero them.
  static double project(std::vector<HeldBody>& bodies, const std::vector<HeldContact>& contacts,
                        double still, double separation, std::vector<int>* separating) {
    std::vector<HeldContact> held = contacts;
    const std::vector<HeldContactMotion> now = held_velocities(bodies, contacts);
    for (std::size_t i = 0; i < held.size(); ++i) {
      HeldContact& c = held[i];
      const HeldContactMotion& m = now[i];
      // Only what is still is held at the velocity level; what slides keeps its motion (no
      // sliding couplings here: the impulses are small by construction).
      c.sticks = c.slip_stopped || plane_coords(c, m.slip_W).norm() <= still;
      c.spin_sticks = c.spin_stopped || std::abs(m.dw_W.dot(c.n_W)) * turning_size(c) <= still;
      c.roll_sticks = c.roll_stopped || plane_coords(c, m.dw_W).norm() * point_size(c) <= still;
      if (!c.sticks) c.friction = 0.0;
      if (!c.spin_sticks) c.torsion_arm = 0.0;
      if (!c.roll_sticks) c.rolling_resistance = 0.0;
    }
    // A contact already separating faster than `separation` (an impact sent its bodies apart)
    // is left out and reported: it lets go.
    for (std::size_t i = 0; i < held.size(); ++i) {
      if (held[i].active && now[i].slip_W.dot(held[i].n_W) > separation) {
        held[i].active = false;
        if (separating) separating->push_back(static_cast<int>(i));
      }
    }
    auto a = std::make_unique<Assembly>(bodies, held, /*velocity_level=*/true);
    {
      const Eigen::Index m = static_cast<Eigen::Index>(a->rows_.size());
      if (m == 0) return 0.0;
    }
    VecX p;
    {
      const Eigen::Index m = static_cast<Eigen::Index>(a->rows_.size());
      const MatX A = a->coupling_matrix();
      VecX rhs(m);
      for (Eigen::Index i = 0; i < m; ++i) rhs(i) = -a->rows_[static_cast<std::size_t>(i)].bias;
      p = Eigen::CompleteOrthogonalDecomposition<MatX>(A).solve(rhs);
      if (!p.allFinite()) return 0.0;
    }
    const Assembly& asm_ = *a;
    const Eigen::Index m = static_cast<Eigen::Index>(asm_.rows_.size());
    double before = 0.0, after = 0.0;
    for (const HeldBody& b : bodies) before += kinetic(b);
    for (Eigen::Index j = 0; j < m; ++j) {
      const Row& r = asm_.rows_[static_cast<std::size_t>(j)];
      for (int q = 0; q < 2; ++q) {
        if (r.body[q] < 0) continue;
        HeldBody& b = bodies[static_cast<std::size_t>(r.body[q])];
        const Vec6 dv = p(j) * r.MW[q];
        b.v_W += dv.head<3>();
        b.w_W += dv.tail<3>();
      }
    }
    for (const HeldBody& b : bodies) after += kinetic(b);
    return after - before;
  }

  // `feasible_forces`: where the system is redundant (a face on four coplanar corners, a box on
  // two, boxes side by side) and the least-norm multipliers break an inequality (a contact that
  // pulls, a centre of pressure outside its patch, friction beyond its cone), the multipliers are
  // moved within the redundancy to meet every inequality if they can (feasible_multipliers). The
  // accelerations do not change; only which forces carry them.
  HeldSolution solve(bool feasible_forces = false) const {
    HeldSolution out;
    const std::size_t nb = bodies_.size();
    out.a_W.assign(nb, Vec3::Zero());
    out.alpha_W.assign(nb, Vec3::Zero());
    // Free accelerations: gravity, and the gyroscopic term I alpha = -w x I w.
    std::vector<Vec6> free(nb);
    for (std::size_t b = 0; b < nb; ++b) {
      const HeldBody& body = bodies_[b];
      free[b] << body.force_W / body.mass,
          body.inv_inertia_W * (-body.w_W.cross(body.inertia_W * body.w_W));
    }
    const Eigen::Index m = static_cast<Eigen::Index>(rows_.size());
    VecX lambda = VecX::Zero(m);
    if (m > 0) {
      const MatX A = coupling_matrix();
      VecX rhs(m);
      for (Eigen::Index i = 0; i < m; ++i) {
        const Row& ri = rows_[static_cast<std::size_t>(i)];
        double value = ri.bias;
        for (int p = 0; p < 2; ++p) {
          if (ri.body[p] >= 0) value += ri.J[p].dot(free[static_cast<std::size_t>(ri.body[p])]);
        }
        rhs(i) = -value;
      }
      if (!A.allFinite() || !rhs.allFinite()) {
        out.status = HeldStatus::kNonFinite;
        return out;
      }
      // Kept from one solve to the next (of the same island, mostly the same size): its storage
      // is allocated once rather than at every solve.
      thread_local Eigen::CompleteOrthogonalDecomposition<MatX> cod;
      cod.compute(A);
      lambda = cod.solve(rhs);
      const double scale = rhs.norm() + A.norm() * lambda.norm();
      out.residual = scale > 0.0 ? (A * lambda - rhs).norm() / scale : 0.0;
      if (!lambda.allFinite()) {
        out.status = HeldStatus::kNonFinite;
        return out;
      }
      if (out.residual > 1e-8) out.status = HeldStatus::kInconsistent;
      if (out.status == HeldStatus::kOk && cod.rank() < m) nearest_feasible(cod, lambda);
      if (feasible_forces && out.status == HeldStatus::kOk) feasible_multipliers(lambda);
    }
    // Accelerations.
    std::vector<Vec6> acc = free;
    for (Eigen::Index j = 0; j < m; ++j) {
      const Row& r = rows_[static_cast<std::size_t>(j)];
      for (int p = 0; p < 2; ++p) {
        if (r.body[p] >= 0) {
          acc[static_cast<std::size_t>(r.body[p])] += lambda(j) * r.MW[p];
        }
      }
    }
    for (std::size_t b = 0; b < nb; ++b) {
      out.a_W[b] = acc[b].head<3>();
      out.alpha_W[b] = acc[b].tail<3>();
    }
    // Forces and relative motion per contact.
    out.forces.assign(contacts_.size(), HeldContactForces{});
    out.motion.assign(contacts_.size(), HeldContactMotion{});
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      const HeldContact& c = contacts_[i];
      const Kinematics k = kinematics_[i] ? *kinematics_[i] : kinematics(c, bodies_);
      HeldContactMotion& mo = out.motion[i];
      mo.slip_W = k.slip;
      mo.dw_W = k.dw;
      Vec6 am = Vec6::Zero(), as = Vec6::Zero();
      if (k.m.body >= 0) am = acc[static_cast<std::size_t>(k.m.body)];
      if (k.s.body >= 0) as = acc[static_cast<std::size_t>(k.s.body)];
      mo.slip_rate_W = k.slip_bias;
      if (k.m.body >= 0) mo.slip_rate_W += k.Jm * am;
      if (k.s.body >= 0) mo.slip_rate_W += k.Js * as;
      const Vec3 alpha_m = k.m.body >= 0 ? Vec3(am.tail<3>()) : k.m.alpha;
      const Vec3 alpha_s = k.s.body >= 0 ? Vec3(as.tail<3>()) : k.s.alpha;
      mo.dalpha_W = alpha_m - alpha_s;
      mo.roll_rate_W = mo.dalpha_W - k.dw.dot(c.n_W) * k.n_dot;
      if (!c.active) continue;
      HeldContactForces& f = out.forces[i];
      const Layout& l = layout_[i];
      f.normal = lambda(l.normal);
      if (c.patch == PatchKind::kPolygon) {
        f.moment = Vec2(lambda(l.moment), lambda(l.moment + 1));
      } else if (c.patch == PatchKind::kSegment) {
        // The moment about m = n x s, reported in (t1, t2).
        const Vec3 M = lambda(l.moment) * segment_axis(c);
        f.moment = Vec2(M.dot(c.t1_W), M.dot(c.t2_W));
      }
      if (l.friction >= 0) {
        f.friction = Vec2(lambda(l.friction), lambda(l.friction + 1));
      } else if (!c.sticks) {
        f.friction = -c.friction * f.normal * c.slip_dir;
      }
      if (l.torsion >= 0) {
        f.torsion = lambda(l.torsion);
      } else if (!c.spin_sticks) {
        f.torsion = -c.torsion_arm * f.normal * c.spin_sign;
      }
      if (l.rolling >= 0) {
        f.rolling = Vec2(lambda(l.rolling), lambda(l.rolling + 1));
      } else if (!c.roll_sticks && c.rolling_resistance > 0.0) {
        f.rolling = -c.rolling_resistance * f.normal * c.roll_dir;
      }
      // Centre of pressure c + n x M / N.
      if (f.normal > 0.0) f.centre_of_pressure = Vec2(-f.moment.y(), f.moment.x()) / f.normal;
    }
    return out;
  }

 private:
  static double kinetic(const HeldBody& b) {
    return 0.5 * b.mass * b.v_W.squaredNorm() + 0.5 * b.w_W.dot(b.inertia_W * b.w_W);
  }
  // A_ij: row i's value per unit multiplier of row j, the sum over the bodies both rows act on
  // of J_i . M^-1 W_j. Gathered body by body: two rows are coupled only through a body they
  // share, and in an island of many bodies most pairs of rows share none. (Two rows share at
  // most two bodies, and a sum of two terms does not depend on their order.)
  MatX coupling_matrix() const {
    const Eigen::Index m = static_cast<Eigen::Index>(rows_.size());
    MatX A = MatX::Zero(m, m);
    // The rows acting on each body, with the side (0 mover, 1 support) it takes in each: body b's
    // are on[begin[b] .. begin[b + 1]), in the order of the rows.
    const std::size_t nb = bodies_.size();
    std::vector<std::size_t> begin(nb + 1, 0);
    for (const Row& r : rows_) {
      for (int q = 0; q < 2; ++q) {
        if (r.body[q] >= 0) ++begin[static_cast<std::size_t>(r.body[q]) + 1];
      }
    }
    for (std::size_t b = 0; b < nb; ++b) begin[b + 1] += begin[b];
    std::vector<std::pair<Eigen::Index, int>> on(begin[nb]);
    std::vector<std::size_t> next(begin.begin(), begin.end() - 1);
    for (Eigen::Index j = 0; j < m; ++j) {
      const Row& r = rows_[static_cast<std::size_t>(j)];
      for (int q = 0; q < 2; ++q) {
        if (r.body[q] >= 0) on[next[static_cast<std::size_t>(r.body[q])]++] = {j, q};
      }
    }
    for (std::size_t b = 0; b < nb; ++b) {
      for (std::size_t u = begin[b]; u < begin[b + 1]; ++u) {
        const auto [i, p] = on[u];
        const Vec6& J = rows_[static_cast<std::size_t>(i)].J[p];
        for (std::size_t v = begin[b]; v < begin[b + 1]; ++v) {
          const auto [j, q] = on[v];
          A(i, j) += J.dot(rows_[static_cast<std::size_t>(j)].MW[q]);
        }
      }
    }
    return A;
  }

  struct Layout {
    Eigen::Index normal = -1, moment = -1, friction = -1, torsion = -1, rolling = -1;
  };

  // One linear inequality on the multipliers: sum of coefficient * lambda(index) >= 0.
  using Inequality = std::vector<std::pair<Eigen::Index, double>>;

  // The inequalities of every active contact, as worst_violation judges them: N >= 0; the
  // centre of pressure within the patch (linear in N and the moments); sticking friction,
  // torsion and rolling within their bounds, the friction and rolling cones as inscribed 16-gons
  // (meeting the polygon meets the cone).
  std::vector<Inequality> inequalities() const {
    constexpr int kSides = 16;
    const double inscribed = std::cos(M_PI / kSides);
    std::vector<Inequality> out;
    auto cone = [&](Eigen::Index normal, Eigen::Index first, double bound) {
      for (int j = 0; j < kSides; ++j) {
        const double angle = 2.0 * M_PI * j / kSides;
        out.push_back({{normal, bound * inscribed},
                       {first, -std::cos(angle)},
                       {first + 1, -std::sin(angle)}});
      }
    };
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      const HeldContact& c = contacts_[i];
      if (!c.active) continue;
      const Layout& l = layout_[i];
      out.push_back({{l.normal, 1.0}});
      if (c.patch == PatchKind::kPolygon) {
        Vec3 a;
        for (std::size_t e = 0; e < c.polygon.size(); ++e) {
          if (!polygon_edge_inequality(c, e, a)) continue;
          out.push_back({{l.normal, a.x()}, {l.moment, a.y()}, {l.moment + 1, a.z()}});
        }
      } else if (c.patch == PatchKind::kSegment) {
        // The centre of pressure -M / N within [lo, hi].
        out.push_back({{l.normal, -c.segment_lo}, {l.moment, -1.0}});
        out.push_back({{l.normal, c.segment_hi}, {l.moment, 1.0}});
      }
      if (l.friction >= 0) cone(l.normal, l.friction, c.friction);
      if (l.torsion >= 0) {
        out.push_back({{l.normal, c.torsion_arm}, {l.torsion, -1.0}});
        out.push_back({{l.normal, c.torsion_arm}, {l.torsion, 1.0}});
      }
      if (l.rolling >= 0) cone(l.normal, l.rolling, c.rolling_resistance);
    }
    return out;
  }

  // Moves `lambda` by a multiplier combination that applies no net wrench to any body (so the
  // accelerations stay, and every row's value) until every inequality holds, if one does: the
  // linear programme "maximise the least margin t, capped at 1 % of the largest normal force"
  // over that null space, by GLPK's simplex; a margin of -1e-9 of that force is rounding (a
  // margin that is zero in every solution: a side contact that carries nothing). Returns
  // whether lambda changed.
  bool feasible_multipliers(VecX& lambda) const {
    const Eigen::Index m = lambda.size();
    const std::vector<Inequality> g = inequalities();
    double scale = 0.0;
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      if (contacts_[i].active) scale = std::max(scale, std::abs(lambda(layout_[i].normal)));
    }
    if (!(scale > 0.0)) return false;
    auto value = [](const Inequality& row, const VecX& x) {
      double sum = 0.0;
      for (const auto& [index, coefficient] : row) sum += coefficient * x(index);
      return sum;
    };
    auto norm = [](const Inequality& row) {
      double sum = 0.0;
      for (const auto& entry : row) sum += entry.second * entry.second;
      return std::sqrt(sum);
    };
    // GLPK is given finite numbers only (it stops the process on some invalid input).
    if (!lambda.allFinite()) return false;
    bool violated = false;
    for (const Inequality& row : g) {
      const double v = value(row, lambda);
      if (!std::isfinite(v)) return false;
      violated = violated || v < 0.0;
    }
    if (!violated) return false;
    // The null space of the wrench map: lambda -> the net wrench on each body.
    const MatX B = wrench_map();
    Eigen::ColPivHouseholderQR<MatX> qr(B.transpose());
    const Eigen::Index rank = qr.rank();
    const Eigen::Index k = m - rank;
    if (k == 0) return false;
    // Q's last k columns: Q applied to them alone (Q has only as many reflectors as B has rows).
    MatX Z = MatX::Zero(m, k);
    Z.bottomRows(k).setIdentity();
    Z.applyOnTheLeft(qr.householderQ());
    if (!Z.allFinite()) return false;
    // Columns y (k, free) and t (<= 1 % of the largest N); rows: (g Z) y - |g| t >= -g lambda.
    glp_prob* lp = glp_create_prob();
    glp_set_obj_dir(lp, GLP_MAX);
    const int rows = static_cast<int>(g.size());
    const int cols = static_cast<int>(k) + 1;
    glp_add_rows(lp, rows);
    glp_add_cols(lp, cols);
    for (int c = 1; c < cols; ++c) glp_set_col_bnds(lp, c, GLP_FR, 0.0, 0.0);
    glp_set_col_bnds(lp, cols, GLP_UP, 0.0, 0.01 * scale);
    glp_set_obj_coef(lp, cols, 1.0);
    std::vector<int> ia{0}, ja{0};
    std::vector<double> ar{0.0};
    for (int r = 0; r < rows; ++r) {
      const Inequality& row = g[static_cast<std::size_t>(r)];
      glp_set_row_bnds(lp, r + 1, GLP_LO, -value(row, lambda), 0.0);
      for (Eigen::Index c = 0; c < k; ++c) {
        double coefficient = 0.0;
        for (const auto& [index, a] : row) coefficient += a * Z(index, c);
        if (coefficient != 0.0) {
          ia.push_back(r + 1);
          ja.push_back(static_cast<int>(c) + 1);
          ar.push_back(coefficient);
        }
      }
      ia.push_back(r + 1);
      ja.push_back(cols);
      ar.push_back(-norm(row));
    }
    glp_load_matrix(lp, static_cast<int>(ia.size()) - 1, ia.data(), ja.data(), ar.data());
    glp_smcp parameters;
    glp_init_smcp(&parameters);
    parameters.msg_lev = GLP_MSG_OFF;
    const int code = glp_simplex(lp, &parameters);
    bool changed = false;
    if (code == 0 && glp_get_status(lp) == GLP_OPT && glp_get_obj_val(lp) >= -1e-9 * scale) {
      VecX y(k);
      for (Eigen::Index c = 0; c < k; ++c) y(c) = glp_get_col_prim(lp, static_cast<int>(c) + 1);
      const VecX moved = lambda + Z * y;
      if (moved.allFinite()) {
        lambda = moved;
        changed = true;
      }
    }
    glp_delete_prob(lp);
    return changed;
  }

  // The net wrench on each body per unit multiplier of each row (6 per body).
  MatX wrench_map() const {
    const Eigen::Index m = static_cast<Eigen::Index>(rows_.size());
    const Eigen::Index nb = static_cast<Eigen::Index>(bodies_.size());
    MatX B = MatX::Zero(6 * nb, m);
    for (Eigen::Index j = 0; j < m; ++j) {
      const Row& r = rows_[static_cast<std::size_t>(j)];
      for (int q = 0; q < 2; ++q) {
        if (r.body[q] >= 0) B.block<6, 1>(6 * r.body[q], j) += r.W[q];
      }
    }
    return B;
  }

  // Where the rows are dependent (A singular) and a multiplier combination leaves every row's
  // value alone but not the bodies' accelerations, the accelerations are not unique: a ball
  // wedged between a floor and a wall, both sticking, may be squeezed between them by any
  // amount, and the rolling resistance or sliding friction that scales with its normal forces
  // turns it accordingly. Among them, the multipliers nearest the least-norm ones (in their own
  // norm) that meet every inequality (inequalities(): N >= 0, pressure in the patch, reactions
  // within their bounds) are taken - the least squeeze that keeps every contact in its cone,
  // continuous in the state, so an integrated motion follows it. Where no multipliers meet them
  // all, or the accelerations are unique (the redundancy is a pure internal force:
  // feasible_multipliers' case), lambda stays.
  void nearest_feasible(const Eigen::CompleteOrthogonalDecomposition<MatX>& cod,
                        VecX& lambda) const {
    const std::vector<Inequality> g = inequalities();
    const Eigen::Index ng = static_cast<Eigen::Index>(g.size());
    MatX G = MatX::Zero(ng, lambda.size());
    for (Eigen::Index i = 0; i < ng; ++i) {
      for (const auto& [index, coefficient] : g[static_cast<std::size_t>(i)]) {
        G(i, index) += coefficient;
      }
    }
    const VecX margin = G * lambda;
    if (!margin.allFinite() || margin.minCoeff() >= 0.0) return;
    // A P = Q [T11 0; 0 0] Z (Eigen's complete orthogonal decomposition): the null space of A
    // is P times the last m - rank rows of Z, transposed (orthonormal).
    const Eigen::Index m = lambda.size(), rank = cod.rank();
    const MatX Z = cod.colsPermutation() * MatX(cod.matrixZ().bottomRows(m - rank).transpose());
    if (Z.cols() == 0 || !Z.allFinite()) return;
    const MatX B = wrench_map();
    if (!((B * Z).norm() > 1e-9 * B.norm())) return;  // the accelerations are unique
    // The smallest move y along the null space with G (lambda + Z y) >= 0.
    const std::optional<VecX> y = nearest_point(G * Z, -margin);
    if (!y) return;
    const VecX moved = lambda + Z * *y;
    if (moved.allFinite()) lambda = moved;
  }

  Vec6 apply_inverse_mass(int body, const Vec6& w) const {
    const HeldBody& b = bodies_[static_cast<std::size_t>(body)];
    Vec6 out;
    out << w.head<3>() / b.mass, b.inv_inertia_W * w.tail<3>();
    return out;
  }

  // A row acting on the mover with wrench (f, tau) at the contact (tau about the mover's centre)
  // and on the support with the opposite (about its own centre).
  Row make_row(int contact, const Kinematics& k) const {
    Row r;
    r.contact = contact;
    r.body[0] = k.m.body;
    r.body[1] = k.s.body;
    return r;
  }
  // Force f applied at the contact point.
  static void add_force(Row& r, const Kinematics& k, const Vec3& f) {
    r.W[0] += wrench(f, k.r_m.cross(f));
    r.W[1] -= wrench(f, k.r_s.cross(f));
  }
  static void add_torque(Row& r, const Vec3& tau) {
    r.W[0] += wrench(Vec3::Zero(), tau);
    r.W[1] -= wrench(Vec3::Zero(), tau);
  }
  // Row value: d . ds/dt + d_dot . s (a linear relative-acceleration row along d).
  // At the velocity level the same J gives d . s, and the bias is the row's present value.
  void linear_rows_value(Row& r, const Kinematics& k, const Vec3& d, const Vec3& d_dot) const {
    r.J[0] = (d.transpose() * k.Jm).transpose();
    r.J[1] = (d.transpose() * k.Js).transpose();
    r.bias = velocity_level_ ? d.dot(k.slip) : d.dot(k.slip_bias) + d_dot.dot(k.slip);
  }
  // The rate of a tangent t of the contact's plane: turned with the support, and kept in the
  // plane as its normal turns at n_dot, so that t . dw held at zero stays zero: d/dt (t . dw) =
  // t . d(dw)/dt - (t . n_dot) (n . dw) + (terms in dw's tangential part). A normal that follows
  // two features' closest points (a ball sliding on a ball) does not turn with the support.
  // (Turned with the support alone, a ball's rolling held on a ball leaked its spin about the
  // turning normal into rolling, 1.5e-8 m/s after a 2 us motion, which the next plan read as
  // rolling against its own deceleration: 169 roll stops of one contact in 0.036 s of a pile of
  // 100 balls.) Where the normal turns with the support (n_dot = w_s x n), this is w_s x t.
  static Vec3 tangent_rate(const HeldContact& c, const Kinematics& k, const Vec3& t) {
    const Vec3 turned = k.s.w.cross(t);
    return turned - c.n_W * (c.n_W.dot(turned) + t.dot(k.n_dot));
  }
  // Row value: a . d(dw)/dt + a_dot . dw (a relative angular-acceleration row about a).
  void angular_row_value(Row& r, const Kinematics& k, const Vec3& a, const Vec3& a_dot) const {
    r.J[0] = wrench(Vec3::Zero(), a);
    r.J[1] = wrench(Vec3::Zero(), -a);
    if (velocity_level_) {
      r.bias = a.dot(k.dw);
      return;
    }
    r.bias = a_dot.dot(k.dw);
    if (k.m.body < 0) r.bias += a.dot(k.m.alpha);
    if (k.s.body < 0) r.bias -= a.dot(k.s.alpha);
  }

  void add_contact(int i) {
    const HeldContact& c = contacts_[static_cast<std::size_t>(i)];
    kinematics_[static_cast<std::size_t>(i)] = kinematics(c, bodies_);
    const Kinematics& k = *kinematics_[static_cast<std::size_t>(i)];
    Layout& l = layout_[static_cast<std::size_t>(i)];
    const Vec3 s_hat = c.slip_dir.x() * c.t1_W + c.slip_dir.y() * c.t2_W;
    // Rocking axes held by the patch, and their rates.
    std::vector<std::pair<Vec3, Vec3>> rocking;
    if (c.patch == PatchKind::kPolygon) {
      rocking = {{c.t1_W, k.s.w.cross(c.t1_W)}, {c.t2_W, k.s.w.cross(c.t2_W)}};
    } else if (c.patch == PatchKind::kSegment) {
      rocking = {{segment_axis(c), segment_axis_rate(c, k)}};
    }
    // Normal: force n at c, plus the sliding couplings that scale with N.
    {
      Row r = make_row(i, k);
      linear_rows_value(r, k, c.n_W, k.n_dot);
      add_force(r, k, c.n_W);
      if (!c.sticks && c.friction > 0.0) add_force(r, k, -c.friction * s_hat);
      if (!c.spin_sticks && c.torsion_arm > 0.0)
        add_torque(r, -c.torsion_arm * c.spin_sign * c.n_W);
      if (!c.roll_sticks && c.rolling_resistance > 0.0) {
        add_torque(r, -c.rolling_resistance * (c.roll_dir.x() * c.t1_W + c.roll_dir.y() * c.t2_W));
      }
      l.normal = push(r);
    }
    // Pressure moments; sliding friction acts at the centre of pressure c + n x M / N, so each
    // moment component also turns the friction force: -mu (n x a) x s_hat per unit.
    for (std::size_t j = 0; j < rocking.size(); ++j) {
      Row r = make_row(i, k);
      angular_row_value(r, k, rocking[j].first, rocking[j].second);
      add_torque(r, rocking[j].first);
      if (!c.sticks && c.friction > 0.0) {
        add_torque(r, -c.friction * c.n_W.cross(rocking[j].first).cross(s_hat));
      }
      const Eigen::Index index = push(r);
      if (j == 0) l.moment = index;
    }
    if (c.sticks && c.friction > 0.0) {
      for (const Vec3* t : {&c.t1_W, &c.t2_W}) {
        Row r = make_row(i, k);
        linear_rows_value(r, k, *t, k.s.w.cross(*t));
        add_force(r, k, *t);
        const Eigen::Index index = push(r);
        if (t == &c.t1_W) l.friction = index;
      }
    }
    if (c.spin_sticks && c.torsion_arm > 0.0) {
      Row r = make_row(i, k);
      angular_row_value(r, k, c.n_W, k.n_dot);
      add_torque(r, c.n_W);
      l.torsion = push(r);
    }
    if (c.patch == PatchKind::kPoint && c.roll_sticks && c.rolling_resistance > 0.0) {
      for (const Vec3* t : {&c.t1_W, &c.t2_W}) {
        Row r = make_row(i, k);
        angular_row_value(r, k, *t, tangent_rate(c, k, *t));
        add_torque(r, *t);
        const Eigen::Index index = push(r);
        if (t == &c.t1_W) l.rolling = index;
      }
    }
  }

  Eigen::Index push(Row r) {
    for (int q = 0; q < 2; ++q) {
      if (r.body[q] >= 0) r.MW[q] = apply_inverse_mass(r.body[q], r.W[q]);
    }
    rows_.push_back(r);
    return static_cast<Eigen::Index>(rows_.size() - 1);
  }

  const std::vector<HeldBody>& bodies_;
  const std::vector<HeldContact>& contacts_;
  bool velocity_level_ = false;
  std::vector<Row> rows_;
  std::vector<Layout> layout_ = std::vector<Layout>(contacts_.size());
  // Each active contact's kinematics, as its rows were built from them.
  std::vector<std::optional<Kinematics>> kinematics_;
};

}  // namespace

std::string_view to_string(HeldStatus status) {
  switch (status) {
    case HeldStatus::kOk: return "ok";
    case HeldStatus::kInconsistent: return "inconsistent";
    case HeldStatus::kNonFinite: return "non-finite";
  }
  return "unknown";
}

HeldSolution solve_held(const std::vector<HeldBody>& bodies,
                        const std::vector<HeldContact>& contacts, bool feasible_forces) {
  return Assembly(bodies, contacts).solve(feasible_forces);
}

std::vector<HeldContactMotion> held_velocities(const std::vector<HeldBody>& bodies,
                                               const std::vector<HeldContact>& contacts) {
  // The velocities alone, as kinematics() computes them (its Jacobians are not needed here).
  std::vector<HeldContactMotion> out(contacts.size());
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const HeldContact& c = contacts[i];
    const Side m = mover_side(c, bodies), s = support_side(c, bodies);
    out[i].slip_W = point_velocity(m, c.c_W - m.x) - point_velocity(s, c.c_W - s.x);
    out[i].dw_W = m.w - s.w;
  }
  return out;
}

void set_torsion_arm(HeldContact& c) {
  switch (c.patch) {
    case PatchKind::kPoint: c.torsion_arm = c.spinning_resistance; return;
    case PatchKind::kSegment:
      c.torsion_arm = c.friction * 0.25 * (c.segment_hi - c.segment_lo);
      return;
    case PatchKind::kPolygon: {
      std::vector<Vec3> patch_W;
      for (const Vec2& p : c.polygon) patch_W.push_back(c.c_W + in_plane(c, p));
      c.torsion_arm = c.friction * mean_distance_over_patch(patch_W, c.n_W, c.c_W);
      return;
    }
  }
}

void reduce_patch(HeldContact& c, int edge) {
  if (c.patch == PatchKind::kPolygon) {
    const std::size_t n = c.polygon.size();
    const Vec2 p0 = c.polygon[static_cast<std::size_t>(edge) % n];
    const Vec2 p1 = c.polygon[(static_cast<std::size_t>(edge) + 1) % n];
    const double length = (p1 - p0).norm();
    c.c_W += in_plane(c, 0.5 * (p0 + p1));
    c.segment_W = in_plane(c, (p1 - p0) / length);
    c.segment_lo = -0.5 * length;
    c.segment_hi = 0.5 * length;
    c.polygon.clear();
    c.patch = PatchKind::kSegment;
  } else if (c.patch == PatchKind::kSegment) {
    c.c_W += (edge == 0 ? c.segment_lo : c.segment_hi) * c.segment_W;
    c.patch = PatchKind::kPoint;
  }
  set_torsion_arm(c);
}

double project_held_velocities(std::vector<HeldBody>& bodies,
                               const std::vector<HeldContact>& contacts, double still,
                               double separation, std::vector<int>* separating) {
  return Assembly::project(bodies, contacts, still, separation, separating);
}

HeldViolation worst_violation(const std::vector<HeldContact>& contacts, const HeldSolution& s,
                              double tolerance) {
  HeldViolation worst;
  // Every inequality is measured in newtons (moments over the patch size), relative to scale.
  double scale = 0.0;
  for (const HeldContactForces& f : s.forces) scale = std::max(scale, std::abs(f.normal));
  if (!(scale > 0.0)) scale = 1.0;
  auto consider = [&](HeldViolation::Kind kind, int contact, int edge, double excess) {
    const double amount = excess / scale;
    if (amount > tolerance && amount > worst.amount) {
      worst.kind = kind;
      worst.contact = contact;
      worst.edge = edge;
      worst.amount = amount;
    }
  };
  // Lift-off first: a contact that pulls makes every other condition of it meaningless.
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    if (contacts[i].active) {
      consider(HeldViolation::Kind::kLiftOff, static_cast<int>(i), -1, -s.forces[i].normal);
    }
  }
  if (worst.kind != HeldViolation::Kind::kNone) return worst;
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const HeldContact& c = contacts[i];
    if (!c.active) continue;
    const HeldContactForces& f = s.forces[i];
    const int ci = static_cast<int>(i);
    const double N = std::max(f.normal, 0.0);
    if (c.patch == PatchKind::kPolygon) {
      const std::size_t n = c.polygon.size();
      Vec3 a;
      for (std::size_t e = 0; e < n; ++e) {
        if (!polygon_edge_inequality(c, e, a)) continue;
        const Vec2& p0 = c.polygon[e];
        const double size = (c.polygon[(e + 1) % n] - p0).norm() + p0.norm();
        consider(HeldViolation::Kind::kTip, ci, static_cast<int>(e),
                 -a.dot(Vec3(N, f.moment.x(), f.moment.y())) / size);
      }
    } else if (c.patch == PatchKind::kSegment) {
      // The centre of pressure along s: -M_m / N, within [lo, hi].
      const double Mm = in_plane(c, f.moment).dot(segment_axis(c));
      const double size = c.segment_hi - c.segment_lo;
      consider(HeldViolation::Kind::kTip, ci, 0, (N * c.segment_lo + Mm) / size);
      consider(HeldViolation::Kind::kTip, ci, 1, (-Mm - N * c.segment_hi) / size);
    }
    if (c.sticks && c.friction > 0.0) {
      consider(HeldViolation::Kind::kSlip, ci, -1, f.friction.norm() - c.friction * N);
    }
    if (c.spin_sticks && c.torsion_arm > 0.0) {
      consider(HeldViolation::Kind::kSpin, ci, -1,
               (std::abs(f.torsion) - c.torsion_arm * N) / c.torsion_arm);
    }
    if (c.patch == PatchKind::kPoint && c.roll_sticks && c.rolling_resistance > 0.0) {
      consider(HeldViolation::Kind::kRoll, ci, -1,
               (f.rolling.norm() - c.rolling_resistance * N) / c.rolling_resistance);
    }
  }
  return worst;
}

namespace {

// The contact let go by this choice whose gap closes fastest under the solution (its gap
// acceleration below -tolerance times the scale), or -1; none of `returned` (brought back once
// already).
int closing_released(const std::vector<HeldContact>& contacts, const HeldModes& modes,
                     double acceleration_scale, double tolerance,
                     const std::vector<int>& returned) {
  int closing = -1;
  double fastest = -tolerance * acceleration_scale;
  for (int i : modes.released) {
    if (std::find(returned.begin(), returned.end(), i) != returned.end()) continue;
    const std::size_t k = static_cast<std::size_t>(i);
    const double gap_acceleration = modes.solution.motion[k].slip_rate_W.dot(contacts[k].n_W);
    if (gap_acceleration < fastest) {
      fastest = gap_acceleration;
      closing = i;
    }
  }
  return closing;
}

// Of the contacts that start to slide from rest along a direction chosen for each alone
// (`started`), the one whose slip, under the modes of all, grows farthest from its direction
// (its rate turned across it or against it): chosen one at a time, a second contact starting to
// slide changes the first's acceleration. -1 if none. (A hull wedged between
// the floor and another, both contacts unable to stick: each started along a direction consistent
// only with the other sticking; one slip turned back at once, stopped, and so again - 8 plans at
// one instant, then stops alternating between the two contacts at shrinking intervals, 27,000 in
// 0.4 s.) Within 1e-3 rad its direction is kept: the integrated motion resists a slip against its
// present direction once it grows past the slip floor. A rate within `tolerance` of zero
// (relative to `acceleration_scale`) is no rate. `rolling`: of contacts that start to roll
// against rolling resistance (their relative rolling and its rate, at the point's size).
int turned_start(const std::vector<HeldContact>& contacts, const HeldSolution& solution,
                 const std::vector<int>& started, double acceleration_scale, double tolerance,
                 bool rolling = false) {
  int worst = -1;
  double farthest = 1e-3;  // the sine of the angle between the slip's rate and its direction
  for (int i : started) {
    const HeldContact& c = contacts[static_cast<std::size_t>(i)];
    if (!c.active || (rolling ? c.roll_sticks : c.sticks)) continue;
    const HeldContactMotion& m = solution.motion[static_cast<std::size_t>(i)];
    const Vec2 rate = rolling ? plane_coords(c, m.roll_rate_W) : plane_coords(c, m.slip_rate_W);
    const Vec2& dir = rolling ? c.roll_dir : c.slip_dir;
    const double scale = rolling ? point_size(c) : 1.0;
    if (!(rate.norm() * scale > tolerance * acceleration_scale)) continue;
    const double off = rate.dot(dir) <= 0.0 ? 2.0 : std::abs(cross2(dir, rate)) / rate.norm();
    if (off > farthest) {
      farthest = off;
      worst = i;
    }
  }
  return worst;
}

// Of the contacts that started to spin from rest (`spun`) and spin still, the one whose spin now
// accelerates against the sign chosen for it fastest (beyond the tolerance), or -1: the torsion
// that let it go was judged under the others' modes of then.
int turned_spin(const std::vector<HeldContact>& contacts, const HeldSolution& solution,
                const std::vector<int>& spun, double acceleration_scale, double tolerance) {
  int worst = -1;
  double fastest = tolerance * acceleration_scale;
  for (int i : spun) {
    const HeldContact& c = contacts[static_cast<std::size_t>(i)];
    if (!c.active || c.spin_sticks) continue;
    const HeldContactMotion& m = solution.motion[static_cast<std::size_t>(i)];
    const double against = -c.spin_sign * m.dalpha_W.dot(c.n_W) * turning_size(c);
    if (against > fastest) {
      fastest = against;
      worst = i;
    }
  }
  return worst;
}

// Of the directions d(theta) = (cos theta, sin theta) over the circle from `theta0`, the first
// where rate(d) lies along d: a root of its component across d, cross(d, rate(d)), scanned in 72
// steps and bisected, kept where the rate grows along d. Nullopt if there is none. `rate` returns
// nullopt where its problem fails.
template <class Rate>
std::optional<Vec2> growing_direction(double theta0, Rate&& rate_along) {
  constexpr int kSteps = 72;
  auto at = [](double theta) { return Vec2(std::cos(theta), std::sin(theta)); };
  auto across = [&](double theta) {
    const std::optional<Vec2> rate = rate_along(at(theta));
    return rate ? cross2(at(theta), *rate) : std::numeric_limits<double>::quiet_NaN();
  };
  double previous = across(theta0);
  for (int k = 1; k <= kSteps; ++k) {
    double lo = theta0 + 2.0 * M_PI * (k - 1) / kSteps, hi = theta0 + 2.0 * M_PI * k / kSteps;
    const double value = across(hi);
    if (std::isfinite(previous) && std::isfinite(value) && (previous < 0.0) != (value < 0.0)) {
      double f_lo = previous;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi);
        const double f_mid = across(mid);
        if (!std::isfinite(f_mid)) break;
        if ((f_mid < 0.0) == (f_lo < 0.0)) {
          lo = mid;
          f_lo = f_mid;
        } else {
          hi = mid;
        }
      }
      const double root = 0.5 * (lo + hi);
      const std::optional<Vec2> rate = rate_along(at(root));
      if (rate && at(root).dot(*rate) > 0.0) return at(root);
    }
    previous = value;
  }
  return std::nullopt;
}

// The slip rate of contacts[i] sliding along d, in (t1, t2), as a function of d (it sets
// contacts[i].slip_dir to d); nullopt where the problem fails.
auto slip_rate_along(const std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts,
                     std::size_t i) {
  return [&bodies, &contacts, i](const Vec2& d) -> std::optional<Vec2> {
    HeldContact& c = contacts[i];
    c.slip_dir = d;
    const HeldSolution trial = solve_held(bodies, contacts);
    if (trial.status != HeldStatus::kOk) return std::nullopt;
    return plane_coords(c, trial.motion[i].slip_rate_W);
  };
}

// The direction a sticking contact beyond its cone starts to slide in: the one along which its
// sliding acceleration points (a fixed point: the unique direction), from `start`, the opposite
// of the friction sticking needed. Iterated d <- rate(d) / |rate(d)|; where that cycles instead
// (seen on curved contacts: the direction flipped between two mirror images 50 times, and the
// slide it chose stopped 1e-7 s later, over and over), found as a root of the slip rate's
// component across the direction, cross(d, rate(d)), over the circle of directions: scanned in
// 72 steps from `start`, bisected, and the first root met where the slip grows along it kept.
// Nullopt if there is none: along every direction the slip would grow against it (friction
// driving the slip). Leaves contacts[i] sliding along the direction tried last.
std::optional<Vec2> unstable_stick_direction(const std::vector<HeldBody>& bodies,
                                             std::vector<HeldContact>& contacts, std::size_t i,
                                             const Vec2& start) {
  auto rate_along = slip_rate_along(bodies, contacts, i);
  Vec2 dir = start;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const std::optional<Vec2> rate = rate_along(dir);
    if (!rate || !(rate->norm() > 0.0)) return dir;  // nothing better to go on
    const Vec2 next = rate->normalized();
    if (next.dot(dir) > 1.0 - 1e-15) return dir;
    dir = next;
  }
  return growing_direction(std::atan2(start.y(), start.x()), rate_along);
}

// How affine_growing_direction's refinement settles: on the sine of the angle from d to rate(d)
// within `sine` (a start from rest, where the rate is of the order of the friction's), or, with
// `rate` > 0, on the rate across d within `rate` times |B| (a slip at the edge of its cone, its
// rate along d small: there the sine swings from -1 to 1 within an angle of lambda / |B|, which
// a secant step overshoots, and a sine of 1e-9 may be out of reach of the solves).
struct Settle {
  double sine = 1e-6;
  double rate = 0.0;
};

// Of the directions d along which rate(d) = lambda d with lambda > 0, the one found from the
// affine fit rate(d) = a + B d (three solves, along e1, -e1, e2): d = (lambda I - B)^-1 a with
// |d| = 1, lambda by bisection on [0, |a| + |B|] (beyond it |d| < 1), refined by secant steps on
// the angle (the normal forces depend on d a little) until `settle`. Nullopt if a solve fails,
// if the fit has no such lambda (nothing grows along any direction: `holds`) - unless settling
// by the rate, where the fit, only near affine, may miss one at the edge of the cone and the
// secant starts from lambda = 0 - or if the refinement does not settle; `guess`, where the fit
// gave one.
template <class Rate>
std::optional<Vec2> affine_growing_direction(Rate&& rate_along, const Settle& settle, bool* holds,
                                             Vec2* guess_out = nullptr) {
  if (holds) *holds = false;
  const std::optional<Vec2> r1 = rate_along(Vec2(1.0, 0.0));
  const std::optional<Vec2> r1m = rate_along(Vec2(-1.0, 0.0));
  const std::optional<Vec2> r2 = rate_along(Vec2(0.0, 1.0));
  if (!r1 || !r1m || !r2) return std::nullopt;
  const Vec2 a = 0.5 * (*r1 + *r1m);
  Eigen::Matrix2d B;
  B.col(0) = 0.5 * (*r1 - *r1m);
  B.col(1) = *r2 - a;
  if (!a.allFinite() || !B.allFinite() || !(a.norm() > 0.0)) return std::nullopt;
  auto along = [&](double lambda) -> Vec2 {
    return (lambda * Eigen::Matrix2d::Identity() - B).fullPivLu().solve(a);
  };
  const bool by_rate = settle.rate > 0.0;
  double lo = 0.0, hi = a.norm() + B.norm();
  if (along(lo).norm() > 1.0) {
    if (!(along(hi).norm() < 1.0)) return std::nullopt;
    for (int it = 0; it < 100 && hi - lo > 1e-15 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (along(mid).norm() > 1.0 ? lo : hi) = mid;
    }
  } else if (by_rate) {
    hi = 0.0;
  } else {
    if (holds) *holds = true;  // no direction it grows along
    return std::nullopt;
  }
  const Vec2 guess = along(0.5 * (lo + hi)).normalized();
  if (!guess.allFinite()) return std::nullopt;
  if (guess_out) *guess_out = guess;
  auto at = [](double theta) { return Vec2(std::cos(theta), std::sin(theta)); };
  // The refinement's function: the rate across d, or the sine.
  std::optional<Vec2> last;  // the rate at the angle `across` was last asked at (theta1, below)
  auto across = [&](double theta) -> double {
    last = rate_along(at(theta));
    if (!last || !(last->norm() > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    return cross2(at(theta), *last) / (by_rate ? 1.0 : last->norm());
  };
  const double rate_tol = settle.rate * B.norm();
  auto settled = [&](double f) {
    return by_rate ? std::abs(f) <= rate_tol : std::abs(f) <= settle.sine;
  };
  double theta0 = std::atan2(guess.y(), guess.x());
  double f0 = across(theta0);
  double theta1 = theta0 + 1e-4, f1 = across(theta1);
  // (The secant steps on the sine go on to 1e-9, past what settles it.)
  auto done = [&](double f) { return by_rate ? settled(f) : std::abs(f) <= 1e-9; };
  for (int it = 0; it < 20 && std::isfinite(f0) && std::isfinite(f1) && !done(f1); ++it) {
    if (f1 == f0) break;
    const double next = theta1 - f1 * (theta1 - theta0) / (f1 - f0);
    theta0 = theta1;
    f0 = f1;
    theta1 = next;
    f1 = across(theta1);
  }
  if (std::isfinite(f1) && settled(f1)) {
    if (last->dot(at(theta1)) > 0.0) return at(theta1);
  }
  return std::nullopt;
}

// The direction a contact whose rolling resistance cannot hold it starts to roll in: d with
// its rolling acceleration rate(d) = lambda d, lambda > 0, rolling along d
// (affine_growing_direction: the resistance's couple is linear in d). Nullopt if a solve fails, if
// no such lambda exists (the resistance can hold it: `holds`), or if the rolling along d does not
// grow along d. (Iterated d <- rate(d) / |rate(d)| the direction cycled: a ball on a ball in a
// pile, 16 rounds without settling at each of 9,000 plans; the search of every direction the slips
// use, unstable_stick_direction, took 367 solves a start.) Leaves contacts[i] rolling along the
// direction tried last.
std::optional<Vec2> roll_start_direction(const std::vector<HeldBody>& bodies,
                                         std::vector<HeldContact>& contacts, std::size_t i,
                                         bool* holds = nullptr) {
  HeldContact& c = contacts[i];
  auto rate_along = [&](const Vec2& d) -> std::optional<Vec2> {
    c.roll_dir = d;
    const HeldSolution trial = solve_held(bodies, contacts);
    if (trial.status != HeldStatus::kOk) return std::nullopt;
    return plane_coords(c, trial.motion[i].roll_rate_W);
  };
  Vec2 guess = Vec2::Zero();
  if (const std::optional<Vec2> d = affine_growing_direction(rate_along, Settle{}, holds, &guess)) {
    return d;
  }
  if ((holds && *holds) || guess == Vec2::Zero()) return std::nullopt;
  // Where the secant steps wander off (far from affine), the root is bracketed over the circle
  // from the guess and bisected, as for a slip.
  return growing_direction(std::atan2(guess.y(), guess.x()), rate_along);
}

}  // namespace

std::optional<Vec2> vanishing_slip_direction(const std::vector<HeldBody>& bodies,
                                             std::vector<HeldContact>& contacts, std::size_t i) {
  HeldContact& c = contacts[i];
  const Vec2 kept = c.slip_dir;
  // Only where it cannot stick: where its friction sticking lies within the cone the slip stops
  // (its stop event), and the rate, far from affine in d there (at mu 10 the friction moves the
  // normal force), may point along d at directions no slip takes. (Without this, Euler's disk at
  // mu 10, its slip below the floor after a plan, slid along such a direction; its contact let
  // go 166 times and it gained 1.4e-4 J.)
  c.sticks = true;
  const HeldSolution stuck = solve_held(bodies, contacts);
  c.sticks = false;
  if (stuck.status != HeldStatus::kOk ||
      !(stuck.forces[i].friction.norm() > c.friction * stuck.forces[i].normal)) {
    return std::nullopt;
  }
  // Settled to within 1e-12 of the friction's own part of the slip rate (Settle).
  const std::optional<Vec2> d =
      affine_growing_direction(slip_rate_along(bodies, contacts, i), Settle{0.0, 1e-12}, nullptr);
  c.slip_dir = d ? *d : kept;
  return d;
}

HeldModes choose_held_modes(const std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts,
                            double still, double tolerance) {
  HeldModes out;
  const std::vector<HeldContactMotion> now = held_velocities(bodies, contacts);
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    HeldContact& c = contacts[i];
    const HeldContactMotion& m = now[i];
    const Vec2 slip = plane_coords(c, m.slip_W);
    c.sticks = c.slip_stopped || slip.norm() <= still;
    if (!c.sticks) c.slip_dir = slip.normalized();
    const double spin = m.dw_W.dot(c.n_W);
    c.spin_sticks = c.spin_stopped || std::abs(spin) * turning_size(c) <= still;
    if (!c.spin_sticks) c.spin_sign = spin > 0.0 ? 1.0 : -1.0;
    const Vec2 rolling = plane_coords(c, m.dw_W);
    c.roll_sticks = c.roll_stopped || rolling.norm() * std::max(point_size(c), 1e-300) <= still;
    if (!c.roll_sticks) c.roll_dir = rolling.normalized();
  }
  const int budget = 8 + 4 * static_cast<int>(contacts.size());
  // Gap accelerations are judged against the largest applied acceleration (gravity's, usually).
  double acceleration_scale = 0.0;
  for (const HeldBody& b : bodies) {
    acceleration_scale = std::max(acceleration_scale, b.force_W.norm() / b.mass);
  }
  if (!(acceleration_scale > 0.0)) acceleration_scale = 1.0;
  std::vector<int> returned;  // contacts brought back, once each (no cycling between two sets)
  std::vector<int> started;   // contacts that start to slide from rest, along a chosen direction
  std::vector<int> rolled;    // contacts that start to roll from rest (rolling resistance)
  std::vector<int> spun;      // contacts that start to spin from rest (spinning resistance)
  int turns = 0;              // directions of `started` and `rolled` chosen again
  // Contact i, sticking beyond its cone, starts to slide along the direction its sliding
  // acceleration points (searched from `start`), and joins `started`. An edge across an edge
  // lets go instead of sliding along such a direction: its contact point runs along both edges,
  // and the slip found along one turned away from it within 1e-6 s, stopped, and was found again
  // - an edge held across a hull's edge did so 37,000 times in 0.085 s. Where there is no such
  // direction, it can neither stick nor slide: friction would drive the slip along every
  // direction (the coupled contacts' Painleve case). It lets go, and is not brought back here:
  // its pair's check meets it as a collision, whose impulse resolves what no force can. (Slid
  // along the opposite of the friction sticking needed, an edge of one hull on the face of
  // another, between two hulls sliding and spinning on the floor, was driven to the
  // integration's slip floor and chattered there, in steps of 5e-9 s, until 1000 steps were
  // rejected - every 1.1e-6 s of simulated time: a pile of 100 hulls did not finish.)
  auto slide_from_rest = [&](int i, const Vec2& start) {
    HeldContact& c = contacts[static_cast<std::size_t>(i)];
    c.sticks = false;
    const std::optional<Vec2> dir =
        c.edge_on_edge
            ? std::nullopt
            : unstable_stick_direction(bodies, contacts, static_cast<std::size_t>(i), start);
    if (dir) {
      c.slip_dir = *dir;
      if (std::find(started.begin(), started.end(), i) == started.end()) started.push_back(i);
      return;
    }
    c.active = false;
    out.released.push_back(i);
    returned.push_back(i);
  };
  // Contact i, its rolling resistance unable to hold it, starts to roll along the direction its
  // rolling accelerates in (roll_start_direction; where there is none found, along `start`, the
  // opposite of the couple sticking needed), and joins `rolled`. `turned`: chosen again under
  // the modes the others took since, where its resistance now holds it, it sticks again.
  // (Rolled along the opposite of the couple alone, a ball on the floor of a pile, pressed by
  // five others, met a rolling acceleration 117 degrees from it: its rolling turned back at
  // once, stopped, and so again, 19,755 plans in 4e-4 s.)
  auto roll_from_rest = [&](int i, const Vec2& start, bool turned) {
    HeldContact& c = contacts[static_cast<std::size_t>(i)];
    c.roll_sticks = false;
    bool holds = false;
    const std::optional<Vec2> dir =
        roll_start_direction(bodies, contacts, static_cast<std::size_t>(i), &holds);
    if (turned && holds) {
      c.roll_sticks = true;  // under the modes the others took since, it holds again
      return;
    }
    c.roll_dir = dir ? *dir : start;
    if (std::find(rolled.begin(), rolled.end(), i) == rolled.end()) rolled.push_back(i);
  };
  for (;;) {
    out.solution = solve_held(bodies, contacts);
    if (out.solution.status != HeldStatus::kOk) return out;
    HeldViolation v = worst_violation(contacts, out.solution, tolerance);
    if (v.kind != HeldViolation::Kind::kNone) {
      // The least-norm forces break a condition; forces that break none may exist all the same
      // (a redundant island: a box on two, boxes side by side). Only their failing changes a mode.
      out.solution = solve_held(bodies, contacts, /*feasible_forces=*/true);
      v = worst_violation(contacts, out.solution, tolerance);
    }
    if (v.kind == HeldViolation::Kind::kNone) {
      // A contact let go earlier must not close now: the friction or the pressure that made it
      // pull may since have changed mode. The one closing fastest comes back (an active set).
      const int back = closing_released(contacts, out, acceleration_scale, tolerance, returned);
      if (back < 0) {
        const int turned =
            turned_start(contacts, out.solution, started, acceleration_scale, tolerance);
        const int turned_roll = turned >= 0
                                    ? -1
                                    : turned_start(contacts, out.solution, rolled,
                                                   acceleration_scale, tolerance, /*rolling=*/true);
        const int spin_turned =
            turned >= 0 || turned_roll >= 0
                ? -1
                : turned_spin(contacts, out.solution, spun, acceleration_scale, tolerance);
        if (turned < 0 && turned_roll < 0 && spin_turned < 0) return out;
        // (Turned one at a time, the directions converge linearly: about 3 times closer a round.)
        if (turns >= 16 * static_cast<int>(started.size() + rolled.size() + spun.size())) {
          out.converged = false;
          return out;
        }
        ++turns;
        ++out.changes;
        if (turned >= 0) {
          slide_from_rest(turned, contacts[static_cast<std::size_t>(turned)].slip_dir);
        } else if (spin_turned >= 0) {
          // Chosen again under the modes the others took since: it sticks where its torsion now
          // holds it, else it spins the way that torsion now gives (kSpin below). (Left spinning
          // against its acceleration, a hull's floor patch, chosen sliding and spinning from
          // rest under two hulls, stopped spinning 4e-8 s later, at once again and again, and
          // its motions broke down: 50 hulls, seed 11.)
          contacts[static_cast<std::size_t>(spin_turned)].spin_sticks = true;
        } else {
          const HeldContact& c = contacts[static_cast<std::size_t>(turned_roll)];
          roll_from_rest(
              turned_roll,
              plane_coords(c,
                           out.solution.motion[static_cast<std::size_t>(turned_roll)].roll_rate_W)
                  .normalized(),
              /*turned=*/true);
        }
        continue;
      }
      if (out.changes >= budget) {
        out.converged = false;
        return out;
      }
      ++out.changes;
      contacts[static_cast<std::size_t>(back)].active = true;
      returned.push_back(back);
      out.released.erase(std::find(out.released.begin(), out.released.end(), back));
      continue;
    }
    if (out.changes >= budget) {
      out.converged = false;
      return out;
    }
    ++out.changes;
    HeldContact& c = contacts[static_cast<std::size_t>(v.contact)];
    const HeldContactForces& f = out.solution.forces[static_cast<std::size_t>(v.contact)];
    switch (v.kind) {
      case HeldViolation::Kind::kNone: break;
      case HeldViolation::Kind::kLiftOff:
        c.active = false;
        out.released.push_back(v.contact);
        break;
      case HeldViolation::Kind::kTip: {
        reduce_patch(c, v.edge);
        // Its reference point moved to the edge (or end): what slides is resisted against its slip
        // there, as along the integrated motion (a spinning pin sliding on a facet of its hull,
        // tipped about an end edge with the slip of the facet's centre, turned into the lane
        // when integrated: it landed again every 4.7e-6 s).
        if (!c.sticks) {
          const Vec2 slip = plane_coords(c, kinematics(c, bodies).slip);
          if (slip.norm() > still) c.slip_dir = slip.normalized();
        }
        break;
      }
      case HeldViolation::Kind::kSpin:
        c.spin_sticks = false;
        c.spin_sign = f.torsion > 0.0 ? -1.0 : 1.0;
        if (std::find(spun.begin(), spun.end(), v.contact) == spun.end()) spun.push_back(v.contact);
        break;
      case HeldViolation::Kind::kRoll:
        roll_from_rest(v.contact, -f.rolling.normalized(), /*turned=*/false);
        break;
      case HeldViolation::Kind::kSlip: slide_from_rest(v.contact, -f.friction.normalized()); break;
    }
  }
}

}  // namespace palpable
