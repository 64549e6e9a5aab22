#include "skytrace/baseband/gps_l1ca.hpp"

#include <cmath>
#include <string>

#include "skytrace/core/constants.hpp"

namespace skytrace::baseband {
namespace {

// G2 delays (chips) of PRN 1-32, IS-GPS-200 Table 3-Ia.
constexpr std::array<int, 32> kG2Delay = {5,   6,   7,   8,   17,  18,  139, 140, 141, 251, 252,
                                          254, 255, 256, 257, 258, 469, 470, 471, 472, 473, 474,
                                          509, 512, 513, 514, 515, 516, 859, 860, 861, 862};

constexpr double kGpsMu_m3_per_s2 = 3.986005e14;  // IS-GPS-200's value for the mean motion

// The ten words of one subframe as 24-bit data fields, filled by bit position (1-based, MSB first).
class SubframeData {
 public:
  // `value` (two's complement when negative) into bits first..first+n-1 of word `word` (1-10).
  void put(int word, int first_bit, int n, std::int64_t value) {
    const auto bits = static_cast<std::uint64_t>(value) & ((std::uint64_t{1} << n) - 1);
    const int shift = 24 - (first_bit + n - 1);
    words_[static_cast<size_t>(word - 1)] |= static_cast<std::uint32_t>(bits << shift);
  }
  // A field that spans two words: its `n_msb` high bits at the end of `word`, the rest at the start
  // of the next word.
  void put_split(int word, int first_bit, int n_msb, int n_total, std::int64_t value) {
    const auto bits = static_cast<std::uint64_t>(value) & ((std::uint64_t{1} << n_total) - 1);
    const int n_lsb = n_total - n_msb;
    put(word, first_bit, n_msb, static_cast<std::int64_t>(bits >> n_lsb));
    put(word + 1, 1, n_lsb, static_cast<std::int64_t>(bits & ((std::uint64_t{1} << n_lsb) - 1)));
  }
  // Reserved bits: alternating ones and zeros (IS-GPS-200 20.3.3.5.1.x), starting with 1.
  void alternate(int word, int first_bit, int n) {
    for (int i = 0; i < n; ++i) put(word, first_bit + i, 1, (i % 2 == 0) ? 1 : 0);
  }
  [[nodiscard]] std::uint32_t word(int w) const { return words_[static_cast<size_t>(w - 1)]; }

