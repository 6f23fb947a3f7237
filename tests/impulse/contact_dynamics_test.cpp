// The contact problem at the acceleration level (impulse/contact_dynamics.hpp) against closed
// forms: a block sliding and sticking on a ramp (with its centre of pressure), a tall block that
// tips, a sphere rolling down a slope and sliding on a plane, a ball rolling on a turning platter,
// two stacked boxes sliding together, torsion and rolling resistance, lift-off, and the modes
// chosen for each.
#include "impulse/contact_dynamics.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using namespace palpable;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

HeldBody box(double mass, const Vec3& half, const Vec3& x, const Vec3& v = Vec3::Zero(),
             const Vec3& w = Vec3::Zero()) {
  HeldBody b;
  b.mass = mass;
  const Vec3 h2 = (2.0 * half).cwiseAbs2();
  b.inertia_W =
      (mass / 12.0 * Vec3(h2.y() + h2.z(), h2.x() + h2.z(), h2.x() + h2.y())).asDiagonal();
  b.inv_inertia_W = b.inertia_W.inverse();
  b.x_W = x;
  b.v_W = v;
  b.w_W = w;
  b.force_W = Vec3(0, 0, -kG * mass);
  return b;
}

HeldBody ball(double mass, double radius, const Vec3& x, const Vec3& v = Vec3::Zero(),
              const Vec3& w = Vec3::Zero()) {
  HeldBody b;
  b.mass = mass;
  b.inertia_W = Mat3::Identity() * 0.4 * mass * radius * radius;
  b.inv_inertia_W = b.inertia_W.inverse();
  b.x_W = x;
  b.v_W = v;
  b.w_W = w;
  b.force_W = Vec3(0, 0, -kG * mass);
  return b;
}

// A contact of body `mover` on a fixed plane through c with normal n; t1 is `t1`.
HeldContact on_plane(int mover, const Vec3& c, const Vec3& n, const Vec3& t1, double mu) {
  HeldContact k;
  k.mover = mover;
  k.c_W = c;
  k.n_W = n;
  k.t1_W = t1;
  k.t2_W = n.cross(t1);
  k.friction = mu;
  return k;
}

// A cylinder (radius r, half-height h, mass m) tilted alpha about y, held at its lower rim's
// lowest point on the plane z = 0 (a curved contact, the rim's tangent its only curvature, r / sin
// alpha; friction mu), under gravity and at rest: the caller sets its velocities.
struct DiskOnRim {
  HeldBody disk;
  HeldContact rim;
  Vec3 axis;
};
DiskOnRim disk_on_rim(double r, double h, double m, double alpha, double mu) {
  DiskOnRim out;
  out.axis = Vec3(std::sin(alpha), 0, std::cos(alpha));
  const Mat3 rot = Eigen::AngleAxisd(alpha, Vec3::UnitY()).toRotationMatrix();
  const double I1 = m * (3 * r * r + 4 * h * h) / 12, I3 = m * r * r / 2;
  HeldBody& disk = out.disk;
  disk.mass = m;
  disk.inertia_W = rot * Vec3(I1, I1, I3).asDiagonal() * rot.transpose();
  disk.inv_inertia_W = disk.inertia_W.inverse();
  disk.x_W = Vec3(0, 0, r * std::sin(alpha) + h * std::cos(alpha));
  disk.force_W = Vec3(0, 0, -kG * m);
  const Vec3 c = disk.x_W - h * out.axis + r * Vec3(std::cos(alpha), 0, -std::sin(alpha));
  out.rim = on_plane(0, c, Vec3::UnitZ(), Vec3::UnitX(), mu);
  out.rim.curved = true;
  out.rim.curvature_W = r / std::sin(alpha) * Vec3::UnitY() * Vec3::UnitY().transpose();
  out.rim.curved_size = r;
  return out;
}

// A square face of half-size h on the contact plane, about c.
void square_patch(HeldContact& k, double h) {
  k.patch = PatchKind::kPolygon;
  k.polygon = {Vec2(-h, -h), Vec2(h, -h), Vec2(h, h), Vec2(-h, h)};
  set_torsion_arm(k);
}

// A 0.2 m cube of 1 kg resting on a ramp at angle theta (normal n in the x-z plane), moving at
// speed v down the slope; its centre is 0.1 m above the contact's reference point.
struct Ramp {
  Vec3 n, down, across;
  std::vector<HeldBody> bodies;
  std::vector<HeldContact> contacts;
  Ramp(double theta, double mu, double v, double half_height = 0.1) {
    n = Vec3(std::sin(theta), 0, std::cos(theta));
    down = Vec3(std::cos(theta), 0, -std::sin(theta));
    across = n.cross(down);
    HeldBody b = box(1.0, Vec3(0.1, 0.1, half_height), half_height * n, v * down);
    // The box's axes along the ramp: its inertia about them (a cube is isotropic, a tall block
    // is not): rotate the diagonal inertia into the ramp frame.
    Mat3 R;
    R.col(0) = down;
    R.col(1) = across;
    R.col(2) = n;
    b.inertia_W = R * b.inertia_W * R.transpose();
    b.inv_inertia_W = b.inertia_W.inverse();
    bodies = {b};
    HeldContact k = on_plane(0, Vec3::Zero(), n, down, mu);
    square_patch(k, 0.1);
    contacts = {k};
  }
};

}  // namespace

TEST_CASE("held: a block sliding down a ramp accelerates at g (sin - mu cos)", "[impulse][held]") {
  const double theta = kPi / 6, mu = 0.3;
  Ramp r(theta, mu, 1.0);
  r.contacts[0].sticks = false;
  r.contacts[0].slip_dir = Vec2(1, 0);  // down the slope
  const HeldSolution s = solve_held(r.bodies, r.contacts);
  REQUIRE(s.status == HeldStatus::kOk);
  const double a = kG * (std::sin(theta) - mu * std::cos(theta));
  CHECK((s.a_W[0] - a * r.down).norm() < 1e-13);
  CHECK(s.alpha_W[0].norm() < 1e-13);
  CHECK(s.forces[0].normal == Approx(kG * std::cos(theta)).epsilon(1e-14));
  // Friction acts uphill at the base, 0.1 m below the centre: the pressure moves mu h downhill.
  CHECK(s.forces[0].centre_of_pressure.x() == Approx(mu * 0.1).epsilon(1e-13));
  CHECK(s.forces[0].centre_of_pressure.y() == Approx(0.0).margin(1e-15));
  CHECK(worst_violation(r.contacts, s, 1e-12).kind == HeldViolation::Kind::kNone);
}

