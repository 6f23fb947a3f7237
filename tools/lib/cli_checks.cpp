#include "tools/lib/cli_checks.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace palpable::tools {

namespace {

// "> 0", ">= 0", "<= 0.5", "in [0.1, 0.5]": the bounds as people read them, the extremes of
// double (which stand for "no bound" or "positive") left out.
std::string bounds_text(double min, double max) {
  const bool positive = min == std::numeric_limits<double>::min();
  const bool no_max = max == std::numeric_limits<double>::max();
  std::ostringstream out;
  if (positive && no_max) {
    out << "> 0";
  } else if (no_max) {
    out << ">= " << min;
  } else if (positive) {
    out << "in (0, " << max << "]";
  } else {
    out << "in [" << min << ", " << max << "]";
  }
  return out.str();
}

}  // namespace

CLI::Validator finite_range(double min, double max) {
  const std::string bounds = bounds_text(min, max);
  return CLI::Validator(
      [min, max, bounds](std::string& text) {
        double x = 0.0;
        if (!CLI::detail::lexical_cast(text, x) || !std::isfinite(x) || x < min || x > max) {
          return "expected a finite number " + bounds + ", got " + text;
        }
        return std::string();
      },
      "FINITE " + bounds);
}

}  // namespace palpable::tools
