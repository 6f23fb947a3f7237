// The contact model through its value interface (scheduler/contact.hpp): hand-posed bodies, one
// closest-feature query, then make_contact / approaching / resolve - no simulation. Each rule of
// DESIGN.md §4's centre-of-pressure model against what it must do: a block landing flat is
// resolved through its centre of mass and does not rock; a rocking block collides along the edge
// landing first; a prism at rest that tips off its face is struck mid-edge; a sliding block whose
// friction its patch cannot carry tips about its front edge; an edge on a face holds only the
// rotation across the edge, moves along it to where the impulse's torque vanishes, and tips past
// its end.
#include "scheduler/contact.hpp"

#include "core/ballistic.hpp"
#include "core/shape.hpp"
#include "tests/support/test_world.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace palpable;

namespace {

constexpr double kPi = 3.14159265358979323846;
const Vec3 kGravity(0.0, 0.0, -9.81);

// Two bodies posed by hand, their geometries and one closest-feature query between them.
struct Posed {
  Body body1, body2;
  ShapeGeometry g1, g2;
  DistanceResult closest;
  Settings settings;
  Posed(Body b1, Body b2, const Settings& s = Settings{})
      : body1(std::move(b1)), body2(std::move(b2)), g1(body1.shape), g2(body2.shape), settings(s) {
    PairCache cache;
    closest = closest_features(g1, Pose{body1.state.x_W, body1.state.q_WM}, g2,
                               Pose{body2.state.x_W, body2.state.q_WM}, cache, settings);
  }
  ContactSide side1() const { return ContactSide{BodyId{0}, body1, g1, body1.state}; }
  ContactSide side2() const { return ContactSide{BodyId{1}, body2, g2, body2.state}; }
  Contact contact() const {
    return make_contact(side1(), side2(), closest, settings, kGravity, /*with_patch=*/true);
  }
  Resolution resolve_it(const Material& m) const {
    return resolve(contact(), side1(), side2(), m, settings, {}, 0.0);
  }
};

// A 0.2 m cube, 1 kg, its bottom face `gap` above the ground, in either pair order.
Posed cube_over_ground(double gap, const Vec3& v, const Vec3& w, bool ground_first) {
  Body cube = test::box_body("cube", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0.3, -0.2, 0.1 + gap),
                             Quat::Identity(), v, w);
  Body ground = test::fixed_ground();
  return ground_first ? Posed(ground, cube) : Posed(cube, ground);
}

// A 0.2 m cube turned 45 degrees about x, standing on its edge along x, `gap` above the ground.
Posed cube_on_edge(const Vec3& v, const Vec3& w) {
  const double h = 0.1 * std::sqrt(2.0);
  Body cube = test::box_body("cube", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, h + 2e-5),
                             test::about(Vec3::UnitX(), kPi / 4), v, w);
  return Posed(cube, test::fixed_ground());
}

}  // namespace

TEST_CASE("contact: a block landing flat is resolved through its centre of mass", "[contact]") {
  for (bool ground_first : {false, true}) {
    CAPTURE(ground_first);
    const Posed posed = cube_over_ground(2e-5, Vec3(0.5, 0, -0.3), Vec3::Zero(), ground_first);
    const Contact c = posed.contact();
    CHECK(c.placement == Placement::kFace);
    CHECK(c.patch.size() == 4);
    // The foot of the centre of mass.
    CHECK(c.point_W.x() == Approx(0.3).margin(1e-15));
    CHECK(c.point_W.y() == Approx(-0.2).margin(1e-15));
    CHECK(approaching(c));

    // mu = 0.3, e = 0.5 (Stronge = Poisson here: the slip direction never turns): the impulse
    // meets the mass alone, p_n = 1.5 m |v_z|, and friction takes mu p_n off the slide.
    const Resolution r = posed.resolve_it(Material{0.3, 0.5});
    CHECK(r.outcome == PressureOutcome::kWithinPatch);
    CHECK(r.record.centre_of_pressure);
    const Vec3& v = ground_first ? r.v2_W : r.v1_W;
    const Vec3& w = ground_first ? r.w2_W : r.w1_W;
    CHECK(v.z() == Approx(0.15).epsilon(1e-12));
    CHECK(v.x() == Approx(0.5 - 0.3 * 0.45).epsilon(1e-12));
    CHECK(v.y() == Approx(0.0).margin(1e-15));
    CHECK(w.norm() == 0.0);  // no rocking at all
    CHECK(r.record.energy_change < 0.0);
  }
}

