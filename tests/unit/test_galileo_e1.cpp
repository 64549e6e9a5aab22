// Galileo E1 OS at the signal level: the memory codes against the ICD's hexadecimal, the CBOC
// waveform's power and shape, I/NAV pages decoded back (deinterleaved as GNSS-SDR does, through a
// Viterbi decoder and the CRC written here) into the record they came from, and the samples'
// pilot and data measured with a correlator written here. GNSS-SDR checks the same end to end in
// tests/integration/test_iq_gnss_sdr.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <map>
#include <numbers>
#include <string>

#include "skytrace/baseband/galileo_e1.hpp"
#include "skytrace/baseband/synthesizer.hpp"
#include "skytrace/core/constants.hpp"

namespace skytrace::baseband {
namespace {

std::uint32_t first_chips(const std::array<std::int8_t, kE1ChipsPerCode>& code, int n) {
  std::uint32_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 1) | (code[static_cast<size_t>(i)] < 0 ? 1U : 0U);
  return v;
}

TEST(GalileoE1, CodesStartWithTheIcdDigitsAndBarelyCorrelate) {
  // Annex C's first six hexadecimal digits of PRN 1 (logic 1 is -1).
  EXPECT_EQ(first_chips(*galileo_e1_primary_code(1, false), 24), 0xF5D710U);
  EXPECT_EQ(first_chips(*galileo_e1_primary_code(1, true), 24), 0xB39340U);
  EXPECT_FALSE(galileo_e1_primary_code(0, false));
  EXPECT_FALSE(galileo_e1_primary_code(51, true));
  // Memory codes: any two of PRN 1-50 (data and pilot) and any shift of one correlate far below
  // the 4092 of a code with itself.
  std::vector<std::array<std::int8_t, kE1ChipsPerCode>> codes;
  for (int prn = 1; prn <= 50; prn += 7) {
    codes.push_back(*galileo_e1_primary_code(prn, false));
    codes.push_back(*galileo_e1_primary_code(prn, true));
  }
  int worst = 0;
  for (size_t a = 0; a < codes.size(); ++a) {
    for (size_t b = a; b < codes.size(); ++b) {
      for (int shift = 0; shift < kE1ChipsPerCode; shift += a == b ? 1 : 97) {
        if (a == b && shift == 0) continue;
        int sum = 0;
        for (int i = 0; i < kE1ChipsPerCode; ++i) {
          sum += codes[a][static_cast<size_t>(i)] *
                 codes[b][static_cast<size_t>((i + shift) % kE1ChipsPerCode)];
        }
        worst = std::max(worst, std::abs(sum));
      }
    }
  }
  EXPECT_LT(worst, 300);
  // CS25_1: hexadecimal 380AD90's first 25 bits.
  std::uint32_t secondary = 0;
  for (std::int8_t chip : galileo_e1c_secondary_code())
    secondary = (secondary << 1) | (chip < 0 ? 1U : 0U);
  EXPECT_EQ(secondary, 0x380AD90U >> 3);
}

TEST(GalileoE1, CbocWaveformHasUnitPowerAndItsComponents) {
  const auto b = *galileo_e1_primary_code(11, false);
  const auto c = *galileo_e1_primary_code(11, true);
  for (int pilot_sign : {1, -1}) {
    const std::vector<float> w = galileo_e1_cboc_waveform(b, c, pilot_sign);
    ASSERT_EQ(w.size(), static_cast<size_t>(kE1ChipsPerCode * kE1SubchipsPerChip));
    double power = 0.0, data = 0.0, pilot = 0.0, boc61 = 0.0;
    for (size_t k = 0; k < w.size(); ++k) {
      const size_t chip = k / kE1SubchipsPerChip;
      const size_t j = k % kE1SubchipsPerChip;
      const double boc11 = j < 6 ? 1.0 : -1.0;
      power += w[k] * w[k];
      data += w[k] * b[chip] * boc11;   // a BOC(1,1) replica of E1-B
      pilot += w[k] * c[chip] * boc11;  // of E1-C
      boc61 += w[k] * b[chip] * (j % 2 == 0 ? 1.0 : -1.0);
    }
    const auto n = static_cast<double>(w.size());
    // Unit power but for the two codes' own correlation rho: 1 - pilot_sign (alpha^2 - beta^2) rho.
    double rho = 0.0;
    for (int i = 0; i < kE1ChipsPerCode; ++i)
      rho += b[static_cast<size_t>(i)] * c[static_cast<size_t>(i)];
    rho /= kE1ChipsPerCode;
    EXPECT_NEAR(power / n, 1.0 - pilot_sign * (9.0 / 11.0) * rho, 1e-6);
    EXPECT_NEAR(power / n, 1.0, 0.05);
    // alpha / sqrt(2) of each component on BOC(1,1) (the cross terms of two codes near zero); the
    // pilot with its sign and the ICD's minus; beta / sqrt(2) of E1-B on BOC(6,1).
    const double alpha = std::sqrt(10.0 / 11.0) / std::sqrt(2.0);
    EXPECT_NEAR(data / n, alpha, 0.03);
    EXPECT_NEAR(pilot / n, -pilot_sign * alpha, 0.03);
    EXPECT_NEAR(boc61 / n, std::sqrt(1.0 / 11.0) / std::sqrt(2.0), 0.03);
  }
}

// A hard-decision Viterbi decoder of the I/NAV code (K = 7, 171 and 133 octal, the second symbol
// of each pair inverted), starting and ending in the zero state.
std::vector<std::uint8_t> viterbi(const std::vector<std::uint8_t>& symbols) {
  const size_t bits = symbols.size() / 2;
  constexpr int kStates = 64;
  std::vector<int> metric(kStates, 1 << 20);
  metric[0] = 0;
  std::vector<std::array<int, kStates>> from(bits);
  std::vector<std::array<std::uint8_t, kStates>> input(bits);
  for (size_t i = 0; i < bits; ++i) {
    std::vector<int> next(kStates, 1 << 20);
    for (int state = 0; state < kStates;
         ++state) {  // state: the six previous bits, newest in bit 5
      for (std::uint32_t u = 0; u <= 1; ++u) {
        const std::uint32_t reg = (u << 6) | static_cast<std::uint32_t>(state);
        const std::uint32_t g1 = static_cast<std::uint32_t>(__builtin_parity(reg & 0171U));
        const std::uint32_t g2 = static_cast<std::uint32_t>(__builtin_parity(reg & 0133U)) ^ 1U;
        const int cost = metric[static_cast<size_t>(state)] + (g1 != symbols[2 * i] ? 1 : 0) +
                         (g2 != symbols[2 * i + 1] ? 1 : 0);
        const int to = static_cast<int>(reg >> 1);
        if (cost < next[static_cast<size_t>(to)]) {
          next[static_cast<size_t>(to)] = cost;
          from[i][static_cast<size_t>(to)] = state;
          input[i][static_cast<size_t>(to)] = static_cast<std::uint8_t>(u);
        }
      }
    }
    metric = next;
  }
  std::vector<std::uint8_t> out(bits);
  int state = 0;
  for (size_t i = bits; i-- > 0;) {
    out[i] = input[i][static_cast<size_t>(state)];
    state = from[i][static_cast<size_t>(state)];
  }
  return out;
}

// The 120 bits of a page part from its 250 symbols: the synchronisation pattern checked, the
// symbols deinterleaved as GNSS-SDR's deinterleaver(8, 30) does, then decoded.
std::vector<std::uint8_t> decode_part(
    const std::array<std::int8_t, kInavSymbolsPerPagePart>& symbols) {
  const std::array<int, 10> sync = {0, 1, 0, 1, 1, 0, 0, 0, 0, 0};
  for (size_t i = 0; i < sync.size(); ++i)
    EXPECT_EQ(symbols[i] < 0 ? 1 : 0, sync[i]) << "sync symbol " << i;
  std::vector<std::uint8_t> deinterleaved(240);
  for (int r = 0; r < 8; ++r) {
    for (int c = 0; c < 30; ++c) {
      deinterleaved[static_cast<size_t>(c * 8 + r)] =
          symbols[static_cast<size_t>(10 + r * 30 + c)] < 0 ? 1 : 0;
    }
  }
  return viterbi(deinterleaved);
}

// The 128 bits of a word: even part bits 2-113, odd part bits 2-17.
std::vector<std::uint8_t> word_of(const std::vector<std::uint8_t>& even,
                                  const std::vector<std::uint8_t>& odd) {
  std::vector<std::uint8_t> word(kInavWordBits);
  for (size_t i = 0; i < 112; ++i) word[i] = even[2 + i];
  for (size_t i = 0; i < 16; ++i) word[112 + i] = odd[2 + i];
  return word;
}

std::uint64_t field(const std::vector<std::uint8_t>& word, int& at, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 1) | word[static_cast<size_t>(at++)];
  return v;
}
std::int64_t signed_field(const std::vector<std::uint8_t>& word, int& at, int n) {
  const std::uint64_t v = field(word, at, n);
  return (v >> (n - 1)) != 0 ? static_cast<std::int64_t>(v) - (std::int64_t{1} << n)
                             : static_cast<std::int64_t>(v);
}

