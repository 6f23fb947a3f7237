#include "tools/lib/cli_checks.hpp"

#include <cmath>
#include <sstream>
#include <string>

namespace palpable::tools {

CLI::Validator finite_range(double min, double max) {
  std::ostringstream name;
  name << "FINITE in [" << min << ", " << max << "]";
  return CLI::Validator(
      [min, max](std::string& text) {
        double x = 0.0;
        if (!CLI::detail::lexical_cast(text, x) || !std::isfinite(x) || x < min || x > max) {
          std::ostringstream out;
          out << "expected a finite number in [" << min << ", " << max << "], got " << text;
          return out.str();
        }
        return std::string();
      },
      name.str());
}

}  // namespace palpable::tools