TEST_CASE("contact: a block rocking faster than the microcollision speed lands on its leading edge",
          "[contact]") {
  // Rocking at 5 rad/s about y: the +x corners approach at 0.5 m/s more than the -x ones, and
  // alike: the block lands along its +x edge, an edge on a face (not at one corner of it, whose
  // friction would turn the block about x and z).
  const Posed posed = cube_over_ground(2e-5, Vec3(0, 0, -0.3), Vec3(0, 5, 0), false);
  const Contact c = posed.contact();
  CHECK(c.placement == Placement::kSegment);
  REQUIRE(c.patch.size() == 2);
  CHECK(c.patch[0].x() == Approx(0.4).margin(1e-12));  // x0 + 0.1: (w x r)_z = -w_y r_x < 0
  CHECK(c.patch[1].x() == Approx(0.4).margin(1e-12));
  CHECK(std::abs(c.segment_dir_W.y()) == Approx(1.0).margin(1e-12));
  CHECK(c.point_W.x() == Approx(0.4).margin(1e-12));
  CHECK(c.point_W.y() == Approx(-0.2).margin(1e-12));  // the foot of the centre of mass
  const Resolution r = posed.resolve_it(Material{0.5, 0.0});
  CHECK(r.record.centre_of_pressure);
  CHECK(r.w1_W.y() != 5.0);  // the edge's impulse turns the block
  CHECK(std::abs(r.w1_W.x()) <= 1e-12);
  CHECK(std::abs(r.w1_W.z()) <= 1e-12);
  CHECK(std::abs(r.v1_W.y()) <= 1e-12);
  // Landing at u_n = -(0.3 + 5 * 0.1) = -0.8 m/s with e = 0: the whole edge leaves at the
  // rebound floor, the microcollision speed.
  for (const Vec3& q : c.patch) {
    const Vec3 arm = q - Vec3(0.3, -0.2, 0.1 + 2e-5);
    CHECK((r.v1_W + r.w1_W.cross(arm)).z() == Approx(c.v_micro).epsilon(1e-9));
  }
}

TEST_CASE("contact: a prism at rest on a slope it tips off is struck mid-edge, not at a corner",
          "[contact]") {
  // A 32-gon prism (circumradius 5 cm, 10 cm long, its axis along y) at rest on a face across a
  // 10 degree slope, 2e-5 m above it: its line of action meets the slope 8.8 mm downhill of the
  // face's centre, beyond the face's downhill edge (4.9 mm), so it tips about that edge. Every
  // corner is still: the tip point, mid-edge, takes the impulse. (At whichever corner rounding
  // made first, the friction turned the prism about the normal and its rolling direction: a
  // 64-gon rolled off 6 mm sideways in 1.5 s.)
  const int sides = 32;
  const double th = 10.0 * kPi / 180.0, L = 0.05, a = kPi / sides;
  const Vec3 n(std::sin(th), 0.0, std::cos(th));
  const Quat q = test::about(Vec3::UnitY(), th) * test::about(Vec3::UnitX(), kPi / 2) *
                 test::about(Vec3::UnitZ(), -kPi / 2 - a);
  const Posed posed(test::dynamic_body("prism", ConvexPolyhedron::prism(L, 0.05, sides), 1.0,
                                       (L * std::cos(a) + 2e-5) * n, q),
                    test::fixed_body("slope", make_halfspace(n, 0.0)));
  const Contact c = posed.contact();
  REQUIRE(c.placement == Placement::kFace);
  const Resolution r = posed.resolve_it(Material{1.0, 0.0});
  CHECK(r.outcome == PressureOutcome::kTipped);
  CHECK(std::abs(r.record.p_W.y()) <= 1e-12);
  const Vec3 down(std::cos(th), 0.0, -std::sin(th));
  CHECK(down.dot(r.record.p_W) == Approx(L * std::sin(a)).epsilon(1e-9));  // the downhill edge
  CHECK(std::abs(r.w1_W.x()) <= 1e-12);
  CHECK(std::abs(r.w1_W.z()) <= 1e-12);
  CHECK(std::abs(r.v1_W.y()) <= 1e-12);
}

