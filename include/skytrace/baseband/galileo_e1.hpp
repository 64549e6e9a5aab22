// Galileo E1 OS as transmitted (Galileo OS SIS ICD Issue 2.1): the E1-B (data) and E1-C (pilot)
// memory codes, E1-C's secondary code, the CBOC(6,1,1/11) waveform, and the I/NAV message of E1-B
// built from broadcast records: words in nominal pages with their CRC, convolutional code and
// interleaving, so that a software receiver decodes the records that nav.rnx holds.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::baseband {

inline constexpr int kE1ChipsPerCode = 4092;   // 1.023 Mchip/s
inline constexpr int kE1CodePeriod_ms = 4;     // one I/NAV symbol per code period
inline constexpr int kE1SubchipsPerChip = 12;  // BOC(6,1)'s half periods
inline constexpr double kE1Carrier_hz = 1575.42e6;
inline constexpr int kInavSymbolsPerPagePart = 250;  // 1 s at 250 symbols/s
inline constexpr int kInavWordBits = 128;

// The primary code of PRN 1-50 (Annex C), E1-B or E1-C (`pilot`), as chips +1 / -1 (logic 0 is +1).
[[nodiscard]] Result<std::array<std::int8_t, kE1ChipsPerCode>> galileo_e1_primary_code(int prn,
                                                                                       bool pilot);
// E1-C's secondary code CS25_1: one chip per 4 ms code period, +1 / -1, its first chip at every
// 100 ms of GST.
[[nodiscard]] const std::array<std::int8_t, 25>& galileo_e1c_secondary_code();

// One code period of E1 (B and C together) as kE1ChipsPerCode x kE1SubchipsPerChip values of unit
// mean square: (e_B (alpha sc_a + beta sc_b) - e_C (alpha sc_a - beta sc_b)) / sqrt(2), sc_a and
// sc_b the BOC(1,1) and BOC(6,1) sub-carriers (sign of a sine: each chip starts positive), alpha^2
// = 10/11, beta^2 = 1/11. The data symbol multiplies e_B; `pilot_sign` (+1 / -1) is e_C's
// secondary chip relative to that symbol.
[[nodiscard]] std::vector<float> galileo_e1_cboc_waveform(
    const std::array<std::int8_t, kE1ChipsPerCode>& e1b,
    const std::array<std::int8_t, kE1ChipsPerCode>& e1c, int pilot_sign);

// The navigation data common to every satellite: the NeQuick-G terms (word 5) and GST-UTC (word 6).
struct InavCommon {
  std::optional<orbits::NequickGCoefficients> ionosphere;
  double utc_a0_s = 0.0, utc_a1_s_per_s = 0.0;
  int utc_tot_s = 0, utc_week = 0;  // reference time of GST-UTC (GST week, full)
  int leap_seconds = 18, leap_seconds_future = 18, leap_week = 0, leap_day = 7;
};

// The word type a nominal E1-B subframe (30 s from GST TOW 1 mod 30, 15 pages of 2 s) sends in
// page `slot` (0-14): the ephemeris (1-4), ionosphere and time (5, at TOW 25 mod 30), GST-UTC (6,
// at 5), and spare words (0, with GST) where the almanac (7-10) and the reduced ephemeris and
// FEC2 words (16-20) would go.
[[nodiscard]] int inav_e1b_word_type(int slot);

// The 128 bits (0/1, first transmitted first) of word `type` (0-6) sent in the page whose even
// part starts at GST week `gst_week` (GPS week - 1024) second `tow_s`: the record's ephemeris,
// clock, SISA, group delays and E1-B/E5b health; 0, 5 and 6 carry that week and second (OS SIS
// ICD: TOW is the GST at the start of the even page part carrying it).
[[nodiscard]] std::array<std::uint8_t, kInavWordBits> inav_word(
    int type, const orbits::KeplerEphemeris& record, const InavCommon& common, int gst_week,
    int tow_s);

// The CRC-24Q (polynomial 0x1864CFB, initial 0) of a bit sequence, first bit first.
[[nodiscard]] std::uint32_t crc24q_bits(const std::vector<std::uint8_t>& bits);

// The 120 bits of the even and the odd page part that carry `word` (a nominal page: no OSNMA, SAR
// or SSP data), the CRC over both parts' leading 196 bits, 6 tail zeros each.
[[nodiscard]] std::array<std::array<std::uint8_t, 120>, 2> inav_page_parts(
    const std::array<std::uint8_t, kInavWordBits>& word);

// A page part as transmitted: the 10-symbol synchronisation pattern, then its 120 bits through the
// rate-1/2 convolutional code (K = 7, 171 and 133 octal, the second output inverted) and the 30 x 8
// block interleaver; symbols +1 / -1 (logic 0 is +1).
[[nodiscard]] std::array<std::int8_t, kInavSymbolsPerPagePart> inav_part_symbols(
    const std::array<std::uint8_t, 120>& bits);

// The convolutional code alone (240 symbols 0/1 from 120 bits, the encoder starting at zero).
[[nodiscard]] std::array<std::uint8_t, 240> inav_convolutional_code(
    const std::array<std::uint8_t, 120>& bits);

// The SISA index (OS SIS ICD 5.1.12) of an accuracy in metres (255: no accuracy prediction).
[[nodiscard]] int sisa_index(double accuracy_m);

}  // namespace skytrace::baseband
