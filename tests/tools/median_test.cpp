// The median of timings: the middle value, the mean of the middle two for an even count,
// whatever the order of the values.
#include "tools/lib/median.hpp"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

TEST_CASE("median: odd counts give the middle value, even counts the mean of the middle two",
          "[tools][median]") {
  using palpable::tools::median;
  CHECK(median({3.0}) == 3.0);
  CHECK(median({5.0, 1.0, 3.0}) == 3.0);
  CHECK(median({4.0, 1.0}) == 2.5);
  CHECK(median({1.0, 9.0, 2.0, 8.0}) == 5.0);
  CHECK(median({2.0, 2.0, 2.0, 7.0}) == 2.0);
  CHECK_THROWS_AS(median({}), std::invalid_argument);

  // Any order of the same values: the same median.
  std::mt19937_64 rng(20261121);
  std::vector<double> values{0.7, 0.1, 0.4, 0.9, 0.3, 0.2};
  for (int k = 0; k < 20; ++k) {
    CAPTURE(k);
    std::shuffle(values.begin(), values.end(), rng);
    CHECK(median(values) == 0.5 * (0.3 + 0.4));
    std::vector<double> odd(values.begin(), values.end() - 1);
    std::vector<double> sorted = odd;
    std::sort(sorted.begin(), sorted.end());
    CHECK(median(odd) == sorted[2]);
  }
}
