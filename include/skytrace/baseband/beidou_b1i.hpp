// BeiDou B1I (BDS-SIS-ICD-B1I-3.0): the 2046-chip ranging codes, the D1 navigation message of MEO
// and IGSO satellites (subframes 1-3 from the broadcast record, with the Neumann-Hoffman secondary
// code) and the D2 message of GEO satellites (PRN 1-5, 59-63: 500 bit/s, the record in the ten
// pages of subframe 1), BCH(15,11) coded and interleaved, so that a software receiver decodes the
// records that nav.rnx holds.
#pragma once

#include <array>
#include <cstdint>

#include "skytrace/core/error.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::baseband {

inline constexpr int kB1iCodeLength = 2046;
inline constexpr double kB1iCarrier_hz = 1561.098e6;

// The ranging code of PRN 1-63 as chips +1 / -1 (logic 0 is +1).
[[nodiscard]] Result<std::array<std::int8_t, kB1iCodeLength>> beidou_b1i_code(int prn);
// Whether a PRN is a GEO satellite's (D2 message at 500 bit/s).
[[nodiscard]] bool beidou_geo_prn(int prn);

// The Neumann-Hoffman code of D1 (20 chips at 1 kHz on each 20 ms bit): +1 / -1.
[[nodiscard]] const std::array<std::int8_t, 20>& beidou_nh_code();

// The 300 bits (0/1, first transmitted first) of the D1 subframe that starts at BDT second of week
// `subframe_start_sow` (a multiple of 6) of BDT week `week`: subframes 1-3 from `record`, 4-5 pages
// with their number and no almanac.
[[nodiscard]] std::array<std::uint8_t, 300> d1_subframe(const orbits::KeplerEphemeris& record,
                                                       const orbits::IonosphereCoefficients& ionosphere, int week,
                                                       int subframe_start_sow);

// The 300 bits (0/1, first transmitted first) of D2 subframe `subframe_id` (1-5) of the 3 s frame
// that starts at BDT second of week `frame_start_sow` (a multiple of 3) of BDT week `week`:
// subframe 1 carries page (frame_start_sow / 3) % 10 + 1 of the record; subframes 2-5 their page
// numbers and no integrity, differential or almanac information.
[[nodiscard]] std::array<std::uint8_t, 300> d2_subframe(const orbits::KeplerEphemeris& record,
                                                       const orbits::IonosphereCoefficients& ionosphere, int week,
                                                       int frame_start_sow, int subframe_id);

// The 4 BCH(15,11) check bits of 11 information bits (g(X) = X^4 + X + 1), MSB first.
[[nodiscard]] std::uint32_t bch15_11_parity(std::uint32_t info11);

}  // namespace skytrace::baseband