TEST_CASE("held: a block that can stick on a ramp sticks, one that cannot slides downhill",
          "[impulse][held]") {
  const double theta = 20.0 * kPi / 180.0;
  {
    Ramp r(theta, 0.5, 0.0);
    const HeldModes m = choose_held_modes(r.bodies, r.contacts, 1e-12, 1e-12);
    REQUIRE(m.solution.status == HeldStatus::kOk);
    CHECK(m.changes == 0);
    CHECK(r.contacts[0].sticks);
    CHECK(m.solution.a_W[0].norm() < 1e-13);
    CHECK(m.solution.alpha_W[0].norm() < 1e-13);
    // Friction holds m g sin theta uphill; the pressure sits tan theta h downhill.
    CHECK(m.solution.forces[0].friction.x() == Approx(-kG * std::sin(theta)).epsilon(1e-13));
    CHECK(m.solution.forces[0].centre_of_pressure.x() ==
          Approx(std::tan(theta) * 0.1).epsilon(1e-12));
  }
  {
    Ramp r(theta, 0.3, 0.0);  // tan 20 deg = 0.364 > 0.3
    const HeldModes m = choose_held_modes(r.bodies, r.contacts, 1e-12, 1e-12);
    REQUIRE(m.solution.status == HeldStatus::kOk);
    CHECK(m.changes == 1);
    CHECK_FALSE(r.contacts[0].sticks);
    CHECK(r.contacts[0].slip_dir.x() == Approx(1.0).epsilon(1e-12));
    CHECK(std::abs(r.contacts[0].slip_dir.y()) < 1e-12);
    const double a = kG * (std::sin(theta) - 0.3 * std::cos(theta));
    CHECK((m.solution.a_W[0] - a * r.down).norm() < 1e-12);
  }
}

TEST_CASE("held: a tall block sticking on a steep ramp tips about its lower edge",
          "[impulse][held]") {
  // A 0.2 x 0.2 x 1 m column on a 30 degree ramp with mu = 1: sticking needs the pressure
  // tan 30 x 0.5 = 0.29 m downhill, outside the 0.1 m half-width: it tips about the downhill
  // edge, which becomes a segment contact.
  Ramp r(kPi / 6, 1.0, 0.0, 0.5);
  const HeldModes m = choose_held_modes(r.bodies, r.contacts, 1e-12, 1e-12);
  REQUIRE(m.solution.status == HeldStatus::kOk);
  CHECK(m.changes >= 1);
  REQUIRE(r.contacts[0].patch == PatchKind::kSegment);
  CHECK(r.contacts[0].c_W.dot(r.down) == Approx(0.1).epsilon(1e-12));
  CHECK(std::abs(r.contacts[0].segment_W.dot(r.across)) == Approx(1.0));
  // Turning forward: about -across x ... the angular acceleration points along +across x down...
  CHECK(std::abs(m.solution.alpha_W[0].dot(r.across)) > 1.0);
  CHECK(m.solution.forces[0].normal > 0.0);
}

TEST_CASE("held: a spinning block that tips while sliding slides against its slip at the edge",
          "[impulse][held]") {
  // A 0.2 x 0.6 x 1 m block sliding at 2 m/s along x and spinning at 10 rad/s about the
  // vertical, mu = 1: friction at its base, 0.5 m below the centre, needs the pressure ~0.45 m
  // ahead, outside the 0.1 m half-width: it tips about its front edge (x = +0.1). Over the face
  // the slip turns with the spin: (2, 0) at its centre, (2, 1) at the front edge's middle. The
  // contact kept is the edge, and its sliding is resisted against the slip there - what the
  // integrated motion resists it against (scheduler/island.cpp, build_problem's `follow`), so the
  // plan and the motion agree on which way the body turns.
  std::vector<HeldBody> bodies = {
      box(1.0, Vec3(0.1, 0.3, 0.5), Vec3(0, 0, 0.5), Vec3(2, 0, 0), Vec3(0, 0, 10))};
  HeldContact k = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 1.0);
  k.patch = PatchKind::kPolygon;
  k.polygon = {Vec2(-0.1, -0.3), Vec2(0.1, -0.3), Vec2(0.1, 0.3), Vec2(-0.1, 0.3)};
  set_torsion_arm(k);
  std::vector<HeldContact> contacts = {k};
  const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
  REQUIRE(m.solution.status == HeldStatus::kOk);
  REQUIRE(contacts[0].patch == PatchKind::kSegment);
  CHECK(contacts[0].c_W.x() == Approx(0.1).epsilon(1e-12));
  REQUIRE_FALSE(contacts[0].sticks);
  const Vec3 slip = held_velocities(bodies, contacts)[0].slip_W;
  CHECK((slip - Vec3(2, 1, 0)).norm() < 1e-12);
  const Vec2 along(slip.dot(contacts[0].t1_W), slip.dot(contacts[0].t2_W));
  CHECK((contacts[0].slip_dir - along.normalized()).norm() < 1e-12);
  // The friction opposes that slip, at its bound.
  const HeldContactForces& f = m.solution.forces[0];
  CHECK(f.friction.normalized().dot(-along.normalized()) == Approx(1.0).epsilon(1e-12));
  CHECK(f.friction.norm() == Approx(f.normal).epsilon(1e-12));
  // Tipping about the front edge: the back of the face lifts.
  const Vec3 back = Vec3(-0.1, 0, 0) - bodies[0].x_W;
  const Vec3 w = bodies[0].w_W;
  CHECK((m.solution.a_W[0] + m.solution.alpha_W[0].cross(back) + w.cross(w.cross(back))).z() > 0.0);
}

TEST_CASE(
    "held: a sphere rolls down a slope at 5/7 g sin theta, sliding, its slip decays at "
    "7/2 mu g",
    "[impulse][held]") {
  const double theta = 0.2, R = 0.05;
  const Vec3 n(std::sin(theta), 0, std::cos(theta));
  const Vec3 down(std::cos(theta), 0, -std::sin(theta));
  std::vector<HeldBody> bodies = {ball(0.1, R, R * n)};
  HeldContact k = on_plane(0, Vec3::Zero(), n, down, 0.5);
  k.sphere_radius = R;
  std::vector<HeldContact> contacts = {k};
  {
    const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    REQUIRE(m.solution.status == HeldStatus::kOk);
    CHECK(contacts[0].sticks);
    CHECK((m.solution.a_W[0] - 5.0 / 7.0 * kG * std::sin(theta) * down).norm() < 1e-13);
    // Rolling: alpha = n x a / R.
    CHECK((m.solution.alpha_W[0] - n.cross(m.solution.a_W[0]) / R).norm() < 1e-11);
  }
  // On a level table, sliding at 2 m/s without spin: ds/dt = -mu g (1 + 1/k), k = 2/5.
  bodies = {ball(0.1, R, Vec3(0, 0, R), Vec3(2, 0, 0))};
  contacts = {on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 0.2)};
  contacts[0].sphere_radius = R;
  const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
  REQUIRE(m.solution.status == HeldStatus::kOk);
  CHECK_FALSE(contacts[0].sticks);
  CHECK((m.solution.motion[0].slip_rate_W - Vec3(-3.5 * 0.2 * kG, 0, 0)).norm() < 1e-12);
  CHECK((m.solution.a_W[0] - Vec3(-0.2 * kG, 0, 0)).norm() < 1e-13);
}

