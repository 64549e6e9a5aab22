#include "skytrace/baseband/glonass_l1of.hpp"

#include <cmath>
#include <initializer_list>

namespace skytrace::baseband {
namespace {

// Writes `value` into bits first..first-n+1 (ICD numbering, 85..1), MSB first.
void put(std::array<std::uint8_t, kGlonassStringBits>& bits, int first, int n, std::uint64_t value) {
  for (int i = 0; i < n; ++i) {
    const int bit_number = first - i;
    bits[static_cast<size_t>(kGlonassStringBits - bit_number)] =
        static_cast<std::uint8_t>((value >> (n - 1 - i)) & 1U);
  }
}
// Sign and magnitude (the ICD's signed fields): the sign in the first bit, 1 for negative.
void put_signed(std::array<std::uint8_t, kGlonassStringBits>& bits, int first, int n, double value, double lsb) {
  const auto magnitude = static_cast<std::uint64_t>(std::llround(std::abs(value) / lsb));
  put(bits, first, 1, value < 0.0 && magnitude != 0 ? 1 : 0);
  put(bits, first - 1, n - 1, magnitude);
}
int bit(const std::array<std::uint8_t, kGlonassStringBits>& bits, int number) {
  return bits[static_cast<size_t>(kGlonassStringBits - number)];
}

// The data bits each check bit covers (ICD 4.7), as bit numbers.
std::array<std::vector<int>, 7> hamming_sets() {
  std::array<std::vector<int>, 7> sets;
  const std::initializer_list<int> i = {9,  10, 12, 13, 15, 17, 19, 20, 22, 24, 26, 28, 30, 32, 34, 35, 37, 39, 41, 43, 45,
                                        47, 49, 51, 53, 55, 57, 59, 61, 63, 65, 66, 68, 70, 72, 74, 76, 78, 80, 82, 84};
  const std::initializer_list<int> j = {9,  11, 12, 14, 15, 18, 19, 21, 22, 25, 26, 29, 30, 33, 34, 36, 37, 40, 41, 44, 45,
                                        48, 49, 52, 53, 56, 57, 60, 61, 64, 65, 67, 68, 71, 72, 75, 76, 79, 80, 83, 84};
  sets[0] = i;
  sets[1] = j;
  auto ranges = [](std::initializer_list<std::pair<int, int>> r) {
    std::vector<int> v;
    for (auto [a, b] : r) {
      for (int k = a; k <= b; ++k) v.push_back(k);
    }
    return v;
  };
  sets[2] = ranges({{10, 12}, {16, 19}, {23, 26}, {31, 34}, {38, 41}, {46, 49}, {54, 57}, {62, 65}, {69, 72}, {77, 80}, {84, 84}});
  sets[3] = ranges({{13, 19}, {27, 34}, {42, 49}, {58, 65}, {73, 80}});
  sets[4] = ranges({{20, 34}, {50, 65}, {81, 84}});
  sets[5] = ranges({{35, 65}});
  sets[6] = ranges({{66, 84}});
  return sets;
}

}  // namespace

const std::array<std::int8_t, kGlonassCodeLength>& glonass_ranging_code() {
  static const std::array<std::int8_t, kGlonassCodeLength> code = [] {
    std::array<std::int8_t, kGlonassCodeLength> c{};
    std::uint32_t r = 0x1FF;  // stage 1 in bit 0 ... stage 9 in bit 8
    for (int n = 0; n < kGlonassCodeLength; ++n) {
      const std::uint32_t out = (r >> 6) & 1U;  // the 7th stage
      c[static_cast<size_t>(n)] = static_cast<std::int8_t>(out == 0 ? 1 : -1);
      const std::uint32_t feedback = ((r >> 4) ^ (r >> 8)) & 1U;  // stages 5 and 9
      r = ((r << 1) | feedback) & 0x1FF;
    }
    return c;
  }();
  return code;
}

void set_gnav_hamming(std::array<std::uint8_t, kGlonassStringBits>& bits) {
  static const auto sets = hamming_sets();
  for (size_t k = 0; k < sets.size(); ++k) {
    int parity = 0;
    for (int b : sets[k]) parity ^= bit(bits, b);
    put(bits, static_cast<int>(k) + 1, 1, static_cast<std::uint64_t>(parity));
  }
  int all = 0;
  for (int b = 1; b <= 7; ++b) all ^= bit(bits, b);
  for (int b = 9; b <= kGlonassStringBits; ++b) all ^= bit(bits, b);
  put(bits, 8, 1, static_cast<std::uint64_t>(all));
}

std::array<std::uint8_t, kGlonassStringBits> gnav_string(const orbits::GlonassEphemeris& e, const GnavCommon& common,
                                                         int string_number, int frame_start_mt,
                                                         int day_in_four_years, int four_year_interval) {
  std::array<std::uint8_t, kGlonassStringBits> b{};
  put(b, 84, 4, static_cast<std::uint64_t>(string_number));
  constexpr double kKm = 1e-3;
  // t_b: the 15-minute interval of the Moscow day at whose middle the record holds.
  const double toe_mt_s = std::fmod(e.toe.gpst_seconds_approx() - gps_minus_utc_s(e.toe) + 10800.0, 86400.0);
  const auto t_b = static_cast<std::uint64_t>(std::llround(toe_mt_s / 900.0)) % 96;
  switch (string_number) {
    case 1: {
      put(b, 78, 2, 1);  // P1: 30 minutes between adjacent t_b
      const int hours = frame_start_mt / 3600;
      const int minutes = (frame_start_mt % 3600) / 60;
      const int half = (frame_start_mt % 60) / 30;
      put(b, 76, 5, static_cast<std::uint64_t>(hours));
      put(b, 71, 6, static_cast<std::uint64_t>(minutes));
      put(b, 65, 1, static_cast<std::uint64_t>(half));
      put_signed(b, 64, 24, e.velocity_mps.x() * kKm, std::ldexp(1.0, -20));
      put_signed(b, 40, 5, e.acceleration_mps2.x() * kKm, std::ldexp(1.0, -30));
      put_signed(b, 35, 27, e.position_m.x() * kKm, std::ldexp(1.0, -11));
      break;
    }
    case 2:
      put(b, 80, 3, e.health != 0 ? 4 : 0);  // B_n: its MSB flags the satellite unhealthy
      put(b, 77, 1, t_b & 1U);                // P2: t_b odd
      put(b, 76, 7, t_b);
      put_signed(b, 64, 24, e.velocity_mps.y() * kKm, std::ldexp(1.0, -20));
      put_signed(b, 40, 5, e.acceleration_mps2.y() * kKm, std::ldexp(1.0, -30));
      put_signed(b, 35, 27, e.position_m.y() * kKm, std::ldexp(1.0, -11));
      break;
    case 3:
      put(b, 80, 1, 0);  // P3: almanac of 4 satellites in this frame (none here)
      put_signed(b, 79, 11, e.gamma_n, std::ldexp(1.0, -40));
      put(b, 67, 2, 0);  // P
      put(b, 65, 1, e.health != 0 ? 1 : 0);  // l_n
      put_signed(b, 64, 24, e.velocity_mps.z() * kKm, std::ldexp(1.0, -20));
      put_signed(b, 40, 5, e.acceleration_mps2.z() * kKm, std::ldexp(1.0, -30));
      put_signed(b, 35, 27, e.position_m.z() * kKm, std::ldexp(1.0, -11));
      break;
    case 4:
      put_signed(b, 80, 22, -e.minus_tau_n_s, std::ldexp(1.0, -30));
      put_signed(b, 58, 5, e.delta_tau_n_s.value_or(0.0), std::ldexp(1.0, -30));
      put(b, 53, 5, static_cast<std::uint64_t>(std::llround(e.age_days)) & 0x1F);
      put(b, 34, 1, 0);  // P4
      put(b, 33, 4, 0);  // F_T
      put(b, 26, 11, static_cast<std::uint64_t>(day_in_four_years));
      put(b, 15, 5, e.satellite.number);
      put(b, 10, 2, 1);  // M: GLONASS-M
      break;
    case 5:
      put(b, 80, 11, static_cast<std::uint64_t>(day_in_four_years));  // N_A
      put_signed(b, 69, 32, common.tau_c_s, std::ldexp(1.0, -31));
      put(b, 36, 5, static_cast<std::uint64_t>(four_year_interval));
      put_signed(b, 31, 22, common.tau_gps_s, std::ldexp(1.0, -30));
      put(b, 9, 1, e.health != 0 ? 1 : 0);
      break;
    default:
      // Almanac strings: C_n, M_n and an empty slot (n_A = 0), the rest zero.
      if (string_number % 2 == 0) put(b, 79, 2, 1);
      break;
  }
  set_gnav_hamming(b);
  return b;
}

std::array<std::int8_t, kGlonassSymbolsPerString> gnav_symbols(const std::array<std::uint8_t, kGlonassStringBits>& bits) {
  std::array<std::int8_t, kGlonassSymbolsPerString> s{};
  // Relative code: each bit is the sum of the data bit and the relative bit before it (the first,
  // the idle bit, starts the chain at 0); then each relative bit as two 10 ms halves, (1, 0) for a
  // one and (0, 1) for a zero (the meander). Symbols: logic 1 is +1.
  int relative = 0;
  for (int i = 0; i < kGlonassStringBits; ++i) {
    relative = i == 0 ? 0 : (relative ^ bits[static_cast<size_t>(i)]);
    s[static_cast<size_t>(2 * i)] = static_cast<std::int8_t>(relative != 0 ? 1 : -1);
    s[static_cast<size_t>(2 * i + 1)] = static_cast<std::int8_t>(relative != 0 ? -1 : 1);
  }
  constexpr std::array<int, 30> kTimeMark = {1, 1, 1, 1, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 0,
                                             1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1, 1, 0};
  for (size_t k = 0; k < kTimeMark.size(); ++k) s[170 + k] = static_cast<std::int8_t>(kTimeMark[k] != 0 ? 1 : -1);
  return s;
}

}  // namespace skytrace::baseband