TEST_CASE("contact: a disk rolling on one facet of its rim is rolling, not resting flat",
          "[contact]") {
  // A 64-gon disk (R 2 cm, 2 mm thick) standing on one facet of its rim (a 2.0 mm by 2 mm
  // patch), rolling along x at 24 rad/s: its centre moves at 0.48 m/s. The centre-of-pressure
  // rule is for a face resting on a face; judged by the patch's own size (1.4 mm x 24 rad/s =
  // 0.034 m/s, under the microcollision speed) it passed as resting and took the rolling away.
  // A coin on the same facet spinning about the vertical is resting on it: the rule applies and
  // keeps the spin.
  const int n = 64;
  const double R = 0.02, h = R * std::cos(kPi / n);
  // Disk axis horizontal (body z to world -y), a facet centred straight down.
  const Quat q = test::about(Vec3::UnitX(), kPi / 2) *
                 test::about(Vec3::UnitZ(), -kPi / 2 - 47.5 * 2 * kPi / n);
  auto disk = [&](const Vec3& v, const Vec3& w) {
    return test::dynamic_body("disk", ConvexPolyhedron::prism(R, 0.001, n), 0.01,
                              Vec3(0, 0, h + 2e-5), q, v, w);
  };
  {
    const Posed rolling(disk(Vec3(24 * h, 0, -0.01), Vec3(0, 24, 0)), test::fixed_ground());
    const Contact c = rolling.contact();
    // It lands along the facet's leading edge (across the rim, along y), an edge on a face: the
    // rotation about that edge, the rolling, stays free.
    CHECK(c.placement == Placement::kSegment);
    CHECK(std::abs(c.segment_dir_W.y()) == Approx(1.0).margin(1e-12));
    const Resolution r = rolling.resolve_it(Material{0.5, 0.0});
    // Still rolling: the landing changes it by 0.3 % (measured); the rule for a face resting on
    // a face, applied, removes every rotation in the contact plane, the rolling included.
    CHECK(r.w1_W.y() > 23.5);
    CHECK(std::abs(r.w1_W.x()) <= 1e-12);
  }
  {
    const Posed spinning(disk(Vec3(0, 0, -0.01), Vec3(0, 0, 20)), test::fixed_ground());
    const Contact c = spinning.contact();
    CHECK(c.placement == Placement::kFace);
    const Resolution r = spinning.resolve_it(Material{0.5, 0.0});
    CHECK(r.record.centre_of_pressure);
    // The spin about the normal is kept, less the torsional friction of the patch over the
    // landing impulse (0.6 % measured).
    CHECK(r.w1_W.z() > 19.5);
    CHECK(r.w1_W.head<2>().norm() < 1e-12);  // nothing in the plane
  }
}

TEST_CASE("contact: stopping the rocking over a tilted disk's rim edge creates no energy",
          "[contact]") {
  // The 64-gon disk tilted 30 degrees from upright, on the lower edge of one rim facet (a
  // segment along x), landing at 0.3 m/s (no microcollision: no rebound at v_micro adds energy)
  // and rocking slowly across it (w_y) while spinning about the vertical. The rule stops the rocking; the disk's principal axes are tilted
  // to the segment's frame, so zeroing w_y alone changes its energy by -I_yz w_y w_z, a gain for
  // one sign of w_y (coins: 3.4e-7 J in one collision). A couple about m = n x s sized to stop
  // the rocking (the plastic projection in the energy metric) never adds energy.
  const int n = 64;
  const double R = 0.02, hh = 0.001, h = R * std::cos(kPi / n), beta = kPi / 2 - kPi / 6;
  const Quat q = test::about(Vec3::UnitX(), beta) *
                 test::about(Vec3::UnitZ(), -kPi / 2 - 47.5 * 2 * kPi / n);
  const double z = h * std::sin(beta) + hh * std::cos(beta) + 2e-5;
  for (double rocking : {-2.0, 2.0}) {
    CAPTURE(rocking);
    const Posed posed(test::dynamic_body("disk", ConvexPolyhedron::prism(R, hh, n), 0.01,
                                         Vec3(0, 0, z), q, Vec3(0, 0, -0.06),
                                         Vec3(0, rocking, 50)),
                      test::fixed_ground());
    const Contact c = posed.contact();
    REQUIRE(c.placement == Placement::kSegment);
    CHECK(std::abs(c.segment_dir_W.x()) == Approx(1.0));
    const Resolution r = posed.resolve_it(Material{0.0, 0.0});
    CHECK(r.record.centre_of_pressure);
    const Vec3 m = c.n_W.cross(c.segment_dir_W);
    CHECK(m.dot(r.w1_W) == Approx(0.0).margin(1e-14));  // the rocking stopped
    CHECK(r.w1_W.z() != 50.0);  // the couple turns the spin too
    CHECK(r.record.energy_change <= 1e-18);
  }
}