TEST_CASE("held: a ball rolling on a platter turning at Omega circles at 2 Omega / 7",
          "[impulse][held]") {
  // Rolling on a plane spinning at Omega about its normal through the origin: dv/dt = (2/7)
  // Omega x v for the centre (DESIGN.md §6).
  const double Omega = 2 * kPi, R = 0.05;
  const Vec3 x(0.3, 0.1, R), v(0.05, 0.1, 0);
  const Vec3 W(0, 0, Omega);
  // Rolling: v + w x (-R n) = W x (x - R n) (the platter's velocity at the contact point).
  const Vec3 n = Vec3::UnitZ();
  const Vec3 u_platter = W.cross(x - R * n);
  // w x (-R n) = u_platter - v: choose w in-plane with R (n x w) = u_platter - v.
  const Vec3 d = u_platter - v;
  const Vec3 w = -n.cross(d) / R;
  std::vector<HeldBody> bodies = {ball(0.1, R, x, v, w)};
  HeldContact k = on_plane(0, Vec3(x.x(), x.y(), 0), n, Vec3::UnitX(), 0.5);
  k.sphere_radius = R;
  k.support_known.w_W = W;
  k.support_known.v_W = Vec3::Zero();
  k.support_known.x_W = Vec3::Zero();
  std::vector<HeldContact> contacts = {k};
  REQUIRE(held_velocities(bodies, contacts)[0].slip_W.norm() < 1e-15);
  const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
  REQUIRE(m.solution.status == HeldStatus::kOk);
  CHECK(contacts[0].sticks);
  CHECK((m.solution.a_W[0] - 2.0 / 7.0 * W.cross(v)).norm() < 1e-13);
  CHECK(m.solution.motion[0].slip_rate_W.norm() < 1e-12);
}

TEST_CASE("held: a box on a sliding block stops with it (two dynamic bodies)", "[impulse][held]") {
  // A 0.5 kg box on a 1 kg block sliding at 1 m/s on a floor with mu 0.3; mu 1 between them.
  // Together they decelerate at 0.3 g; the box needs 0.3 g x 0.5 kg of friction < 1 x its weight.
  std::vector<HeldBody> bodies = {box(1.0, Vec3(0.2, 0.2, 0.1), Vec3(0, 0, 0.1), Vec3(1, 0, 0)),
                                  box(0.5, Vec3(0.1, 0.1, 0.1), Vec3(0, 0, 0.3), Vec3(1, 0, 0))};
  HeldContact floor = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 0.3);
  square_patch(floor, 0.2);
  HeldContact between = on_plane(1, Vec3(0, 0, 0.2), Vec3::UnitZ(), Vec3::UnitX(), 1.0);
  between.support = 0;
  square_patch(between, 0.1);
  std::vector<HeldContact> contacts = {floor, between};
  const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
  REQUIRE(m.solution.status == HeldStatus::kOk);
  CHECK_FALSE(contacts[0].sticks);
  CHECK(contacts[1].sticks);
  for (int b = 0; b < 2; ++b) {
    CHECK((m.solution.a_W[b] - Vec3(-0.3 * kG, 0, 0)).norm() < 1e-12);
    CHECK(m.solution.alpha_W[b].norm() < 1e-12);
  }
  CHECK(m.solution.forces[0].normal == Approx(1.5 * kG).epsilon(1e-13));
  CHECK(m.solution.forces[1].normal == Approx(0.5 * kG).epsilon(1e-13));
  CHECK(m.solution.forces[1].friction.x() == Approx(-0.5 * 0.3 * kG).epsilon(1e-12));
}

TEST_CASE(
    "held: torsion slows a spinning face at mu g r_eff / (I / m), rolling resistance a ball "
    "at 5 d g / 7 r",
    "[impulse][held]") {
  {
    // A cube spinning flat at 3 rad/s on the ground (not sliding).
    std::vector<HeldBody> bodies = {
        box(1.0, Vec3(0.1, 0.1, 0.1), Vec3(0, 0, 0.1), Vec3::Zero(), Vec3(0, 0, 3))};
    HeldContact k = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 0.4);
    square_patch(k, 0.1);
    std::vector<HeldContact> contacts = {k};
    const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    REQUIRE(m.solution.status == HeldStatus::kOk);
    CHECK_FALSE(contacts[0].spin_sticks);
    const double I = bodies[0].inertia_W(2, 2);
    CHECK(m.solution.alpha_W[0].z() == Approx(-contacts[0].torsion_arm * kG / I).epsilon(1e-13));
    // r_eff of a square of side a about its centre: a (sqrt 2 + ln(1 + sqrt 2)) / 6.
    const double a = 0.2;
    CHECK(contacts[0].torsion_arm ==
          Approx(0.4 * a * (std::sqrt(2.0) + std::log(1 + std::sqrt(2.0))) / 6.0).epsilon(1e-12));
  }
  {
    const double R = 0.05, d = 1e-3;
    std::vector<HeldBody> bodies = {
        ball(0.1, R, Vec3(0, 0, R), Vec3(1, 0, 0), Vec3(0, 1.0 / R, 0))};
    HeldContact k = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 0.5);
    k.sphere_radius = R;
    k.rolling_resistance = d;
    std::vector<HeldContact> contacts = {k};
    const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    REQUIRE(m.solution.status == HeldStatus::kOk);
    CHECK(contacts[0].sticks);
    CHECK_FALSE(contacts[0].roll_sticks);
    CHECK(m.solution.a_W[0].x() == Approx(-5.0 * d * kG / (7.0 * R)).epsilon(1e-12));
  }
}

TEST_CASE("held: a contact that would have to pull lets go", "[impulse][held]") {
  // A box "resting" under a ceiling: gravity pulls it away.
  std::vector<HeldBody> bodies = {box(1.0, Vec3(0.1, 0.1, 0.1), Vec3(0, 0, -0.1))};
  HeldContact k = on_plane(0, Vec3::Zero(), -Vec3::UnitZ(), Vec3::UnitX(), 0.5);
  square_patch(k, 0.1);
  std::vector<HeldContact> contacts = {k};
  const HeldModes m = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
  REQUIRE(m.solution.status == HeldStatus::kOk);
  CHECK_FALSE(contacts[0].active);
  REQUIRE(m.released.size() == 1);
  CHECK((m.solution.a_W[0] - Vec3(0, 0, -kG)).norm() < 1e-15);
}

TEST_CASE("held: the velocity projection zeroes the approach and the rocking, nothing else",
          "[impulse][held]") {
  // A cube arriving at 1 cm/s onto the ground while sliding at 1 m/s and rocking slightly.
  std::vector<HeldBody> bodies = {
      box(1.0, Vec3(0.1, 0.1, 0.1), Vec3(0, 0, 0.1), Vec3(1, 0, -0.01), Vec3(0.02, 0, 0.5))};
  HeldContact k = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), 0.5);
  square_patch(k, 0.1);
  std::vector<HeldContact> contacts = {k};
  const double dE = project_held_velocities(bodies, contacts, 1e-12);
  CHECK(dE <= 0.0);
  const HeldContactMotion after = held_velocities(bodies, contacts)[0];
  CHECK(std::abs(after.slip_W.z()) < 1e-15);
  CHECK(std::abs(after.dw_W.x()) < 1e-15);
  CHECK(std::abs(after.dw_W.y()) < 1e-15);
  CHECK(bodies[0].w_W.z() == Approx(0.5));  // the spin about n is not still: kept
  CHECK(bodies[0].v_W.x() == Approx(1.0));  // nor is the slide
}