 private:
  std::array<std::uint32_t, 10> words_{};
};

std::int64_t scaled(double value, double lsb) { return std::llround(value / lsb); }
double semicircles(double rad) { return rad / constants::kPi; }

int parity_bits(std::uint32_t d24, bool d29, bool d30) {
  auto d = [&](int i) { return static_cast<int>((d24 >> (24 - i)) & 1U); };
  auto sum = [&](std::initializer_list<int> idx) {
    int s = 0;
    for (int i : idx) s ^= d(i);
    return s;
  };
  const int p25 = (d29 ? 1 : 0) ^ sum({1, 2, 3, 5, 6, 10, 11, 12, 13, 14, 17, 18, 20, 23});
  const int p26 = (d30 ? 1 : 0) ^ sum({2, 3, 4, 6, 7, 11, 12, 13, 14, 15, 18, 19, 21, 24});
  const int p27 = (d29 ? 1 : 0) ^ sum({1, 3, 4, 5, 7, 8, 12, 13, 14, 15, 16, 19, 20, 22});
  const int p28 = (d30 ? 1 : 0) ^ sum({2, 4, 5, 6, 8, 9, 13, 14, 15, 16, 17, 20, 21, 23});
  const int p29 = (d30 ? 1 : 0) ^ sum({1, 3, 5, 6, 7, 9, 10, 14, 15, 16, 17, 18, 21, 22, 24});
  const int p30 = (d29 ? 1 : 0) ^ sum({3, 5, 6, 8, 9, 10, 11, 13, 15, 19, 22, 23, 24});
  return (p25 << 5) | (p26 << 4) | (p27 << 3) | (p28 << 2) | (p29 << 1) | p30;
}

// Words 2 and 10 end in two non-information bits chosen so that the word's D29 and D30 are zero.
std::uint32_t with_zero_tail(std::uint32_t d24, bool d29_prev, bool d30_prev) {
  for (std::uint32_t t = 0; t < 4; ++t) {
    const std::uint32_t candidate = (d24 & ~std::uint32_t{3}) | t;
    if ((lnav_word(candidate, d29_prev, d30_prev) & 3U) == 0) return candidate;
  }
  return d24;  // unreachable: two free bits always solve the two parity equations
}

// Subframe 4 page -> SV ID (data ID 01), IS-GPS-200 Table 20-V.
constexpr std::array<int, 25> kSubframe4SvId = {57, 25, 26, 27, 28, 57, 29, 30, 31, 32, 57, 62, 52,
                                                53, 54, 57, 55, 56, 58, 59, 57, 60, 61, 62, 63};

void put_almanac(SubframeData& d, const orbits::KeplerEphemeris* eph, int prn, const LnavCommon& c) {
  d.put(3, 1, 2, 1);
  d.put(3, 3, 6, prn);
  if (eph == nullptr) {  // no record: a dummy almanac page (SV ID 0)
    d = SubframeData{};
    d.put(3, 1, 2, 1);
    d.alternate(3, 9, 16);
    for (int w = 4; w <= 9; ++w) d.alternate(w, 1, 24);
    d.alternate(10, 1, 22);
    return;
  }
  const double a_m = eph->sqrt_a_sqrtm * eph->sqrt_a_sqrtm;
  const double n_rad_per_s = std::sqrt(kGpsMu_m3_per_s2 / (a_m * a_m * a_m)) + eph->delta_n_rad_per_s;
  const double dt_s = static_cast<double>(c.almanac_toa_s) - eph->toe_sow +
                      604800.0 * static_cast<double>(c.almanac_week - eph->week);
  d.put(3, 9, 16, scaled(eph->eccentricity, std::ldexp(1.0, -21)));
  d.put(4, 1, 8, c.almanac_toa_s / 4096);
  d.put(4, 9, 16, scaled(semicircles(eph->i0_rad) - 0.3, std::ldexp(1.0, -19)));
  d.put(5, 1, 16, scaled(semicircles(eph->omega_dot_rad_per_s), std::ldexp(1.0, -38)));
  d.put(5, 17, 8, eph->health & 0xFF);
  d.put(6, 1, 24, scaled(eph->sqrt_a_sqrtm, std::ldexp(1.0, -11)));
  d.put(7, 1, 24, scaled(semicircles(eph->omega0_rad + eph->omega_dot_rad_per_s * dt_s), std::ldexp(1.0, -23)));
  d.put(8, 1, 24, scaled(semicircles(eph->omega_rad), std::ldexp(1.0, -23)));
  double m_sc = semicircles(eph->m0_rad + n_rad_per_s * dt_s);
  m_sc -= 2.0 * std::floor((m_sc + 1.0) / 2.0);  // into [-1, 1)
  d.put(9, 1, 24, scaled(m_sc, std::ldexp(1.0, -23)));
  const std::int64_t af0 = scaled(eph->af0_s, std::ldexp(1.0, -20));
  d.put(10, 1, 8, (af0 >> 3) & 0xFF);
  d.put(10, 9, 11, scaled(eph->af1_s_per_s, std::ldexp(1.0, -38)));
  d.put(10, 20, 3, af0 & 7);
}

}  // namespace

Result<std::array<std::int8_t, kCaCodeLength>> gps_ca_code(int prn) {
  if (prn < 1 || prn > static_cast<int>(kG2Delay.size())) {
    return make_error(ErrorCode::kInvalidArgument,
                      "GPS C/A code: PRN " + std::to_string(prn) + " is not one of 1-32");
  }
  std::array<std::uint8_t, kCaCodeLength> g1{};
  std::array<std::uint8_t, kCaCodeLength> g2{};
  std::uint32_t r1 = 0x3FF;  // stage 1 in bit 0 ... stage 10 in bit 9, all ones at the start
  std::uint32_t r2 = 0x3FF;
  auto stage = [](std::uint32_t r, int s) { return (r >> (s - 1)) & 1U; };
  for (int i = 0; i < kCaCodeLength; ++i) {
    g1[static_cast<size_t>(i)] = static_cast<std::uint8_t>(stage(r1, 10));
    g2[static_cast<size_t>(i)] = static_cast<std::uint8_t>(stage(r2, 10));
    const std::uint32_t f1 = stage(r1, 3) ^ stage(r1, 10);  // G1 = 1 + x^3 + x^10
    const std::uint32_t f2 = stage(r2, 2) ^ stage(r2, 3) ^ stage(r2, 6) ^ stage(r2, 8) ^ stage(r2, 9) ^
                             stage(r2, 10);  // G2 = 1 + x^2 + x^3 + x^6 + x^8 + x^9 + x^10
    r1 = ((r1 << 1) | f1) & 0x3FF;
    r2 = ((r2 << 1) | f2) & 0x3FF;
  }
  const int delay = kG2Delay[static_cast<size_t>(prn - 1)];
  std::array<std::int8_t, kCaCodeLength> code{};
  for (int i = 0; i < kCaCodeLength; ++i) {
    const int bit = g1[static_cast<size_t>(i)] ^ g2[static_cast<size_t>((i - delay + kCaCodeLength) % kCaCodeLength)];
    code[static_cast<size_t>(i)] = static_cast<std::int8_t>(bit == 0 ? 1 : -1);
  }
  return code;
}

std::uint32_t lnav_word(std::uint32_t data24, bool d29_prev, bool d30_prev) {
  data24 &= 0xFFFFFF;
  const std::uint32_t sent = d30_prev ? (~data24 & 0xFFFFFF) : data24;
  return (sent << 6) | static_cast<std::uint32_t>(parity_bits(data24, d29_prev, d30_prev));
}

bool lnav_parity_ok(std::uint32_t word30, bool d29_prev, bool d30_prev) {
  std::uint32_t data24 = (word30 >> 6) & 0xFFFFFF;
  if (d30_prev) data24 = ~data24 & 0xFFFFFF;
  return static_cast<int>(word30 & 0x3F) == parity_bits(data24, d29_prev, d30_prev);
}

int ura_index(double accuracy_m) {
  constexpr std::array<double, 15> kBound_m = {2.4,  3.4,   4.85,  6.85,  9.65,   13.65,  24.0,  48.0,
                                               96.0, 192.0, 384.0, 768.0, 1536.0, 3072.0, 6144.0};
  for (size_t i = 0; i < kBound_m.size(); ++i) {
    if (accuracy_m <= kBound_m[i]) return static_cast<int>(i);
  }
  return 15;
}

std::array<std::uint8_t, kLnavBitsPerSubframe> lnav_subframe(const orbits::KeplerEphemeris& eph,
                                                             const LnavCommon& common, int week,
                                                             int subframe_start_sow) {
  const int subframe_id = (subframe_start_sow / 6) % 5 + 1;
  const int page = (subframe_start_sow / 30) % 25 + 1;
  SubframeData d;
  // TLM: preamble 10001011, the TLM message and flags zero.
  d.put(1, 1, 8, 0x8B);
  // HOW: the truncated TOW count of the next subframe, alert 0, anti-spoofing on, the subframe ID.
  d.put(2, 1, 17, ((subframe_start_sow + 6) / 6) % 100800);
  d.put(2, 19, 1, 1);
  d.put(2, 20, 3, subframe_id);
  const auto iodc = static_cast<std::int64_t>(eph.iodc) & 0x3FF;
  switch (subframe_id) {
    case 1: {
      WeekTow toc = eph.toc.to_week_tow(TimeScale::kGpst);
      d.put(3, 1, 10, week % 1024);
      d.put(3, 11, 2, eph.codes_on_l2);
      d.put(3, 13, 4, ura_index(eph.accuracy_m));
      d.put(3, 17, 6, eph.health & 0x3F);
      d.put(3, 23, 2, iodc >> 8);
      d.put(4, 1, 1, eph.l2p_data_flag);
      d.alternate(4, 2, 23);
      d.alternate(5, 1, 24);
      d.alternate(6, 1, 24);
      d.alternate(7, 1, 16);
      d.put(7, 17, 8, scaled(eph.group_delays.tgd_s, std::ldexp(1.0, -31)));
      d.put(8, 1, 8, iodc & 0xFF);
      d.put(8, 9, 16, std::llround(toc.tow_s / 16.0));
      d.put(9, 1, 8, scaled(eph.af2_s_per_s2, std::ldexp(1.0, -55)));
      d.put(9, 9, 16, scaled(eph.af1_s_per_s, std::ldexp(1.0, -43)));
      d.put(10, 1, 22, scaled(eph.af0_s, std::ldexp(1.0, -31)));
      break;
    }
    case 2:
      d.put(3, 1, 8, eph.iode & 0xFF);
      d.put(3, 9, 16, scaled(eph.crs_m, std::ldexp(1.0, -5)));
      d.put(4, 1, 16, scaled(semicircles(eph.delta_n_rad_per_s), std::ldexp(1.0, -43)));
      d.put_split(4, 17, 8, 32, scaled(semicircles(eph.m0_rad), std::ldexp(1.0, -31)));
      d.put(6, 1, 16, scaled(eph.cuc_rad, std::ldexp(1.0, -29)));
      d.put_split(6, 17, 8, 32, scaled(eph.eccentricity, std::ldexp(1.0, -33)));
      d.put(8, 1, 16, scaled(eph.cus_rad, std::ldexp(1.0, -29)));
      d.put_split(8, 17, 8, 32, scaled(eph.sqrt_a_sqrtm, std::ldexp(1.0, -19)));
      d.put(10, 1, 16, std::llround(eph.toe_sow / 16.0));
      d.put(10, 17, 1, eph.fit_interval_h > 4.0 ? 1 : 0);
      break;
    case 3:
      d.put(3, 1, 16, scaled(eph.cic_rad, std::ldexp(1.0, -29)));
      d.put_split(3, 17, 8, 32, scaled(semicircles(eph.omega0_rad), std::ldexp(1.0, -31)));
      d.put(5, 1, 16, scaled(eph.cis_rad, std::ldexp(1.0, -29)));
      d.put_split(5, 17, 8, 32, scaled(semicircles(eph.i0_rad), std::ldexp(1.0, -31)));
      d.put(7, 1, 16, scaled(eph.crc_m, std::ldexp(1.0, -5)));
      d.put_split(7, 17, 8, 32, scaled(semicircles(eph.omega_rad), std::ldexp(1.0, -31)));
      d.put(9, 1, 24, scaled(semicircles(eph.omega_dot_rad_per_s), std::ldexp(1.0, -43)));
      d.put(10, 1, 8, eph.iode & 0xFF);
      d.put(10, 9, 14, scaled(semicircles(eph.idot_rad_per_s), std::ldexp(1.0, -43)));
      break;
    case 4: {
      SubframeData p;
      const int sv_id = kSubframe4SvId[static_cast<size_t>(page - 1)];
      const bool almanac_page = (page >= 2 && page <= 5) || (page >= 7 && page <= 10);
      if (almanac_page) {
        put_almanac(p, common.almanac[static_cast<size_t>(sv_id)], sv_id, common);
      } else if (page == 18) {
        p.put(3, 1, 2, 1);
        p.put(3, 3, 6, sv_id);
        const orbits::KlobucharCoefficients k = common.ionosphere.value_or(orbits::KlobucharCoefficients{});
        p.put(3, 9, 8, scaled(k.alpha[0], std::ldexp(1.0, -30)));
        p.put(3, 17, 8, scaled(k.alpha[1], std::ldexp(1.0, -27)));
        p.put(4, 1, 8, scaled(k.alpha[2], std::ldexp(1.0, -24)));
        p.put(4, 9, 8, scaled(k.alpha[3], std::ldexp(1.0, -24)));
        p.put(4, 17, 8, scaled(k.beta[0], std::ldexp(1.0, 11)));
        p.put(5, 1, 8, scaled(k.beta[1], std::ldexp(1.0, 14)));
        p.put(5, 9, 8, scaled(k.beta[2], std::ldexp(1.0, 16)));
        p.put(5, 17, 8, scaled(k.beta[3], std::ldexp(1.0, 16)));
        p.put(6, 1, 24, scaled(common.utc_a1_s_per_s, std::ldexp(1.0, -50)));
        p.put_split(7, 1, 24, 32, scaled(common.utc_a0_s, std::ldexp(1.0, -30)));
        p.put(8, 9, 8, common.utc_tot_s / 4096);
        p.put(8, 17, 8, common.utc_week % 256);
        p.put(9, 1, 8, common.leap_seconds);
        p.put(9, 9, 8, common.leap_week % 256);
        p.put(9, 17, 8, common.leap_day);
        p.put(10, 1, 8, common.leap_seconds_future);
        p.alternate(10, 9, 14);
      } else if (page == 25) {
        // Anti-spoofing on and the signal configuration of each PRN (1011: A-S, L2C capable),
        // then the 6-bit health of PRN 25-32.
        p.put(3, 1, 2, 1);
        p.put(3, 3, 6, sv_id);
        auto config = [&](int prn) { return common.almanac[static_cast<size_t>(prn)] != nullptr ? 0xB : 0x0; };
        auto health = [&](int prn) {
          const auto* a = common.almanac[static_cast<size_t>(prn)];
          return a != nullptr ? (a->health & 0x3F) : 0x3F;
        };
        int prn = 1;
        for (int bit = 9; bit <= 21; bit += 4) p.put(3, bit, 4, config(prn++));
        for (int w = 4; w <= 7; ++w) {
          for (int bit = 1; bit <= 21; bit += 4) p.put(w, bit, 4, config(prn++));
        }
        for (int bit = 1; bit <= 13; bit += 4) p.put(8, bit, 4, config(prn++));
        p.put(8, 19, 6, health(25));
        for (int i = 0; i < 4; ++i) p.put(9, 1 + 6 * i, 6, health(26 + i));
        for (int i = 0; i < 3; ++i) p.put(10, 1 + 6 * i, 6, health(30 + i));
      } else {  // pages without data here: reserved bits
        p.put(3, 1, 2, 1);
        p.put(3, 3, 6, sv_id);
        p.alternate(3, 9, 16);
        for (int w = 4; w <= 9; ++w) p.alternate(w, 1, 24);
        p.alternate(10, 1, 22);
      }
      for (int w = 3; w <= 10; ++w) d.put(w, 1, 24, p.word(w));
      break;
    }
    case 5: {
      SubframeData p;
      if (page <= 24) {
        put_almanac(p, common.almanac[static_cast<size_t>(page)], page, common);
      } else {  // page 25: toa, week and the health of PRN 1-24
        p.put(3, 1, 2, 1);
        p.put(3, 3, 6, 51);
        p.put(3, 9, 8, common.almanac_toa_s / 4096);
        p.put(3, 17, 8, common.almanac_week % 256);
        for (int prn = 1; prn <= 24; ++prn) {
          const auto* a = common.almanac[static_cast<size_t>(prn)];
          const int w = 4 + (prn - 1) / 4;
          p.put(w, 1 + 6 * ((prn - 1) % 4), 6, a != nullptr ? (a->health & 0x3F) : 0x3F);
        }
        p.alternate(10, 1, 22);
      }
      for (int w = 3; w <= 10; ++w) d.put(w, 1, 24, p.word(w));
      break;
    }
    default: break;
  }
  // Parity: each word's bits follow from the previous word's D29* and D30*; the subframe before
  // ends in zeros (its word 10's t bits), as does the HOW.
  std::array<std::uint8_t, kLnavBitsPerSubframe> bits{};
  bool d29 = false;
  bool d30 = false;
  for (int w = 1; w <= 10; ++w) {
    std::uint32_t data = d.word(w);
    if (w == 2 || w == 10) data = with_zero_tail(data, d29, d30);
    const std::uint32_t word = lnav_word(data, d29, d30);
    for (int b = 0; b < 30; ++b) bits[static_cast<size_t>(30 * (w - 1) + b)] = static_cast<std::uint8_t>((word >> (29 - b)) & 1U);
    d29 = ((word >> 1) & 1U) != 0;
    d30 = (word & 1U) != 0;
  }
  return bits;
}

}  // namespace skytrace::baseband
