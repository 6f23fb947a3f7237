// GJK's simplex step: the closest point of a simplex to the origin by enumerating its faces
// (see gjk.hpp for why not Johnson's recursion).
#include "distance/gjk.hpp"

#include <Eigen/Dense>

#include <cmath>

namespace palpable {

bool reduce_to_closest_face(GjkSimplex& simplex) {
  const int n = simplex.count;
  double best_sq = kInfinity;
  int best_mask = 0;
  std::array<double, 4> best_weights{};
  bool inside = false;
  for (int mask = 1; mask < (1 << n); ++mask) {
    std::array<int, 4> idx{};
    int k = 0;
    for (int i = 0; i < n; ++i) {
      if (mask & (1 << i)) idx[k++] = i;
    }
    // Minimise |w0 + sum_j mu_j e_j| with e_j = w_j - w0: the normal equations G mu = -E^T w0.
    const Vec3& w0 = simplex.points[idx[0]].w;
    std::array<double, 4> lambda{};
    if (k == 1) {
      lambda[0] = 1.0;
    } else {
      // Fixed-capacity matrices: the query allocates nothing.
      Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 3> E(3, k - 1);
      double scale = 1.0;
      for (int j = 1; j < k; ++j) {
        E.col(j - 1) = simplex.points[idx[j]].w - w0;
        scale *= E.col(j - 1).squaredNorm();
      }
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3> G = E.transpose() * E;
      const double det = G.determinant();
      // A face that is flat to rounding (its Gram determinant a tiny fraction of the product of
      // its edge lengths squared): its lower faces stand for it.
      if (!(std::abs(det) > 1e-13 * scale)) continue;
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> mu =
          G.partialPivLu().solve(-E.transpose() * w0);
      double sum = 0.0;
      bool positive = true;
      for (int j = 1; j < k; ++j) {
        lambda[j] = mu(j - 1);
        sum += mu(j - 1);
        positive = positive && mu(j - 1) >= 0.0;
      }
      lambda[0] = 1.0 - sum;
      if (!positive || !(lambda[0] >= 0.0)) continue;
    }
    Vec3 v = Vec3::Zero();
    for (int j = 0; j < k; ++j) v += lambda[j] * simplex.points[idx[j]].w;
    const double sq = k == 4 ? 0.0 : v.squaredNorm();
    // Prefer the smaller face on a tie (fewer points to carry).
    if (sq < best_sq) {
      best_sq = sq;
      best_mask = mask;
      best_weights = lambda;
      inside = k == 4;
    }
  }
  if (best_mask == 0) {
    // Every face was rejected (non-finite input): keep the newest point alone.
    simplex.points[0] = simplex.points[n - 1];
    simplex.count = 1;
    simplex.weights[0] = 1.0;
    simplex.v = simplex.points[0].w;
    return false;
  }
  GjkSimplex reduced;
  int k = 0;
  for (int i = 0; i < n; ++i) {
    if (!(best_mask & (1 << i))) continue;
    reduced.points[k] = simplex.points[i];
    reduced.weights[k] = best_weights[k];
    ++k;
  }
  reduced.count = k;
  reduced.v = Vec3::Zero();
  for (int j = 0; j < k; ++j) reduced.v += reduced.weights[j] * reduced.points[j].w;
  if (inside) reduced.v = Vec3::Zero();
  simplex = reduced;
  return inside;
}

}  // namespace palpable
