#include "skytrace/baseband/beidou_b1i.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/broadcast.hpp"

namespace skytrace::baseband {
namespace {

// G2 phase of each PRN as a shift of G2's own sequence (chips): the ICD's tap pairs of PRN 1-37
// (1+3, 1+4, ..., 10+11) give exactly these shifts (the unit test derives them), 38-63 its
// three-tap assignments.
constexpr std::array<int, 63> kG2Shift = {
    712,  1581, 1414, 1550, 581,  771,  1311, 1043, 1549, 359,  710,  1579, 1548, 1103, 579,  769,
    358,  709,  1411, 1547, 1102, 578,  357,  1577, 1410, 1546, 1101, 707,  1576, 1409, 1545, 354,
    705,  1574, 353,  704,  352,  1828, 1525, 1775, 26,   452,  1386, 615,  1178, 1982, 923,  1427,
    1493, 1362, 1735, 1022, 1907, 697,  1331, 1964, 1228, 1826, 1523, 1773, 24,   1651, 1785};

// Fills data bits first..first+n-1 (1-based positions of the decoded 300-bit subframe: each word's
// 22 (word 1: 26) information bits, then its parity) with `value`, MSB first; a field listed in
// parts continues in the next part.
struct SubframeFields {
  std::array<std::uint8_t, 300> bits{};
  void put(std::initializer_list<std::pair<int, int>> parts, std::int64_t value) {
    int total = 0;
    for (auto [first, n] : parts) total += n;
    const auto v = static_cast<std::uint64_t>(value) & (total >= 64 ? ~0ULL : ((1ULL << total) - 1));
    int remaining = total;
    for (auto [first, n] : parts) {
      for (int i = 0; i < n; ++i) {
        --remaining;
        bits[static_cast<size_t>(first - 1 + i)] = static_cast<std::uint8_t>((v >> remaining) & 1U);
      }
    }
  }
};

std::int64_t scaled(double value, double lsb) { return std::llround(value / lsb); }
double semicircles(double rad) { return rad / constants::kPi; }

// The 300 transmitted bits of a subframe whose information bits `f` holds (D1 and D2 alike): word
// 1's first 15 bits as they are, then the BCH(15,11) word of its bits 16-26; words 2-10 each as two
// BCH words (11 information bits, 4 check bits) sent interleaved bit by bit.
std::array<std::uint8_t, 300> encoded(const SubframeFields& f) {
  std::array<std::uint8_t, 300> out{};
  auto bits_of = [&](int first, int n) {
    std::uint32_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 1) | f.bits[static_cast<size_t>(first - 1 + i)];
    return v;
  };
  for (int i = 0; i < 26; ++i) out[static_cast<size_t>(i)] = f.bits[static_cast<size_t>(i)];
  const std::uint32_t p1 = bch15_11_parity(bits_of(16, 11));
  for (int i = 0; i < 4; ++i) out[static_cast<size_t>(26 + i)] = static_cast<std::uint8_t>((p1 >> (3 - i)) & 1U);
  for (int w = 1; w < 10; ++w) {
    const int first = 30 * w + 1;
    const std::uint32_t info_a = bits_of(first, 11);
    const std::uint32_t info_b = bits_of(first + 11, 11);
    const std::uint32_t a = (info_a << 4) | bch15_11_parity(info_a);
    const std::uint32_t b = (info_b << 4) | bch15_11_parity(info_b);
    for (int c = 0; c < 15; ++c) {
      out[static_cast<size_t>(30 * w + 2 * c)] = static_cast<std::uint8_t>((a >> (14 - c)) & 1U);
      out[static_cast<size_t>(30 * w + 2 * c + 1)] = static_cast<std::uint8_t>((b >> (14 - c)) & 1U);
    }
  }
  return out;
}

}  // namespace

bool beidou_geo_prn(int prn) {
  return prn >= 1 && prn <= 63 && orbits::is_beidou_geo(SatelliteId{GnssSystem::kBeiDou, static_cast<std::uint8_t>(prn)});
}

