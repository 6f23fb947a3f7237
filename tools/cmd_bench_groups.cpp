// `palpable bench groups`: issue 15's property check of simultaneous-impact groups at any count
// (the suite runs 2,000 of the same stream), and `palpable bench group-cost`: the cost of
// resolving a group of k contacts against k (median of repeated timings). Benchmarks, not tests:
// they print JSON lines; `bench groups` exits 1 if any group breaks a bound.
#include "impulse/group_impulse.hpp"
#include "tools/commands.hpp"
#include "tools/lib/exit_codes.hpp"
#include "tools/lib/median.hpp"
#include "tools/lib/random_groups.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

using palpable::GroupBody;
using palpable::GroupContact;
using palpable::GroupResult;
using palpable::Mat3;
using palpable::Vec3;
using palpable::tools::GroupFigures;
using palpable::tools::RandomGroup;

// The worst value of one figure over the run and the group that reached it.
struct Worst {
  double value = -palpable::kInfinity;
  std::int64_t group = -1;
  void see(double v, std::int64_t g) {
    if (v > value) {
      value = v;
      group = g;
    }
  }
  nlohmann::json json() const { return {{"value", value}, {"group", group}}; }
};

int run_groups(std::int64_t first, std::int64_t count, std::uint64_t seed,
               palpable::RestitutionLaw law) {
  palpable::GroupOptions options;
  options.law = law;
  palpable::tools::RandomGroups groups(seed);
  for (std::int64_t i = 0; i < first; ++i) groups.next();  // drawn, not resolved
  const palpable::tools::GroupBounds bounds;
  Worst energy_ratio, cone_excess, negative_normal, normal_deficit, normal_mismatch, momentum;
  std::int64_t violations = 0, unconverged = 0, scaled = 0, pushed = 0, contacts = 0;
  nlohmann::json first_violations = nlohmann::json::array();
  const auto start = std::chrono::steady_clock::now();
  for (std::int64_t i = first; i < first + count; ++i) {
    const RandomGroup g = groups.next();
    const GroupResult r = palpable::resolve_group(g.bodies, g.contacts, options);
    const GroupFigures f = palpable::tools::group_figures(g, r);
    contacts += static_cast<std::int64_t>(g.contacts.size());
    unconverged += r.converged ? 0 : 1;
    scaled += r.restitution_scale < 1.0 ? 1 : 0;
    pushed += r.final_push ? 1 : 0;
    energy_ratio.see(f.energy_ratio, i);
    cone_excess.see(f.cone_excess, i);
    negative_normal.see(f.negative_normal, i);
    normal_deficit.see(f.normal_deficit, i);
    normal_mismatch.see(f.normal_mismatch, i);
    momentum.see(f.momentum_error, i);
    if (palpable::tools::violates(f, bounds)) {
      ++violations;
      if (first_violations.size() < 10) first_violations.push_back(i);
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nlohmann::json line{{"bench", "groups"},
                      {"seed", seed},
                      {"law", std::string(palpable::to_string(law))},
                      {"first", first},
                      {"count", count},
                      {"contacts", contacts},
                      {"violations", violations},
                      {"first_violations", first_violations},
                      {"unconverged", unconverged},
                      {"restitution_scaled", scaled},
                      {"final_push", pushed},
                      {"worst_energy_ratio", energy_ratio.json()},
                      {"worst_cone_excess", cone_excess.json()},
                      {"worst_negative_normal", negative_normal.json()},
                      {"worst_normal_deficit", normal_deficit.json()},
                      {"worst_normal_mismatch", normal_mismatch.json()},
                      {"worst_momentum_error", momentum.json()},
                      {"bounds",
                       {{"energy_excess_J", bounds.energy_excess},
                        {"cone_excess", bounds.cone_excess},
                        {"negative_normal", bounds.negative_normal},
                        {"normal_deficit", bounds.normal_deficit},
                        {"normal_mismatch", bounds.normal_mismatch},
                        {"momentum_error", bounds.momentum_error}}},
                      {"seconds", seconds}};
  std::cout << line.dump() << std::endl;
  return violations == 0 ? palpable::tools::kExitOk : palpable::tools::kExitFailure;
}

// A 1 kg, 0.2 m cube landing on a fixed floor, sliding and spinning a little, touching at k
// points spread evenly on the circle of radius 0.1 m under its centre: a face's patch (k >= 3).
RandomGroup patch_group(int k) {
  RandomGroup g;
  GroupBody cube;
  cube.inv_mass = 1.0;
  cube.inv_inertia_W = Mat3::Identity() / (0.2 * 0.2 / 6.0);
  cube.v_W = Vec3(0.5, 0.2, -2.0);
  cube.w_W = Vec3(0.3, -0.2, 0.1);
  g.bodies = {cube, GroupBody{}};
  g.with_fixed = true;
  for (int i = 0; i < k; ++i) {
    const double a = 2.0 * 3.14159265358979323846 * i / k;
    GroupContact c;
    c.body1 = 0;
    c.body2 = 1;
    c.point_W = Vec3(0.1 * std::cos(a), 0.1 * std::sin(a), -0.1);
    c.n_W = Vec3::UnitZ();
    c.friction = 0.5;
    c.restitution = 0.5;
    g.contacts.push_back(c);
  }
  return g;
}

// Median over `repeats` of the mean time per group of one pass over `set`.
double median_ns(const std::vector<RandomGroup>& set, int repeats, double& sink) {
  auto pass = [&] {
    for (const RandomGroup& g : set)
      sink += palpable::resolve_group(g.bodies, g.contacts).energy_after;
  };
  return palpable::tools::median_ns_per_call(pass, repeats, 1 << 20) /
         static_cast<double>(set.size());
}

int run_cost(const std::vector<int>& ks, int repeats, int set_size, std::uint64_t seed) {
  double sink = 0.0;
  for (const std::string family : {"patch", "random"}) {
    double k1_ns = 0.0;
    for (int k : ks) {
      std::vector<RandomGroup> set;
      if (family == "patch") {
        set.push_back(patch_group(k));
      } else {
        palpable::tools::RandomGroups groups(seed);
        for (int i = 0; i < set_size; ++i) set.push_back(groups.next(k));
      }
      double iterations = 0.0;
      int unconverged = 0, pushed = 0, violations = 0;
      for (const RandomGroup& g : set) {
        const GroupResult r = palpable::resolve_group(g.bodies, g.contacts);
        iterations += r.iterations;
        unconverged += r.converged ? 0 : 1;
        pushed += r.final_push ? 1 : 0;
        violations += palpable::tools::violates(palpable::tools::group_figures(g, r)) ? 1 : 0;
      }
      const double ns = median_ns(set, repeats, sink);
      if (k == ks.front()) k1_ns = ns;
      nlohmann::json line{{"bench", "group_cost"},
                          {"family", family},
                          {"k", k},
                          {"groups", set.size()},
                          {"median_ns_per_group", ns},
                          {"ratio_to_k" + std::to_string(ks.front()), ns / k1_ns},
                          {"mean_iterations", iterations / static_cast<double>(set.size())},
                          {"unconverged", unconverged},
                          {"final_push", pushed},
                          {"violations", violations},
                          {"repeats", repeats}};
      std::cout << line.dump() << std::endl;
    }
  }
  if (sink == 0.1234567) std::cout << "";  // keeps the timed work observable
  return palpable::tools::kExitOk;
}

palpable::tools::CommandRegistration groups_registration{
    "bench groups", [](CLI::App& app) {
      app.description(
          "Resolves a stream of random simultaneous-impact groups (2-8 contacts among 1-4 "
          "dynamic bodies and a fixed one; random masses, inertias, mu, e; the suite's property "
          "test runs the first 2,000 of seed 20261124) and prints one JSON line: violations of "
          "the bounds (energy created, an impulse outside its cone, a contact left approaching, "
          "momentum), the worst of each figure and the group that reached it. Exit 1 if any "
          "group breaks a bound.\n\nExample:\n  palpable bench groups --count 100000 --seed "
          "20261124\n  palpable bench groups --first 50000 --count 50000   (its second half)\n  "
          "palpable bench groups --law stronge   (Stronge's energetic law per contact)");
      auto count = std::make_shared<std::int64_t>(100000);
      auto seed = std::make_shared<std::uint64_t>(20261124);
      auto first = std::make_shared<std::int64_t>(0);
      app.add_option("--count", *count, "number of groups (default 100000)")
          ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40));
      app.add_option("--first", *first,
                     "index of the first group resolved (the ones before are drawn and skipped), "
                     "so that a long run can be split over processes; default 0")
          ->check(CLI::Range(std::int64_t{0}, std::int64_t{1} << 40));
      app.add_option("--seed", *seed, "seed of the stream (default 20261124, the suite's)");
      auto law = std::make_shared<std::string>("poisson");
      app.add_option("--law", *law,
                     "restitution law of the expansion: \"poisson\" (default) or \"stronge\"")
          ->check(CLI::IsMember({"poisson", "stronge"}));
      return std::function<int()>([first, count, seed, law] {
        return run_groups(*first, *count, *seed,
                          *law == "stronge" ? palpable::RestitutionLaw::kStronge
                                            : palpable::RestitutionLaw::kPoisson);
      });
    }};

