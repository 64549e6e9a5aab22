#include "skytrace/receiver/stages/signal_power.hpp"

#include <cmath>

#include "skytrace/core/satellite_catalog.hpp"
#include "skytrace/receiver/stages/measurement_errors.hpp"

namespace skytrace::receiver::stages {

namespace {
std::int64_t gpst_day(const GnssTime& t) { return static_cast<std::int64_t>(std::floor(t.gpst_seconds_approx() / 86400.0)); }
}  // namespace

const SatelliteSignals::Facts& SatelliteSignals::facts(const SatelliteId& sat, const Signal& signal, const GnssTime& t) {
  const std::int64_t day = gpst_day(t);
  auto [it, inserted] = facts_.try_emplace(std::make_pair(sat, signal));
  Facts& f = it->second;
  if (inserted || f.gpst_day != day) {
    f.gpst_day = day;
    f.transmitted = transmits(sat, signal, t);
    const auto info = satellite_info(sat, t);
    f.power_offset_db = info ? block_power_offset_db(info->block_id, signal) : 0.0;
    f.code_bias_m = info ? block_code_bias_m(info->block_id, signal) : 0.0;
  }
  return f;
}

}  // namespace skytrace::receiver::stages
