// NMEA 0183 v4.11 sentences from a position fix, as a multi-constellation receiver sends them:
// GGA, RMC, GSA (one per system, with the system ID), GSV (talker per constellation, signal ID),
// VTG, ZDA and GST. Times are UTC (GPST minus the leap seconds of core/time).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/geoid.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/positioning/spp.hpp"

namespace skytrace::io {

// Which sentences an epoch carries (in this order: GGA, GSA..., GSV..., RMC, VTG, ZDA, GST).
struct NmeaSettings {
  bool gga = true;
  bool gsa = true;
  bool gsv = true;
  bool rmc = true;
  bool vtg = true;
  bool zda = true;
  bool gst = true;
  // GGA's altitude above mean sea level and geoid separation come from this model (nullptr:
  // ellipsoidal height, separation 0); the process's default_geoid() unless set.
  const GeoidGrid* geoid = default_geoid();
};

// The checksum of a sentence body (the characters between '$' and '*'): two upper-case hex digits.
[[nodiscard]] std::string nmea_checksum(std::string_view body);
// "$" + body + "*" + checksum + "\r\n".
[[nodiscard]] std::string nmea_sentence(std::string_view body);
// Whether a line ("$...*hh", with or without CR LF) carries a correct checksum.
[[nodiscard]] bool nmea_checksum_valid(std::string_view line);

// NMEA 4.11 system ID (GSA/GSV field): GPS 1, GLONASS 2, Galileo 3, BeiDou 4, QZSS 5, NavIC 6;
// SBAS reports under GPS (1).
[[nodiscard]] int nmea_system_id(GnssSystem system);
// Talker of a constellation's GSV: GP (GPS and SBAS), GL, GA, GB, GQ, GI.
[[nodiscard]] std::string_view nmea_talker(GnssSystem system);
// Satellite ID as NMEA 4.11 numbers it: GPS 1-32, SBAS 33-64 (PRN - 87), GLONASS 65-96 (slot + 64),
// Galileo 1-36, BeiDou 1-63, QZSS 1-10 (PRN - 192), NavIC 1-14. nullopt when not representable.
[[nodiscard]] std::optional<int> nmea_satellite_id(const SatelliteId& satellite);
// Signal ID of the GSV sentence (NMEA 4.11, one hex digit 1-F); 0 ("all signals") when the
// standard has no ID for the signal (e.g. GPS L1C, GLONASS CDMA signals).
[[nodiscard]] int nmea_signal_id(const Signal& signal);

// All sentences of one epoch, each "$...*hh\r\n". A fix of type kNone gives the no-fix forms
// (GGA quality 0, RMC status V, GSA mode 1) with the time of the epoch tag.
[[nodiscard]] std::vector<std::string> nmea_epoch(const positioning::PositionFix& fix,
                                                  const NmeaSettings& settings = {});

}  // namespace skytrace::io
