// A held link's geometry (scheduler/held_link.hpp) on hand-made links, without a simulation: which
// edge of the support's face a reduced patch lies on (support_edge_under), where the link's plane
// is tilted from that face, as a face-on-face link made from a closest-feature query's normal is;
// which pairs of edges a held link watches, and their separation (edge_watch_candidates,
// edge_separation), against closed forms and a brute-force separating-axis test.
#include "scheduler/held_link.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <utility>
#include <vector>

using namespace palpable;

namespace {

constexpr double kPi = 3.14159265358979323846;

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

// The one piece of a convex polyhedron's geometry, posed in the world.
struct PosedPiece {
  ShapeGeometry geometry;
  Mat3 R;
  Vec3 origin;
  PosedPiece(ConvexPolyhedron shape, const Quat& q, const Vec3& x)
      : geometry(std::make_shared<const Shape>(std::move(shape))),
        R(q.toRotationMatrix()),
        origin(x) {}
  const ShapeGeometry::Piece& piece() const { return geometry.pieces().front(); }
  const FeatureMesh& mesh() const { return *piece().mesh; }
  Vec3 vertex(int v) const { return origin + R * mesh().vertex(v); }
  Vec3 edge(int h) const { return R * (mesh().head(h) - mesh().tail(h)); }
};

std::vector<EdgeWatch> candidates(const PosedPiece& mover, const PosedPiece& support,
                                  std::vector<bool> held = {}) {
  held.resize(static_cast<std::size_t>(mover.mesh().num_vertices()), false);
  return edge_watch_candidates(mover.piece(), mover.R, mover.origin, held, support.piece(),
                               support.R, support.origin, 1e-4);
}

double separation(const PosedPiece& mover, const PosedPiece& support, const EdgeWatch& w) {
  return edge_separation(support.mesh(), support.R, support.origin, mover.mesh(), mover.R,
                         mover.origin, w);
}

// The separation of two pieces along `axis`: the mover's least extent along it less the
// support's greatest.
double along(const PosedPiece& mover, const PosedPiece& support, const Vec3& axis) {
  double mover_lo = kInfinity, support_hi = -kInfinity;
  for (int v = 0; v < mover.mesh().num_vertices(); ++v) {
    mover_lo = std::min(mover_lo, axis.dot(mover.vertex(v)));
  }
  for (int v = 0; v < support.mesh().num_vertices(); ++v) {
    support_hi = std::max(support_hi, axis.dot(support.vertex(v)));
  }
  return mover_lo - support_hi;
}

// The separating-axis test by brute force: the largest separation of the two pieces along any
// face normal or cross product of two edges (negative: they overlap, by at least that much).
double separating_axis(const PosedPiece& a, const PosedPiece& b) {
  std::vector<Vec3> axes;
  for (const PosedPiece* p : {&a, &b}) {
    for (int f = 0; f < p->mesh().num_faces(); ++f) axes.push_back(p->R * p->mesh().face_normal(f));
  }
  for (int h = 0; h < a.mesh().num_half_edges(); ++h) {
    for (int k = 0; k < b.mesh().num_half_edges(); ++k) {
      const Vec3 n = a.edge(h).cross(b.edge(k));
      if (n.norm() > 1e-9 * a.edge(h).norm() * b.edge(k).norm()) axes.push_back(n.normalized());
    }
  }
  double best = -kInfinity;
  for (const Vec3& n : axes) {
    double a_lo = kInfinity, a_hi = -kInfinity, b_lo = kInfinity, b_hi = -kInfinity;
    for (int v = 0; v < a.mesh().num_vertices(); ++v) {
      a_lo = std::min(a_lo, n.dot(a.vertex(v)));
      a_hi = std::max(a_hi, n.dot(a.vertex(v)));
    }
    for (int v = 0; v < b.mesh().num_vertices(); ++v) {
      b_lo = std::min(b_lo, n.dot(b.vertex(v)));
      b_hi = std::max(b_hi, n.dot(b.vertex(v)));
    }
    best = std::max({best, b_lo - a_hi, a_lo - b_hi});
  }
  return best;
}

}  // namespace