TEST_CASE("contact: a tall block sliding fast tips about its front edge", "[contact]") {
  // A 0.1 x 0.1 x 1 m column landing flat at 2 m/s forward: its centre of mass is 0.5 m up, so
  // the line of action of an impulse with mu = 0.5 meets the ground 0.25 m ahead of the foot,
  // far outside the 0.05 m half-width: the column tips about its front edge at x0 + 0.05.
  Body column = test::box_body("column", Vec3(0.05, 0.05, 0.5), 1.0, Vec3(0, 0, 0.5 + 2e-5),
                               Quat::Identity(), Vec3(2, 0, -0.3));
  const Posed posed(column, test::fixed_ground());
  CHECK(posed.contact().placement == Placement::kFace);
  const Resolution r = posed.resolve_it(Material{0.5, 0.0});
  CHECK(r.outcome == PressureOutcome::kTipped);
  CHECK_FALSE(r.record.centre_of_pressure);
  CHECK(r.record.p_W.x() == Approx(0.05).margin(1e-12));
  CHECK(r.record.p_W.y() == Approx(0.0).margin(1e-12));
  CHECK(r.w1_W.y() > 0.0);  // friction at the front edge below the centre turns it forward
  CHECK(r.record.energy_change < 0.0);
}

TEST_CASE("contact: an edge on a face holds the rotation across it, not about it", "[contact]") {
  // Rolling about the edge (w_x = 3) and rocking slightly across it (w_y = 0.01, well inside the
  // microcollision speed over the 0.2 m edge): frictionless, the normal impulse acts straight
  // below the centre of mass, so the rolling is untouched while the rocking is taken out.
  const Posed posed = cube_on_edge(Vec3(0, 0, -0.3), Vec3(3, 0.01, 0));
  const Contact c = posed.contact();
  REQUIRE(c.patch.size() == 2);
  CHECK(c.placement == Placement::kSegment);
  CHECK(std::abs(c.segment_dir_W.x()) == Approx(1.0));
  const Resolution r = posed.resolve_it(Material{0.0, 0.5});
  CHECK(r.outcome == PressureOutcome::kWithinPatch);
  CHECK(r.w1_W.x() == Approx(3.0).epsilon(1e-12));
  CHECK(r.w1_W.y() == Approx(0.0).margin(1e-15));
}

TEST_CASE("contact: friction along an edge moves the pressure along it, or tips past its end",
          "[contact]") {
  // Sliding along the edge at 1 m/s: friction -mu p_n x at depth h below the centre of mass (the
  // contact point lies on the ground, 0.1 sqrt 2 + 2e-5 m down) has a torque about y that the
  // pressure cancels by moving h mu ahead - inside the 0.1 m half-edge for mu = 0.5 (0.0707 m),
  // beyond it for mu = 1 (0.1414 m): the cube tips.
  const double h = 0.1 * std::sqrt(2.0) + 2e-5;
  {
    const Resolution r = cube_on_edge(Vec3(1, 0, -0.3), Vec3::Zero()).resolve_it({0.5, 0.0});
    CHECK(r.outcome == PressureOutcome::kMovedOnSegment);
    CHECK(r.record.centre_of_pressure);
    CHECK(r.record.p_W.x() == Approx(h * 0.5).epsilon(1e-12));
    CHECK(r.w1_W.y() == Approx(0.0).margin(1e-12));  // the torque across the edge was carried
  }
  {
    const Resolution r = cube_on_edge(Vec3(1, 0, -0.3), Vec3::Zero()).resolve_it({1.0, 0.0});
    CHECK(r.outcome == PressureOutcome::kTipped);
    CHECK_FALSE(r.record.centre_of_pressure);
    CHECK(r.record.p_W.x() == Approx(0.1).epsilon(1e-9));  // the end of the edge
    CHECK(r.w1_W.y() > 0.0);
  }
}

TEST_CASE("contact: placements of spheres and of two dynamic bodies face to face", "[contact]") {
  {
    const Posed posed(test::sphere_body("ball", 0.1, 1.0, Vec3(0, 0, 0.1 + 1e-5)),
                      test::fixed_ground());
    const Contact c = posed.contact();
    CHECK(c.placement == Placement::kSphere);
    CHECK(c.slip_at_centre());
  }
  {
    // Two dynamic bodies face to face: the patch holds their relative rotation (DESIGN.md §4's
    // rule for a stack), found at the patch's centroid.
    const Posed posed(test::box_body("top", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.3 + 2e-5),
                                     Quat::Identity(), Vec3(0, 0, -0.2)),
                      test::box_body("bottom", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.1)));
    const Contact c = posed.contact();
    CHECK(c.dynamic == DynamicSide::kBoth);
    CHECK(c.patch.size() == 4);
    CHECK(c.placement == Placement::kFace);
    CHECK(c.point_W.x() == Approx(0.0).margin(1e-15));
    CHECK(c.point_W.y() == Approx(0.0).margin(1e-15));
  }
  {
    // Rocking relative to each other faster than the microcollision speed: the corner.
    const Posed posed(test::box_body("top", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.3 + 2e-5),
                                     Quat::Identity(), Vec3(0, 0, -0.2), Vec3(0.5, 0, 0)),
                      test::box_body("bottom", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.1)));
    CHECK(posed.contact().placement == Placement::kPoint);
  }
}

