// Stage 3 of the observation model: signal power. Which of the listed signals a satellite
// transmits, the power its block delivers, and the C/N0 of each signal from the link budget
// (link_budget.hpp: satellite power at the true range and off-boresight angle, the receiver
// antenna's gain, losses, noise density, vegetation) plus the multipath change of prompt power.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <unordered_map>
#include <utility>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/receiver/link_budget.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/receiver/stages/signal_key.hpp"

namespace skytrace::receiver::stages {

// What a satellite transmits (core::transmits: GPS L5 only from Block IIF on, no B2I from
// BeiDou-3, ...), its block's power offset (block_power_offset_db) and the code offset its records
// do not broadcast (block_code_bias_m), cached per GPST day.
class SatelliteSignals {
 public:
  struct Facts {
    std::int64_t gpst_day = 0;  // the day they hold for
    bool transmitted = false;
    double power_offset_db = 0.0;
    double code_bias_m = 0.0;
  };
  // Both at once (one lookup), kept per GPST day; the reference holds until the next call.
  [[nodiscard]] const Facts& facts(const SatelliteId& sat, const Signal& signal, const GnssTime& t);

 private:
  std::unordered_map<SignalKey, Facts, SignalKeyHash> facts_;
};

// C/N0 (dB-Hz) of a signal from a satellite (`link`: its geometry towards the receiver) seen in
// `direction`, through `attenuation_db` of vegetation, from a satellite delivering
// `power_offset_db` over its signal's row, with the multipath change of prompt power
// (MultipathErrors::power_db, 0 without multipath).
[[nodiscard]] inline double signal_cn0_dbhz(const ReceiverProfile& profile, const TrackedSignal& tracked,
                                            SatelliteLink& link, const AzimuthElevation& direction,
                                            double attenuation_db, double power_offset_db, double multipath_power_db) {
  return link_budget(profile, tracked, link, direction.elevation_deg, direction.azimuth_deg, attenuation_db,
                     power_offset_db)
             .cn0_dbhz() +
         multipath_power_db;
}

}  // namespace skytrace::receiver::stages
