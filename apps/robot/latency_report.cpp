#include "latency_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace skytrace::live {

LatencySummary summarize_latencies(std::vector<double> latencies_s) {
  LatencySummary out;
  if (latencies_s.empty()) return out;
  std::sort(latencies_s.begin(), latencies_s.end());
  const auto quantile_ms = [&](double q) {
    const auto index = static_cast<size_t>(std::ceil(q * static_cast<double>(latencies_s.size()))) - 1;
    return 1e3 * latencies_s[std::min(index, latencies_s.size() - 1)];
  };
  double sum_s = 0.0;
  for (double s : latencies_s) sum_s += s;
  out.epochs = latencies_s.size();
  out.mean_ms = 1e3 * sum_s / static_cast<double>(latencies_s.size());
  out.p50_ms = quantile_ms(0.5);
  out.p90_ms = quantile_ms(0.9);
  out.p99_ms = quantile_ms(0.99);
  out.max_ms = 1e3 * latencies_s.back();
  return out;
}

std::string latency_json(const std::string& scenario, double rate_hz, const LatencySummary& s) {
  return fmt::format(
      "{{\"scenario\": \"{}\", \"rate_hz\": {}, \"epochs\": {}, \"mean_ms\": {:.4f}, \"p50_ms\": {:.4f}, "
      "\"p90_ms\": {:.4f}, \"p99_ms\": {:.4f}, \"max_ms\": {:.4f}}}\n",
      scenario, rate_hz, s.epochs, s.mean_ms, s.p50_ms, s.p90_ms, s.p99_ms, s.max_ms);
}

}  // namespace skytrace::live
