#pragma once
// The median of repeated timings, the one figure the benchmarks and `palpable sweep` report.
#include <vector>

namespace palpable::tools {

// The middle value of `values` (taken by value and sorted); for an even count, the mean of the
// middle two. Throws std::invalid_argument for no values (a median of nothing is a bug).
double median(std::vector<double> values);

}  // namespace palpable::tools
