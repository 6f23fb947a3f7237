// stop_imminent (scheduler/island.hpp): at a plan made by a stop, the other sliding components of
// the island that would stop within the scheduler's progress floor are stopped with it; at any
// plan, the decelerating slips and rollings no faster than the next motion's slip floor. Blocks
// sliding and spinning on a fixed floor, whose stops are closed forms: a block sliding at v
// decelerates at mu g and stops after v / (mu g); one spinning at w decelerates at
// mu g r_eff m / I_zz.
#include "scheduler/island.hpp"

#include <catch2/catch.hpp>

#include <vector>

using namespace palpable;

namespace {

constexpr double kG = 9.81;
constexpr double kMu = 0.5;
constexpr double kResolution = 1e-6;  // the default progress floor [s]

// A 0.2 m cube of 1 kg resting on the floor at x, moving at v, turning at w.
HeldBody cube(double x, const Vec3& v, const Vec3& w) {
  HeldBody b;
  b.mass = 1.0;
  b.inertia_W = Mat3::Identity() * (1.0 / 12.0) * 2.0 * 0.2 * 0.2;
  b.inv_inertia_W = b.inertia_W.inverse();
  b.x_W = Vec3(x, 0.0, 0.1);
  b.v_W = v;
  b.w_W = w;
  b.force_W = Vec3(0.0, 0.0, -kG);
  return b;
}

// Its face on the floor: a square patch of half-size 0.1 under it, friction kMu, sliding along
// +x and spinning positively unless told it sticks.
HeldContact face_on_floor(int mover, double x) {
  HeldContact k;
  k.mover = mover;
  k.c_W = Vec3(x, 0.0, 0.0);
  k.n_W = Vec3::UnitZ();
  k.t1_W = Vec3::UnitX();
  k.t2_W = Vec3::UnitY();
  k.friction = kMu;
  k.patch = PatchKind::kPolygon;
  k.polygon = {Vec2(-0.1, -0.1), Vec2(0.1, -0.1), Vec2(0.1, 0.1), Vec2(-0.1, 0.1)};
  set_torsion_arm(k);
  k.sticks = false;
  k.slip_dir = Vec2(1.0, 0.0);
  k.spin_sticks = true;
  return k;
}

// Two cubes side by side: the first's slip has just stopped (the plan's cause), the second
// slides at v. Returns whether stop_imminent stopped the second.
bool second_stopped(double v) {
  std::vector<HeldBody> bodies = {cube(0.0, Vec3::Zero(), Vec3::Zero()),
                                  cube(1.0, Vec3(v, 0.0, 0.0), Vec3::Zero())};
  std::vector<HeldContact> contacts = {face_on_floor(0, 0.0), face_on_floor(1, 1.0)};
  contacts[0].slip_stopped = true;
  stop_imminent(bodies, contacts, kResolution);
  CHECK(contacts[0].slip_stopped);  // left as it was
  CHECK_FALSE(contacts[1].spin_stopped);
  CHECK_FALSE(contacts[1].roll_stopped);
  return contacts[1].slip_stopped;
}

}  // namespace

TEST_CASE("stop_imminent: a slip that would stop within the progress floor stops now",
          "[scheduler][island]") {
  const double closing = kMu * kG * kResolution;  // the speed a slip sheds in that time
  CHECK(second_stopped(0.5 * closing));
  CHECK(second_stopped(0.99 * closing));
  CHECK_FALSE(second_stopped(1.01 * closing));
  CHECK_FALSE(second_stopped(2.0 * closing));
  CHECK_FALSE(second_stopped(1e-3));
}

TEST_CASE("stop_imminent: a slip that accelerates, and a contact that sticks, are left alone",
          "[scheduler][island]") {
  // The second cube slides slowly but is pushed along faster than friction holds it (a force of
  // 2 mu g along +x): its slip grows.
  std::vector<HeldBody> bodies = {cube(0.0, Vec3::Zero(), Vec3::Zero()),
                                  cube(1.0, Vec3(1e-8, 0.0, 0.0), Vec3::Zero())};
  bodies[1].force_W.x() = 2.0 * kMu * kG;
  std::vector<HeldContact> contacts = {face_on_floor(0, 0.0), face_on_floor(1, 1.0)};
  contacts[0].slip_stopped = true;
  stop_imminent(bodies, contacts, kResolution);
  CHECK_FALSE(contacts[1].slip_stopped);
  // Sticking, it has no slip to stop.
  contacts[1].sticks = true;
  bodies[1].force_W.x() = 0.0;
  stop_imminent(bodies, contacts, kResolution);
  CHECK_FALSE(contacts[1].slip_stopped);
}

