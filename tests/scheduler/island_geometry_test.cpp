// A held link's geometry (scheduler/island.hpp) on hand-made links, without a simulation: which
// edge of the support's face a reduced patch lies on (support_edge_under), where the link's plane
// is tilted from that face, as a face-on-face link made from a closest-feature query's normal is.
#include "scheduler/island.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace palpable;

namespace {

// A triangle face of a support, in its frame, and a link whose plane is the face's tilted by
// `tilt` radians about the x axis (the face's normal is z).
HeldLink tilted_link(double tilt) {
  HeldLink link;
  link.support_face_S = {Vec3(-0.006, -0.005, 0.0), Vec3(0.0365, -0.002, 0.0),
                         Vec3(0.022, 0.018, 0.0)};
  link.normal_S = Vec3(0.0, -std::sin(tilt), std::cos(tilt));
  link.point_S = Vec3::Zero();
  link.t1_S = link.normal_S.unitOrthogonal();
  return link;
}

// Points on edge e of the face, seen along the link's normal: the edge's points at fractions
// `at`, moved `height` along the normal and `off` within the plane, away from the face.
std::vector<Vec3> over_edge(const HeldLink& link, const BodyState& support, std::size_t e,
                            const std::vector<double>& at, double height, double off) {
  const Mat3 R = support.q_WM.toRotationMatrix();
  const Vec3 n = R * link.normal_S;
  const Vec3 a = support.x_W + R * link.support_face_S[e];
  const Vec3 b = support.x_W + R * link.support_face_S[(e + 1) % link.support_face_S.size()];
  const Vec3 c = support.x_W + R * link.support_face_S[(e + 2) % link.support_face_S.size()];
  Vec3 d = b - a;
  d -= n * n.dot(d);
  Vec3 out = (a - c) - n * n.dot(a - c);  // within the plane, away from the face
  out = (out - d * d.dot(out) / d.squaredNorm()).normalized();
  std::vector<Vec3> points;
  for (double s : at) points.push_back(a + s * (b - a) + height * n + off * out);
  return points;
}

}  // namespace

TEST_CASE("island: a reduced patch on the edge of a support's face tilted from the plane is on it",
          "[island]") {
  // A posed support: turned and moved, so that nothing lines up with the world's axes.
  BodyState support;
  support.x_W = Vec3(0.3, -0.2, 0.05);
  support.q_WM = Quat(Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, -0.5).normalized()));
  for (double tilt : {0.0, 1e-6, 1e-4, 3e-3}) {
    CAPTURE(tilt);
    const HeldLink link = tilted_link(tilt);
    for (std::size_t e = 0; e < 3; ++e) {
      CAPTURE(e);
      // On the edge (the patch sits at the held gap above the plane): found, whatever the tilt.
      // Measured along the tilted edge itself, 1e-4 rad put such points 1e-6 m off it.
      CHECK(support_edge_under(link, support, over_edge(link, support, e, {0.2, 0.6}, 1e-4, 0.0)) ==
            static_cast<int>(e));
      CHECK(support_edge_under(link, support, over_edge(link, support, e, {0.5}, 0.0, 0.0)) ==
            static_cast<int>(e));
      // A micrometre off the edge within the plane, or one point of two off it: not on it.
      CHECK(support_edge_under(link, support,
                               over_edge(link, support, e, {0.2, 0.6}, 1e-4, 1e-6)) == -1);
      std::vector<Vec3> one_off = over_edge(link, support, e, {0.2}, 1e-4, 0.0);
      one_off.push_back(over_edge(link, support, e, {0.7}, 1e-4, -1e-6).front());
      CHECK(support_edge_under(link, support, one_off) == -1);
    }
  }
  // A support without a face (a halfspace's link) has no edge.
  HeldLink unbounded = tilted_link(0.0);
  unbounded.support_face_S.clear();
  CHECK(support_edge_under(unbounded, support, {Vec3::Zero()}) == -1);
}
