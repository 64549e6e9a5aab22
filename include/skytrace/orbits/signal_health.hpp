// Signal health as broadcast: which signals of a satellite a navigation record declares usable,
// decoded per system and message from the health word RINEX stores in the record.
//
//   GPS LNAV (IS-GPS-200 20.3.3.3.1.4, Table 20-VIII): 6 bits; the MSB summarises the NAV data
//     (1: some or all bad, nothing is used), the 5 LSBs name the signal components that are weak,
//     dead or without data modulation. Dead components are unusable, weak ones and those without
//     data still range. Codes 28 (SV temporarily out) and 31 (more anomalies than one code can
//     say) make every signal unusable.
//   QZSS LNAV (IS-QZSS-PNT-005 4.1.2.3): one bit per signal, 1 = unhealthy: bit 5 (MSB) L1 (the
//     C/A or C/B code transmitted), bit 4 L1 C/A, bit 3 L2C, bit 2 L5, bit 1 L1C, bit 0 (LSB)
//     L1C/B. A satellite transmitting L1 C/A sets the L1C/B bit (earlier issues: the L6/LEX bit),
//     so health 1 is a fully usable L1 C/A, L2C, L5 and L1C satellite.
//   GPS and QZSS CNAV/CNAV-2 (RINEX 4; IS-GPS-200 30.3.3.1.1.2, IS-GPS-800 3.5.3.6): bit 0 L1,
//     bit 1 L2, bit 2 L5; 1 = all codes on that carrier bad.
//   Galileo (RINEX 3/4 "SV health", OS SIS ICD 5.1.9.3): bit 0 E1-B DVS, bits 1-2 E1-B HS, bit 3
//     E5a DVS, bits 4-5 E5a HS, bit 6 E5b DVS, bits 7-8 E5b HS. A component is used when its HS
//     is 0 (signal OK) and its DVS 0 (navigation data valid), as receivers and RTKLIB do; E5
//     AltBOC needs both E5a and E5b. I/NAV carries E1-B and E5b, F/NAV E5a (RINEX leaves the other
//     bits zero): a component, or E6, the record's message does not carry is judged by those it
//     does.
//   BeiDou: D1/D2 SatH1 and the CNAV1/2/3 health status, 0 = healthy, for the whole satellite.
//   NavIC: 0 = healthy, for the whole satellite.
//   GLONASS FDMA: B_n (RINEX "health", MSB of B_n) and, from RINEX 3.05, l_n (bit 2 of the
//     health flags of the fourth line); 1 = unhealthy, for every FDMA signal.
//   SBAS (RINEX 3 health): bits 0-3 MT17 health (bit 0 set = ranging off), bit 4 = MT17 health
//     unavailable (bits 0-3 then say nothing).
// A signal the word says nothing about (QZSS L6 and L5S, GPS/QZSS CNAV L6) counts as healthy.
#pragma once

#include <span>
#include <string>

#include "skytrace/core/signal.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::orbits {

// The two parts of a GPS LNAV health word.
struct GpsLnavHealth {
  bool nav_data_bad = false;  // MSB: some or all NAV data bad
  int signal_code = 0;        // 5 LSBs: Table 20-VIII code, 0 = all signals OK
};
[[nodiscard]] GpsLnavHealth decode_gps_lnav_health(int health);
// Whether a GPS signal is usable under a Table 20-VIII code (the MSB not considered).
[[nodiscard]] bool gps_lnav_signal_usable(int signal_code, const Signal& signal);

// Whether the record declares `signal` (of the record's system) usable.
[[nodiscard]] bool signal_healthy(const KeplerEphemeris& eph, const Signal& signal);
[[nodiscard]] bool signal_healthy(const GlonassEphemeris& eph, const Signal& signal);
[[nodiscard]] bool signal_healthy(const SbasEphemeris& eph, const Signal& signal);

// Whether a record may serve orbit and clock for a receiver that wants `wanted`: one of the wanted
// signals of the record's system is healthy; when `wanted` holds none of its system (a caller
// without signals in mind), one of the system's catalogued signals is.
[[nodiscard]] bool record_usable(const KeplerEphemeris& eph, std::span<const Signal> wanted = {});
[[nodiscard]] bool record_usable(const GlonassEphemeris& eph, std::span<const Signal> wanted = {});
[[nodiscard]] bool record_usable(const SbasEphemeris& eph, std::span<const Signal> wanted = {});

// Why a record makes a signal unusable, for truth.csv and messages, e.g. "GPS LNAV health 23 (L1
// signals dead)" or "Galileo health 0x30 (E5a HS 3)".
[[nodiscard]] std::string health_description(const KeplerEphemeris& eph);
[[nodiscard]] std::string health_description(const GlonassEphemeris& eph);
[[nodiscard]] std::string health_description(const SbasEphemeris& eph);

}  // namespace skytrace::orbits
