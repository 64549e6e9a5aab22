#include "skytrace/core/error_histogram.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace skytrace {

void ErrorHistogram::add(double error_m) {
  if (!std::isfinite(error_m)) return;
  error_m = std::abs(error_m);
  if (bins_.empty()) bins_.assign(kBins, 0);
  size_t bin = 0;
  if (error_m > kSmallest_m) {
    const double index = std::floor(std::log10(error_m / kSmallest_m) * kBinsPerDecade);
    bin = static_cast<size_t>(std::min(index, static_cast<double>(kBins - 1)));
  }
  ++bins_[bin];
  ++count_;
  max_m_ = std::max(max_m_, error_m);
}

double ErrorHistogram::quantile_m(double q) const {
  if (count_ == 0) return std::numeric_limits<double>::quiet_NaN();
  const double wanted = q * static_cast<double>(count_);
  std::uint64_t below = 0;
  for (size_t i = 0; i < bins_.size(); ++i) {
    below += bins_[i];
    if (static_cast<double>(below) >= wanted) {
      return kSmallest_m * std::pow(10.0, (static_cast<double>(i) + 0.5) / kBinsPerDecade);
    }
  }
  return bin_upper_m(kBins - 1);
}

double ErrorHistogram::bin_upper_m(size_t bin) {
  return kSmallest_m * std::pow(10.0, static_cast<double>(bin + 1) / kBinsPerDecade);
}

}  // namespace skytrace
