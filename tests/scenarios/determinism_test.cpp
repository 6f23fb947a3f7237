// Determinism (after Box2D's determinism test): every shipped scene, run to its end, must reach
// the committed hash of its final state - every body's position, orientation and velocities, bit
// for bit, and the number of events. A change of behaviour, intended or not, fails here: an
// intended one updates the table below in the same commit and says in its message what changed
// and why. PALPABLE_PRINT_HASHES=1 prints the table as it is now.
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"

#include <catch2/catch.hpp>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

using namespace palpable;

namespace {

// FNV-1a over bytes.
void mix(std::uint64_t& h, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    h ^= bytes[i];
    h *= 0x100000001b3ull;
  }
}
void mix(std::uint64_t& h, double x) {
  mix(h, &x, sizeof x);
}

std::uint64_t final_state_hash(const std::string& scene_file) {
  const Scene scene = scene_from_json(
      read_json_file(std::string(PALPABLE_SOURCE_DIR) + "/scenarios/" + scene_file), scene_file);
  Simulation sim(scene.world, SimulationOptions{scene.output_interval});
  sim.run_until(scene.end_time, nullptr);
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::uint32_t i = 0; i < sim.world().bodies.size(); ++i) {
    const BodyState s = sim.state_at(BodyId{i}, scene.end_time);
    for (int k = 0; k < 3; ++k) mix(h, s.x_W[k]);
    for (int k = 0; k < 4; ++k) mix(h, s.q_WM.coeffs()[k]);
    for (int k = 0; k < 3; ++k) mix(h, s.v_W[k]);
    for (int k = 0; k < 3; ++k) mix(h, s.w_W[k]);
  }
  const std::uint64_t events = sim.stats().events;
  mix(h, &events, sizeof events);
  return h;
}

struct Expected {
  const char* scene;
  std::uint64_t hash;
};

// The committed final-state hashes of the shipped scenes.
const Expected kExpected[] = {
    {"ball_on_platter.json", 0x05f50177987f5e0bull},
    {"balls_in_dish.json", 0xcd7e8267597d57f7ull},
    {"block_on_ramp_accelerating.json", 0x7baccee39ea4ad1eull},
    {"block_on_ramp_decelerating.json", 0x8369ce1c7eaca70aull},
    {"bowling.json", 0x5baeb39707965197ull},
    {"chain_of_balls.json", 0x7406d24437bd46daull},
    {"coins.json", 0x531c6b9c92b7712cull},
    {"cylinder_rolling_slope.json", 0x4bc4bf6ecb23e51aull},
    {"eulers_disk.json", 0xaf30eba8493be1b7ull},
    {"pool_break.json", 0xe0d5e77eeedce905ull},
    {"rattleback.json", 0xc63f4131f2972f5aull},
    {"rattleback_kane_levinson.json", 0xddaf8ae9034ea0c8ull},
    {"rolling_coin.json", 0xcb95544cac3e7151ull},
    {"sphere_slide_to_roll.json", 0x9f92366eb6da51e0ull},
    {"tippe_top.json", 0xb0256fcc7c8b3d5full},
};

}  // namespace

TEST_CASE("every shipped scene reaches its committed final-state hash",
          "[scenarios][determinism]") {
  const bool print = std::getenv("PALPABLE_PRINT_HASHES") != nullptr;
  for (const Expected& e : kExpected) {
    CAPTURE(e.scene);
    const std::uint64_t h = final_state_hash(e.scene);
    if (print)
      std::printf("    {\"%s\", 0x%016llxull},\n", e.scene, static_cast<unsigned long long>(h));
    CHECK(h == e.hash);
  }
}
