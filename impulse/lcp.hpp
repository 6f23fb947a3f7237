#pragma once
// The linear complementarity problem: given M (n x n) and q, find z >= 0 with w = M z + q >= 0
// and z . w = 0. Solved by Lemke's complementary pivoting with the covering vector of ones and a
// lexicographic ratio test (Cottle, Pang & Stone, "The Linear Complementarity Problem", 1992,
// sections 4.4 and 4.9): it terminates, with a solution where M is copositive-plus (positive
// semi-definite, a P-matrix, the friction problems of Stewart & Trinkle) and the problem is
// feasible, or on a secondary ray, which reports "no solution found". Dense tableau: for the few
// dozen unknowns of one island's contacts.
#include <Eigen/Dense>

namespace palpable {

struct LcpSolution {
  bool solved = false;  // false: a secondary ray, the pivot budget spent, or non-finite input
  Eigen::VectorXd z, w;
  int pivots = 0;
};

LcpSolution solve_lcp(const Eigen::MatrixXd& M, const Eigen::VectorXd& q);

}  // namespace palpable
