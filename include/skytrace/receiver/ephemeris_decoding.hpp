// When a receiver that outputs a satellite only once it holds a broadcast ephemeris for it (profile
// key tracking.output_requires_ephemeris) comes to hold one.
#pragma once

#include <optional>
#include <vector>

#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/broadcast.hpp"

namespace skytrace::receiver {

// A satellite acquired at `acquired` (after none of its signals was tracked) is held from the
// earliest, over its records usable for `signals` (orbits::record_usable) still valid at or after
// `acquired`, of
//
//     max(acquired + decode time of the record's message, transmission time of the record)
//
// A receiver cannot use a record before it was transmitted; one transmitted before `acquired` is
// being repeated and takes the decode time (orbits::ephemeris_decode_time_s: LNAV 30 s, I/NAV
// 30 s, ...). With one message per satellite this is max(acquired + decode time, T0), T0 the
// earliest transmission time; with merged broadcast files T0 is usually before `acquired`.
// Records count only when one of `signals` (those the receiver tracks of the satellite) carries
// their message (orbits::signal_carries); when none does (the file was written by a receiver
// decoding another message), every record counts with its decode time alone. A transmission time
// the file does not give, or one after the end of the record's validity (impossible, so the field
// is wrong: e.g. GLONASS t_k in Moscow time), falls back to the decode time.
// nullopt when no record is valid at or after `acquired` (nothing to decode).
// The generator holds every satellite tracked at the run's first epoch at once (a receiver that
// ran before), and keeps holding a satellite once held (re-acquisition keeps the ephemeris).
[[nodiscard]] std::optional<GnssTime> ephemeris_held_from(const orbits::BroadcastEphemerides& ephemerides,
                                                          const SatelliteId& satellite, const GnssTime& acquired,
                                                          const std::vector<Signal>& signals);

}  // namespace skytrace::receiver