namespace {

// A contact between two boxes of the problem: `mover` on `support` across the plane through c
// with normal n (support to mover), over the rectangle of half-sizes (a, b) along (t1, n x t1).
HeldContact between_boxes(int mover, int support, const Vec3& c, const Vec3& n, const Vec3& t1,
                          double a, double b, double mu) {
  HeldContact k = on_plane(mover, c, n, t1, mu);
  k.support = support;
  k.patch = PatchKind::kPolygon;
  k.polygon = {Vec2(-a, -b), Vec2(a, -b), Vec2(a, b), Vec2(-a, b)};
  set_torsion_arm(k);
  return k;
}

// A pyramid of 0.1 m boxes of 1 kg, `rows` at the bottom, each row's boxes touching side by side
// and each box above resting on two: every contact held (floor, side and bridging), all at rest.
// Its constraints are redundant (a box on two supports, side contacts that carry nothing).
void pyramid(int rows, std::vector<HeldBody>& bodies, std::vector<HeldContact>& contacts) {
  const double h = 0.1, mu = 0.5;
  std::vector<std::vector<int>> index(static_cast<std::size_t>(rows));
  for (int r = 0; r < rows; ++r) {
    const int k = rows - r;
    for (int j = 0; j < k; ++j) {
      index[static_cast<std::size_t>(r)].push_back(static_cast<int>(bodies.size()));
      bodies.push_back(
          box(1.0, Vec3(h / 2, h / 2, h / 2), Vec3((j - (k - 1) / 2.0) * h, 0, h / 2 + r * h)));
    }
  }
  auto x_of = [&](int i) { return bodies[static_cast<std::size_t>(i)].x_W; };
  for (int r = 0; r < rows; ++r) {
    const auto& row = index[static_cast<std::size_t>(r)];
    for (std::size_t j = 0; j < row.size(); ++j) {
      const Vec3 x = x_of(row[j]);
      if (r == 0) {
        HeldContact k = on_plane(row[j], Vec3(x.x(), 0, 0), Vec3::UnitZ(), Vec3::UnitX(), mu);
        square_patch(k, h / 2);
        contacts.push_back(k);
      } else {
        // On the two below, over the half of each it covers.
        for (int s :
             {row[j] - static_cast<int>(row.size()) - 1, row[j] - static_cast<int>(row.size())}) {
          const Vec3 below = x_of(s);
          contacts.push_back(between_boxes(row[j], s,
                                           Vec3(0.5 * (x.x() + below.x()), 0, x.z() - h / 2),
                                           Vec3::UnitZ(), Vec3::UnitX(), h / 4, h / 2, mu));
        }
      }
      if (j + 1 < row.size()) {  // side by side with the next: n along +x, t1 along y
        contacts.push_back(between_boxes(row[j + 1], row[j], Vec3(x.x() + h / 2, 0, x.z()),
                                         Vec3::UnitX(), Vec3::UnitY(), h / 2, h / 2, mu));
      }
    }
  }
}

}  // namespace

TEST_CASE("held: a pyramid of boxes at rest is held by forces that meet every inequality",
          "[impulse][held]") {
  // The least-norm multipliers of a redundant pyramid pull at some contacts (or push outside a
  // patch, or beyond a friction cone); the pyramid stands all the same, and the forces that say
  // so exist. feasible_forces finds them (GLPK over the redundancy): the same accelerations
  // (none), no violation, and choosing the modes lets nothing go.
  for (int rows : {2, 3, 4, 6}) {
    CAPTURE(rows);
    std::vector<HeldBody> bodies;
    std::vector<HeldContact> contacts;
    pyramid(rows, bodies, contacts);
    const HeldSolution least = solve_held(bodies, contacts);
    const HeldSolution feasible = solve_held(bodies, contacts, /*feasible_forces=*/true);
    REQUIRE(least.status == HeldStatus::kOk);
    REQUIRE(feasible.status == HeldStatus::kOk);
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      CHECK(least.a_W[b].norm() < 1e-12);
      CHECK(feasible.a_W[b].norm() < 1e-12);
      CHECK(feasible.alpha_W[b].norm() < 1e-10);
    }
    CHECK(worst_violation(contacts, feasible, 1e-9).kind == HeldViolation::Kind::kNone);
    // The total upward force on the floor is the pyramid's weight.
    double floor_load = 0.0;
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      if (contacts[i].support < 0) floor_load += feasible.forces[i].normal;
    }
    CHECK(floor_load == Approx(kG * static_cast<double>(bodies.size())).epsilon(1e-12));
    if (rows >= 3) {  // why it is needed: least norm breaks an inequality here
      CHECK(worst_violation(contacts, least, 1e-9).kind != HeldViolation::Kind::kNone);
    }
    std::vector<HeldContact> chosen = contacts;
    const HeldModes m = choose_held_modes(bodies, chosen, 1e-12, 1e-9);
    CHECK(m.changes == 0);
    CHECK(m.released.empty());
    // A patch with a repeated vertex (a zero-length edge) bounds nothing more: the same answer.
    std::vector<HeldContact> repeated = contacts;
    for (HeldContact& k : repeated) {
      if (k.patch == PatchKind::kPolygon) k.polygon.insert(k.polygon.begin(), k.polygon.front());
    }
    const HeldSolution again = solve_held(bodies, repeated, /*feasible_forces=*/true);
    REQUIRE(again.status == HeldStatus::kOk);
    CHECK(worst_violation(repeated, again, 1e-9).kind == HeldViolation::Kind::kNone);
  }
}

TEST_CASE("held: a ball held as a curved surface moves exactly as the held sphere",
          "[impulse][held]") {
  // The same ball twice: as a sphere (contact point under its centre, sphere_radius) and as a
  // smooth surface touching at a material point that moves over it (curved, H = R (I - n n^T)).
  // The two descriptions of one contact must give one motion, rolling on a platter and sliding.
  const double R = 0.05, Omega = 2 * kPi;
  const Vec3 n = Vec3::UnitZ();
  for (const bool sliding : {false, true}) {
    CAPTURE(sliding);
    const Vec3 x(0.3, 0.1, R), v(0.05, 0.1, 0);
    const Vec3 W(0, 0, Omega);
    const Vec3 w = sliding ? Vec3(3.0, -1.0, 7.0) : Vec3(-n.cross(W.cross(x - R * n) - v) / R);
    std::vector<HeldBody> bodies = {ball(0.1, R, x, v, w)};
    HeldContact k = on_plane(0, Vec3(x.x(), x.y(), 0), n, Vec3::UnitX(), 0.5);
    k.support_known.w_W = W;
    HeldContact sphere = k, curved = k;
    sphere.sphere_radius = R;
    curved.curved = true;
    curved.curvature_W = R * (Mat3::Identity() - n * n.transpose());
    curved.curved_size = R;
    std::vector<HeldContact> a = {sphere}, b = {curved};
    const HeldModes ma = choose_held_modes(bodies, a, 1e-12, 1e-12);
    const HeldModes mb = choose_held_modes(bodies, b, 1e-12, 1e-12);
    REQUIRE(ma.solution.status == HeldStatus::kOk);
    REQUIRE(mb.solution.status == HeldStatus::kOk);
    CHECK(a[0].sticks == !sliding);
    CHECK(b[0].sticks == a[0].sticks);
    CHECK((ma.solution.a_W[0] - mb.solution.a_W[0]).norm() <= 1e-13);
    CHECK((ma.solution.alpha_W[0] - mb.solution.alpha_W[0]).norm() <= 1e-11);
    CHECK(std::abs(ma.solution.forces[0].normal - mb.solution.forces[0].normal) <= 1e-14);
    CHECK((ma.solution.motion[0].slip_rate_W - mb.solution.motion[0].slip_rate_W).norm() <= 1e-12);
  }
}

