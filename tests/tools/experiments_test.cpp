// The paper's experiments as shipped scenes, run through `palpable run`'s code path, against what
// must physically hold: no penetration, nobody leaves the table or dish, no energy created
// beyond what the microcollision floor lends (each resting body re-lifted by up to the envelope).
#include "core/ballistic.hpp"
#include "core/shape.hpp"
#include "tools/lib/run_scene.hpp"

#include <catch2/catch.hpp>

#include <cmath>

using palpable::BodyState;
using palpable::Vec3;
using palpable::tools::RunOptions;
using palpable::tools::RunResult;

namespace {

// Both contact models run every experiment (DESIGN.md §8): Mirtich's microcollisions and the
// persistent hold.
const char* const kModels[] = {"microcollisions", "persistent"};

RunResult run(const std::string& name, const std::string& model,
              const std::vector<std::string>& more = {}) {
  RunOptions options;
  options.scene_path = std::string(PALPABLE_SOURCE_DIR) + "/scenarios/" + name;
  options.overrides.push_back("/settings/contact_model=\"" + model + "\"");
  for (const std::string& o : more) options.overrides.push_back(o);
  return palpable::tools::run_scene(options);
}

// Kinetic plus potential energy of the dynamic bodies in sample k.
double mechanical_energy(const RunResult& r, std::size_t k) {
  const auto& world = r.scene.world;
  double e = 0.0;
  for (std::size_t i = 0; i < world.bodies.size(); ++i) {
    const auto& body = world.bodies[i];
    if (!body.is_dynamic()) continue;
    const BodyState& s = r.trace.samples[k][i];
    e += palpable::kinetic_energy(body, s) - body.mass.mass * world.gravity_W.dot(s.x_W);
  }
  return e;
}

// What the microcollision floor may add: every dynamic body lifted by up to two envelopes.
double floor_allowance(const RunResult& r) {
  double a = 0.0;
  for (const auto& body : r.scene.world.bodies) {
    if (body.is_dynamic()) {
      a +=
          body.mass.mass * r.scene.world.gravity_W.norm() * 2.0 * r.scene.world.settings.envelope_m;
    }
  }
  return a;
}

void check_common(const RunResult& r) {
  CHECK(r.stats.penetrations == 0);
  CHECK(r.stats.retry_limit_hits == 0);
  CHECK(r.stats.impulse_failures == 0);
  CHECK(r.stats.distance_failures == 0);
  const double e0 = mechanical_energy(r, 0);
  const double allowance = floor_allowance(r);
  double worst = -1e300;
  for (std::size_t k = 0; k < r.trace.samples.size(); ++k) {
    worst = std::max(worst, mechanical_energy(r, k) - e0);
  }
  INFO("initial energy " << e0 << " J, largest gain " << worst << " J, allowance " << allowance);
  CHECK(worst <= allowance);
}

}  // namespace

TEST_CASE("chain of balls: the far ball leaves, everyone stays on the table",
          "[tools][experiments]") {
  for (const char* model : kModels) {
    CAPTURE(model);
    const bool persistent = std::string(model) == "persistent";
    (void)persistent;
    RunResult r = run("chain_of_balls.json", model);
    check_common(r);
    const auto& world = r.scene.world;
    const std::size_t last = world.find_body("ball7").index;
    double fastest_last = 0.0;
    for (const auto& sample : r.trace.samples) {
      fastest_last = std::max(fastest_last, sample[last].v_W.x());
      for (std::size_t i = 1; i < world.bodies.size(); ++i) {
        const double radius = 0.0125;
        // Never through the table (a ball held touching it sits at its radius to rounding, 3e-17
        // m measured). Balls may hop: ball-ball friction on spinning balls has a vertical
        // component (a fraction of a millimetre here).
        CHECK(sample[i].x_W.z() >= radius - 1e-12);
        CHECK(sample[i].x_W.z() <= 2 * radius);
      }
    }
    // Momentum passes down the chain: the far ball moves off at most of the striker's speed.
    CHECK(fastest_last > 0.5);
  }
}

