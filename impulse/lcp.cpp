#include "impulse/lcp.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace palpable {

LcpSolution solve_lcp(const Eigen::MatrixXd& M, const Eigen::VectorXd& q) {
  const Eigen::Index n = q.size();
  LcpSolution out;
  out.z = Eigen::VectorXd::Zero(n);
  out.w = q;
  if (M.rows() != n || M.cols() != n || !M.allFinite() || !q.allFinite()) return out;
  if (n == 0 || q.minCoeff() >= 0.0) {
    out.solved = true;
    return out;
  }
  // Tableau rows: w - M z - 1 z0 = q. Columns: w (0..n-1), z (n..2n-1), z0 (2n), right side (2n+1).
  // The w columns hold the basis inverse throughout (the lexicographic keys).
  const Eigen::Index z0 = 2 * n, rhs = 2 * n + 1;
  // Row-major: a pivot works along rows, which are then contiguous.
  using Tableau = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Tableau T = Tableau::Zero(n, 2 * n + 2);
  T.leftCols(n).setIdentity();
  T.middleCols(n, n) = -M;
  T.col(z0).setConstant(-1.0);
  T.col(rhs) = q;
  std::vector<Eigen::Index> basis(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) basis[static_cast<std::size_t>(i)] = i;
  auto pivot = [&](Eigen::Index row, Eigen::Index col) {
    T.row(row) /= T(row, col);
    for (Eigen::Index i = 0; i < n; ++i) {
      if (i != row && T(i, col) != 0.0) T.row(i) -= T(i, col) * T.row(row);
    }
    basis[static_cast<std::size_t>(row)] = col;
    ++out.pivots;
  };
  // z0 enters where q is most negative: every w becomes >= 0.
  Eigen::Index row = 0;
  T.col(rhs).minCoeff(&row);
  Eigen::Index leaving = basis[static_cast<std::size_t>(row)];
  pivot(row, z0);
  const int budget = 50 * static_cast<int>(n) + 100;
  for (int iteration = 0; iteration < budget; ++iteration) {
    // The complement of the variable that left enters.
    const Eigen::Index entering = leaving < n ? leaving + n : leaving - n;
    const double scale = T.col(entering).cwiseAbs().maxCoeff();
    const double tiny = 1e-12 * scale;
    std::vector<Eigen::Index> ties;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (T(i, entering) > tiny) ties.push_back(i);
    }
    if (ties.empty()) return out;  // a secondary ray
    // Lexicographic minimum of (rhs, basis inverse rows) / pivot column, key by key.
    for (Eigen::Index key = -1; key < n && ties.size() > 1; ++key) {
      const Eigen::Index col = key < 0 ? rhs : key;
      double best = INFINITY;
      for (Eigen::Index i : ties) best = std::min(best, T(i, col) / T(i, entering));
      const double within = 1e-12 * std::abs(best);
      std::vector<Eigen::Index> kept;
      for (Eigen::Index i : ties) {
        if (T(i, col) / T(i, entering) <= best + within) kept.push_back(i);
      }
      ties = kept;
      // z0 leaving ends the run: prefer it among exact ties of the ratio.
      if (key < 0) {
        for (Eigen::Index i : ties) {
          if (basis[static_cast<std::size_t>(i)] == z0) ties = {i};
        }
      }
    }
    row = ties.front();
    leaving = basis[static_cast<std::size_t>(row)];
    pivot(row, entering);
    if (leaving == z0) {
      out.z.setZero();
      for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Index v = basis[static_cast<std::size_t>(i)];
        if (v >= n && v < 2 * n) out.z(v - n) = std::max(T(i, rhs), 0.0);
      }
      out.w = M * out.z + q;
      out.solved = out.z.allFinite();
      return out;
    }
  }
  return out;
}

