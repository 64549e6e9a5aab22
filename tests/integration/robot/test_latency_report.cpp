// The live nodes' latency summary in bounded memory: its quantiles against the nearest rank of the
// sorted values, its memory the same after a million epochs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "latency_report.hpp"

namespace skytrace::live {
namespace {

TEST(LatencyRecorder, QuantilesAreTheNearestRankWithinABinAndMemoryStaysBounded) {
  LatencyRecorder recorder;
  EXPECT_TRUE(recorder.empty());
  EXPECT_EQ(recorder.summary().epochs, 0U);
  std::mt19937_64 rng(5);
  std::lognormal_distribution<double> latency(std::log(2e-4), 0.8);  // ~0.2 ms, a long tail
  std::vector<double> values;
  for (int i = 0; i < 200'000; ++i) {
    values.push_back(latency(rng));
    recorder.add(values.back());
  }
  recorder.add(std::nan(""));  // ignored
  recorder.add(-1.0);
  std::sort(values.begin(), values.end());
  const auto exact_ms = [&](double q) {
    return 1e3 * values[static_cast<size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1];
  };
  const LatencySummary s = recorder.summary();
  EXPECT_EQ(s.epochs, values.size());
  EXPECT_NEAR(s.p50_ms, exact_ms(0.5), 0.005 * exact_ms(0.5));
  EXPECT_NEAR(s.p90_ms, exact_ms(0.9), 0.005 * exact_ms(0.9));
  EXPECT_NEAR(s.p99_ms, exact_ms(0.99), 0.005 * exact_ms(0.99));
  EXPECT_DOUBLE_EQ(s.max_ms, 1e3 * values.back());
  double sum = 0.0;
  for (double v : values) sum += v;
  EXPECT_NEAR(s.mean_ms, 1e3 * sum / static_cast<double>(values.size()), 1e-9);
  // Beyond the bins' range: clamped into the first and last bin, the maximum exact.
  LatencyRecorder extremes;
  extremes.add(0.0);
  extremes.add(1e-9);
  extremes.add(500.0);
  EXPECT_DOUBLE_EQ(extremes.summary().max_ms, 500e3);
  EXPECT_LT(extremes.summary().p50_ms, 1e-3);
}

}  // namespace
}  // namespace skytrace::live