TEST_CASE("pool break: the rack scatters, no ball leaves the table, no energy created",
          "[tools][experiments]") {
  for (const char* model : kModels) {
    CAPTURE(model);
    const bool persistent = std::string(model) == "persistent";
    (void)persistent;
    RunResult r = run("pool_break.json", model);
    check_common(r);
    const auto& world = r.scene.world;
    const double radius = 0.028575, half_length = 1.27, half_width = 0.635;
    int scattered = 0;
    for (std::size_t i = 2; i < world.bodies.size(); ++i) {
      for (const auto& sample : r.trace.samples) {
        const Vec3& x = sample[i].x_W;
        CHECK(std::abs(x.x()) <= half_length - radius + world.settings.envelope_m);
        CHECK(std::abs(x.y()) <= half_width - radius + world.settings.envelope_m);
        // Never through the cloth (a ball held touching it sits at its radius to rounding);
        // hops off spinning balls' friction stay below a ball radius.
        CHECK(x.z() >= radius - 1e-12);
        CHECK(x.z() <= 2 * radius);
      }
      if (world.bodies[i].name != "cue" &&
          (r.trace.samples.back()[i].x_W - r.trace.samples.front()[i].x_W).norm() > 0.05) {
        ++scattered;
      }
    }
    CHECK(scattered >= 10);
    CHECK(r.stats.collisions > 15);

    // Momentum: until the first ball reaches a cushion, only gravity and the cloth act on the
    // balls from outside (ball-ball impulses cancel in pairs). The cloth's normal impulse so far is
    // exactly N = M g t + P_z(t) - P_z(0), and Coulomb bounds its friction by mu N, so
    // |P_xy(t) - P_xy(0)| <= mu_cloth (M g t + P_z(t) - P_z(0)).
    const double mu_cloth = 0.2, g = -world.gravity_W.z();
    auto momentum = [&](std::size_t k) {
      Vec3 p = Vec3::Zero();
      for (std::size_t i = 2; i < world.bodies.size(); ++i) {
        p += world.bodies[i].mass.mass * r.trace.samples[k][i].v_W;
      }
      return p;
    };
    double total_mass = 0.0;
    for (std::size_t i = 2; i < world.bodies.size(); ++i) total_mass += world.bodies[i].mass.mass;
    const Vec3 p0 = momentum(0);
    // No ball is faster than all the kinetic energy in it allows, so between two samples none
    // moves further than `reach`: a sample with every ball further than that from the cushions
    // comes before any cushion contact.
    double kinetic = 0.0, lightest = 1e300;
    for (std::size_t i = 2; i < world.bodies.size(); ++i) {
      kinetic += palpable::kinetic_energy(world.bodies[i], r.trace.samples[0][i]);
      lightest = std::min(lightest, world.bodies[i].mass.mass);
    }
    const double interval = r.trace.times[1] - r.trace.times[0];
    const double reach =
        std::sqrt(2.0 * kinetic / lightest) * interval + radius + 2.0 * world.settings.envelope_m;
    std::size_t checked = 0;
    for (std::size_t k = 0; k < r.trace.samples.size(); ++k) {
      bool near_cushion = false;
      for (std::size_t i = 2; i < world.bodies.size(); ++i) {
        const Vec3& x = r.trace.samples[k][i].x_W;
        near_cushion = near_cushion || std::abs(x.x()) >= half_length - reach ||
                       std::abs(x.y()) >= half_width - reach;
      }
      if (near_cushion) break;
      const Vec3 p = momentum(k);
      const double t = r.trace.times[k];
      CAPTURE(t);
      CHECK((p - p0).head<2>().norm() <=
            mu_cloth * (total_mass * g * t + p.z() - p0.z()) + 1e-12 * p0.norm());
      ++checked;
    }
    CHECK(checked > 10);  // the break itself happens before any ball reaches a cushion
  }
}

TEST_CASE("balls in a dish: they land in it, stay in it and come to rest", "[tools][experiments]") {
  for (const char* model : kModels) {
    CAPTURE(model);
    const bool persistent = std::string(model) == "persistent";
    RunResult r = run("balls_in_dish.json", model);
    check_common(r);
    if (persistent) {
      // A ball held on the bottom and touching another one must not chatter: its floor contact,
      // let go while the friction between the balls stuck, comes back once that friction slides
      // (it had 2,271 collisions of hold and immediate release, 11.7 s of CPU); and a ball
      // rolling beside a wall it touches is not re-checked at the progress floor (1,371 floored
      // bounds).
      CHECK(r.stats.collisions < 500);
      CHECK(r.stats.floored_bounds < 300);
      // A spin starting from rounding noise (1e-22 rad/s) against the sense its torque drives it
      // in is no reversal: judged by the noise's sign, an island stopped that spin every 5e-12 s,
      // thousands of times (the run went past 100 s of CPU; 125 mode changes in all since).
      CHECK(r.stats.mode_changes < 1000);
    }
    const auto& world = r.scene.world;
    const double radius = 0.02, apothem = 0.08, eps = world.settings.envelope_m;
    const double rim_radius = apothem + 0.2 * std::cos(25.0 * M_PI / 180.0);
    const auto& end = r.trace.samples.back();
    const auto& second_before = r.trace.samples[r.trace.samples.size() - 101];
    for (std::size_t i = 1; i < world.bodies.size(); ++i) {
      CAPTURE(world.bodies[i].name);
      for (const auto& sample : r.trace.samples) {
        CHECK(std::hypot(sample[i].x_W.x(), sample[i].x_W.y()) < rim_radius);
        CHECK(sample[i].x_W.z() >= radius - 1e-12);  // never through the bottom
      }
      // At rest on the flat bottom (rolling and spinning resistance of 0.1 mm took out the
      // rolling): not moving, not spinning, bouncing within the microcollision envelope.
      CHECK(std::hypot(end[i].x_W.x(), end[i].x_W.y()) < apothem);
      CHECK(end[i].x_W.z() <= radius + 2.0 * eps);
      CHECK(end[i].v_W.head<2>().norm() < 1e-9);
      CHECK(end[i].w_W.norm() * radius < 1e-9);
      CHECK((end[i].x_W - second_before[i].x_W).head<2>().norm() < 1e-9);
    }
  }
}

