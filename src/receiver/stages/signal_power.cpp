#include "skytrace/receiver/stages/signal_power.hpp"

#include <cmath>

#include "skytrace/core/satellite_catalog.hpp"

namespace skytrace::receiver::stages {

namespace {
std::int64_t gpst_day(const GnssTime& t) { return static_cast<std::int64_t>(std::floor(t.gpst_seconds_approx() / 86400.0)); }
}  // namespace

bool SatelliteSignals::transmitted(const SatelliteId& sat, const Signal& signal, const GnssTime& t) {
  const std::int64_t day = gpst_day(t);
  auto [it, inserted] = transmits_.try_emplace(std::make_pair(sat, signal), day, false);
  if (inserted || it->second.first != day) it->second = {day, transmits(sat, signal, t)};
  return it->second.second;
}

double SatelliteSignals::power_offset_db(const SatelliteId& sat, const Signal& signal, const GnssTime& t) {
  const std::int64_t day = gpst_day(t);
  auto [it, inserted] = power_offset_db_.try_emplace(std::make_pair(sat, signal), day, 0.0);
  if (inserted || it->second.first != day) {
    const auto info = satellite_info(sat, t);
    it->second = {day, info ? block_power_offset_db(info->block_id, signal) : 0.0};
  }
  return it->second.second;
}

}  // namespace skytrace::receiver::stages
