// Which satellite flies under which PRN on a given date, its block (generation), and which
// signals it broadcasts. A receiver records only what is transmitted: GPS L2C only on IIR-M and
// later, L5 only on IIF and III, L1C only on III; BeiDou B2I only on BDS-2, B1C/B2a only on BDS-3
// MEO/IGSO; and so on. The data is a built-in, dated, read-only table (see docs/satellites.md for
// its sources, its known gaps and how to update it).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace {

// Satellite generations that differ in the signals they broadcast. Names follow the block
// names of the IGS satellite metadata SINEX file where one exists (block_name()).
enum class SatelliteBlock : std::uint8_t {
  kUnknown,
  kGpsIIA,
  kGpsIIRA,
  kGpsIIRB,
  kGpsIIRM,
  kGpsIIF,
  kGpsIIIA,
  kGlonassM,
  kGlonassMPlus,  // GLONASS-M with an L3 CDMA payload (serials 755..761, IGS SVN R855..R861)
  kGlonassK1,
  kGlonassK2,
  kGalileoIov,    // IGS "GAL-1"
  kGalileoFoc,    // IGS "GAL-2"
  kBds2Geo,
  kBds2Igso,
  kBds2Meo,
  kBds3Geo,
  kBds3Igso,
  kBds3Meo,
  kBds3SIgso,     // BDS-3 experimental (demonstration) satellites
  kBds3SMeo,
  kQzs1,
  kQzs2Igso,
  kQzs2Geo,
  kQzs2A,         // QZS-1R
  kSbasGeo,
};

// "GPS-IIF", "GLO-K1", "BDS-3M", "QZS-2I", ...
[[nodiscard]] std::string_view block_name(SatelliteBlock block);

// One satellite occupying one PRN (GLONASS: slot) over one time span.
struct SatelliteInfo {
  SatelliteId id;
  int svn = 0;  // IGS space vehicle number without the letter (G063 -> 63); 0 when no source gives it
  SatelliteBlock block_id = SatelliteBlock::kUnknown;
  std::string block;    // block_name(block_id)
  GnssTime valid_from;  // first instant of the assignment
  GnssTime valid_until; // first instant after the assignment (exclusive); far future when open
  bool open_ended = false;  // still assigned at the time the table was compiled
};

// Whether a satellite broadcasts a signal at a date.
enum class SignalAvailability : std::uint8_t {
  kNo,         // the satellite has no such signal (or it is known to be switched off)
  kYes,        // broadcast at that date; a receiver able to track it records it
  kUncertain,  // a payload may exist but the broadcast is not guaranteed: test or demonstration
               // signals, signals switched on and off, or a satellite/date the table does not know
};

// The catalogued satellite using `id` at time `t`, or nullopt when the table has no row for it
// (unknown satellite, gap between two known assignments, or a system without rows such as NavIC).
[[nodiscard]] std::optional<SatelliteInfo> satellite_info(const SatelliteId& id, const GnssTime& t);

// All catalogued satellites of one system in service at `t`, ordered by satellite number.
[[nodiscard]] std::vector<SatelliteInfo> catalogued_satellites(GnssSystem system, const GnssTime& t);

// Signal availability per block. For a satellite/date not in the table a conservative default per
// system applies: legacy signals that every satellite of the system broadcasts are kYes, the rest
// kUncertain (GPS: L1 C/A and P(Y) only; BeiDou by PRN range: C01-C18 BDS-2 signals, C19-C58
// BDS-3 MEO/IGSO signals, C59-C63 BDS-3 GEO signals; Galileo: every Galileo signal; GLONASS: FDMA
// G1 C/A and G1/G2 P; QZSS: L1C and L5; NavIC: L5 and S; SBAS: L1 C/A). A signal of another system,
// or one missing from the signal catalogue, is kNo.
[[nodiscard]] SignalAvailability signal_availability(const SatelliteId& id, const Signal& signal,
                                                     const GnssTime& t);

// True when the satellite broadcasts the signal at that date (signal_availability() == kYes).
[[nodiscard]] bool transmits(const SatelliteId& id, const Signal& signal, const GnssTime& t);

}  // namespace skytrace
