// GLONASS L1OF as transmitted (ICD GLONASS, edition 5.1): the 511-chip ranging code, and the
// navigation strings built from the broadcast records (ephemeris strings 1-4, time string 5) with
// their Hamming code, in relative bi-binary code with the time mark, so that a software receiver
// decodes the records that nav.rnx holds.
#pragma once

#include <array>
#include <cstdint>

#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::baseband {

inline constexpr int kGlonassCodeLength = 511;
inline constexpr int kGlonassStringBits = 85;
inline constexpr int kGlonassSymbolsPerString = 200;  // 10 ms symbols: 170 of data, 30 of the time mark
inline constexpr double kGlonassBandCentre_hz = 1602.0e6;
inline constexpr double kGlonassChannelStep_hz = 562.5e3;

// The ranging code (G(X) = 1 + X^5 + X^9, all ones at the start, read at the 7th stage) as chips
// +1 / -1 (logic 0 is +1).
[[nodiscard]] const std::array<std::int8_t, kGlonassCodeLength>& glonass_ranging_code();

// What every satellite's string 5 carries: the time scale corrections and the date.
struct GnavCommon {
  double tau_c_s = 0.0;    // GLONASS time to UTC(SU) (RINEX GLUT)
  double tau_gps_s = 0.0;  // GLONASS time to GPS time, fractional part (RINEX GLGP)
};

// The 85 bits of string `string_number` (1-15) of the frame that starts at `frame_start_mt`
// seconds of the Moscow day (MT = UTC(SU) + 3 h, a multiple of 30), on day `day_in_four_years`
// (1-1461, N_T) of four-year interval `four_year_interval` (N_4, 1 for 1996-1999), from `record`.
// Index 0 is bit 85 (the idle bit, sent first), index 84 bit 1; bits 8-1 are the Hamming code.
// Strings 6-15 carry empty almanac slots (n_A = 0): the almanac is not simulated.
[[nodiscard]] std::array<std::uint8_t, kGlonassStringBits> gnav_string(const orbits::GlonassEphemeris& record,
                                                                      const GnavCommon& common, int string_number,
                                                                      int frame_start_mt, int day_in_four_years,
                                                                      int four_year_interval);

// The Hamming check bits 1-8 of a string whose bits 9-85 are set (ICD 4.7): index as gnav_string.
void set_gnav_hamming(std::array<std::uint8_t, kGlonassStringBits>& bits);

// The 200 symbols (+1 / -1, 10 ms each) of a string: its bits in relative code, each as a meander
// pair, then the 30-symbol time mark.
[[nodiscard]] std::array<std::int8_t, kGlonassSymbolsPerString> gnav_symbols(
    const std::array<std::uint8_t, kGlonassStringBits>& bits);

}  // namespace skytrace::baseband
