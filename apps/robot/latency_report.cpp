#include "latency_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace skytrace::live {
namespace {

constexpr double kLowest_s = 1e-7;
constexpr double kHighest_s = 100.0;
constexpr double kBinRatio = 1.005;
const double kLogRatio = std::log(kBinRatio);
const auto kBins = static_cast<size_t>(std::ceil(std::log(kHighest_s / kLowest_s) / std::log(kBinRatio))) + 1;

size_t bin_of(double seconds) {
  if (!(seconds > kLowest_s)) return 0;
  return std::min(kBins - 1, static_cast<size_t>(std::log(seconds / kLowest_s) / kLogRatio));
}
// The geometric centre of bin k: [kLowest * r^k, kLowest * r^(k+1)).
double centre_of(size_t bin) { return kLowest_s * std::exp((static_cast<double>(bin) + 0.5) * kLogRatio); }

}  // namespace

LatencyRecorder::LatencyRecorder() : bins_(kBins, 0) {}

void LatencyRecorder::add(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return;
  ++bins_[bin_of(seconds)];
  ++count_;
  sum_s_ += seconds;
  max_s_ = std::max(max_s_, seconds);
}

LatencySummary LatencyRecorder::summary() const {
  LatencySummary out;
  if (count_ == 0) return out;
  const auto quantile_ms = [&](double q) {
    const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_))));
    std::uint64_t seen = 0;
    for (size_t k = 0; k < bins_.size(); ++k) {
      seen += bins_[k];
      if (seen >= rank) return 1e3 * std::min(centre_of(k), max_s_);
    }
    return 1e3 * max_s_;
  };
  out.epochs = static_cast<size_t>(count_);
  out.mean_ms = 1e3 * sum_s_ / static_cast<double>(count_);
  out.p50_ms = quantile_ms(0.5);
  out.p90_ms = quantile_ms(0.9);
  out.p99_ms = quantile_ms(0.99);
  out.max_ms = 1e3 * max_s_;
  return out;
}

std::string latency_json(const std::string& scenario, double rate_hz, const LatencySummary& s) {
  return fmt::format(
      "{{\"scenario\": \"{}\", \"rate_hz\": {}, \"epochs\": {}, \"mean_ms\": {:.4f}, \"p50_ms\": {:.4f}, "
      "\"p90_ms\": {:.4f}, \"p99_ms\": {:.4f}, \"max_ms\": {:.4f}}}\n",
      scenario, rate_hz, s.epochs, s.mean_ms, s.p50_ms, s.p90_ms, s.p99_ms, s.max_ms);
}

}  // namespace skytrace::live