TEST_CASE("island: a held link watches two edges crossing where no vertex enters", "[island]") {
  // Two cubes (half side 0.05 m) whose edges cross at right angles: the support turned 45 degrees
  // about x (its top is an edge along x), the mover 45 degrees about y (its bottom an edge along
  // y), over the support's edge at x0, its bottom edge `gap` above the support's top edge.
  const double h = 0.05, top = h * std::sqrt(2.0);
  const PosedPiece support(ConvexPolyhedron::box(Vec3::Constant(h)),
                           Quat(Eigen::AngleAxisd(kPi / 4, Vec3::UnitX())), Vec3::Zero());
  // `about_z` turns the mover's edge about the vertical, away from crossing at right angles.
  auto mover = [&](double x0, double gap, double about_z = 0.0, double y0 = 0.0) {
    return PosedPiece(
        ConvexPolyhedron::box(Vec3::Constant(h)),
        Quat(Eigen::AngleAxisd(about_z, Vec3::UnitZ()) * Eigen::AngleAxisd(kPi / 4, Vec3::UnitY())),
        Vec3(x0, y0, 2.0 * top + gap));
  };
  for (const double gap : {5e-5, 0.0, -3e-5}) {
    CAPTURE(gap);
    const PosedPiece m = mover(0.01, gap);
    const std::vector<EdgeWatch> watch = candidates(m, support);
    // The two crossing edges, and no other pair: their separation is the gap, negative once the
    // mover's edge has gone into the support (crossed, no vertex of either inside the other).
    REQUIRE(watch.size() == 1);
    CHECK(std::abs(support.edge(watch[0].support_edge).normalized().x()) == Approx(1.0));
    CHECK(std::abs(m.edge(watch[0].mover_edge).normalized().y()) == Approx(1.0));
    CHECK(std::abs(separation(m, support, watch[0]) - gap) <= 1e-15);
    CHECK(std::abs(separating_axis(support, m) - gap) <= 1e-15);
    // Followed as the mover moves down 8e-5 m and along both edges, and as it turns: the
    // separation along the turned edges' normal, as the separating-axis test has it.
    const PosedPiece lower = mover(0.02, gap - 8e-5, 0.0, 0.01);
    CHECK(std::abs(separation(lower, support, watch[0]) - (gap - 8e-5)) <= 1e-15);
    const PosedPiece turned = mover(0.01, gap, 0.3);
    CHECK(std::abs(separation(turned, support, watch[0]) - gap) <= 1e-15);
    CHECK(std::abs(separating_axis(support, turned) - gap) <= 1e-15);
    // The mover's edge held (both its ends in the held feature): the tip event's, not watched.
    std::vector<bool> held(8, false);
    held[m.mesh().tail_vertex(watch[0].mover_edge)] = true;
    held[m.mesh().head_vertex(watch[0].mover_edge)] = true;
    CHECK(candidates(m, support, held).empty());
  }
  // Farther apart than the envelope (1e-4 m); crossing beyond the end of the support's edge
  // (x0 = 0.06 > 0.05: the mover's edge passes its end vertex, which the vertex watches see);
  // edges parallel or within 1e-3 rad of it (the mover's edge turned onto the support's, edge
  // on edge along x, 5e-5 m above it): none.
  CHECK(candidates(mover(0.01, 2e-4), support).empty());
  CHECK(candidates(mover(0.06, 5e-5), support).empty());
  CHECK(candidates(mover(0.0, 5e-5, kPi / 2), support).empty());
  CHECK(candidates(mover(0.0, 5e-5, kPi / 2 - 5e-4), support).empty());
  // Chosen 2e-3 rad from parallel, then turned through it to 1e-8 rad the other side: the
  // edges' cross product reverses, the separation along the watch's axis does not (the
  // separating-axis test still has them 5e-5 m apart).
  const std::vector<EdgeWatch> near = candidates(mover(0.0, 5e-5, kPi / 2 - 2e-3), support);
  REQUIRE(near.size() == 1);
  CHECK(separation(mover(0.0, 5e-5, kPi / 2 + 1e-8), support, near[0]) == Approx(5e-5));
  CHECK(separating_axis(support, mover(0.0, 5e-5, kPi / 2 + 1e-8)) == Approx(5e-5));
}

TEST_CASE("island: along each watched pair of edges, the separation is the two hulls'",
          "[island]") {
  // Random hulls of 10 points placed near touching (the separating-axis test's separation
  // within 2e-5 m of zero, either side): for every pair of edges watched, its separation is the
  // two hulls' along its axis (the mover's least extent less the support's greatest), so the
  // axis lies in both edges' normal cones, oriented out of the support, and no more than the
  // separating-axis test's. Where that axis is the one the test finds, the two agree.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto hull = [&] {
    std::vector<Vec3> points;
    for (int k = 0; k < 10; ++k) points.push_back(0.02 * Vec3(u(rng), u(rng), u(rng)));
    return ConvexPolyhedron::from_points(points);
  };
  auto turn = [&] { return Quat(u(rng), u(rng), u(rng), u(rng)).normalized(); };
  int watched = 0, deepest_is_sat = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const PosedPiece support(hull(), turn(), Vec3::Zero());
    const Vec3 direction = Vec3(u(rng), u(rng), u(rng)).normalized();
    const ConvexPolyhedron shape = hull();
    const Quat q = turn();
    // Along `direction`, bisected to where the separating-axis test reads `target`.
    const double target = 2e-5 * u(rng);
    double lo = 0.0, hi = 0.1;
    for (int it = 0; it < 80; ++it) {
      const double mid = 0.5 * (lo + hi);
      (separating_axis(support, PosedPiece(shape, q, mid * direction)) < target ? lo : hi) = mid;
    }
    const PosedPiece mover(shape, q, hi * direction);
    const double sat = separating_axis(support, mover);
    double deepest = kInfinity;
    for (const EdgeWatch& w : candidates(mover, support)) {
      ++watched;
      const double g = separation(mover, support, w);
      CHECK(std::abs(g - along(mover, support, w.axis_W)) <= 1e-12);
      CHECK(g <= sat + 1e-12);
      deepest = std::min(deepest, g);
    }
    if (std::abs(deepest - sat) <= 1e-12) ++deepest_is_sat;
  }
  std::printf(
      "edge watch: %d pairs watched over 1500 placements, the separating-axis value in %d\n",
      watched, deepest_is_sat);
  CHECK(watched > 500);
  CHECK(deepest_is_sat > 100);
}

