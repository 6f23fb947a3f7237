// libccd MPR cross-check wrappers (distance/crosscheck/mpr.cpp): intersection verdicts and the
// penetration depth and direction on closed-form overlaps.
#include "distance/crosscheck/mpr.hpp"

#include "core/check.hpp"
#include "distance_test_support.hpp"

#include <catch2/catch.hpp>

using namespace palpable;
using namespace palpable::test;

TEST_CASE("MPR intersection verdicts and penetration of spheres and cubes", "[distance][mpr]") {
  const TestShape a = make_test_shape("a", Sphere{0.5});
  const TestShape b = make_test_shape("b", Sphere{0.25});
  const MprShape sa(*a.geometry, Pose{});
  MprShape sb(*b.geometry, Pose{Vec3(0.8, 0, 0), Quat::Identity()});
  CHECK_FALSE(mpr_intersect(sa, sb));
  sb.set_pose(Pose{Vec3(0.65, 0, 0), Quat::Identity()});
  CHECK(mpr_intersect(sa, sb));
  const MprPenetration p = mpr_penetration(sa, sb);
  REQUIRE(p.intersecting);
  CHECK(p.depth == Approx(0.1).epsilon(1e-6));
  // libccd's convention: moving body 2 by depth * direction separates them; here direction is
  // +x, from body 1 toward body 2 (so the contact normal n of DESIGN.md §3 is -direction).
  CHECK((p.direction_W - Vec3::UnitX()).norm() < 1e-6);

  // Face-on-face cubes (where libccd 2.1's EPA returns NaN directions, DESIGN.md §3).
  const TestShape box = cube();
  const MprShape c1(*box.geometry, Pose{});
  const MprShape c2(*box.geometry, Pose{Vec3(0.1, 0.2, 0.9), Quat::Identity()});
  const MprPenetration q = mpr_penetration(c1, c2);
  REQUIRE(q.intersecting);
  CHECK(std::isfinite(q.direction_W.norm()));
  CHECK(q.depth > 0.0);
  CHECK(q.depth <= 0.1 + 1e-9);  // the portal depth never exceeds the true minimum here
  const MprShape c3(*box.geometry, Pose{Vec3(0.0, 0.0, 1.0 + 1e-6), Quat::Identity()});
  CHECK_FALSE(mpr_intersect(c1, c3));

  const TestShape ground = make_test_shape("ground", Halfspace{Vec3::UnitZ(), 0.0});
  CHECK_THROWS_AS(MprShape(*ground.geometry, Pose{}), InputError);
}

TEST_CASE("penetration recovery follows the sign convention", "[distance][mpr]") {
  const TestShape box = cube();
  const Pose lower{};
  const Pose upper{Vec3(0.05, -0.02, 0.97), Quat(Eigen::AngleAxisd(0.01, Vec3::UnitX()))};
  PairCache cache;
  const DistanceResult r = closest_features(*box.geometry, upper, *box.geometry, lower, cache, 100);
  REQUIRE(r.status == ContactStatus::kPenetrating);
  const PenetrationRecovery rec =
      recover_penetration(*box.geometry, upper, *box.geometry, lower, r);
  REQUIRE(rec.intersecting);
  CHECK(rec.normal_W.z() > 0.99);  // body 1 (upper) is pushed up
  CHECK(rec.depth > 0.0);
  CHECK(rec.depth < 0.05);
  // Moving body 1 by depth (plus a hair) along the normal separates the pair.
  const Pose moved{upper.x_W + (rec.depth + 1e-9) * rec.normal_W, upper.q_WM};
  const DistanceResult after =
      closest_features(*box.geometry, moved, *box.geometry, lower, cache, 100);
  CHECK(after.status == ContactStatus::kSeparated);
}