namespace {

// Linear and angular momentum (about the world origin) of two bodies, and their kinetic energy.
struct Totals {
  Vec3 p = Vec3::Zero(), l = Vec3::Zero();
  double energy = 0.0;
};
Totals totals(const Body& b1, const BodyState& s1, const Body& b2, const BodyState& s2) {
  Totals t;
  for (const auto& [b, s] : {std::pair{&b1, &s1}, std::pair{&b2, &s2}}) {
    t.p += b->mass.mass * s->v_W;
    t.l += angular_momentum_W(b->mass, *s) + s->x_W.cross(b->mass.mass * s->v_W);
    t.energy += kinetic_energy(*b, *s);
  }
  return t;
}

BodyState after(const BodyState& s, const Vec3& v, const Vec3& w) {
  BodyState out = s;
  out.v_W = v;
  out.w_W = w;
  return out;
}

}  // namespace

TEST_CASE("contact: a box landing flat on a dynamic box acts through the patch, turning neither",
          "[contact][group]") {
  // A 1 kg box onto a 2 kg box (0.2 m cubes) at 0.2 m/s, in both pair orders. Frictionless,
  // e = 0.5: the impulse meets the reduced mass alone, p_n = 1.5 m_red 0.2, and neither turns.
  // With mu = 0.3 and a slide of 0.3 m/s along x: friction's couple d x p turns both alike
  // (W = (I1 + I2)^-1 [d]x), the faces stay parallel, and momentum and angular momentum are
  // kept, energy is not created.
  for (bool top_first : {true, false}) {
    for (double mu : {0.0, 0.3}) {
      CAPTURE(top_first, mu);
      const Body top = test::box_body("top", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.3 + 2e-5),
                                      Quat::Identity(), Vec3(mu > 0 ? 0.3 : 0.0, 0, -0.2));
      const Body bottom = test::box_body("bottom", Vec3(0.1, 0.1, 0.1), 2.0, Vec3(0, 0, 0.1));
      const Posed posed = top_first ? Posed(top, bottom) : Posed(bottom, top);
      const Contact c = posed.contact();
      REQUIRE(c.placement == Placement::kFace);
      const Resolution r = posed.resolve_it(Material{mu, 0.5});
      CHECK(r.outcome == PressureOutcome::kWithinPatch);
      CHECK(r.record.centre_of_pressure);
      const BodyState s1 = after(posed.body1.state, r.v1_W, r.w1_W);
      const BodyState s2 = after(posed.body2.state, r.v2_W, r.w2_W);
      const BodyState& s_top = top_first ? s1 : s2;
      const double m_red = 2.0 / 3.0;
      CHECK(std::abs(r.record.impulse_W.z()) == Approx(1.5 * m_red * 0.2).epsilon(1e-12));
      CHECK(s_top.v_W.z() == Approx(-0.2 + 1.5 * m_red * 0.2 / 1.0).epsilon(1e-12));
      CHECK((r.w1_W - r.w2_W).norm() <= 1e-15);  // the faces stay parallel
      const Totals before = totals(posed.body1, posed.body1.state, posed.body2, posed.body2.state);
      const Totals now = totals(posed.body1, s1, posed.body2, s2);
      CHECK((now.p - before.p).norm() <= 1e-15);
      CHECK((now.l - before.l).norm() <= 1e-15);
      CHECK(now.energy <= before.energy * (1.0 + 1e-15));
      if (mu == 0.0) {
        CHECK(r.w1_W.norm() == 0.0);
        CHECK(r.w2_W.norm() == 0.0);
      } else {
        // Friction turns them about y, with the rate W p of held_rotation_response.
        CHECK(std::abs(r.w1_W.y()) > 1e-3);
        CHECK(r.w1_W.x() == Approx(0.0).margin(1e-15));
      }
    }
  }
}