orbits::KeplerEphemeris sample_record() {
  orbits::KeplerEphemeris r;
  r.satellite = SatelliteId{GnssSystem::kGalileo, 24};
  r.message = orbits::NavMessage::kGalileoInav;
  r.toe = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  r.toc = r.toe;
  r.week = 2111;
  r.toe_sow = 345600.0;
  r.iode = 63;
  r.af0_s = 5.385041295085e-03;
  r.af1_s_per_s = -1.985256403714e-11;
  r.af2_s_per_s2 = 0.0;
  r.crs_m = 25.21875;
  r.delta_n_rad_per_s = 2.65653922695e-09;
  r.m0_rad = -0.6291263400373;
  r.cuc_rad = 1.190230250359e-06;
  r.eccentricity = 3.792505012825e-04;
  r.cus_rad = 1.065805554390e-05;
  r.sqrt_a_sqrtm = 5440.604196548;
  r.cic_rad = -1.676380634308e-08;
  r.omega0_rad = 0.2148454613587;
  r.cis_rad = 7.636845111847e-08;
  r.i0_rad = 0.9803631488374;
  r.crc_m = 120.96875;
  r.omega_rad = 0.8826948113934;
  r.omega_dot_rad_per_s = -5.267005106190e-09;
  r.idot_rad_per_s = -5.560945921433e-10;
  r.accuracy_m = 3.12;
  r.group_delays.bgd_e1e5a_s = 4.563480615616e-08;
  r.group_delays.bgd_e1e5b_s = 5.098991096020e-08;
  r.health = 0;
  return r;
}