palpable::tools::CommandRegistration cost_registration{
    "bench group-cost", [](CLI::App& app) {
      app.description(
          "Median cost of resolving one group of k contacts, k = 1..8, 16, 32, with its ratio to "
          "the smallest k measured in the same run; JSON lines. Two families: `patch`, a cube "
          "landing sliding on a floor at k points of a circle (a face's patch), and `random`, "
          "the first --groups groups of the random stream with k contacts each.\n\nExample:\n"
          "  palpable bench group-cost --repeats 7");
      auto repeats = std::make_shared<int>(7);
      auto set_size = std::make_shared<int>(32);
      auto seed = std::make_shared<std::uint64_t>(20261124);
      auto ks =
          std::make_shared<std::vector<int>>(std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 16, 32});
      app.add_option("--repeats", *repeats, "timed repeats per figure (median), >= 5")
          ->check(CLI::Range(5, 1000));
      app.add_option("--groups", *set_size, "random groups per k (default 32)")
          ->check(CLI::Range(1, 100000));
      app.add_option("--seed", *seed, "seed of the random family (default 20261124)");
      app.add_option("--k", *ks, "contact counts, ascending (default 1..8 16 32)")
          ->check(CLI::Range(1, 64));
      return std::function<int()>([=] { return run_cost(*ks, *repeats, *set_size, *seed); });
    }};

}  // namespace
