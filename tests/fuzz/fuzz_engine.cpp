// libFuzzer target: the engine on valid scenes with mutated numbers. The input picks a shipped
// scene and rewrites some of its numbers (each mutation: which number, and a new value made from
// the old one or from the input's bytes); a scene that still loads is run for a short while under
// an event cap. The loader may refuse the scene (InputError), the simulation may refuse it at the
// start or stop on its progress guard (InputError); an InvariantError from a scene the loader
// accepted is a finding (issue 20: invariant failures impossible from validated input).
#include "core/check.hpp"
#include "scenarios/json_reader.hpp"
#include "scenarios/scene.hpp"
#include "scheduler/simulation.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#ifndef PALPABLE_FUZZ_SCENES
#error "PALPABLE_FUZZ_SCENES: the directory of the shipped scenes"
#endif

namespace {

using nlohmann::json;

constexpr const char* kScenes[] = {"coins.json",          "bowling.json",
                                   "chain_of_balls.json", "ball_on_platter.json",
                                   "pool_break.json",     "block_on_ramp_decelerating.json",
                                   "balls_in_dish.json",  "sphere_slide_to_roll.json"};
constexpr std::size_t kNumScenes = sizeof(kScenes) / sizeof(kScenes[0]);
constexpr std::uint64_t kMaxEvents = 2000;
constexpr double kMaxSimulatedTime = 0.1;  // [s] of each scene

struct Base {
  json doc;
  std::vector<json::json_pointer> numbers;  // every number in the document
};

void collect(const json& value, const json::json_pointer& at,
             std::vector<json::json_pointer>& out) {
  if (value.is_number()) {
    out.push_back(at);
  } else if (value.is_array()) {
    for (std::size_t i = 0; i < value.size(); ++i) collect(value[i], at / i, out);
  } else if (value.is_object()) {
    for (auto it = value.begin(); it != value.end(); ++it) collect(it.value(), at / it.key(), out);
  }
}

const std::vector<Base>& bases() {
  static const std::vector<Base> all = [] {
    std::vector<Base> out;
    for (const char* name : kScenes) {
      Base b;
      b.doc = palpable::read_json_file(std::string(PALPABLE_FUZZ_SCENES) + "/" + name);
      collect(b.doc, json::json_pointer(), b.numbers);
      out.push_back(std::move(b));
    }
    return out;
  }();
  return all;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const Base& base = bases()[data[0] % kNumScenes];
  json doc = base.doc;
  // Mutations of 10 bytes: 2 pick the number, 1 the operation, 7 (or 8) its operand.
  for (std::size_t at = 1; at + 10 <= size; at += 10) {
    const std::size_t which = (data[at] | (data[at + 1] << 8)) % base.numbers.size();
    const std::uint8_t op = data[at + 2];
    double operand = 0.0;
    std::memcpy(&operand, data + at + 2, sizeof operand);  // 8 bytes, op's included
    json& slot = doc[base.numbers[which]];
    const double old = slot.get<double>();
    double value = old;
    switch (op % 6) {
      case 0: value = operand; break;                                // any double
      case 1: value = old * std::ldexp(1.0, (op >> 3) - 16); break;  // scaled by 2^-16..2^15
      case 2: value = -old; break;
      case 3: value = 0.0; break;
      case 4: value = old + std::ldexp(1.0, (op >> 3) - 24); break;  // nudged
      case 5: value = std::nextafter(old, (op & 8) ? HUGE_VAL : -HUGE_VAL); break;
    }
    if (!std::isfinite(value)) continue;  // JSON holds finite numbers only
    if (slot.is_number_integer() && std::abs(value) < 9e18) {
      slot = static_cast<long long>(value);
    } else {
      slot = value;
    }
  }
  palpable::Scene scene;
  try {
    scene = palpable::scene_from_json(doc, "fuzz.json");
  } catch (const palpable::InputError&) {
    return 0;
  }
  try {
    palpable::SimulationOptions options;
    options.output_interval = scene.output_interval;
    palpable::Simulation simulation(scene.world, options);
    const double t_end = std::min(scene.end_time, kMaxSimulatedTime);
    for (std::uint64_t n = 0; n < kMaxEvents && !simulation.step(t_end).done; ++n) {
    }
  } catch (const palpable::InputError&) {
    // Refused at the start (overlap), or stopped by the progress guard: named, not a crash.
  } catch (const palpable::InvariantError& e) {
    std::fprintf(stderr, "invariant failure from a validated scene: %s\n", e.what());
    std::abort();
  }
  return 0;
}