TEST_CASE("held: Euler's disk rolling on its rim at its steady motion keeps it",
          "[impulse][held]") {
  // A cylinder (radius r, half-height h) tilted alpha, centre of mass at rest, rolling without
  // slipping on its lower rim, its axis precessing at Omega with Omega^2 = g D / (sin alpha
  // [r D / 2 - (r^2/4 - h^2/3) cos alpha]), D = r cos alpha - h sin alpha, and spinning at
  // -Omega D / r about its axis: the steady motion (Moffatt, Nature 2000, for the thin disk). Held
  // at its rim point - a curved contact, the rim's tangent its only curvature, r / sin alpha - the
  // centre of mass must stay at rest (a = 0, no friction force) and the angular velocity precess
  // with the axis, dw/dt = Omega z x w. Without the rim point's motion over the rim the normal
  // force and the turning come out wrong.
  const double r = 0.0375, h = 0.005, m = 0.45;
  for (const double alpha_deg : {5.0, 20.0, 60.0}) {
    CAPTURE(alpha_deg);
    const double alpha = alpha_deg * kPi / 180.0;
    const double D = r * std::cos(alpha) - h * std::sin(alpha);
    const double Omega = std::sqrt(
        kG * D / (std::sin(alpha) * (r * D / 2 - (r * r / 4 - h * h / 3) * std::cos(alpha))));
    const double spin = -Omega * D / r;
    DiskOnRim held = disk_on_rim(r, h, m, alpha, 0.3);
    HeldBody& disk = held.disk;
    disk.w_W = spin * held.axis + Vec3(0, 0, Omega);
    REQUIRE(std::abs(held.rim.c_W.z()) < 1e-16);
    std::vector<HeldBody> bodies = {disk};
    std::vector<HeldContact> contacts = {held.rim};
    REQUIRE(held_velocities(bodies, contacts)[0].slip_W.norm() < 1e-15);
    const HeldModes modes = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    REQUIRE(modes.solution.status == HeldStatus::kOk);
    CHECK(contacts[0].sticks);
    const double scale = Omega * disk.w_W.norm();
    CHECK(modes.solution.a_W[0].norm() <= 1e-12 * kG);
    CHECK((modes.solution.alpha_W[0] - Vec3(0, 0, Omega).cross(disk.w_W)).norm() <= 1e-12 * scale);
    CHECK(modes.solution.forces[0].normal == Approx(m * kG).epsilon(1e-12));
    CHECK(modes.solution.forces[0].friction.norm() <= 1e-12 * m * kG);
  }
}

TEST_CASE(
    "held: a ball wedged in a corner, both contacts sticking, is squeezed no more than its cones "
    "need",
    "[impulse][held]") {
  // A ball on a floor against a wall at x = R, pushed into the wall, turning about the line
  // through its two contact points (neither slips). Its rows are dependent (the squeeze between
  // the two points is free) and the rolling resistance, d N at each contact, turns it with the
  // squeeze: the accelerations are not unique. The least-norm multipliers need more friction at
  // the wall than mu N; the solution must be one whose forces meet every cone, and the rolling
  // resistance must slow the turning.
  const double R = 0.025, m = 0.1;
  for (const double push : {0.2, 0.5, 1.0}) {
    for (const double d : {1e-3, 5e-3}) {
      for (const double w : {-20.0, 20.0}) {
        CAPTURE(push, d, w);
        const Vec3 axis = Vec3(1, 0, 1).normalized();
        const Vec3 centre(0, 0, R);
        const Vec3 p_floor(0, 0, 0), p_wall(R, 0, R);
        HeldBody b = ball(m, R, centre, (w * axis).cross(centre - p_floor), w * axis);
        b.force_W += Vec3(push, 0.3 * push, 0);
        std::vector<HeldBody> bodies = {b};
        HeldContact floor = on_plane(0, p_floor, Vec3::UnitZ(), Vec3::UnitX(), 0.5);
        HeldContact wall = on_plane(0, p_wall, -Vec3::UnitX(), Vec3::UnitY(), 0.5);
        for (HeldContact* k : {&floor, &wall}) {
          k->sphere_radius = R;
          k->rolling_resistance = d;
        }
        std::vector<HeldContact> contacts = {floor, wall};
        const HeldModes modes = choose_held_modes(bodies, contacts, 1e-9, 1e-9);
        REQUIRE(modes.solution.status == HeldStatus::kOk);
        CHECK(modes.converged);
        CHECK(modes.released.empty());
        const HeldSolution& s = modes.solution;
        for (std::size_t i = 0; i < 2; ++i) {
          CAPTURE(i);
          CHECK(contacts[i].sticks);
          CHECK_FALSE(contacts[i].roll_sticks);
          CHECK(s.forces[i].normal >= 0.0);
          CHECK(s.forces[i].friction.norm() <=
                contacts[i].friction * s.forces[i].normal * (1 + 1e-9));
          CHECK(s.motion[i].slip_rate_W.norm() <= 1e-9);
        }
        // It turns about the line through its contacts as a pendulum on that axis: I_L alpha =
        // the applied torque about it plus the rolling resistance's, which opposes the turning.
        const Vec3 arm = centre - p_floor;
        const double I_L = 0.4 * m * R * R + m * arm.cross(axis).squaredNorm();
        const double applied = arm.cross(b.force_W).dot(axis);
        double resisting = 0.0;
        for (std::size_t i = 0; i < 2; ++i) {
          const Vec2& t = s.forces[i].rolling;
          resisting += (t.x() * contacts[i].t1_W + t.y() * contacts[i].t2_W).dot(axis);
        }
        CHECK(resisting * w < 0.0);
        CHECK(s.alpha_W[0].dot(axis) == Approx((applied + resisting) / I_L).epsilon(1e-9));
      }
    }
  }
}

namespace {

// Ball 0 (radius Rm) on ball 1 (radius Rs), touching at the centres' line: its normal follows
// the centres (n_dot from their relative velocity), friction 0.5 sliding, rolling resistance 1e-3
// held; the caller sets the rest of the modes.
HeldContact ball_on_ball(const std::vector<HeldBody>& b, double Rm, double Rs) {
  HeldContact k;
  k.mover = 0;
  k.support = 1;
  const Vec3 d = b[0].x_W - b[1].x_W;
  k.n_W = d.normalized();
  k.t1_W = k.n_W.unitOrthogonal();
  k.t2_W = k.n_W.cross(k.t1_W);
  k.c_W = b[1].x_W + Rs * k.n_W;
  k.sphere_radius = Rm;
  k.has_n_dot = true;
  const Vec3 dv = b[0].v_W - b[1].v_W;
  k.n_dot_W = (dv - dv.dot(k.n_W) * k.n_W) / d.norm();
  k.friction = 0.5;
  k.sticks = false;
  k.rolling_resistance = 1e-3;
  return k;
}

// The contact's velocities (contact_of rebuilds it from the bodies) after the bodies move for h
// under the solution's accelerations; dw reduced to the rolling, its part in the tangent plane.
template <class ContactOf>
HeldContactMotion motion_along(const std::vector<HeldBody>& bodies, const HeldSolution& s, double h,
                               const ContactOf& contact_of) {
  std::vector<HeldBody> b = bodies;
  for (std::size_t i = 0; i < b.size(); ++i) {
    b[i].x_W += bodies[i].v_W * h + 0.5 * s.a_W[i] * h * h;
    b[i].v_W += s.a_W[i] * h;
    b[i].w_W += s.alpha_W[i] * h;
  }
  const HeldContact c = contact_of(b);
  HeldContactMotion m = held_velocities(b, {c})[0];
  m.dw_W -= m.dw_W.dot(c.n_W) * c.n_W;
  return m;
}

}  // namespace

