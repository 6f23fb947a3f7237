// Lemke's method (impulse/lcp.hpp) against brute force: every complementary basis of a small LCP
// tried in turn (2^n of them), on random problems of the classes it is meant for.
#include "impulse/lcp.hpp"

#include <catch2/catch.hpp>

#include <random>

using namespace palpable;

namespace {

using MatX = Eigen::MatrixXd;
using VecX = Eigen::VectorXd;

// Every solution's z found by enumerating which variables may be positive.
std::vector<VecX> enumerate(const MatX& M, const VecX& q) {
  const Eigen::Index n = q.size();
  std::vector<VecX> found;
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    std::vector<Eigen::Index> in;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (mask & (1u << i)) in.push_back(i);
    }
    VecX z = VecX::Zero(n);
    if (!in.empty()) {
      const Eigen::Index k = static_cast<Eigen::Index>(in.size());
      MatX A(k, k);
      VecX b(k);
      for (Eigen::Index r = 0; r < k; ++r) {
        b(r) = -q(in[static_cast<std::size_t>(r)]);
        for (Eigen::Index c = 0; c < k; ++c) {
          A(r, c) = M(in[static_cast<std::size_t>(r)], in[static_cast<std::size_t>(c)]);
        }
      }
      Eigen::FullPivLU<MatX> lu(A);
      if (!lu.isInvertible()) continue;
      const VecX x = lu.solve(b);
      for (Eigen::Index r = 0; r < k; ++r) z(in[static_cast<std::size_t>(r)]) = x(r);
    }
    const VecX w = M * z + q;
    if (z.minCoeff() >= -1e-9 && w.minCoeff() >= -1e-9) found.push_back(z);
  }
  return found;
}

void check_solution(const MatX& M, const VecX& q, const LcpSolution& s) {
  const double scale = 1.0 + q.cwiseAbs().maxCoeff() + M.cwiseAbs().maxCoeff();
  REQUIRE(s.solved);
  CHECK(s.z.minCoeff() >= 0.0);
  CHECK(s.w.minCoeff() >= -1e-10 * scale);
  CHECK((M * s.z + q - s.w).cwiseAbs().maxCoeff() <= 1e-12 * scale * (1.0 + s.z.norm()));
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    CHECK(std::abs(s.z(i) * s.w(i)) <= 1e-10 * scale * (1.0 + s.z.norm()));
  }
}

}  // namespace

TEST_CASE("lcp: Lemke finds the unique solution of P-matrix problems brute force finds",
          "[impulse][lcp]") {
  std::mt19937_64 rng(20261127);
  std::normal_distribution<double> normal;
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Index n = 1 + trial % 8;
    MatX A(n, n), S(n, n);
    for (Eigen::Index i = 0; i < n; ++i) {
      for (Eigen::Index j = 0; j < n; ++j) {
        A(i, j) = normal(rng);
        S(i, j) = normal(rng);
      }
    }
    // Positive definite plus skew-symmetric: a P-matrix (unique solution for every q).
    const MatX M = A * A.transpose() + 0.1 * MatX::Identity(n, n) + (S - S.transpose());
    VecX q(n);
    for (Eigen::Index i = 0; i < n; ++i) q(i) = normal(rng);
    const LcpSolution s = solve_lcp(M, q);
    check_solution(M, q, s);
    const std::vector<VecX> all = enumerate(M, q);
    REQUIRE(all.size() == 1);
    CHECK((s.z - all.front()).cwiseAbs().maxCoeff() <= 1e-9 * (1.0 + all.front().norm()));
    ++checked;
  }
  CHECK(checked == 400);
}

TEST_CASE("lcp: degenerate and semi-definite problems are solved, an infeasible one is not",
          "[impulse][lcp]") {
  SECTION("q >= 0: z = 0") {
    const MatX M = MatX::Identity(3, 3);
    const VecX q = VecX::Ones(3);
    const LcpSolution s = solve_lcp(M, q);
    REQUIRE(s.solved);
    CHECK(s.z.isZero());
    CHECK(s.pivots == 0);
  }
  SECTION("ties in the ratio test (equal rows, equal q)") {
    MatX M(3, 3);
    M << 1, 1, 0, 1, 1, 0, 0, 0, 1;
    VecX q(3);
    q << -1, -1, -1;
    check_solution(M, q, solve_lcp(M, q));
  }
  SECTION("positive semi-definite, singular") {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    for (int trial = 0; trial < 100; ++trial) {
      const Eigen::Index n = 2 + trial % 6;
      MatX A(n, 1 + n / 2);
      for (Eigen::Index i = 0; i < A.rows(); ++i) {
        for (Eigen::Index j = 0; j < A.cols(); ++j) A(i, j) = normal(rng);
      }
      // q in the range of M plus a non-negative part: feasible, so Lemke must solve it.
      const MatX M = A * A.transpose();
      VecX y(n), p(n);
      for (Eigen::Index i = 0; i < n; ++i) {
        y(i) = std::abs(normal(rng));
        p(i) = std::abs(normal(rng));
      }
      const VecX q = -M * y + p;
      check_solution(M, q, solve_lcp(M, q));
    }
  }
  SECTION("infeasible: w = -z - 1 cannot be >= 0") {
    const MatX M = -MatX::Identity(1, 1);
    const VecX q = -VecX::Ones(1);
    CHECK_FALSE(solve_lcp(M, q).solved);
  }
  SECTION("non-finite input") {
    MatX M = MatX::Identity(2, 2);
    M(0, 1) = NAN;
    CHECK_FALSE(solve_lcp(M, -VecX::Ones(2)).solved);
  }
}
