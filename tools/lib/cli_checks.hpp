#pragma once
// CLI11 checks for numeric options: CLI::Range lets "nan" through (NaN compares false against
// both bounds), so the benchmarks' real-valued options use this instead. CLI11 names the option
// in its message ("--warmup: ...") and exits with its usage error.
#include <CLI/CLI.hpp>

namespace palpable::tools {

// A finite number x with min <= x <= max. For "positive" pass std::numeric_limits<double>::min().
CLI::Validator finite_range(double min, double max);

}  // namespace palpable::tools