TEST_CASE(
    "held: two dynamic spheres' slip and rolling rates are their derivatives along the motion",
    "[impulse][held]") {
  // A ball sliding over another, both free and turning: the problem's slip rate (ds/dt following
  // the contact point, with the normal's rate) against a central difference of the slip over the
  // motion its accelerations give (the contact rebuilt from the centres at t +- dt). So too the
  // rolling rate: the rate of dw's part in the tangent plane as the normal turns, which the
  // relative angular acceleration alone is not (the spin about the turning normal turns into
  // rolling). (Taken as that alone, a ball on a ball in a pile, rolling from rest at 3e-6
  // rad/s^2 by the plan, turned back within 8e-9 s under its 0.0033 rad/s spin, stopped, and so
  // again, 15,831 times in 4 ms.)
  const double Rm = 0.025, Rs = 0.03;
  for (int trial = 0; trial < 4; ++trial) {
    CAPTURE(trial);
    const Vec3 xs(0.01 * trial, 0, 0.03);
    const Vec3 n0 = Vec3(0.3 + 0.1 * trial, -0.2, 1.0 - 2.0 * (trial % 2)).normalized();
    std::vector<HeldBody> bodies = {
        ball(0.1, Rm, xs + (Rm + Rs) * n0, Vec3(0.3, -0.2, 0.1), Vec3(5, -7, 3 * trial)),
        ball(0.2, Rs, xs, Vec3(-0.1, 0.2, 0.05), Vec3(-4, 2, 8))};
    const Vec3 rel = bodies[0].v_W - bodies[1].v_W;
    bodies[0].v_W -= rel.dot(n0) * n0;  // touching, not approaching
    auto contact_of = [&](const std::vector<HeldBody>& b) {
      HeldContact k = ball_on_ball(b, Rm, Rs);
      k.roll_sticks = false;
      return k;
    };
    std::vector<HeldContact> contacts = {contact_of(bodies)};
    const HeldContactMotion now = held_velocities(bodies, contacts)[0];
    const HeldContact& k = contacts[0];
    contacts[0].slip_dir = Vec2(now.slip_W.dot(k.t1_W), now.slip_W.dot(k.t2_W)).normalized();
    contacts[0].roll_dir = Vec2(now.dw_W.dot(k.t1_W), now.dw_W.dot(k.t2_W)).normalized();
    const HeldSolution s = solve_held(bodies, contacts);
    REQUIRE(s.status == HeldStatus::kOk);
    const double dt = 1e-6;
    const HeldContactMotion ahead = motion_along(bodies, s, dt, contact_of);
    const HeldContactMotion behind = motion_along(bodies, s, -dt, contact_of);
    const Vec3 difference = (ahead.slip_W - behind.slip_W) / (2.0 * dt);
    CHECK((difference - s.motion[0].slip_rate_W).norm() <= 1e-6 * (1.0 + difference.norm()));
    auto tangential = [&](const Vec3& v) { return Vec3(v - v.dot(k.n_W) * k.n_W); };
    const Vec3 rolling = tangential((ahead.dw_W - behind.dw_W) / (2.0 * dt));
    CHECK((rolling - tangential(s.motion[0].roll_rate_W)).norm() <= 1e-6 * (1.0 + rolling.norm()));
    // (The relative angular acceleration alone misses the spin's part, here of order 1e-1.)
    CHECK((rolling - tangential(s.motion[0].dalpha_W)).norm() > 1e-3 * (1.0 + rolling.norm()));
    // And the gap holds: its second derivative, n . ds/dt + dn/dt . s, is zero.
    CHECK(std::abs(s.motion[0].slip_rate_W.dot(k.n_W) + k.n_dot_W.dot(now.slip_W)) <= 1e-9);
  }
}

TEST_CASE("held: a ball's rolling held sticking on a ball stays zero as the normal turns",
          "[impulse][held]") {
  // A ball sliding over another (both free) without rolling on it, spinning about their common
  // normal: its rolling resistance holds the rolling (dw's part in the tangent plane, which turns
  // with the normal) at zero along the motion the accelerations give: a central difference of it,
  // the contact rebuilt from the centres at t +- dt. Sliding, the normal does not turn with the
  // support. (Held about tangents turned with the support alone, the spin about the turning
  // normal leaked into rolling, here 11 to 18 rad/s^2; in a pile of 100 balls it rolled a held
  // ball at 1.5e-8 m/s within 2 us, which the next plan read as rolling against its own
  // deceleration: 169 roll stops of one contact in 0.036 s.)
  const double Rm = 0.025, Rs = 0.03;
  for (int trial = 0; trial < 4; ++trial) {
    CAPTURE(trial);
    const Vec3 n0 = Vec3(0.3 + 0.1 * trial, -0.2, 1.0 - 0.5 * trial).normalized();
    const Vec3 xs(0.01 * trial, 0, 0.03);
    const Vec3 w_s(-4, 2, 8), v_s(-0.1, 0.2, 0.05);
    const Vec3 w_m = w_s + (3.0 + 2.0 * trial) * n0;  // spinning about the normal only
    // Slipping at 0.2 m/s along a tangent (the contact points' velocities otherwise equal).
    const Vec3 slip = 0.2 * n0.unitOrthogonal();
    const Vec3 v_m = v_s + w_s.cross(Rs * n0) + w_m.cross(Rm * n0) + slip;
    std::vector<HeldBody> bodies = {ball(0.1, Rm, xs + (Rm + Rs) * n0, v_m, w_m),
                                    ball(0.2, Rs, xs, v_s, w_s)};
    auto contact_of = [&](const std::vector<HeldBody>& b) {
      HeldContact k = ball_on_ball(b, Rm, Rs);
      k.slip_dir = Vec2(slip.dot(k.t1_W), slip.dot(k.t2_W)).normalized();
      return k;  // rolling held
    };
    const std::vector<HeldContact> contacts = {contact_of(bodies)};
    const HeldContact& k = contacts[0];
    // The normal turns, and not with the support.
    REQUIRE((k.n_dot_W - w_s.cross(k.n_W)).norm() > 1.0);
    const HeldSolution s = solve_held(bodies, contacts);
    REQUIRE(s.status == HeldStatus::kOk);
    const double dt = 1e-6;
    const HeldContactMotion ahead = motion_along(bodies, s, dt, contact_of);
    const HeldContactMotion behind = motion_along(bodies, s, -dt, contact_of);
    const Vec3 roll_rate = (ahead.dw_W - behind.dw_W) / (2.0 * dt);
    CHECK(roll_rate.norm() <= 1e-6);
    // And as the problem reports it: the rolling rate's part in the tangent plane.
    const Vec3 reported = s.motion[0].roll_rate_W;
    CHECK((reported - reported.dot(k.n_W) * k.n_W).norm() <= 1e-9);
  }
}

namespace {

// A fixed-seed linear congruential generator: uniform(lo, hi).
struct Uniform {
  unsigned state;
  double operator()(double lo, double hi) {
    state = state * 1664525u + 1013904223u;
    return lo + (hi - lo) * static_cast<double>(state >> 8) / static_cast<double>(1u << 24);
  }
};

}  // namespace

