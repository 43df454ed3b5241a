#pragma once

// Quantiles and means of timing samples, for the benchmark programs that print tables.

#include <algorithm>
#include <vector>

namespace tangent::bench {

/// The p-quantile (0 ≤ p < 1) of a sample (sorted copy; the nearest rank below).
inline double Quantile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

inline double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

}  // namespace tangent::bench
