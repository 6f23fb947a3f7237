// tools/lib/free_body: the principal frame is a proper rotation of the modelling frame that
// reproduces the given inertia, and bad moments are rejected as input errors.
#include "tools/lib/free_body.hpp"

#include "core/check.hpp"

#include <catch2/catch.hpp>

namespace palpable::tools {

TEST_CASE("free_body: principal frame reproduces the modelling-frame inertia", "[free_body]") {
  for (const Vec3& m :
       {Vec3(1, 2, 3), Vec3(3, 2, 1), Vec3(2, 3, 1), Vec3(2, 1, 2.5), Vec3(1, 1, 1.5)}) {
    CAPTURE(m);
    const Body body = make_free_body("b", 2.0, m);
    const Vec3& I = body.mass.principal_moments;
    CHECK(I.x() <= I.y());
    CHECK(I.y() <= I.z());
    const Mat3 R_MB = body.mass.q_MB.toRotationMatrix();
    CHECK(std::abs(R_MB.determinant() - 1.0) <= 1e-15);
    CHECK((R_MB * I.asDiagonal() * R_MB.transpose() - Mat3(m.asDiagonal())).norm() <= 1e-15);
    CHECK(body.mass.inv_mass == 0.5);
  }
}

TEST_CASE("free_body: bad moments are input errors", "[free_body]") {
  CHECK_THROWS_AS(check_moments_of_inertia(Vec3(1, 2, 4), "--inertia"), InputError);
  CHECK_THROWS_AS(check_moments_of_inertia(Vec3(1, -2, 2), "--inertia"), InputError);
  CHECK_THROWS_AS(check_moments_of_inertia(Vec3(1, 0, 1), "--inertia"), InputError);
  CHECK_THROWS_AS(check_moments_of_inertia(Vec3(1, std::nan(""), 1), "--inertia"), InputError);
  CHECK_NOTHROW(check_moments_of_inertia(Vec3(1, 2, 3), "--inertia"));  // a flat plate
  CHECK_NOTHROW(check_moments_of_inertia(Vec3(1, 2, 2.5), "--inertia"));
}

}  // namespace palpable::tools