TEST_CASE("held: contacts that start to roll from rest roll along their rolling accelerations",
          "[impulse][held]") {
  // A ball at rest on the floor with a second ball at rest on it, each pushed by a random force
  // and torque, rolling resistance at both contacts: a contact whose resistance cannot hold it
  // starts to roll, along the direction its rolling accelerates in under the modes of all (the
  // opposite of the couple sticking needed is that direction only for a contact alone; in a
  // pile of 100 balls a ball's rolling so started accelerated 117 degrees away from it, turned
  // back at once, stopped, and so again, 19,755 times in 4e-4 s). Fixed seed; every case must
  // settle with each rolling along its acceleration.
  Uniform uniform{54321u};
  auto random_direction = [&] {
    return Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)).normalized();
  };
  int rolling = 0, unsettled = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double r = 0.05;
    std::vector<HeldBody> bodies = {ball(uniform(0.1, 1.0), r, Vec3(0, 0, r))};
    const Vec3 up = Vec3(uniform(-0.4, 0.4), uniform(-0.4, 0.4), 1.0).normalized();
    bodies.push_back(ball(uniform(0.1, 1.0), r, bodies[0].x_W + 2.0 * r * up));
    HeldContact floor = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), uniform(1.0, 2.0));
    HeldContact on = on_plane(1, bodies[0].x_W + r * up, up, up.cross(Vec3::UnitX()).normalized(),
                              uniform(1.0, 2.0));
    on.support = 0;
    for (HeldContact* k : {&floor, &on}) {
      k->sphere_radius = r;
      k->rolling_resistance = uniform(1e-4, 5e-3);
    }
    std::vector<HeldContact> contacts = {floor, on};
    for (HeldBody& b : bodies) {
      b.force_W += uniform(0.0, 0.3) * kG * b.mass * random_direction();
      b.force_W.z() = std::min(b.force_W.z(), -0.5 * kG * b.mass);  // pressed, not lifted
    }
    const HeldModes modes = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    if (modes.solution.status != HeldStatus::kOk || !modes.converged) {
      ++unsettled;
      continue;
    }
    CHECK(worst_violation(contacts, modes.solution, 1e-9).kind == HeldViolation::Kind::kNone);
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      const HeldContact& c = contacts[i];
      if (!c.active || c.roll_sticks) continue;
      const Vec3& alpha_W = modes.solution.motion[i].dalpha_W;
      const Vec2 rate(alpha_W.dot(c.t1_W), alpha_W.dot(c.t2_W));
      if (rate.norm() * r <= 1e-9) continue;  // no acceleration: no direction to roll along
      ++rolling;
      INFO("trial " << trial << " contact " << i);
      CHECK(rate.dot(c.roll_dir) > 0.0);
      CHECK(std::abs(rate.x() * c.roll_dir.y() - rate.y() * c.roll_dir.x()) <= 1e-3 * rate.norm());
    }
  }
  // Most cases start something rolling, and none is left unsettled.
  CHECK(rolling > 200);
  CHECK(unsettled == 0);
}

TEST_CASE("held: contacts that start to slide from rest together slide along their accelerations",
          "[impulse][held]") {
  // A ball wedged at rest between the floor and a leaning wall, pushed by a random force, and a
  // second ball on it against a second wall: contacts that cannot stick start to slide, each
  // along the direction its slip accelerates in under the modes of all (chosen one at a time, the
  // first one's direction is consistent only with the others sticking, and its slip turns back
  // at once). Fixed seed; every case must end with each slide along its acceleration, or let go.
  Uniform uniform{12345u};
  int started = 0, unsettled = 0, released = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double r = 0.05;
    const bool two = trial % 2 == 1;
    std::vector<HeldBody> bodies = {ball(uniform(0.1, 1.0), r, Vec3(0, 0, r))};
    std::vector<HeldContact> contacts;
    contacts.push_back(on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), uniform(0.1, 1.0)));
    // The wall leans over the ball: its normal points back at it, partly down.
    const double lean = uniform(-0.6, 0.6), turn = uniform(0.0, 2.0 * kPi);
    const Vec3 out(std::cos(turn), std::sin(turn), 0.0);
    const Vec3 n = (-std::cos(lean) * out + std::sin(lean) * Vec3::UnitZ()).normalized();
    const Vec3 t1 = n.cross(Vec3::UnitZ()).normalized();
    contacts.push_back(on_plane(0, bodies[0].x_W - r * n, n, t1, uniform(0.1, 1.0)));
    bodies[0].force_W += uniform(0.0, 3.0) * kG * bodies[0].mass *
                         Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-0.5, 0.5)).normalized();
    if (two) {
      // The second ball on the first, leaning on a second wall across.
      const Vec3 up = Vec3(uniform(-0.5, 0.5), uniform(-0.5, 0.5), 1.0).normalized();
      bodies.push_back(ball(uniform(0.1, 1.0), r, bodies[0].x_W + 2.0 * r * up));
      HeldContact on = on_plane(1, bodies[0].x_W + r * up, up, up.cross(Vec3::UnitX()).normalized(),
                                uniform(0.1, 1.0));
      on.support = 0;
      contacts.push_back(on);
      const Vec3 m = Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-0.3, 0.3)).normalized();
      contacts.push_back(on_plane(1, bodies[1].x_W + r * m, -m,
                                  (-m).cross(Vec3::UnitZ()).normalized(), uniform(0.1, 1.0)));
      bodies[1].force_W += uniform(0.0, 3.0) * kG * bodies[1].mass * m;
    }
    const HeldModes modes = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    if (modes.solution.status != HeldStatus::kOk || !modes.converged) {
      ++unsettled;
      continue;
    }
    released += static_cast<int>(modes.released.size());
    CHECK(worst_violation(contacts, modes.solution, 1e-9).kind == HeldViolation::Kind::kNone);
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      const HeldContact& c = contacts[i];
      if (!c.active || c.sticks) continue;
      ++started;
      const Vec3 rate_W = modes.solution.motion[i].slip_rate_W;
      const Vec2 rate(rate_W.dot(c.t1_W), rate_W.dot(c.t2_W));
      if (rate.norm() <= 1e-9) continue;  // no acceleration: no direction to slide along
      INFO("trial " << trial << " contact " << i);
      CHECK(rate.dot(c.slip_dir) > 0.0);
      CHECK(std::abs(rate.x() * c.slip_dir.y() - rate.y() * c.slip_dir.x()) <= 1e-3 * rate.norm());
    }
  }
  // Most cases start something sliding, none is left unsettled, some let a contact go.
  CHECK(started > 150);
  CHECK(unsettled == 0);
  CHECK(released > 0);
}

