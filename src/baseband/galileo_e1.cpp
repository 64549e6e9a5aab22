#include "skytrace/baseband/galileo_e1.hpp"

#include <cmath>
#include <string>

#include "galileo_e1_codes.hpp"
#include "skytrace/core/constants.hpp"

namespace skytrace::baseband {
namespace {

// A word's bits filled field after field, MSB first (two's complement for signed fields; a field
// wider than 64 bits, word 0's 88 spare ones, is the value sign-extended).
struct WordBits {
  std::array<std::uint8_t, kInavWordBits> bits{};
  int at = 0;
  void put(int n, std::int64_t value) {
    const auto v = static_cast<std::uint64_t>(value);
    for (int i = n - 1; i >= 0; --i) {
      const std::uint64_t bit = i < 64 ? (v >> i) & 1U : (value < 0 ? 1U : 0U);
      bits[static_cast<size_t>(at++)] = static_cast<std::uint8_t>(bit);
    }
  }
};

std::int64_t scaled(double value, double lsb) { return std::llround(value / lsb); }
double semicircles(double rad) { return rad / constants::kPi; }
double p2(int e) { return std::ldexp(1.0, e); }

// The RINEX health bits of a Galileo record (bit 0 E1-B DVS, 1-2 E1-B HS, 3 E5a DVS, 4-5 E5a HS,
// 6 E5b DVS, 7-8 E5b HS).
int e1b_dvs(int health) { return health & 1; }
int e1b_hs(int health) { return (health >> 1) & 3; }
int e5b_dvs(int health) { return (health >> 6) & 1; }
int e5b_hs(int health) { return (health >> 7) & 3; }

constexpr std::array<std::uint8_t, 10> kSyncPattern = {0, 1, 0, 1, 1, 0, 0, 0, 0, 0};

}  // namespace

Result<std::array<std::int8_t, kE1ChipsPerCode>> galileo_e1_primary_code(int prn, bool pilot) {
  if (prn < 1 || prn > 50) {
    return make_error(ErrorCode::kInvalidArgument,
                      "Galileo E1 code: PRN " + std::to_string(prn) + " is not one of 1-50");
  }
  const char* hex =
      (pilot ? detail::kGalileoE1cPrimaryHex : detail::kGalileoE1bPrimaryHex)[prn - 1];
  std::array<std::int8_t, kE1ChipsPerCode> code{};
  for (int digit = 0; digit < kE1ChipsPerCode / 4; ++digit) {
    const char c = hex[digit];
    const int value = c >= '0' && c <= '9'   ? c - '0'
                      : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                             : c - 'a' + 10;
    for (int b = 0; b < 4; ++b) {
      code[static_cast<size_t>(4 * digit + b)] =
          static_cast<std::int8_t>(((value >> (3 - b)) & 1) == 0 ? 1 : -1);
    }
  }
  return code;
}

const std::array<std::int8_t, 25>& galileo_e1c_secondary_code() {
  static const std::array<std::int8_t, 25> code = [] {
    constexpr char kBits[] = "0011100000001010110110010";  // CS25_1, hexadecimal 380AD90
    std::array<std::int8_t, 25> c{};
    for (size_t i = 0; i < c.size(); ++i) c[i] = static_cast<std::int8_t>(kBits[i] == '0' ? 1 : -1);
    return c;
  }();
  return code;
}

std::vector<float> galileo_e1_cboc_waveform(const std::array<std::int8_t, kE1ChipsPerCode>& e1b,
                                            const std::array<std::int8_t, kE1ChipsPerCode>& e1c,
                                            int pilot_sign) {
  const double alpha = std::sqrt(10.0 / 11.0);
  const double beta = std::sqrt(1.0 / 11.0);
  std::vector<float> w(static_cast<size_t>(kE1ChipsPerCode * kE1SubchipsPerChip));
  for (int chip = 0; chip < kE1ChipsPerCode; ++chip) {
    for (int j = 0; j < kE1SubchipsPerChip; ++j) {
      const double sc_a = j < kE1SubchipsPerChip / 2 ? 1.0 : -1.0;  // BOC(1,1): one period a chip
      const double sc_b = j % 2 == 0 ? 1.0 : -1.0;                  // BOC(6,1): six periods a chip
      const double b = e1b[static_cast<size_t>(chip)];
      const double c = pilot_sign * e1c[static_cast<size_t>(chip)];
      w[static_cast<size_t>(chip * kE1SubchipsPerChip + j)] = static_cast<float>(
          (b * (alpha * sc_a + beta * sc_b) - c * (alpha * sc_a - beta * sc_b)) / std::sqrt(2.0));
    }
  }
  return w;
}

int inav_e1b_word_type(int slot) {
  // OS SIS ICD (E1-B nominal sub-frame): 2, 4, 6, almanac (7/9, 8/10), reduced ephemeris and
  // FEC2 (16-20), 0, 1, 3, 5, 0, 0. The almanac, 16 and 17-20 are sent as spare words here:
  // GNSS-SDR 0.0.17 would publish an ephemeris from word 16 with its angles left in semicircles.
  constexpr std::array<int, 15> kTypes = {2, 4, 6, 0, 0, 0, 0, 0, 0, 0, 1, 3, 5, 0, 0};
  return kTypes[static_cast<size_t>(((slot % 15) + 15) % 15)];
}

int sisa_index(double accuracy_m) {
  if (!(accuracy_m >= 0.0) || accuracy_m > 6.0) return 255;
  if (accuracy_m < 0.5) return static_cast<int>(std::lround(accuracy_m / 0.01));
  if (accuracy_m < 1.0) return 50 + static_cast<int>(std::lround((accuracy_m - 0.5) / 0.02));
  if (accuracy_m < 2.0) return 75 + static_cast<int>(std::lround((accuracy_m - 1.0) / 0.04));
  return 100 + static_cast<int>(std::lround((accuracy_m - 2.0) / 0.16));
}

std::array<std::uint8_t, kInavWordBits> inav_word(int type, const orbits::KeplerEphemeris& r,
                                                  const InavCommon& common, int gst_week,
                                                  int tow_s) {
  WordBits w;
  w.put(6, type);
  const int iodnav = r.iode & 0x3FF;
  switch (type) {
    case 1:
      w.put(10, iodnav);
      w.put(14, scaled(r.toe_sow, 60.0));
      w.put(32, scaled(semicircles(r.m0_rad), p2(-31)));
      w.put(32, scaled(r.eccentricity, p2(-33)));
      w.put(32, scaled(r.sqrt_a_sqrtm, p2(-19)));
      w.put(2, 0);
      break;
    case 2:
      w.put(10, iodnav);
      w.put(32, scaled(semicircles(r.omega0_rad), p2(-31)));
      w.put(32, scaled(semicircles(r.i0_rad), p2(-31)));
      w.put(32, scaled(semicircles(r.omega_rad), p2(-31)));
      w.put(14, scaled(semicircles(r.idot_rad_per_s), p2(-43)));
      w.put(2, 0);
      break;
    case 3:
      w.put(10, iodnav);
      w.put(24, scaled(semicircles(r.omega_dot_rad_per_s), p2(-43)));
      w.put(16, scaled(semicircles(r.delta_n_rad_per_s), p2(-43)));
      w.put(16, scaled(r.cuc_rad, p2(-29)));
      w.put(16, scaled(r.cus_rad, p2(-29)));
      w.put(16, scaled(r.crc_m, p2(-5)));
      w.put(16, scaled(r.crs_m, p2(-5)));
      w.put(8, sisa_index(r.accuracy_m));
      break;
    case 4: {
      w.put(10, iodnav);
      w.put(6, r.satellite.number);
      w.put(16, scaled(r.cic_rad, p2(-29)));
      w.put(16, scaled(r.cis_rad, p2(-29)));
      const WeekTow toc = r.toc.to_week_tow(TimeScale::kGpst);
      w.put(14, scaled(toc.tow_s, 60.0));
      w.put(31, scaled(r.af0_s, p2(-34)));
      w.put(21, scaled(r.af1_s_per_s, p2(-46)));
      w.put(6, scaled(r.af2_s_per_s2, p2(-59)));
      w.put(2, 0);
      break;
    }
    case 5: {
      const orbits::NequickGCoefficients az =
          common.ionosphere.value_or(orbits::NequickGCoefficients{});
      w.put(11, scaled(az.ai0_sfu, p2(-2)));
      w.put(11, scaled(az.ai1_sfu_per_deg, p2(-8)));
      w.put(14, scaled(az.ai2_sfu_per_deg2, p2(-15)));
      w.put(5, 0);  // no ionospheric disturbance in any region
      w.put(10, scaled(r.group_delays.bgd_e1e5a_s, p2(-32)));
      w.put(10, scaled(r.group_delays.bgd_e1e5b_s, p2(-32)));
      w.put(2, e5b_hs(r.health));
      w.put(2, e1b_hs(r.health));
      w.put(1, e5b_dvs(r.health));
      w.put(1, e1b_dvs(r.health));
      w.put(12, gst_week & 0xFFF);
      w.put(20, tow_s);
      w.put(23, 0);
      break;
    }
    case 6:
      w.put(32, scaled(common.utc_a0_s, p2(-30)));
      w.put(24, scaled(common.utc_a1_s_per_s, p2(-50)));
      w.put(8, common.leap_seconds);
      w.put(8, common.utc_tot_s / 3600);
      w.put(8, common.utc_week & 0xFF);
      w.put(8, common.leap_week & 0xFF);
      w.put(3, common.leap_day);
      w.put(8, common.leap_seconds_future);
      w.put(20, tow_s);
      w.put(3, 0);
      break;
    default:  // 0: spare word with GST (time field '10')
      w.put(2, 2);
      w.put(88, 0);
      w.put(12, gst_week & 0xFFF);
      w.put(20, tow_s);
      break;
  }
  return w.bits;
}

std::uint32_t crc24q_bits(const std::vector<std::uint8_t>& bits) {
  std::uint32_t crc = 0;
  for (const std::uint8_t bit : bits) {
    const std::uint32_t top = ((crc >> 23) & 1U) ^ (bit & 1U);
    crc = (crc << 1) & 0xFFFFFFU;
    if (top != 0) crc ^= 0x864CFBU;
  }
  return crc;
}

std::array<std::array<std::uint8_t, 120>, 2> inav_page_parts(
    const std::array<std::uint8_t, kInavWordBits>& word) {
  std::array<std::array<std::uint8_t, 120>, 2> parts{};
  auto& even = parts[0];
  auto& odd = parts[1];
  // Even: even/odd 0, page type 0 (nominal), data j (the word's first 112 bits), tail.
  for (int i = 0; i < 112; ++i) even[static_cast<size_t>(2 + i)] = word[static_cast<size_t>(i)];
  // Odd: even/odd 1, page type 0, data k (the word's last 16 bits), reserved 1 (40), SAR (22),
  // spare (2), CRC (24), reserved 2 (8), tail.
  odd[0] = 1;
  for (int i = 0; i < 16; ++i) odd[static_cast<size_t>(2 + i)] = word[static_cast<size_t>(112 + i)];
  std::vector<std::uint8_t> covered(even.begin(), even.begin() + 114);
  covered.insert(covered.end(), odd.begin(), odd.begin() + 82);
  const std::uint32_t crc = crc24q_bits(covered);
  for (int i = 0; i < 24; ++i)
    odd[static_cast<size_t>(82 + i)] = static_cast<std::uint8_t>((crc >> (23 - i)) & 1U);
  return parts;
}

std::array<std::uint8_t, 240> inav_convolutional_code(const std::array<std::uint8_t, 120>& bits) {
  // The register holds the current bit in its most significant place (bit 6) and the six before it
  // below; each generator's octal digits tap it MSB first.
  constexpr std::uint32_t kG1 = 0171;
  constexpr std::uint32_t kG2 = 0133;
  std::array<std::uint8_t, 240> out{};
  std::uint32_t reg = 0;
  for (size_t i = 0; i < bits.size(); ++i) {
    reg = ((reg >> 1) | (static_cast<std::uint32_t>(bits[i] & 1U) << 6)) & 0x7FU;
    out[2 * i] = static_cast<std::uint8_t>(__builtin_parity(reg & kG1));
    out[2 * i + 1] = static_cast<std::uint8_t>(__builtin_parity(reg & kG2) ^ 1);  // G2 inverted
  }
  return out;
}

std::array<std::int8_t, kInavSymbolsPerPagePart> inav_part_symbols(
    const std::array<std::uint8_t, 120>& bits) {
  const std::array<std::uint8_t, 240> coded = inav_convolutional_code(bits);
  std::array<std::int8_t, kInavSymbolsPerPagePart> symbols{};
  for (size_t i = 0; i < kSyncPattern.size(); ++i)
    symbols[i] = static_cast<std::int8_t>(kSyncPattern[i] == 0 ? 1 : -1);
  // Block interleaver of 30 columns and 8 rows: written column by column, read row by row.
  constexpr int kRows = 8;
  constexpr int kColumns = 30;
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kColumns; ++c) {
      const std::uint8_t s = coded[static_cast<size_t>(c * kRows + r)];
      symbols[static_cast<size_t>(10 + r * kColumns + c)] =
          static_cast<std::int8_t>(s == 0 ? 1 : -1);
    }
  }
  return symbols;
}

}  // namespace skytrace::baseband
