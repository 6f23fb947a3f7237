#pragma once
// The median of repeated timings, the one figure the benchmarks and `palpable sweep` report.
#include <chrono>
#include <vector>

namespace palpable::tools {

// The middle value of `values` (taken by value and sorted); for an even count, the mean of the
// middle two. Throws std::invalid_argument for no values (a median of nothing is a bug).
double median(std::vector<double> values);

// Median over `repeats` of the time per call of `work` [ns]: calls are timed in batches, the batch
// doubled (up to `max_batch`) until one takes ~5 ms, so that the clock's resolution and the
// loop's overhead do not count.
template <class Work>
double median_ns_per_call(Work&& work, int repeats, int max_batch) {
  auto time_batch = [&](int batch) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < batch; ++i) work();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  int batch = 1;
  while (time_batch(batch) <= 5e-3 && batch <= max_batch) batch *= 2;
  std::vector<double> per_call;
  for (int r = 0; r < repeats; ++r) per_call.push_back(time_batch(batch) * 1e9 / batch);
  return median(std::move(per_call));
}

}  // namespace palpable::tools
