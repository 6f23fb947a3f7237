#include "impulse/lcp.hpp"

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

}  // namespace palpable
