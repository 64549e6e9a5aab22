// Receiver observations and fixes as the stream formats of io see them: the neutral RTCM epoch,
// the RTCM station of a receiver, NMEA text of a fix.
#pragma once

#include <Eigen/Core>

#include <string>

#include "skytrace/io/rtcm3.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {

// The tracked signals of an epoch (pseudorange, phase, Doppler, C/N0, lock time, half-cycle flag).
[[nodiscard]] io::RtcmEpoch to_rtcm_epoch(const receiver::EpochObservations& epoch);

// The reference station of a receiver: its antenna reference point (marker + antenna height up +
// offsets) and the antenna height, for message 1006.
[[nodiscard]] io::RtcmStation rtcm_station(const Eigen::Vector3d& marker_m, const ReceiverSettings& receiver,
                                           int station_id = 0);

}  // namespace skytrace::sim
