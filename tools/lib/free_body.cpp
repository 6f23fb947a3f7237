#include "tools/lib/free_body.hpp"

#include "core/check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace palpable::tools {

void check_moments_of_inertia(const Vec3& moments_M, const std::string& where) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(moments_M[i]) || moments_M[i] <= 0.0) {
      throw InputError(where, "expected three finite positive moments of inertia");
    }
  }
  for (int i = 0; i < 3; ++i) {
    const double others = moments_M[(i + 1) % 3] + moments_M[(i + 2) % 3];
    if (moments_M[i] > others * (1.0 + 1e-12)) {
      throw InputError(where,
                       "moments violate the triangle inequality (each must be <= the sum of "
                       "the other two for a real body)");
    }
  }
}

Body make_free_body(const std::string& name, double mass, const Vec3& moments_M) {
  PALPABLE_CHECK(std::isfinite(mass) && mass > 0.0, "mass must be finite and positive");
  std::array<int, 3> order{0, 1, 2};
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return moments_M[a] < moments_M[b]; });
  // Column j of R_MB is the modelling axis that becomes principal axis j; flip the last column
  // if the permutation is odd so that R_MB is a proper rotation.
  Mat3 R_MB = Mat3::Zero();
  for (int j = 0; j < 3; ++j) R_MB(order[j], j) = 1.0;
  if (R_MB.determinant() < 0.0) R_MB.col(2) = -R_MB.col(2);
  Body body;
  body.name = name;
  body.motion = MotionKind::kDynamic;
  body.mass.mass = mass;
  body.mass.inv_mass = 1.0 / mass;
  body.mass.principal_moments = Vec3(moments_M[order[0]], moments_M[order[1]], moments_M[order[2]]);
  body.mass.q_MB = Quat(R_MB).normalized();
  body.mass.inertia_M = moments_M.asDiagonal();
  return body;
}

}  // namespace palpable::tools