TEST_CASE("contact: a box landing on the edge of a dynamic box turns it, or tips over a heavy one",
          "[contact][group]") {
  // The top box overhangs by three quarters of its width: its patch with the bottom box is a
  // 5 cm strip under its far side, its centre of mass outside it. On an equal free box, the
  // pressure that keeps the faces parallel lies at the strip's middle: the two turn together
  // as one body (dw = (I1 + I2)^-1 d x p about +y, the same for both). On a box a thousand times
  // heavier - nearly the ground - keeping the faces parallel would need a pressure outside the
  // strip: the top tips about the strip's edge, as over a fixed face.
  for (double mass : {1.0, 1000.0}) {
    CAPTURE(mass);
    const Posed posed(test::box_body("top", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0.15, 0, 0.3 + 2e-5),
                                     Quat::Identity(), Vec3(0, 0, -0.2)),
                      test::box_body("bottom", Vec3(0.1, 0.1, 0.1), mass, Vec3(0, 0, 0.1)));
    const Contact c = posed.contact();
    REQUIRE(c.placement == Placement::kFace);
    const Resolution r = posed.resolve_it(Material{0.0, 0.5});
    if (mass == 1.0) {
      CHECK(r.outcome == PressureOutcome::kWithinPatch);
      CHECK(r.w1_W.y() > 0.1);
      CHECK((r.w1_W - r.w2_W).norm() <= 1e-15);
    } else {
      CHECK(r.outcome == PressureOutcome::kTipped);
      CHECK(r.record.p_W.x() == Approx(0.1).margin(1e-12));  // on the bottom box's edge
      CHECK(r.w1_W.y() > 0.1);  // the top turns down over the edge (+x down: about +y)
      CHECK(r.w2_W.norm() < 1e-2 * r.w1_W.norm());
    }
    const Totals before = totals(posed.body1, posed.body1.state, posed.body2, posed.body2.state);
    const Totals now = totals(posed.body1, after(posed.body1.state, r.v1_W, r.w1_W), posed.body2,
                              after(posed.body2.state, r.v2_W, r.w2_W));
    CHECK((now.p - before.p).norm() <= 1e-15 * mass);
    CHECK((now.l - before.l).norm() <= 1e-15 * mass);
    CHECK(now.energy <= before.energy * (1.0 + 1e-15));
  }
}

TEST_CASE("contact: a box rocking onto a dynamic box lands along its edge, not on one corner",
          "[contact][group]") {
  // The top box, turned 0.2 rad about y and rocking at 3 rad/s about y, lands with its lowest
  // edge (along y) on the bottom box's face. Both are dynamic, so the centre-of-pressure rule
  // does not apply; the whole edge approaches at once, and nothing in the problem has a y: the
  // collision's point is the edge's point nearest the foot of the top's centre (y = 0), and no
  // velocity along y, nor rotation about x or z, comes out of it. (At one of the edge's two
  // corners, y = +-0.1, the top left turning about x and z.)
  for (double spin : {3.0, -3.0}) {
    CAPTURE(spin);
    const double a = 0.2 * (spin > 0 ? 1.0 : -1.0);
    const Posed posed(
        test::box_body("top", Vec3(0.1, 0.1, 0.1), 1.0,
                       Vec3(0, 0, 0.2 + 2e-5 + 0.1 * (std::sin(std::abs(a)) + std::cos(a))),
                       test::about(Vec3::UnitY(), a), Vec3(0, 0, -0.5), Vec3(0, spin, 0)),
        test::box_body("bottom", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.1)));
    const Contact c = posed.contact();
    REQUIRE(c.placement == Placement::kPoint);
    CHECK(std::abs(c.point_W.y()) <= 1e-15);
    CHECK(std::abs(c.point_W.x()) == Approx(0.1 * (std::cos(a) - std::sin(std::abs(a)))));
    const Resolution r = posed.resolve_it(Material{0.5, 0.5});
    for (const Vec3& v : {r.v1_W, r.v2_W}) CHECK(std::abs(v.y()) <= 1e-14);
    for (const Vec3& w : {r.w1_W, r.w2_W}) {
      CHECK(std::abs(w.x()) <= 1e-14);
      CHECK(std::abs(w.z()) <= 1e-14);
    }
    CHECK(r.v1_W.z() > -0.5);  // it did collide
  }
}

