// Lemke's method (impulse/lcp.hpp) against brute force: every complementary basis of a small LCP
// tried in turn (2^n of them), on random problems of the classes it is meant for.
#include "impulse/lcp.hpp"

#include <catch2/catch.hpp>

#include <optional>
#include <random>

using namespace palpable;

namespace {

using MatX = Eigen::MatrixXd;
using VecX = Eigen::VectorXd;

// The indices i < n whose bit is set in mask: one subset of a brute-force enumeration.
std::vector<Eigen::Index> members(unsigned mask, Eigen::Index n) {
  std::vector<Eigen::Index> in;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (mask & (1u << i)) in.push_back(i);
  }
  return in;
}

// Every solution's z found by enumerating which variables may be positive.
std::vector<VecX> enumerate(const MatX& M, const VecX& q) {
  const Eigen::Index n = q.size();
  std::vector<VecX> found;
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    const std::vector<Eigen::Index> in = members(mask, n);
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

namespace {

// The point of {y : C y >= d} nearest the origin by brute force: the projection of the origin
// onto every affine set {C_S y = d_S} of independent rows S (the nearest point lies in the
// relative interior of a face, the projection onto that face's affine hull), the least of those
// that meet every inequality. nullopt where none does (the set is empty). Independent rows are
// at most C.cols(), so only the subsets that small are visited.
std::optional<VecX> nearest_by_enumeration(const MatX& C, const VecX& d) {
  const Eigen::Index m = C.rows(), k = C.cols();
  const double tolerance = 1e-9 * (d.cwiseAbs().maxCoeff() + 1.0);
  std::optional<VecX> best;
  std::vector<Eigen::Index> in;
  auto consider = [&]() {
    VecX y = VecX::Zero(k);
    if (!in.empty()) {
      const MatX Cs = C(in, Eigen::placeholders::all);
      Eigen::FullPivLU<MatX> lu(Cs * Cs.transpose());
      if (!lu.isInvertible()) return;
      y = Cs.transpose() * lu.solve(d(in));
    }
    if ((C * y - d).minCoeff() < -tolerance) return;
    if (!best || y.norm() < best->norm()) best = y;
  };
  auto subsets_from = [&](auto&& self, Eigen::Index from) -> void {
    consider();
    if (static_cast<Eigen::Index>(in.size()) == k) return;
    for (Eigen::Index i = from; i < m; ++i) {
      in.push_back(i);
      self(self, i + 1);
      in.pop_back();
    }
  };
  subsets_from(subsets_from, 0);
  return best;
}

MatX random_matrix(std::mt19937_64& rng, Eigen::Index rows, Eigen::Index cols) {
  std::normal_distribution<double> normal;
  MatX A(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) A(i, j) = normal(rng);
  }
  return A;
}

}  // namespace

TEST_CASE("nearest_point: the nearest point of a polyhedron, against enumeration of its faces",
          "[impulse][lcp]") {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  int reused_count = 0, calls = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Eigen::Index k = 1 + trial % 4, m = 3 + trial % 9;
    CAPTURE(trial, k, m);
    const MatX C = random_matrix(rng, m, k);
    // d = C y0 - slack, slack >= 0 (y0 meets every inequality: the set is not empty); a few
    // trials leave it possibly empty.
    const VecX y0 = random_matrix(rng, k, 1);
    VecX slack = random_matrix(rng, m, 1).cwiseAbs();
    VecX d = C * y0 - slack;
    if (trial % 10 == 9) d = random_matrix(rng, m, 1) + VecX::Constant(m, 1.0);
    // The same problem, then a sequence of small moves of it (an integrated motion's solves):
    // the later calls may be answered from a remembered active set, and must agree all the same.
    for (int move = 0; move < 6; ++move) {
      CAPTURE(move);
      const MatX Cm = C + 1e-6 * move * random_matrix(rng, m, k);
      const VecX dm = d + 1e-6 * move * random_matrix(rng, m, 1);
      const std::optional<VecX> expected = nearest_by_enumeration(Cm, dm);
      bool reused = false;
      const std::optional<VecX> got = nearest_point(Cm, dm, &reused);
      ++calls;
      reused_count += reused ? 1 : 0;
      REQUIRE(got.has_value() == expected.has_value());
      if (!got) continue;
      CHECK((*got - *expected).norm() <= 1e-9 * (expected->norm() + 1.0));
      CHECK((Cm * *got - dm).minCoeff() >= -1e-9 * (dm.cwiseAbs().maxCoeff() + 1.0));
    }
  }
  // The remembered active sets answer most of the moved problems (k >= 2; one column is an
  // interval, solved directly).
  CAPTURE(reused_count, calls);
  CHECK(reused_count >= calls / 3);
}

TEST_CASE("nearest_point: a remembered active set that no longer holds is not used",
          "[impulse][lcp]") {
  // y >= (1, 1) componentwise, then the same rows with the first bound dropped to -1: the
  // first answer's active set {0, 1}, tried first, gives (-1, 1) with a negative multiplier:
  // not the nearest point, (0, 1).
  MatX C = MatX::Identity(2, 2);
  VecX d(2);
  d << 1.0, 1.0;
  REQUIRE(nearest_point(C, d).has_value());
  d << -1.0, 1.0;
  const std::optional<VecX> y = nearest_point(C, d);
  REQUIRE(y.has_value());
  CHECK((*y - Eigen::Vector2d(0.0, 1.0)).norm() <= 1e-15);
  // An empty set after a non-empty one: y_1 >= 1 and -y_1 >= 0.
  MatX E(2, 2);
  E << 1, 0, -1, 0;
  VecX e(2);
  e << 1.0, 0.0;
  CHECK_FALSE(nearest_point(E, e).has_value());
}

TEST_CASE("nearest_point: many nearly parallel inequalities in few unknowns", "[impulse][lcp]") {
  // Rows in groups of 16 nearly parallel ones (the facets of an inscribed 16-gon cone, seen
  // from the null space of a redundant island: nearest_feasible's problems), most of them
  // broken at the origin, against enumeration of every active set of at most k rows. Of the 40
  // sets, 18 are not empty. (The dual LCP over every broken row at once is a tableau of up to 48
  // or 64 rows of rank k here.)
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Index k = 2 + trial % 2, groups = 3 + trial % 2;
    CAPTURE(trial, k);
    MatX C(16 * groups, k);
    VecX d(16 * groups);
    for (Eigen::Index g = 0; g < groups; ++g) {
      const VecX axis = random_matrix(rng, k, 1).normalized();
      const MatX spread = random_matrix(rng, k, 2);
      const double offset = normal(rng);
      for (int j = 0; j < 16; ++j) {
        const double angle = 2.0 * M_PI * j / 16;
        const VecX row =
            axis + 0.3 * (std::cos(angle) * spread.col(0) + std::sin(angle) * spread.col(1));
        C.row(16 * g + j) = row.transpose();
        d(16 * g + j) = offset + 1.0;
      }
    }
    const std::optional<VecX> expected = nearest_by_enumeration(C, d);
    const std::optional<VecX> got = nearest_point(C, d);
    REQUIRE(got.has_value() == expected.has_value());
    if (!got) continue;
    CHECK((*got - *expected).norm() <= 1e-9 * (expected->norm() + 1.0));
  }
}