namespace {

// The nearest point to the origin of {y : C y >= d} if `active` is its active set: y = C_a^T mu
// with C_a C_a^T mu = d_a (the active inequalities met as equalities), mu >= 0 and every
// inequality met - the optimality conditions of a strictly convex problem, so y is then its
// one answer. nullopt otherwise (another active set; dependent active rows).
std::optional<Eigen::VectorXd> active_set_point(const Eigen::MatrixXd& C, const Eigen::VectorXd& d,
                                                const std::vector<Eigen::Index>& active,
                                                double tolerance) {
  const Eigen::Index n = static_cast<Eigen::Index>(active.size());
  for (const Eigen::Index row : active) {
    if (row >= C.rows()) return std::nullopt;
  }
  const Eigen::MatrixXd Ca = C(active, Eigen::placeholders::all);
  const Eigen::VectorXd da = d(active);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(C.cols());
  if (n > 0) {
    if (n > C.cols()) return std::nullopt;
    const Eigen::LLT<Eigen::MatrixXd> gram(Ca * Ca.transpose());
    if (gram.info() != Eigen::Success) return std::nullopt;
    const Eigen::VectorXd mu = gram.solve(da);
    if (!mu.allFinite() || mu.minCoeff() < 0.0) return std::nullopt;
    y = Ca.transpose() * mu;
    if ((Ca * y - da).cwiseAbs().maxCoeff() > tolerance) return std::nullopt;
  }
  if ((C * y - d).minCoeff() < -tolerance) return std::nullopt;
  return y;
}

}  // namespace

std::optional<Eigen::VectorXd> nearest_point(const Eigen::MatrixXd& C, const Eigen::VectorXd& d,
                                             bool* reused) {
  if (reused) *reused = false;
  if (C.cols() == 1) {
    // One free direction (a ball in a corner): the interval of y meeting every inequality,
    // and its point nearest zero.
    double lo = -INFINITY, hi = INFINITY;
    for (Eigen::Index i = 0; i < C.rows(); ++i) {
      if (C(i, 0) > 0.0) {
        lo = std::max(lo, d(i) / C(i, 0));
      } else if (C(i, 0) < 0.0) {
        hi = std::min(hi, d(i) / C(i, 0));
      } else if (d(i) > 0.0) {
        return std::nullopt;
      }
    }
    if (!(lo <= hi)) return std::nullopt;
    return Eigen::VectorXd::Constant(1, std::clamp(0.0, lo, hi));
  }
  const double tolerance = 1e-12 * (d.cwiseAbs().maxCoeff() + 1e-300);
  // The active sets of the last few answers (those of an island along its integrated motion
  // barely change from one solve to the next): where one of them still gives the answer, no
  // LCP is solved (see active_set_point).
  thread_local std::vector<std::vector<Eigen::Index>> recent;
  for (std::size_t r = 0; r < recent.size(); ++r) {
    if (std::optional<Eigen::VectorXd> y = active_set_point(C, d, recent[r], tolerance)) {
      std::rotate(recent.begin(), recent.begin() + static_cast<std::ptrdiff_t>(r),
                  recent.begin() + static_cast<std::ptrdiff_t>(r) + 1);
      if (reused) *reused = true;
      return y;
    }
  }
  std::vector<Eigen::Index> subset;
  Eigen::VectorXd y = Eigen::VectorXd::Zero(C.cols());
  Eigen::VectorXd mu;  // the last LCP's multipliers, one per entry of `subset` it was solved over
  for (int round = 0; round < 50; ++round) {
    const Eigen::VectorXd slack = C * y - d;
    bool added = false;
    const std::size_t solved_over = subset.size();
    for (Eigen::Index i = 0; i < slack.size(); ++i) {
      if (slack(i) < -tolerance && std::find(subset.begin(), subset.end(), i) == subset.end()) {
        subset.push_back(i);
        added = true;
      }
    }
    if (!added) {
      std::vector<Eigen::Index> active;
      for (std::size_t i = 0; i < solved_over; ++i) {
        if (mu(static_cast<Eigen::Index>(i)) > 0.0) active.push_back(subset[i]);
      }
      constexpr std::size_t kRecent = 4;
      recent.insert(recent.begin(), std::move(active));
      if (recent.size() > kRecent) recent.pop_back();
      return y;
    }
    const Eigen::MatrixXd Cs = C(subset, Eigen::placeholders::all);
    const Eigen::VectorXd ds = d(subset);
    const LcpSolution lcp = solve_lcp(Cs * Cs.transpose(), -ds);
    if (!lcp.solved) return std::nullopt;
    y = Cs.transpose() * lcp.z;
    mu = lcp.z;
  }
  return std::nullopt;
}

}  // namespace palpable
