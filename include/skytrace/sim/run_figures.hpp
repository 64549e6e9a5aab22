// The figures of a run per receiver, for summary.json and the tables of sweeps: solution types,
// availability, time to first fix, fix error percentiles against the truth, and the share of tracked
// satellites received by line of sight, with multipath or only by NLOS paths. Memory stays bounded
// (error histograms), however long the run.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "skytrace/core/error_histogram.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/sim/sinks.hpp"

namespace skytrace::sim {

class RunFigures final : public EpochSink {
 public:
  explicit RunFigures(const std::vector<SinkReceiver>& receivers);
  Status add(const SinkEpoch& epoch) override;
  Status finish() override { return Ok{}; }

  // One object per receiver (see docs/outputs.md, summary.json "receivers").
  [[nodiscard]] nlohmann::json to_json() const;

 private:
  struct Receiver {
    std::string name;
    std::int64_t epochs = 0;
    std::optional<GnssTime> first_epoch;
    std::array<std::int64_t, 6> epochs_per_fix_type{};  // positioning::FixType order
    double first_fix_s =  // seconds since the first epoch
        std::numeric_limits<double>::quiet_NaN();
    double first_rtk_fixed_s = std::numeric_limits<double>::quiet_NaN();
    ErrorHistogram horizontal_error, vertical_error;
    std::int64_t fixes_with_error = 0;
    double satellites_used_sum = 0.0;
    std::int64_t tracked = 0, line_of_sight = 0, multipath = 0, nlos = 0, blocked = 0, attenuated = 0;
    std::int64_t signals = 0;
  };
  std::vector<Receiver> receivers_;
};

}  // namespace skytrace::sim