Result<std::array<std::int8_t, kB1iCodeLength>> beidou_b1i_code(int prn) {
  if (prn < 1 || prn > 63) {
    return make_error(ErrorCode::kInvalidArgument, "BeiDou B1I code: PRN " + std::to_string(prn) + " is not one of 1-63");
  }
  auto stage = [](std::uint32_t r, int s) { return (r >> (s - 1)) & 1U; };
  constexpr int kPeriod = 2047;
  std::vector<std::uint8_t> g1(kPeriod), g2(kPeriod);
  std::uint32_t r1 = 0x2AA;  // 01010101010, stage 1 in bit 0
  std::uint32_t r2 = 0x2AA;
  for (int n = 0; n < kPeriod; ++n) {
    g1[static_cast<size_t>(n)] = static_cast<std::uint8_t>(stage(r1, 11));
    g2[static_cast<size_t>(n)] = static_cast<std::uint8_t>(stage(r2, 11));
    // G1 = 1 + X + X^7 + X^8 + X^9 + X^10 + X^11; G2 = 1 + X + X^2 + X^3 + X^4 + X^5 + X^8 + X^9 + X^11
    const std::uint32_t f1 = stage(r1, 1) ^ stage(r1, 7) ^ stage(r1, 8) ^ stage(r1, 9) ^ stage(r1, 10) ^ stage(r1, 11);
    const std::uint32_t f2 = stage(r2, 1) ^ stage(r2, 2) ^ stage(r2, 3) ^ stage(r2, 4) ^ stage(r2, 5) ^ stage(r2, 8) ^
                             stage(r2, 9) ^ stage(r2, 11);
    r1 = ((r1 << 1) | f1) & 0x7FF;
    r2 = ((r2 << 1) | f2) & 0x7FF;
  }
  const int shift = kG2Shift[static_cast<size_t>(prn - 1)];
  std::array<std::int8_t, kB1iCodeLength> code{};
  for (int n = 0; n < kB1iCodeLength; ++n) {  // the 2047-chip Gold code less its last chip
    const int bit = g1[static_cast<size_t>(n)] ^ g2[static_cast<size_t>((n + shift) % kPeriod)];
    code[static_cast<size_t>(n)] = static_cast<std::int8_t>(bit == 0 ? 1 : -1);
  }
  return code;
}

const std::array<std::int8_t, 20>& beidou_nh_code() {
  static const std::array<std::int8_t, 20> nh = [] {
    constexpr std::array<int, 20> kBits = {0, 0, 0, 0, 0, 1, 0, 0, 1, 1, 0, 1, 0, 1, 0, 0, 1, 1, 1, 0};
    std::array<std::int8_t, 20> c{};
    for (size_t i = 0; i < kBits.size(); ++i) c[i] = static_cast<std::int8_t>(kBits[i] == 0 ? 1 : -1);
    return c;
  }();
  return nh;
}

std::uint32_t bch15_11_parity(std::uint32_t info11) {
  // Remainder of info(X) * X^4 divided by X^4 + X + 1.
  std::uint32_t r = (info11 & 0x7FF) << 4;
  for (int bit = 14; bit >= 4; --bit) {
    if ((r >> bit) & 1U) r ^= 0x13U << (bit - 4);
  }
  return r & 0xF;
}