TEST_CASE("contact: what approaches, and what carries riders", "[contact]") {
  // At rest on the ground with gravity pressing: it must collide again (an e = 0 collision
  // leaves it so); lifting off at 1 cm/s: not.
  CHECK(approaching(cube_over_ground(0.0, Vec3::Zero(), Vec3::Zero(), false).contact()));
  CHECK_FALSE(approaching(cube_over_ground(0.0, Vec3(0, 0, 0.01), Vec3::Zero(), false).contact()));
  // Two dynamic spheres touching at rest: nothing presses them together.
  {
    Posed posed(test::sphere_body("a", 0.1, 1.0, Vec3(0, 0, 0)),
                test::sphere_body("b", 0.1, 1.0, Vec3(0.2 + 1e-6, 0, 0)));
    CHECK_FALSE(approaching(posed.contact()));
  }
  // A face resting on the ground, arriving slower than the microcollision speed, carries what
  // rests on it; the same arriving fast does not; a face against a wall never does.
  const Settings s;
  CHECK(carries_riders(cube_over_ground(2e-5, Vec3(0, 0, -0.01), Vec3::Zero(), false).contact(), s,
                       kGravity));
  CHECK_FALSE(carries_riders(
      cube_over_ground(2e-5, Vec3(0, 0, -1.0), Vec3::Zero(), false).contact(), s, kGravity));
  Body wall = test::fixed_body("wall", make_halfspace(Vec3::UnitX(), 0.0));
  Body cube = test::box_body("cube", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0.1 + 2e-5, 0, 1),
                             Quat::Identity(), Vec3(-0.01, 0, 0));
  const Posed against_wall(cube, wall);
  REQUIRE(against_wall.contact().placement == Placement::kFace);
  CHECK_FALSE(carries_riders(against_wall.contact(), s, kGravity));
}

