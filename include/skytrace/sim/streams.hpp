// Receiver observations and fixes as the stream formats of io see them: the neutral RTCM epoch,
// the RTCM station of a receiver, NMEA text of a fix.
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

// The navigation engine's settings for a receiver of a scenario: its elevation mask (at least 5
// degrees), Klobuchar when the navigation data has GPS coefficients, Saastamoinen.
[[nodiscard]] positioning::SolverSettings default_solver_settings(const ReceiverSettings& receiver,
                                                                  const orbits::BroadcastEphemerides& ephemerides);

// The RTK engine's settings for a rover of a scenario (receivers[].rtk): the rover profile's `rtk`
// section, the elevation mask at least the receiver's, GLONASS ambiguities fixed only when base and
// rover are of one profile, single-point settings as default_solver_settings.
[[nodiscard]] Result<positioning::RtkSettings> rtk_settings(const Scenario& scenario, size_t rover_index,
                                                            const orbits::BroadcastEphemerides& ephemerides);

// The stream outputs of one receiver of `skytrace run`: the RTCM 3 stream a reference receiver
// would send (obs.rtcm3), and the position engine's fixes as NMEA sentences (fix.nmea) and as CSV
// (fix.csv), built epoch by epoch and written at the end.
class RunStreams {
 public:
  RunStreams(const orbits::BroadcastEphemerides& ephemerides, const ReceiverSettings& receiver,
             const Eigen::Vector3d& marker_m, bool rtcm3, bool nmea, bool fix_csv = false,
             std::optional<positioning::RtkSettings> rtk = std::nullopt);
  // An RTK rover's fix waits for its base's epoch: add_base (or add_base(nullptr)) completes it.
  [[nodiscard]] Status add(const receiver::EpochObservations& epoch);
  [[nodiscard]] bool is_rtk_rover() const { return rtk_.has_value(); }
  [[nodiscard]] Status add_base(const positioning::BaseEpoch* base);
  // Writes the files asked for (atomically) into `dir`; `suffix` goes before the extension.
  [[nodiscard]] Status write(const std::filesystem::path& dir, const std::string& suffix = "") const;
  [[nodiscard]] const std::vector<std::uint8_t>& rtcm3_bytes() const { return rtcm_bytes_; }
  [[nodiscard]] const std::string& nmea_text() const { return nmea_text_; }

 private:
  const orbits::BroadcastEphemerides& ephemerides_;
  std::optional<io::Rtcm3Stream> rtcm_;
  std::optional<positioning::SinglePointSolver> solver_;
  std::optional<positioning::RtkEngine> rtk_;
  std::optional<positioning::EpochMeasurements> pending_;  // the rover's epoch awaiting its base
  [[nodiscard]] Status emit(const positioning::PositionFix& fix);
  std::vector<std::uint8_t> rtcm_bytes_;
  std::string nmea_text_;
  bool nmea_ = false;
  bool fix_csv_ = false;
  std::string fix_text_;
};

}  // namespace skytrace::sim
