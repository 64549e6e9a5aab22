// The per-epoch latency summary the live nodes write on exit (`latency_report`): C++17, shared by
// the ROS 1 and ROS 2 nodes.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace skytrace::live {

struct LatencySummary {
  size_t epochs = 0;
  double mean_ms = 0.0, p50_ms = 0.0, p90_ms = 0.0, p99_ms = 0.0, max_ms = 0.0;
};
// Quantiles of the epochs' step-and-publish times (nearest rank); zero epochs give zeros.
[[nodiscard]] LatencySummary summarize_latencies(std::vector<double> latencies_s);
// One line of JSON: scenario, rate, epochs, mean/p50/p90/p99/max in ms.
[[nodiscard]] std::string latency_json(const std::string& scenario, double rate_hz, const LatencySummary& summary);

}  // namespace skytrace::live