TEST_CASE("held: contacts that start to spin from rest spin the way their torsion lets them",
          "[impulse][held]") {
  // A block at rest on the floor and a box sliding and spinning on it, placed off its middle, and
  // a third box at rest on the box: the box's friction and torsion turn the block, whose floor
  // patch starts to slide and spin from rest where it cannot stick, and the top box's patch may
  // too. A spin let go against the torsion sticking needed, judged under the modes of then, can
  // accelerate the other way once other contacts slide (its direction is not chosen with
  // theirs): every contact spinning from rest must end with its spin accelerating along its sign,
  // or stick. Fixed seed.
  Uniform uniform{4242u};
  int spun = 0, unsettled = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double h = 0.1;
    std::vector<HeldBody> bodies = {box(uniform(0.2, 2.0), Vec3(h, h, 0.05), Vec3(0, 0, 0.05))};
    const Vec3 off(uniform(-0.05, 0.05), uniform(-0.05, 0.05), 0.0);
    bodies.push_back(box(uniform(0.2, 2.0), Vec3(0.04, 0.04, 0.04), off + Vec3(0, 0, 0.14),
                         Vec3(uniform(-1, 1), uniform(-1, 1), 0), Vec3(0, 0, uniform(-20, 20))));
    bodies.push_back(box(uniform(0.1, 1.0), Vec3(0.03, 0.03, 0.03),
                         bodies[1].x_W + Vec3(0, 0, 0.07),
                         bodies[1].v_W + bodies[1].w_W.cross(Vec3(0, 0, 0.07)), bodies[1].w_W));
    std::vector<HeldContact> contacts;
    HeldContact floor = on_plane(0, Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX(), uniform(0.05, 0.6));
    square_patch(floor, h);
    contacts.push_back(floor);
    HeldContact on =
        on_plane(1, off + Vec3(0, 0, 0.1), Vec3::UnitZ(), Vec3::UnitX(), uniform(0.2, 1.0));
    on.support = 0;
    square_patch(on, 0.04);
    contacts.push_back(on);
    HeldContact top =
        on_plane(2, off + Vec3(0, 0, 0.18), Vec3::UnitZ(), Vec3::UnitX(), uniform(0.05, 1.0));
    top.support = 1;
    square_patch(top, 0.03);
    contacts.push_back(top);
    const HeldModes modes = choose_held_modes(bodies, contacts, 1e-12, 1e-12);
    if (modes.solution.status != HeldStatus::kOk || !modes.converged) {
      ++unsettled;
      continue;
    }
    CHECK(worst_violation(contacts, modes.solution, 1e-9).kind == HeldViolation::Kind::kNone);
    const std::vector<HeldContactMotion> now = held_velocities(bodies, contacts);
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      const HeldContact& c = contacts[i];
      if (!c.active || c.spin_sticks || std::abs(now[i].dw_W.dot(c.n_W)) > 1e-9) continue;
      ++spun;  // spinning from rest
      INFO("trial " << trial << " contact " << i);
      CHECK(c.spin_sign * modes.solution.motion[i].dalpha_W.dot(c.n_W) > -1e-9);
    }
  }
  CHECK(spun > 50);
  CHECK(unsettled == 0);
}

TEST_CASE("held: a vanishing slip slides along the direction its slip accelerates in",
          "[impulse][held]") {
  // Euler's disk (a cylinder held at its lower rim, a curved contact) rolling without slip in a
  // random state - tilt, angular velocity, friction - so that the rolling needs a friction force
  // whose direction the precession turns: where that force lies beyond mu N, the contact slides
  // from a slip of zero along d with its slip rate lambda d, lambda > 0 (the acceleration-level
  // Coulomb law), and vanishing_slip_direction must find it; where it lies within, there is none.
  // The oracle: the roots of the slip rate's component across d, scanned over 3,600 directions
  // and bisected. The rim's anisotropy (the rolling and the sliding across the rim move the disk
  // differently) makes d differ from the opposite of the friction sticking needs: counted, so
  // that a shortcut along that direction fails here.
  const double r = 0.0375, h = 0.005, m = 0.45;
  Uniform uniform{2718u};
  int slides = 0, sticks = 0, turned = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double alpha = uniform(3.0, 60.0) * kPi / 180.0, mu = uniform(0.05, 1.0);
    DiskOnRim held = disk_on_rim(r, h, m, alpha, mu);
    HeldBody& disk = held.disk;
    disk.w_W = Vec3(uniform(-4, 4), uniform(-4, 4), uniform(-40, 40));
    disk.v_W = -disk.w_W.cross(held.rim.c_W - disk.x_W);  // rolling: no slip at the rim point
    std::vector<HeldBody> bodies = {disk};
    std::vector<HeldContact> contacts = {held.rim};
    REQUIRE(held_velocities(bodies, contacts)[0].slip_W.norm() < 1e-12);
    const HeldSolution stuck = solve_held(bodies, contacts);
    REQUIRE(stuck.status == HeldStatus::kOk);
    if (!(stuck.forces[0].normal > 0.0)) continue;  // it would lift off: not this test's case
    const double need = stuck.forces[0].friction.norm() / (mu * stuck.forces[0].normal);
    // The oracle's roots.
    contacts[0].sticks = false;
    auto rate_along = [&](double theta) {
      contacts[0].slip_dir = Vec2(std::cos(theta), std::sin(theta));
      const HeldSolution s = solve_held(bodies, contacts);
      REQUIRE(s.status == HeldStatus::kOk);
      const Vec3 rate = s.motion[0].slip_rate_W;
      return Vec2(rate.dot(contacts[0].t1_W), rate.dot(contacts[0].t2_W));
    };
    auto across = [&](double theta) {
      const Vec2 rate = rate_along(theta);
      return std::cos(theta) * rate.y() - std::sin(theta) * rate.x();
    };
    std::vector<double> roots;
    constexpr int kScan = 3600;
    for (int j = 0; j < kScan; ++j) {
      double lo = 2 * kPi * j / kScan, hi = 2 * kPi * (j + 1) / kScan;
      double f_lo = across(lo);
      if ((f_lo < 0) == (across(hi) < 0)) continue;
      for (int it = 0; it < 60; ++it) {
        const double mid = 0.5 * (lo + hi), f_mid = across(mid);
        if ((f_mid < 0) == (f_lo < 0)) {
          lo = mid;
          f_lo = f_mid;
        } else {
          hi = mid;
        }
      }
      const double root = 0.5 * (lo + hi);
      if (rate_along(root).dot(Vec2(std::cos(root), std::sin(root))) > 0.0) roots.push_back(root);
    }
    INFO("trial " << trial << " friction needed / (mu N) " << need);
    contacts[0].slip_dir = Vec2::UnitX();
    const std::optional<Vec2> d = vanishing_slip_direction(bodies, contacts, 0);
    if (need < 1.0 - 1e-6) {
      ++sticks;
      CHECK(roots.empty());
      CHECK(!d);
      CHECK(contacts[0].slip_dir == Vec2::UnitX());  // unchanged
      continue;
    }
    if (need <= 1.0 + 1e-6) continue;  // the edge: either answer is within the solves' rounding
    ++slides;
    REQUIRE(roots.size() == 1);
    REQUIRE(d);
    CHECK(contacts[0].slip_dir == *d);
    const Vec2 root(std::cos(roots[0]), std::sin(roots[0]));
    CHECK(std::abs(d->x() * root.y() - d->y() * root.x()) <= 1e-8);
    CHECK(d->dot(root) > 0.0);
    const Vec2 opposite = -stuck.forces[0].friction.normalized();
    if (std::abs(d->x() * opposite.y() - d->y() * opposite.x()) > 1e-2) ++turned;
  }
  INFO("slides " << slides << " sticks " << sticks << " turned " << turned);
  CHECK(slides > 50);
  CHECK(sticks > 50);
  CHECK(turned > 20);
}
