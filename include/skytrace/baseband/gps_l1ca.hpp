// GPS L1 C/A as transmitted (IS-GPS-200): the Gold codes and the LNAV navigation message built from
// broadcast ephemeris records, bit for bit, so that a software receiver decodes the records that
// nav.rnx holds.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::baseband {

inline constexpr int kCaCodeLength = 1023;
inline constexpr double kCaChipRate_hz = 1.023e6;
inline constexpr int kLnavBitsPerSubframe = 300;
inline constexpr double kLnavBitPeriod_s = 0.02;

// The C/A code of PRN 1-63 (G2 delays of IS-GPS-200 Table 3-Ia and 3-Ib) as chips +1 / -1 (logic 0
// is +1, so that the modulo-2 sum of code and data is their product).
[[nodiscard]] Result<std::array<std::int8_t, kCaCodeLength>> gps_ca_code(int prn);

// One 30-bit word from its 24 data bits (d1 the MSB) and the last two bits of the previous word:
// the 24 bits complemented when D30* is set, then the six parity bits (IS-GPS-200 Table 20-XIV).
[[nodiscard]] std::uint32_t lnav_word(std::uint32_t data24, bool d29_prev, bool d30_prev);
// Whether a 30-bit word's parity holds with the previous word's D29* and D30* (for tests and readers).
[[nodiscard]] bool lnav_parity_ok(std::uint32_t word30, bool d29_prev, bool d30_prev);

// The navigation data common to every satellite: ionosphere (subframe 4 page 18) and the UTC
// parameters, from the navigation files' header.
struct LnavCommon {
  std::optional<orbits::KlobucharCoefficients> ionosphere;
  double utc_a0_s = 0.0, utc_a1_s_per_s = 0.0;
  int utc_tot_s = 0, utc_week = 0;  // reference time of the UTC parameters
  int leap_seconds = 18, leap_seconds_future = 18, leap_week = 0, leap_day = 1;
  // The almanac (subframe 5 pages 1-24, subframe 4 pages 2-5 and 7-10): a record per PRN, taken from
  // the broadcast ephemerides (nullptr where the satellite has none).
  std::array<const orbits::KeplerEphemeris*, 33> almanac{};
  int almanac_week = 0;  // full GPS week of toa
  int almanac_toa_s = 0;
};

// The 300 bits (0/1, first transmitted first) of the subframe that starts at GPS second of week
// `subframe_start_sow` (a multiple of 6) of week `week`, from `record` (subframes 1-3) and `common`
// (subframes 4-5, whose page follows from the time). `previous_d30` is the last bit of the
// subframe before (0 for the ones this module builds: its last word's t bits zero D29 and D30).
[[nodiscard]] std::array<std::uint8_t, kLnavBitsPerSubframe> lnav_subframe(const orbits::KeplerEphemeris& record,
                                                                           const LnavCommon& common, int week,
                                                                           int subframe_start_sow);

// The URA index (IS-GPS-200 20.3.3.3.1.3) of an accuracy in metres.
[[nodiscard]] int ura_index(double accuracy_m);

}  // namespace skytrace::baseband
