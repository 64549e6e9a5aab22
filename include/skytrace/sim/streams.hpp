// Receiver observations and fixes as the stream formats of io see them: the neutral RTCM epoch,
// the RTCM station of a receiver, the ephemerides in use; and the position engine of a receiver.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/io/nmea.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/positioning/rtk.hpp"
#include "skytrace/positioning/spp.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {

// The tracked signals of an epoch (pseudorange, phase, Doppler, C/N0, lock time, half-cycle flag).
[[nodiscard]] io::RtcmEpoch to_rtcm_epoch(const receiver::EpochObservations& epoch);

// The reference station of a receiver: its antenna reference point (marker + antenna height up +
// offsets) and the antenna height, for message 1006.
[[nodiscard]] io::RtcmStation rtcm_station(const Eigen::Vector3d& marker_m, const ReceiverSettings& receiver,
                                           int station_id = 0);

// The ephemeris records a receiver decodes for the satellites it tracks at an epoch: per signal the
// record of the signal's message (Galileo F/NAV for E5a, I/NAV for E1/E5b), else any valid one.
struct RecordsInUse {
  std::vector<const orbits::KeplerEphemeris*> kepler;
  std::vector<const orbits::GlonassEphemeris*> glonass;
};
[[nodiscard]] RecordsInUse records_in_use(const orbits::BroadcastEphemerides& ephemerides,
                                          const receiver::EpochObservations& epoch);

// One epoch of a receiver's RTCM 3 stream: MSM7 of its tracked signals and the ephemeris messages of
// `records` (the records in use at the epoch) as the stream schedules them.
[[nodiscard]] Result<std::vector<std::uint8_t>> rtcm3_epoch_bytes(io::Rtcm3Stream& stream,
                                                                  const receiver::EpochObservations& epoch,
                                                                  const RecordsInUse& records);

// The navigation engine's settings for a receiver of a scenario: its elevation mask (at least 5
// degrees), Klobuchar when the navigation data has GPS coefficients, Saastamoinen.
[[nodiscard]] positioning::SolverSettings default_solver_settings(const ReceiverSettings& receiver,
                                                                  const orbits::BroadcastEphemerides& ephemerides);

// The RTK engine's settings for a rover of a scenario (receivers[].rtk): the rover profile's `rtk`
// section, the elevation mask at least the receiver's, GLONASS ambiguities fixed only when base and
// rover are of one profile, single-point settings as default_solver_settings.
[[nodiscard]] Result<positioning::RtkSettings> rtk_settings(const Scenario& scenario, size_t rover_index,
                                                            const orbits::BroadcastEphemerides& ephemerides);
// The same for corrections from outside the scenario (an RTCM stream): GLONASS ambiguities float.
[[nodiscard]] Result<positioning::RtkSettings> rtk_settings_without_base(const ReceiverSettings& rover,
                                                                         const Scenario& scenario,
                                                                         const orbits::BroadcastEphemerides& ephemerides);

// The position engine of one receiver of a run: single point, or RTK for a rover (receivers[].rtk)
// with its base's epoch of the same instant.
class FixStage {
 public:
  FixStage(const orbits::BroadcastEphemerides& ephemerides, const ReceiverSettings& receiver,
           std::optional<positioning::RtkSettings> rtk = std::nullopt);
  [[nodiscard]] bool is_rtk_rover() const { return rtk_.has_value(); }
  // `base`: the base's epoch of this instant for an RTK rover (nullptr when it has none); ignored
  // by single point.
  [[nodiscard]] Result<positioning::PositionFix> solve(const receiver::EpochObservations& epoch,
                                                       const positioning::BaseEpoch* base = nullptr);
  // The same from the epoch's measurements (to_measurements).
  [[nodiscard]] Result<positioning::PositionFix> solve(const positioning::EpochMeasurements& measurements,
                                                       const positioning::BaseEpoch* base = nullptr);

 private:
  std::optional<positioning::SinglePointSolver> solver_;
  std::optional<positioning::RtkEngine> rtk_;
};

}  // namespace skytrace::sim