TEST_CASE(
    "contact: a held polyhedron presses its contact at its corner's acceleration, a ball "
    "at its centre's",
    "[contact]") {
  // A cube turned 20 degrees about x stands on its lowest edge, 2e-5 m above the ground. Held
  // (its island's accelerations given), its centre does not accelerate; turning about x at
  // alpha, the edge, at y = -0.1 (cos - sin) from the centre, moves down at alpha times that
  // lever; spinning at w, the contact point (midway across the gap, 1e-5 m below the edge) is
  // drawn up towards the centre at w^2 times its depth below it. The pressing acceleration g_n
  // is their sum, not the centre's.
  const double th = 20.0 * kPi / 180.0, c = std::cos(th), s = std::sin(th);
  const double alpha = 50.0;
  auto pressing = [&](double w, const Vec3* angular) {
    Body cube = test::box_body("cube", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.1 * (s + c) + 2e-5),
                               test::about(Vec3::UnitX(), th), Vec3::Zero(), Vec3(w, 0, 0));
    const Posed posed(cube, test::fixed_ground());
    const Vec3 still = Vec3::Zero();
    const ContactSide held{BodyId{0}, posed.body1, posed.g1, posed.body1.state, &still, angular};
    return make_contact(held, posed.side2(), posed.closest, posed.settings, kGravity, true).g_n;
  };
  const Vec3 tipping(alpha, 0, 0), lifting(-alpha, 0, 0);
  CHECK(pressing(0.0, &tipping) == Approx(alpha * 0.1 * (c - s)).epsilon(1e-9));
  CHECK(pressing(2.0, &tipping) ==
        Approx(alpha * 0.1 * (c - s) - 4.0 * (0.1 * (s + c) + 1e-5)).epsilon(1e-9));
  CHECK(pressing(0.0, &lifting) == 0.0);
  // A body held at this instant, its plan pending, counts as held still: no rotation's terms.
  CHECK(pressing(2.0, nullptr) == 0.0);
  // A held ball rolling and turning faster: its gap's acceleration is its centre's (zero), though
  // its material point at the contact is drawn up at w^2 R.
  Body ball = test::sphere_body("ball", 0.1, 1.0, Vec3(0, 0, 0.1 + 2e-5));
  ball.state.w_W = Vec3(5.0, 0, 0);
  const Posed rolling(ball, test::fixed_ground());
  const Vec3 down(0, 0, -1.0);
  const ContactSide held_ball{BodyId{0},           rolling.body1, rolling.g1,
                              rolling.body1.state, &down,         &tipping};
  CHECK(make_contact(held_ball, rolling.side2(), rolling.closest, rolling.settings, kGravity, true)
            .g_n == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("contact: the energy a collision may create is the integration's and the floor's",
          "[contact]") {
  // Without gravity nothing presses the contact: the allowance is the integration tolerance
  // times |p| |u_n| and rounding - for a 1 kg cube landing at 0.3 m/s, about 1e-10 J.
  Body cube = test::box_body("cube", Vec3(0.1, 0.1, 0.1), 1.0, Vec3(0, 0, 0.1 + 2e-5),
                             Quat::Identity(), Vec3(0.2, 0, -0.3));
  const Posed posed(cube, test::fixed_ground());
  for (double e : {0.0, 0.5, 1.0}) {
    CAPTURE(e);
    const Contact c = make_contact(posed.side1(), posed.side2(), posed.closest, posed.settings,
                                   Vec3::Zero(), /*with_patch=*/true);
    const Resolution r =
        resolve(c, posed.side1(), posed.side2(), Material{0.0, e}, posed.settings, {}, 0.0);
    CHECK(r.energy_allowance < 1e-9);
    CHECK(r.record.energy_change <= r.energy_allowance);
    // Frictionless through the centre of mass: (1/2) m v_n^2 (e^2 - 1) exactly.
    CHECK(r.record.energy_change == Approx(0.5 * 0.09 * (e * e - 1.0)).margin(1e-15));
  }
  // Under gravity the rebound floor may lend (1/2) |p| v_micro.
  const Resolution r = posed.resolve_it(Material{0.0, 0.0});
  const double v_micro = std::sqrt(2.0 * 9.81 * posed.settings.envelope_m);
  CHECK(r.energy_allowance >= 0.5 * r.record.impulse_W.norm() * v_micro);
}

TEST_CASE("contact: a true disk flat, on its rim, on its side, and an ellipsoid at a point",
          "[contact][smooth]") {
  const double r = 0.02, h = 0.002, gap = 2e-5;
  auto disk = [&](const Vec3& x, const Quat& q, const Vec3& v, const Vec3& w) {
    return test::dynamic_body("disk", make_cylinder(r, h), 0.02, x, q, v, w);
  };
  SECTION("landing flat: the inscribed 16-gon, resolved through the centre of mass") {
    Posed posed(disk(Vec3(0.1, 0.2, h + gap), Quat::Identity(), Vec3(0.3, 0, -0.5), Vec3::Zero()),
                test::fixed_ground());
    const Contact c = posed.contact();
    REQUIRE(c.patch.size() == 16);
    CHECK(c.placement == Placement::kFace);
    CHECK((c.point_W - Vec3(0.1, 0.2, 0.0)).norm() <= 1e-12);
    // No rocking from the impulse: the in-plane angular velocity stays zero.
    const Resolution res = posed.resolve_it(Material{0.5, 0.0});
    CHECK(std::hypot(res.w1_W.x(), res.w1_W.y()) <= 1e-12);
  }
  // A point contact is placed midway across the gap.
  SECTION("rolling on its rim (tilted 30 degrees): one point, the rim's lowest") {
    const Quat q = test::about(Vec3::UnitX(), kPi / 6);
    const double z = r * std::sin(kPi / 6) + h * std::cos(kPi / 6);
    Posed posed(disk(Vec3(0, 0, z + gap), q, Vec3(0, 0, -0.1), Vec3(0, 0, 20)),
                test::fixed_ground());
    const Contact c = posed.contact();
    CHECK(c.patch.size() == 1);
    CHECK(c.placement == Placement::kPoint);
    CHECK(std::abs(c.point_W.z() - gap / 2) <= 1e-12);
    CHECK(std::abs(c.point_W.y() - (-r * std::cos(kPi / 6) + h * std::sin(kPi / 6))) <= 1e-12);
  }
  SECTION("on its side (axis horizontal): the side's segment") {
    const Quat q = test::about(Vec3::UnitX(), kPi / 2);
    Posed posed(disk(Vec3(0, 0, r + gap), q, Vec3(0, 0, -0.1), Vec3::Zero()), test::fixed_ground());
    const Contact c = posed.contact();
    REQUIRE(c.patch.size() == 2);
    CHECK((c.patch[0] - c.patch[1]).norm() == Approx(2 * h).epsilon(1e-12));
    CHECK(c.placement == Placement::kSegment);
  }
  SECTION("an ellipsoid touches at its support point") {
    Body egg = test::dynamic_body("egg", make_ellipsoid(Vec3(0.02, 0.03, 0.05)), 0.1,
                                  Vec3(0, 0, 0.05 + gap), Quat::Identity(), Vec3(0, 0, -0.2));
    Posed posed(egg, test::fixed_ground());
    const Contact c = posed.contact();
    CHECK(c.patch.size() == 1);
    CHECK(c.placement == Placement::kPoint);
    CHECK((c.point_W - Vec3(0, 0, gap / 2)).norm() <= 1e-12);
  }
}