TEST_CASE("stop_imminent: a spin that would stop within the progress floor stops now",
          "[scheduler][island]") {
  // Torsion mu N r_eff about the normal, N = m g: the spin decelerates at mu g r_eff / I_zz
  // (r_eff = torsion_arm / mu).
  const HeldContact probe = face_on_floor(0, 0.0);
  const double alpha = kG * probe.torsion_arm / cube(0.0, Vec3::Zero(), Vec3::Zero()).inertia_W(2, 2);
  const double closing = alpha * kResolution;
  for (const double factor : {0.5, 2.0}) {
    std::vector<HeldBody> bodies = {cube(0.0, Vec3::Zero(), Vec3::Zero()),
                                    cube(1.0, Vec3::Zero(), Vec3(0.0, 0.0, factor * closing))};
    std::vector<HeldContact> contacts = {face_on_floor(0, 0.0), face_on_floor(1, 1.0)};
    contacts[0].slip_stopped = true;
    contacts[1].sticks = true;
    contacts[1].spin_sticks = false;
    contacts[1].spin_sign = 1.0;
    stop_imminent(bodies, contacts, kResolution);
    INFO("spin at " << factor << " of the closing rate");
    CHECK(contacts[1].spin_stopped == (factor < 1.0));
    CHECK_FALSE(contacts[1].slip_stopped);
  }
}

TEST_CASE("stop_imminent: a decelerating slip no faster than the motion's floor stops at any plan",
          "[scheduler][island]") {
  // No stop made this plan (resolution 0): only the floor applies. A cube sliding at v sheds
  // mu g per second; at 1e-6 m/s it would take 2e-7 s to stop, well beyond a zero resolution.
  const double floor = 5e-7;
  for (const double v : {0.5 * floor, 0.99 * floor, 1.01 * floor, 10.0 * floor}) {
    std::vector<HeldBody> bodies = {cube(0.0, Vec3(v, 0.0, 0.0), Vec3::Zero())};
    std::vector<HeldContact> contacts = {face_on_floor(0, 0.0)};
    stop_imminent(bodies, contacts, 0.0, floor);
    INFO("slip at " << v / floor << " of the floor");
    CHECK(contacts[0].slip_stopped == (v <= floor));
    // Without a floor, nothing stops.
    contacts[0].slip_stopped = false;
    stop_imminent(bodies, contacts, 0.0);
    CHECK_FALSE(contacts[0].slip_stopped);
  }
}

TEST_CASE("stop_imminent: the floor leaves a growing slip and judges the present direction",
          "[scheduler][island]") {
  const double floor = 5e-7;
  // Pushed along +x at 2 mu g, sliding at a tenth of the floor: its slip grows (a start from
  // rest), and it goes on sliding.
  std::vector<HeldBody> bodies = {cube(0.0, Vec3(0.1 * floor, 0.0, 0.0), Vec3::Zero())};
  bodies[0].force_W.x() = 2.0 * kMu * kG;
  std::vector<HeldContact> contacts = {face_on_floor(0, 0.0)};
  stop_imminent(bodies, contacts, 0.0, floor);
  CHECK_FALSE(contacts[0].slip_stopped);
  // Unpushed, sliding along -y while the plan's direction still says +x: resisted against +x it
  // would turn rather than shrink (its rate across it), resisted against its present direction,
  // as its motion resists it, it decelerates - and stops.
  bodies = {cube(0.0, Vec3(0.0, -0.5 * floor, 0.0), Vec3::Zero())};
  contacts = {face_on_floor(0, 0.0)};
  REQUIRE(contacts[0].slip_dir.x() == 1.0);
  stop_imminent(bodies, contacts, 0.0, floor);
  CHECK(contacts[0].slip_stopped);
  CHECK(contacts[0].slip_dir.x() == 1.0);  // the direction itself is left to the plan
}

TEST_CASE("stop_imminent: the floor does not stop a spin", "[scheduler][island]") {
  // A cube spinning on its face at a speed (at its reach) below the floor, decelerating: only the
  // resolution stops a spin (the note in island.hpp).
  const double floor = 5e-7;
  std::vector<HeldBody> bodies = {cube(0.0, Vec3::Zero(), Vec3(0.0, 0.0, 1e-7))};
  std::vector<HeldContact> contacts = {face_on_floor(0, 0.0)};
  contacts[0].sticks = true;
  contacts[0].spin_sticks = false;
  contacts[0].spin_sign = 1.0;
  stop_imminent(bodies, contacts, 0.0, floor);
  CHECK_FALSE(contacts[0].spin_stopped);
  // The resolution does (it would stop within 1 s).
  stop_imminent(bodies, contacts, 1.0, floor);
  CHECK(contacts[0].spin_stopped);
}