TEST(GalileoE1, InavPagesDecodeBackToTheRecord) {
  const orbits::KeplerEphemeris r = sample_record();
  InavCommon common;
  common.ionosphere = orbits::NequickGCoefficients{66.25, 0.2578125, 0.01300048828125};
  common.utc_a0_s = 1.862645149231e-09;
  common.utc_a1_s_per_s = 8.881784197001e-16;
  common.leap_seconds = 18;
  constexpr int kGstWeek = 2111 - 1024;
  constexpr int kTow = 345630;
  auto decoded_word = [&](int type) {
    const auto parts = inav_page_parts(inav_word(type, r, common, kGstWeek, kTow));
    const auto even = decode_part(inav_part_symbols(parts[0]));
    const auto odd = decode_part(inav_part_symbols(parts[1]));
    EXPECT_EQ(even[0], 0);  // even part first
    EXPECT_EQ(odd[0], 1);
    for (int i = 114; i < 120; ++i) EXPECT_EQ(even[static_cast<size_t>(i)], 0);  // tails
    // CRC-24Q over even bits 0-113 and odd bits 0-81, in odd bits 82-105.
    std::vector<std::uint8_t> covered(even.begin(), even.begin() + 114);
    covered.insert(covered.end(), odd.begin(), odd.begin() + 82);
    std::uint32_t crc = 0;
    for (std::uint8_t bit : covered) {  // the CRC's own bitwise definition
      const bool top = ((crc >> 23) & 1U) != bit;
      crc = (crc << 1) & 0xFFFFFFU;
      if (top) crc ^= 0x864CFBU;
    }
    int at = 82;
    EXPECT_EQ(field(odd, at, 24), crc) << "word type " << type;
    const std::vector<std::uint8_t> word = word_of(even, odd);
    at = 0;
    EXPECT_EQ(field(word, at, 6), static_cast<std::uint64_t>(type));
    return word;
  };
  const double pi = constants::kPi;
  {
    const auto w = decoded_word(1);
    int at = 6;
    EXPECT_EQ(field(w, at, 10), 63U);
    EXPECT_EQ(field(w, at, 14) * 60, 345600U);
    EXPECT_NEAR(signed_field(w, at, 32) * std::ldexp(pi, -31), r.m0_rad, 1.5e-9);
    EXPECT_NEAR(field(w, at, 32) * std::ldexp(1.0, -33), r.eccentricity, 1e-10);
    EXPECT_NEAR(field(w, at, 32) * std::ldexp(1.0, -19), r.sqrt_a_sqrtm, 1e-6);
  }
  {
    const auto w = decoded_word(2);
    int at = 16;
    EXPECT_NEAR(signed_field(w, at, 32) * std::ldexp(pi, -31), r.omega0_rad, 1.5e-9);
    EXPECT_NEAR(signed_field(w, at, 32) * std::ldexp(pi, -31), r.i0_rad, 1.5e-9);
    EXPECT_NEAR(signed_field(w, at, 32) * std::ldexp(pi, -31), r.omega_rad, 1.5e-9);
    EXPECT_NEAR(signed_field(w, at, 14) * std::ldexp(pi, -43), r.idot_rad_per_s, 2e-13);
  }
  {
    const auto w = decoded_word(3);
    int at = 16;
    EXPECT_NEAR(signed_field(w, at, 24) * std::ldexp(pi, -43), r.omega_dot_rad_per_s, 2e-13);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(pi, -43), r.delta_n_rad_per_s, 2e-13);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(1.0, -29), r.cuc_rad, 1e-9);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(1.0, -29), r.cus_rad, 1e-9);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(1.0, -5), r.crc_m, 0.02);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(1.0, -5), r.crs_m, 0.02);
    EXPECT_EQ(field(w, at, 8), 107U);  // SISA 3.12 m: 100 + (3.12 - 2) / 0.16
  }
  {
    const auto w = decoded_word(4);
    int at = 16;
    EXPECT_EQ(field(w, at, 6), 24U);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(1.0, -29), r.cic_rad, 1e-9);
    EXPECT_NEAR(signed_field(w, at, 16) * std::ldexp(1.0, -29), r.cis_rad, 1e-9);
    EXPECT_EQ(field(w, at, 14) * 60, 345600U);
    EXPECT_NEAR(signed_field(w, at, 31) * std::ldexp(1.0, -34), r.af0_s, 1e-10);
    EXPECT_NEAR(signed_field(w, at, 21) * std::ldexp(1.0, -46), r.af1_s_per_s, 2e-14);
  }
  {
    const auto w = decoded_word(5);
    int at = 6;
    EXPECT_NEAR(field(w, at, 11) * 0.25, 66.25, 1e-9);
    EXPECT_NEAR(signed_field(w, at, 11) * std::ldexp(1.0, -8), 0.2578125, 1e-9);
    EXPECT_NEAR(signed_field(w, at, 14) * std::ldexp(1.0, -15), 0.01300048828125, 1e-9);
    at += 5;
    EXPECT_NEAR(signed_field(w, at, 10) * std::ldexp(1.0, -32), r.group_delays.bgd_e1e5a_s,
                2.4e-10);
    EXPECT_NEAR(signed_field(w, at, 10) * std::ldexp(1.0, -32), r.group_delays.bgd_e1e5b_s,
                2.4e-10);
    EXPECT_EQ(field(w, at, 6), 0U);  // E5b and E1-B signal health and data validity
    EXPECT_EQ(field(w, at, 12), static_cast<std::uint64_t>(kGstWeek));
    EXPECT_EQ(field(w, at, 20), static_cast<std::uint64_t>(kTow));
  }
  {
    const auto w = decoded_word(6);
    int at = 6;
    EXPECT_NEAR(signed_field(w, at, 32) * std::ldexp(1.0, -30), common.utc_a0_s, 1e-9);
    EXPECT_NEAR(signed_field(w, at, 24) * std::ldexp(1.0, -50), common.utc_a1_s_per_s, 1e-15);
    EXPECT_EQ(signed_field(w, at, 8), 18);
    at += 8 + 8 + 8 + 3 + 8;
    EXPECT_EQ(field(w, at, 20), static_cast<std::uint64_t>(kTow));
  }
  {
    const auto w = decoded_word(0);
    int at = 6;
    EXPECT_EQ(field(w, at, 2), 2U);
    at += 88;
    EXPECT_EQ(field(w, at, 12), static_cast<std::uint64_t>(kGstWeek));
    EXPECT_EQ(field(w, at, 20), static_cast<std::uint64_t>(kTow));
  }
  // A nominal subframe sends the ephemeris, ionosphere and GST-UTC once each.
  std::vector<int> types;
  for (int slot = 0; slot < 15; ++slot) types.push_back(inav_e1b_word_type(slot));
  for (int type = 1; type <= 6; ++type)
    EXPECT_EQ(std::count(types.begin(), types.end(), type), 1) << type;
}