TEST_CASE("coins: they bounce on their rims, land flat and spin down to rest on the table",
          "[tools][experiments]") {
  for (const char* model : kModels) {
    CAPTURE(model);
    const bool persistent = std::string(model) == "persistent";
    (void)persistent;
    RunResult r = run("coins.json", model);
    check_common(r);
    const auto& world = r.scene.world;
    const double radius = 0.01213, eps = world.settings.envelope_m;
    const auto& end = r.trace.samples.back();
    double fastest_spin = 0.0;
    for (std::size_t i = 1; i < world.bodies.size(); ++i) {
      CAPTURE(world.bodies[i].name);
      for (const auto& sample : r.trace.samples) {
        const BodyState& s = sample[i];
        fastest_spin = std::max(fastest_spin, s.w_W.norm());
        // The lowest point of the coin (a 32-gon prism) is never below the table.
        const double lowest =
            palpable::support_W(*world.bodies[i].shape, s.x_W, s.q_WM, -Vec3::UnitZ()).z();
        CHECK(lowest >= -1e-12);
        CHECK(std::hypot(s.x_W.x(), s.x_W.y()) < 0.2);
      }
      // At rest, flat: the axis within the envelope's tilt of the vertical, resting on a face.
      const BodyState& s = end[i];
      const Vec3 axis = s.q_WM * Vec3::UnitZ();
      CHECK(std::abs(axis.z()) >= std::cos(2.0 * eps / radius));
      // Resting: its lowest point bounces within the microcollision envelope (it collides anywhere
      // within one envelope and rises by at most one more).
      CHECK(palpable::support_W(*world.bodies[i].shape, s.x_W, s.q_WM, -Vec3::UnitZ()).z() <=
            2.0 * eps);
      CHECK(s.v_W.head<2>().norm() < 1e-9);
      CHECK(s.w_W.norm() < 1e-9);
    }
    CHECK(fastest_spin >= 40.0);  // they did spin (the scene starts them at 10 to 40 rad/s)
    CHECK(r.stats.collisions > 5);
    if (!persistent) CHECK(r.stats.centre_of_pressure > 100);  // microcollisions on faces
    if (persistent) CHECK(r.stats.rests >= 5);                 // every coin put at rest
  }
}

TEST_CASE("bowling: run on until everything lies still, no two bodies ever overlap",
          "[tools][experiments]") {
  // The scene ends at 5 s; by 19 s the fallen pins have rolled and slid to rest against the ball
  // and each other. Under the persistent model the ball held a pin by an edge that its point of
  // contact ran along: 361,018 overlapping queries from 18.02 s, 2.9 mm deep, until the held
  // contact's acceleration took in that run.
  for (const char* model : kModels) {
    CAPTURE(model);
    RunResult r = run("bowling.json", model, {"/end_time=19"});
    check_common(r);
  }
}

TEST_CASE("bowling: the ball knocks the pins down and everything stays on the pin deck",
          "[tools][experiments]") {
  for (const char* model : kModels) {
    CAPTURE(model);
    const bool persistent = std::string(model) == "persistent";
    (void)persistent;
    RunResult r = run("bowling.json", model);
    check_common(r);
    const auto& world = r.scene.world;
    const double eps = world.settings.envelope_m;
    int fallen = 0;
    for (std::size_t i = 0; i < world.bodies.size(); ++i) {
      const auto& body = world.bodies[i];
      if (!body.is_dynamic()) continue;
      CAPTURE(body.name);
      for (std::size_t k = 0; k < r.trace.samples.size(); ++k) {
        const BodyState& s = r.trace.samples[k][i];
        CAPTURE(r.trace.times[k]);
        // Never through the lane, the kickbacks (inner faces at |y| = 0.8 m) or the pit cushion
        // (inner face at x = 21.3 m): the extreme points of the body's shape.
        // How far the body reaches along d.
        auto extreme = [&](const Vec3& d) {
          return palpable::support_W(*body.shape, s.x_W, s.q_WM, d).dot(d);
        };
        CHECK(extreme(-Vec3::UnitZ()) <= 1e-12);  // the lowest point is at z >= 0
        CHECK(extreme(Vec3::UnitY()) <= 0.8 + 1e-12);
        CHECK(extreme(-Vec3::UnitY()) <= 0.8 + 1e-12);  // y >= -0.8
        CHECK(extreme(Vec3::UnitX()) <= 21.3 + 1e-12);
      }
      if (body.name.rfind("pin", 0) == 0) {
        const Vec3 axis = r.trace.samples.back()[i].q_WM * Vec3::UnitZ();
        if (axis.z() < 0.5) ++fallen;  // tilted more than 60 degrees: down
        CHECK(r.trace.samples.back()[i].v_W.head<2>().norm() < 0.5);
      }
    }
    INFO("pins down: " << fallen);
    CHECK(fallen >= 7);
    CHECK(r.stats.collisions > 50);
    CHECK(eps == 1e-3);  // the paper's envelope
  }
}
