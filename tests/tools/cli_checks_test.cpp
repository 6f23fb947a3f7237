// The benchmarks' numeric option check: finite values inside the bounds pass; NaN, infinities,
// values outside and non-numbers fail with a message naming the option.
#include "tools/lib/cli_checks.hpp"

#include <catch2/catch.hpp>

#include <limits>
#include <string>
#include <vector>

namespace {

// Parses `--x value` through CLI11; returns the error message, empty on success.
std::string parse(const CLI::Validator& check, const std::string& value) {
  CLI::App app;
  double x = 0.0;
  app.add_option("--x", x)->check(check);
  std::vector<std::string> args{value, "--x"};  // CLI11 takes them in reverse
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST_CASE("finite_range rejects NaN, infinities and values outside, naming the option",
          "[tools][cli]") {
  using palpable::tools::finite_range;
  const CLI::Validator non_negative = finite_range(0.0, std::numeric_limits<double>::max());
  const CLI::Validator positive =
      finite_range(std::numeric_limits<double>::min(), std::numeric_limits<double>::max());
  for (const char* ok : {"0", "1.5", "1e300"}) {
    CAPTURE(ok);
    CHECK(parse(non_negative, ok).empty());
  }
  for (const char* bad : {"nan", "NaN", "inf", "-inf", "-1", "-1e-300", "abc", "1e400"}) {
    CAPTURE(bad);
    const std::string message = parse(non_negative, bad);
    CHECK(message.find("--x") != std::string::npos);
    CHECK(message.find("finite") != std::string::npos);
  }
  CHECK(parse(positive, "1e-3").empty());
  CHECK(parse(positive, "0") == "--x: expected a finite number > 0, got 0");
  CHECK(parse(non_negative, "-1") == "--x: expected a finite number >= 0, got -1");
  CHECK(!parse(finite_range(0.0, 0.5), "0.6").empty());
  CHECK(parse(finite_range(0.0, 0.5), "0.5").empty());
}