TEST(GalileoE1, CodingFollowsTheIcdsVectors) {
  // CRC-24Q's check value ("123456789").
  std::vector<std::uint8_t> bits;
  for (const char ch : std::string("123456789")) {
    for (int i = 7; i >= 0; --i) bits.push_back(static_cast<std::uint8_t>((ch >> i) & 1));
  }
  EXPECT_EQ(crc24q_bits(bits), 0xCDE703U);
  // The OS SIS ICD's encoded SSP examples: the last 16 symbols of a page part whose last eight
  // data bits are the SSP word (then the tail).
  const std::array<std::pair<const char*, const char*>, 3> ssp = {
      {{"00000100", "1110100100100101"},
       {"00101011", "0110110001001110"},
       {"00101111", "1101000000111110"}}};
  for (const auto& [plain, encoded] : ssp) {
    std::array<std::uint8_t, 120> part{};
    for (int i = 0; i < 8; ++i)
      part[static_cast<size_t>(106 + i)] = static_cast<std::uint8_t>(plain[i] - '0');
    const auto coded = inav_convolutional_code(part);
    std::string last;
    for (size_t i = 224; i < 240; ++i) last += static_cast<char>('0' + coded[i]);
    EXPECT_EQ(last, encoded) << plain;
  }
}

// The band's symbols as transmitted: on E1-B the even page parts start at odd GST seconds, word 5
// at TOW 25 (mod 30) carrying that TOW.
TEST(GalileoE1, EvenPagePartsStartAtOddSecondsAndWordFiveAtTwentyFive) {
  const orbits::KeplerEphemeris record = sample_record();
  auto signals = make_galileo_e1_signals({}, 2111, [&](int, const GnssTime&) { return &record; });
  ASSERT_TRUE(signals->code(24, 0));
  constexpr std::int64_t kTow = 345625;  // 25 mod 30
  auto part_at = [&](std::int64_t tow_s) {
    std::array<std::int8_t, kInavSymbolsPerPagePart> symbols{};
    for (int i = 0; i < kInavSymbolsPerPagePart; ++i) {
      symbols[static_cast<size_t>(i)] =
          static_cast<std::int8_t>(signals->sign(24, tow_s * 250 + i));
    }
    return decode_part(symbols);
  };
  const auto even = part_at(kTow);
  const auto odd = part_at(kTow + 1);
  EXPECT_EQ(even[0], 0);
  EXPECT_EQ(odd[0], 1);
  const std::vector<std::uint8_t> word = word_of(even, odd);
  int at = 0;
  EXPECT_EQ(field(word, at, 6), 5U);
  at = 6 + 11 + 11 + 14 + 5 + 10 + 10 + 6;
  EXPECT_EQ(field(word, at, 12), 2111U - 1024U);
  EXPECT_EQ(field(word, at, 20), static_cast<std::uint64_t>(kTow));
  // Form: the pilot's secondary chip against the data symbol, one per 4 ms.
  const std::int64_t period = kTow * 250 + 7;
  EXPECT_EQ(
      signals->form(24, period),
      galileo_e1c_secondary_code()[static_cast<size_t>(period % 25)] == signals->sign(24, period)
          ? 0
          : 1);
}

