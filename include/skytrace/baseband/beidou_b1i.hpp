// BeiDou B1I as transmitted by MEO and IGSO satellites (BDS-SIS-ICD-B1I-3.0): the 2046-chip
// ranging codes and the D1 navigation message built from the broadcast records (subframes 1-3,
// BCH(15,11) coded and interleaved, with the Neumann-Hoffman secondary code), so that a software
// receiver decodes the records that nav.rnx holds. GEO satellites (PRN 1-5, 59-63: D2) are not
// generated.
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

// The 4 BCH(15,11) check bits of 11 information bits (g(X) = X^4 + X + 1), MSB first.
[[nodiscard]] std::uint32_t bch15_11_parity(std::uint32_t info11);

}  // namespace skytrace::baseband
