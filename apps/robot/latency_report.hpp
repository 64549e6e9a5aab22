// The per-epoch latency summary the live nodes write on exit (`latency_report`): C++17, shared by
// the ROS 1 and ROS 2 nodes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace skytrace::live {

struct LatencySummary {
  size_t epochs = 0;
  double mean_ms = 0.0, p50_ms = 0.0, p90_ms = 0.0, p99_ms = 0.0, max_ms = 0.0;
};

// The epochs' step-and-publish times in memory that does not grow with the run (a node runs for
// days): a histogram of logarithmic bins 0.5 % wide from 0.1 us to 100 s, with the exact count,
// sum and maximum. Quantiles (nearest rank) are their bin's geometric centre, within 0.25 %.
class LatencyRecorder {
 public:
  LatencyRecorder();
  void add(double seconds);
  [[nodiscard]] bool empty() const { return count_ == 0; }
  [[nodiscard]] LatencySummary summary() const;  // zero epochs give zeros

 private:
  std::vector<std::uint64_t> bins_;
  std::uint64_t count_ = 0;
  double sum_s_ = 0.0, max_s_ = 0.0;
};

// One line of JSON: scenario, rate, epochs, mean/p50/p90/p99/max in ms.
[[nodiscard]] std::string latency_json(const std::string& scenario, double rate_hz, const LatencySummary& summary);

}  // namespace skytrace::live