// Noise-free samples of one satellite: per 4 ms code period the pilot's prompt follows E1-C's
// secondary code and the data's prompt the I/NAV symbols, both on the in-phase carrier.
TEST(GalileoE1, SamplesCarryThePilotsSecondaryCodeAndTheDataSymbols) {
  constexpr double fs = 8.184e6;
  constexpr int kPrn = 24;
  constexpr double kDoppler_hz = 2563.8;
  constexpr double kPseudorange0_m = 23'636'670.5;
  const double wavelength_m = constants::kSpeedOfLight_mps / kE1Carrier_hz;
  const orbits::KeplerEphemeris record = sample_record();
  SynthesizerSettings settings;
  settings.sample_rate_hz = fs;
  settings.format = SampleFormat::kGrComplex;
  settings.start = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  settings.noise = false;
  auto signals = make_galileo_e1_signals({}, 2111, [&](int, const GnssTime&) { return &record; });
  BandSignals* band = signals.get();
  BasebandSynthesizer synthesizer(settings, std::move(signals));
  auto arrival_at = [&](double t) {
    Arrival a;
    a.id = kPrn;
    a.carrier_hz = kE1Carrier_hz;
    a.pseudorange_m = kPseudorange0_m - kDoppler_hz * wavelength_m * t;
    a.carrier_phase_cycles = a.pseudorange_m / wavelength_m + 0.3;
    a.doppler_hz = kDoppler_hz;
    a.antenna_cn0_dbhz = 50.0;
    return a;
  };
  std::string bytes;
  ASSERT_TRUE(synthesizer.add_instant(0.0, {arrival_at(0.0)}, bytes));
  ASSERT_TRUE(synthesizer.add_instant(1.0, {arrival_at(1.0)}, bytes));
  const size_t samples = bytes.size() / 8;
  std::vector<std::complex<float>> x(samples);
  std::memcpy(x.data(), bytes.data(), bytes.size());

  const auto b = *galileo_e1_primary_code(kPrn, false);
  const auto c = *galileo_e1_primary_code(kPrn, true);
  const double start_ms = 345600.0 * 1000.0;
  // Sums over each whole code period of the transmission time, with BOC(1,1) replicas.
  std::map<std::int64_t, std::pair<std::complex<double>, std::complex<double>>>
      prompts;  // period: data, pilot
  for (size_t k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) / fs;
    const Arrival a = arrival_at(t);
    const double tx_periods =
        ((t - a.pseudorange_m / constants::kSpeedOfLight_mps) * 1000.0 + start_ms) / 4.0;
    const auto period = static_cast<std::int64_t>(std::floor(tx_periods));
    const double chip = (tx_periods - static_cast<double>(period)) * kE1ChipsPerCode;
    const auto chip_index = static_cast<size_t>(chip);
    const double boc = chip - std::floor(chip) < 0.5 ? 1.0 : -1.0;
    const std::complex<double> derotated =
        std::complex<double>(x[k]) *
        std::polar(1.0, 2.0 * std::numbers::pi * a.carrier_phase_cycles);
    auto& [data, pilot] = prompts[period];
    data += derotated * (b[chip_index] * boc);
    pilot += derotated * (c[chip_index] * boc);
  }
  prompts.erase(prompts.begin());  // partial periods at either end
  prompts.erase(std::prev(prompts.end()));
  ASSERT_GE(prompts.size(), 240U);
  int secondary_wrong = 0, symbols_wrong = 0;
  double quadrature = 0.0, in_phase = 0.0;
  for (const auto& [period, p] : prompts) {
    const int secondary = galileo_e1c_secondary_code()[static_cast<size_t>(period % 25)];
    // E1-C enters with the ICD's minus sign.
    secondary_wrong += (p.second.real() < 0 ? 1 : -1) != secondary ? 1 : 0;
    symbols_wrong += (p.first.real() > 0 ? 1 : -1) != band->sign(kPrn, period) ? 1 : 0;
    quadrature += std::abs(p.first.imag()) + std::abs(p.second.imag());
    in_phase += std::abs(p.first.real()) + std::abs(p.second.real());
  }
  EXPECT_EQ(secondary_wrong, 0);
  EXPECT_EQ(symbols_wrong, 0);
  EXPECT_LT(quadrature, 0.02 * in_phase);
}

}  // namespace
}  // namespace skytrace::baseband
