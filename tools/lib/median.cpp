#include "tools/lib/median.hpp"

#include <algorithm>
#include <stdexcept>

namespace palpable::tools {

double median(std::vector<double> values) {
  if (values.empty()) throw std::invalid_argument("median of no values");
  const std::size_t n = values.size();
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(values.begin(), middle, values.end());
  if (n % 2 == 1) return *middle;
  // The lower middle value is the largest of those before `middle`.
  const double lower = *std::max_element(values.begin(), middle);
  return 0.5 * (lower + *middle);
}

}  // namespace palpable::tools