TEST_CASE("island: the edge watch sees the crossing of two hulls in a pile", "[island]") {
  // tools/stacks/pile.py 200 hull 0.5 --seed 1, at 0.4464308 s (1de97ee): p56 held on a face of
  // p47 (at rest on the floor) by an edge, a vertex of p56 hanging beyond p47's rim. Two edges of
  // p56 had crossed two of p47's near that vertex, 60.6 um deep along an edge-edge axis, no vertex
  // of either inside the other; the pair was then found overlapping 54,162 times. The states
  // below are the two bodies' at that instant (centre of mass and orientation, printed at full
  // precision), the vertices those of the scene. Among the pairs of edges watched there, the
  // deepest is the brute-force separating-axis test's overlap.
  const std::vector<Vec3> p47 = {
      {0.017958640800025405, -0.024047588933351155, -0.01598866548073745},
      {-0.008626640131401919, -0.009346578172408731, 0.016709815642782802},
      {-0.012380021859193603, -0.009689322504354737, -0.0006207926511913528},
      {0.022540362183743883, -0.010274252235011978, 0.006685218695842973},
      {-0.022570030720604334, -0.0034279944633615334, 0.021360654239718037},
      {-0.014129754797252442, -0.007176919367855101, 0.007707237720116514},
      {0.003277072494533316, 0.0038015772705169634, 0.005427635556423983},
      {0.008769326721271058, -0.00886680403991924, -0.0074141911809886725},
      {-0.0051496906739248345, 0.001116851622039082, 0.0033500834168440283},
      {0.01869826957295377, -0.005208192772305269, -0.0025376159138793992},
      {0.016632722124881538, 0.02355374682614004, -0.012855221689583819},
      {0.011521509155525918, -0.012619406327980975, 0.012056015830681222}};
  const std::vector<Vec3> p56 = {
      {-0.020624636857363793, 0.0006184739738101137, 0.02055964207829295},
      {-0.013276422734759553, -0.009631352690022327, 0.005567981325770417},
      {0.0036737484593010947, 0.0030241095640626166, -0.005398213256889096},
      {-0.022955285880651818, 0.004761745046444433, -0.011161673847988425},
      {0.006021198063467716, -0.003105674975034039, -0.011569094319178392},
      {0.02478944989638391, -0.008918127501572611, 0.023552390541573265},
      {-0.0011145027571792601, 0.0017007682676372267, -0.011555889430016826},
      {-0.016309390684530106, 0.010307310684758493, -0.002222816535940815},
      {0.0042584309689350855, -0.01587030689381922, 0.0004983067413742923},
      {0.007934306337610143, 0.01298789529764878, 0.00832736741474506},
      {-0.0043105773669988474, 0.009262326195821173, 0.004843576773418783},
      {-0.0011297815471843012, 0.0065150556045339356, -0.009681917720620487}};
  const PosedPiece support(
      ConvexPolyhedron::from_points(p47),
      Quat(-0.96562771853012674, 0.054172932275807661, 0.21705565741636632, 0.13234517066554471),
      Vec3(-0.16558422842815185, 0.069119505100050299, 0.008064505375399553));
  const PosedPiece mover(
      ConvexPolyhedron::from_points(p56),
      Quat(-0.66975194110131187, -0.50726537037565311, 0.53547588025029225, 0.085905547427690188),
      Vec3(-0.17445409943717607, 0.078289356881341685, 0.025077522431611276));
  const double overlap = separating_axis(support, mover);
  CHECK(overlap == Approx(-6.06e-5).epsilon(0.01));
  const std::vector<EdgeWatch> watch = candidates(mover, support);
  REQUIRE(!watch.empty());
  double deepest = kInfinity;
  for (const EdgeWatch& w : watch) deepest = std::min(deepest, separation(mover, support, w));
  CHECK(std::abs(deepest - overlap) <= 1e-12);
}

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