std::array<std::uint8_t, 300> d1_subframe(const orbits::KeplerEphemeris& eph,
                                          const orbits::IonosphereCoefficients& ionosphere, int week,
                                          int subframe_start_sow) {
  const int subframe_id = (subframe_start_sow / 6) % 5 + 1;
  SubframeFields f;
  f.put({{1, 11}}, 0b11100010010);  // preamble; Rev (12-15) zero
  f.put({{16, 3}}, subframe_id);
  f.put({{19, 8}, {31, 12}}, subframe_start_sow);
  const double pi = constants::kPi;
  switch (subframe_id) {
    case 1: {
      const WeekTow toc = eph.toc.to_week_tow(TimeScale::kBdt);
      f.put({{43, 1}}, eph.health != 0 ? 1 : 0);
      f.put({{44, 5}}, eph.iodc);  // AODC
      f.put({{49, 4}}, 0);         // URAI
      f.put({{61, 13}}, week);
      f.put({{74, 9}, {91, 8}}, std::llround(toc.tow_s / 8.0));
      f.put({{99, 10}}, scaled(eph.group_delays.tgd1_s, 0.1e-9));
      f.put({{109, 4}, {121, 6}}, scaled(eph.group_delays.tgd2_s, 0.1e-9));
      const orbits::KlobucharCoefficients k = ionosphere.beidou.value_or(orbits::KlobucharCoefficients{});
      f.put({{127, 8}}, scaled(k.alpha[0], std::ldexp(1.0, -30)));
      f.put({{135, 8}}, scaled(k.alpha[1], std::ldexp(1.0, -27)));
      f.put({{151, 8}}, scaled(k.alpha[2], std::ldexp(1.0, -24)));
      f.put({{159, 8}}, scaled(k.alpha[3], std::ldexp(1.0, -24)));
      f.put({{167, 6}, {181, 2}}, scaled(k.beta[0], std::ldexp(1.0, 11)));
      f.put({{183, 8}}, scaled(k.beta[1], std::ldexp(1.0, 14)));
      f.put({{191, 8}}, scaled(k.beta[2], std::ldexp(1.0, 16)));
      f.put({{199, 4}, {211, 4}}, scaled(k.beta[3], std::ldexp(1.0, 16)));
      f.put({{215, 11}}, scaled(eph.af2_s_per_s2, std::ldexp(1.0, -66)));
      f.put({{226, 7}, {241, 17}}, scaled(eph.af0_s, std::ldexp(1.0, -33)));
      f.put({{258, 5}, {271, 17}}, scaled(eph.af1_s_per_s, std::ldexp(1.0, -50)));
      f.put({{288, 5}}, eph.iode);  // AODE
      break;
    }
    case 2:
      f.put({{43, 10}, {61, 6}}, scaled(semicircles(eph.delta_n_rad_per_s), std::ldexp(1.0, -43)));
      f.put({{67, 16}, {91, 2}}, scaled(eph.cuc_rad, std::ldexp(1.0, -31)));
      f.put({{93, 20}, {121, 12}}, scaled(semicircles(eph.m0_rad), std::ldexp(1.0, -31)));
      f.put({{133, 10}, {151, 22}}, scaled(eph.eccentricity, std::ldexp(1.0, -33)));
      f.put({{181, 18}}, scaled(eph.cus_rad, std::ldexp(1.0, -31)));
      f.put({{199, 4}, {211, 14}}, scaled(eph.crc_m, std::ldexp(1.0, -6)));
      f.put({{225, 8}, {241, 10}}, scaled(eph.crs_m, std::ldexp(1.0, -6)));
      f.put({{251, 12}, {271, 20}}, scaled(eph.sqrt_a_sqrtm, std::ldexp(1.0, -19)));
      f.put({{291, 2}}, std::llround(eph.toe_sow / 8.0) >> 15);
      break;
    case 3:
      f.put({{43, 10}, {61, 5}}, std::llround(eph.toe_sow / 8.0) & 0x7FFF);
      f.put({{66, 17}, {91, 15}}, scaled(semicircles(eph.i0_rad), std::ldexp(1.0, -31)));
      f.put({{106, 7}, {121, 11}}, scaled(eph.cic_rad, std::ldexp(1.0, -31)));
      f.put({{132, 11}, {151, 13}}, scaled(semicircles(eph.omega_dot_rad_per_s), std::ldexp(1.0, -43)));
      f.put({{164, 9}, {181, 9}}, scaled(eph.cis_rad, std::ldexp(1.0, -31)));
      f.put({{190, 13}, {211, 1}}, scaled(semicircles(eph.idot_rad_per_s), std::ldexp(1.0, -43)));
      f.put({{212, 21}, {241, 11}}, scaled(semicircles(eph.omega0_rad), std::ldexp(1.0, -31)));
      f.put({{252, 11}, {271, 21}}, scaled(semicircles(eph.omega_rad), std::ldexp(1.0, -31)));
      break;
    default:
      f.put({{44, 7}}, (subframe_start_sow / 30) % 24 + 1);  // page number; no almanac
      break;
  }
  (void)pi;
  return encoded(f);
}

