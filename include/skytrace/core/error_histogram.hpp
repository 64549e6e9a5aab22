// Distribution of position errors in bounded memory: percentiles of every epoch of a run, however
// long, from log-spaced bins (100 per decade, each 2.3 % wide, 0.1 mm to 100 km).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace skytrace {

class ErrorHistogram {
 public:
  static constexpr size_t kBins = 900;
  static constexpr double kBinsPerDecade = 100.0;
  static constexpr double kSmallest_m = 1e-4;  // errors below fall in bin 0; above 100 km in the last

  // Non-finite errors are not counted.
  void add(double error_m);
  [[nodiscard]] std::uint64_t count() const { return count_; }
  [[nodiscard]] double max_m() const { return max_m_; }
  // The error below which a fraction q of the counted errors lie (the bin's geometric centre); NaN
  // when nothing was counted.
  [[nodiscard]] double quantile_m(double q) const;
  // Per bin: how many errors fell in it (empty until the first error), and the bin's upper edge.
  [[nodiscard]] const std::vector<std::uint32_t>& bins() const { return bins_; }
  [[nodiscard]] static double bin_upper_m(size_t bin);

 private:
  std::vector<std::uint32_t> bins_;
  std::uint64_t count_ = 0;
  double max_m_ = 0.0;
};

}  // namespace skytrace