std::array<std::uint8_t, 300> d2_subframe(const orbits::KeplerEphemeris& eph,
                                          const orbits::IonosphereCoefficients& ionosphere, int week,
                                          int frame_start_sow, int subframe_id) {
  // BDS-SIS-ICD-B1I-3.0 5.3: 3 s frames of five 0.6 s subframes; every subframe of a frame carries
  // the frame's SOW. Subframe 1 sends the basic navigation information in 10 pages, one per frame
  // (30 s for all); subframes 2-4 (integrity and differential corrections) in 6 pages, subframe 5
  // (almanac, time offsets) in 120. Fields the ICD splits over two pages are sent as their most
  // significant bits on the first page (an arithmetic shift of the two's complement) and the rest
  // on the next (put() keeps the low bits).
  const int frame = frame_start_sow / 3;
  SubframeFields f;
  f.put({{1, 11}}, 0b11100010010);  // preamble; Rev (12-15) zero
  f.put({{16, 3}}, subframe_id);
  f.put({{19, 8}, {31, 12}}, frame_start_sow);
  if (subframe_id == 1) {
    const int page = frame % 10 + 1;
    f.put({{43, 4}}, page);
    const orbits::KlobucharCoefficients k = ionosphere.beidou.value_or(orbits::KlobucharCoefficients{});
    const std::int64_t af1 = scaled(eph.af1_s_per_s, std::ldexp(1.0, -50));
    const std::int64_t cuc = scaled(eph.cuc_rad, std::ldexp(1.0, -31));
    const std::int64_t ecc = scaled(eph.eccentricity, std::ldexp(1.0, -33));
    const std::int64_t cic = scaled(eph.cic_rad, std::ldexp(1.0, -31));
    const std::int64_t i0 = scaled(semicircles(eph.i0_rad), std::ldexp(1.0, -31));
    const std::int64_t omega_dot = scaled(semicircles(eph.omega_dot_rad_per_s), std::ldexp(1.0, -43));
    const std::int64_t omega = scaled(semicircles(eph.omega_rad), std::ldexp(1.0, -31));
    switch (page) {
      case 1: {
        const WeekTow toc = eph.toc.to_week_tow(TimeScale::kBdt);
        f.put({{47, 1}}, eph.health != 0 ? 1 : 0);
        f.put({{48, 5}}, eph.iodc);  // AODC
        f.put({{61, 4}}, 0);         // URAI
        f.put({{65, 13}}, week);
        f.put({{78, 5}, {91, 12}}, std::llround(toc.tow_s / 8.0));
        f.put({{103, 10}}, scaled(eph.group_delays.tgd1_s, 0.1e-9));
        f.put({{121, 10}}, scaled(eph.group_delays.tgd2_s, 0.1e-9));
        break;
      }
      case 2:
        f.put({{47, 6}, {61, 2}}, scaled(k.alpha[0], std::ldexp(1.0, -30)));
        f.put({{63, 8}}, scaled(k.alpha[1], std::ldexp(1.0, -27)));
        f.put({{71, 8}}, scaled(k.alpha[2], std::ldexp(1.0, -24)));
        f.put({{79, 4}, {91, 4}}, scaled(k.alpha[3], std::ldexp(1.0, -24)));
        f.put({{95, 8}}, scaled(k.beta[0], std::ldexp(1.0, 11)));
        f.put({{103, 8}}, scaled(k.beta[1], std::ldexp(1.0, 14)));
        f.put({{111, 2}, {121, 6}}, scaled(k.beta[2], std::ldexp(1.0, 16)));
        f.put({{127, 8}}, scaled(k.beta[3], std::ldexp(1.0, 16)));
        break;
      case 3:
        f.put({{101, 12}, {121, 12}}, scaled(eph.af0_s, std::ldexp(1.0, -33)));
        f.put({{133, 4}}, af1 >> 18);
        break;
      case 4:
        f.put({{47, 6}, {61, 12}}, af1);
        f.put({{73, 10}, {91, 1}}, scaled(eph.af2_s_per_s2, std::ldexp(1.0, -66)));
        f.put({{92, 5}}, eph.iode);  // AODE
        f.put({{97, 16}}, scaled(semicircles(eph.delta_n_rad_per_s), std::ldexp(1.0, -43)));
        f.put({{121, 14}}, cuc >> 4);
        break;
      case 5:
        f.put({{47, 4}}, cuc);
        f.put({{51, 2}, {61, 22}, {91, 8}}, scaled(semicircles(eph.m0_rad), std::ldexp(1.0, -31)));
        f.put({{99, 14}, {121, 4}}, scaled(eph.cus_rad, std::ldexp(1.0, -31)));
        f.put({{125, 10}}, ecc >> 22);
        break;
      case 6:
        f.put({{47, 6}, {61, 16}}, ecc);
        f.put({{77, 6}, {91, 22}, {121, 4}}, scaled(eph.sqrt_a_sqrtm, std::ldexp(1.0, -19)));
        f.put({{125, 10}}, cic >> 8);
        break;
      case 7:
        f.put({{47, 6}, {61, 2}}, cic);
        f.put({{63, 18}}, scaled(eph.cis_rad, std::ldexp(1.0, -31)));
        f.put({{81, 2}, {91, 15}}, std::llround(eph.toe_sow / 8.0));
        f.put({{106, 7}, {121, 14}}, i0 >> 11);
        break;
      case 8:
        f.put({{47, 6}, {61, 5}}, i0);
        f.put({{66, 17}, {91, 1}}, scaled(eph.crc_m, std::ldexp(1.0, -6)));
        f.put({{92, 18}}, scaled(eph.crs_m, std::ldexp(1.0, -6)));
        f.put({{110, 3}, {121, 16}}, omega_dot >> 5);
        break;
      case 9:
        f.put({{47, 5}}, omega_dot);
        f.put({{52, 1}, {61, 22}, {91, 9}}, scaled(semicircles(eph.omega0_rad), std::ldexp(1.0, -31)));
        f.put({{100, 13}, {121, 14}}, omega >> 5);
        break;
      default:  // page 10
        f.put({{47, 5}}, omega);
        f.put({{52, 1}, {61, 13}}, scaled(semicircles(eph.idot_rad_per_s), std::ldexp(1.0, -43)));
        break;
    }
  } else if (subframe_id == 5) {
    f.put({{44, 7}}, frame % 120 + 1);  // page number; no almanac
  } else {
    f.put({{43, 4}}, frame % 6 + 1);  // page number; no integrity or differential information
  }
  return encoded(f);
}

}  // namespace skytrace::baseband
