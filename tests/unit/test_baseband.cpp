// GPS L1 C/A at the signal level: the Gold codes against IS-GPS-200's table, the LNAV parity
// against the decoders' mask form of the same equations, subframes decoded back by an independent
// reader of this test into the record they came from, and the samples' power, code phase and
// carrier measured with a correlator written here.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <map>
#include <numbers>
#include <random>

#include "skytrace/baseband/beidou_b1i.hpp"
#include "skytrace/baseband/gps_l1ca.hpp"
#include "skytrace/baseband/synthesizer.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::baseband {
namespace {

// IS-GPS-200 Table 3-Ia: the first 10 chips of PRN 1-32 in octal (first chip the leading bit).
constexpr std::array<int, 32> kFirstTenChipsOctal = {01440, 01620, 01710, 01744, 01133, 01455, 01131, 01454,
                                                     01626, 01504, 01642, 01750, 01764, 01772, 01775, 01776,
                                                     01156, 01467, 01633, 01715, 01746, 01763, 01063, 01706,
                                                     01743, 01761, 01770, 01774, 01127, 01453, 01625, 01712};

TEST(GpsCaCode, FirstTenChipsMatchTheIcdTable) {
  for (int prn = 1; prn <= 32; ++prn) {
    auto code = gps_ca_code(prn);
    ASSERT_TRUE(code);
    int first_ten = 0;
    for (int i = 0; i < 10; ++i) first_ten = (first_ten << 1) | ((*code)[static_cast<size_t>(i)] < 0 ? 1 : 0);
    EXPECT_EQ(first_ten, kFirstTenChipsOctal[static_cast<size_t>(prn - 1)]) << "PRN " << prn;
  }
  EXPECT_FALSE(gps_ca_code(0));
  EXPECT_FALSE(gps_ca_code(33));
}

TEST(GpsCaCode, GoldCodesCorrelateAtTheThreeLevels) {
  // Periodic auto- (off peak) and cross-correlations of Gold codes of degree 10 take only the
  // values -65, -1 and 63; each code has 512 ones and 511 zeros.
  std::vector<std::array<std::int8_t, kCaCodeLength>> codes;
  for (int prn = 1; prn <= 32; ++prn) codes.push_back(*gps_ca_code(prn));
  for (size_t a = 0; a < codes.size(); a += 7) {
    int sum = 0;
    for (auto c : codes[a]) sum += c;
    EXPECT_EQ(sum, -1);  // one more -1 (logic 1) than +1
    for (size_t b = a; b < codes.size(); b += 5) {
      for (int lag = 0; lag < kCaCodeLength; lag += 31) {
        if (a == b && lag == 0) continue;
        int r = 0;
        for (int i = 0; i < kCaCodeLength; ++i) {
          r += codes[a][static_cast<size_t>(i)] * codes[b][static_cast<size_t>((i + lag) % kCaCodeLength)];
        }
        EXPECT_TRUE(r == -65 || r == -1 || r == 63) << a + 1 << " " << b + 1 << " lag " << lag << ": " << r;
      }
    }
  }
}

// The decoders' form of the parity equations (IS-GPS-200 20.3.5.2): D29*, D30* and D1-D30 in a
// 32-bit word, one mask per parity bit.
int mask_parity(std::uint32_t word32) {
  constexpr std::array<std::uint32_t, 6> kMasks = {0xBB1F3480, 0x5D8F9A40, 0xAEC7CD00, 0x5763E680, 0x6BB1F340, 0x8B7A89C0};
  if ((word32 & 0x40000000U) != 0) word32 ^= 0x3FFFFFC0U;  // D30* set: the data bits came complemented
  int parity = 0;
  for (std::uint32_t mask : kMasks) {
    parity <<= 1;
    parity |= static_cast<int>(__builtin_popcount(word32 & mask) & 1);
  }
  return parity;
}

TEST(Lnav, ParityAgreesWithTheMaskFormOfTheIcdEquations) {
  std::mt19937 random(7);
  for (int i = 0; i < 2000; ++i) {
    const std::uint32_t data = random() & 0xFFFFFF;
    const bool d29 = (random() & 1) != 0;
    const bool d30 = (random() & 1) != 0;
    const std::uint32_t word = lnav_word(data, d29, d30);
    const std::uint32_t word32 = (d29 ? 0x80000000U : 0U) | (d30 ? 0x40000000U : 0U) | word;
    EXPECT_EQ(static_cast<int>(word & 0x3F), mask_parity(word32));
    EXPECT_TRUE(lnav_parity_ok(word, d29, d30));
    EXPECT_FALSE(lnav_parity_ok(word ^ (1U << (6 + random() % 24)), d29, d30));  // one data bit flipped
    // The data bits go out complemented after a word ending in 1.
    EXPECT_EQ((word >> 6) & 0xFFFFFF, d30 ? (~data & 0xFFFFFF) : data);
  }
}

// An LNAV reader of this test: words checked and uncomplemented, fields read by bit position.
class SubframeReader {
 public:
  explicit SubframeReader(const std::array<std::uint8_t, kLnavBitsPerSubframe>& bits) {
    bool d29 = false;
    bool d30 = false;
    for (int w = 0; w < 10; ++w) {
      std::uint32_t word = 0;
      for (int b = 0; b < 30; ++b) word = (word << 1) | bits[static_cast<size_t>(30 * w + b)];
      const std::uint32_t word32 = (d29 ? 0x80000000U : 0U) | (d30 ? 0x40000000U : 0U) | word;
      parity_ok_ = parity_ok_ && static_cast<int>(word & 0x3F) == mask_parity(word32);
      std::uint32_t data = (word >> 6) & 0xFFFFFF;
      if (d30) data = ~data & 0xFFFFFF;
      data_[static_cast<size_t>(w)] = data;
      d29 = ((word >> 1) & 1U) != 0;
      d30 = (word & 1U) != 0;
    }
    last_two_bits_ = (d29 ? 2 : 0) | (d30 ? 1 : 0);
  }
  [[nodiscard]] bool parity_ok() const { return parity_ok_; }
  [[nodiscard]] int last_two_bits() const { return last_two_bits_; }
  [[nodiscard]] std::uint64_t bits(int word, int first, int n) const {
    return (data_[static_cast<size_t>(word - 1)] >> (24 - (first + n - 1))) & ((std::uint64_t{1} << n) - 1);
  }
  [[nodiscard]] std::int64_t signed_bits(int word, int first, int n) const { return to_signed(bits(word, first, n), n); }
  // A field of n_msb bits at the end of `word` and the rest at the start of the next.
  [[nodiscard]] std::uint64_t split(int word, int first, int n_msb, int n_total) const {
    return (bits(word, first, n_msb) << (n_total - n_msb)) | bits(word + 1, 1, n_total - n_msb);
  }
  [[nodiscard]] static std::int64_t to_signed(std::uint64_t v, int n) {
    return (v & (std::uint64_t{1} << (n - 1))) != 0 ? static_cast<std::int64_t>(v) - (std::int64_t{1} << n)
                                                     : static_cast<std::int64_t>(v);
  }

 private:
  std::array<std::uint32_t, 10> data_{};
  bool parity_ok_ = true;
  int last_two_bits_ = 0;
};

TEST(Lnav, SubframesDecodeBackToTheBroadcastRecord) {
  const auto nav_file = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  if (!std::filesystem::exists(nav_file)) GTEST_SKIP() << "ESBC navigation file absent";
  auto nav = orbits::read_rinex_nav(nav_file);
  ASSERT_TRUE(nav);
  int checked = 0;
  for (const orbits::KeplerEphemeris& eph : nav->kepler) {
    if (eph.satellite.system != GnssSystem::kGps || checked >= 12) continue;
    ++checked;
    LnavCommon common;
    common.ionosphere = nav->ionosphere.gps;
    const WeekTow toe = eph.toe.to_week_tow(TimeScale::kGpst);
    const int frame_sow = static_cast<int>(std::floor(toe.tow_s / 30.0)) * 30;  // subframe 1 of a frame
    std::array<SubframeReader, 5> sf = {SubframeReader(lnav_subframe(eph, common, toe.week, frame_sow)),
                                        SubframeReader(lnav_subframe(eph, common, toe.week, frame_sow + 6)),
                                        SubframeReader(lnav_subframe(eph, common, toe.week, frame_sow + 12)),
                                        SubframeReader(lnav_subframe(eph, common, toe.week, frame_sow + 18)),
                                        SubframeReader(lnav_subframe(eph, common, toe.week, frame_sow + 24))};
    for (int i = 0; i < 5; ++i) {
      SCOPED_TRACE(eph.satellite.to_string() + " subframe " + std::to_string(i + 1));
      EXPECT_TRUE(sf[static_cast<size_t>(i)].parity_ok());
      EXPECT_EQ(sf[static_cast<size_t>(i)].last_two_bits(), 0);  // t bits zero D29 and D30
      EXPECT_EQ(sf[static_cast<size_t>(i)].bits(1, 1, 8), 0x8Bu);  // preamble
      EXPECT_EQ(sf[static_cast<size_t>(i)].bits(2, 20, 3), static_cast<std::uint64_t>(i + 1));
      EXPECT_EQ(sf[static_cast<size_t>(i)].bits(2, 1, 17), static_cast<std::uint64_t>((frame_sow + 6 * i + 6) / 6));
    }
    const double pi = constants::kPi;
    // Each field back within half its least significant bit (the RINEX values are the broadcast
    // integers scaled, so the round trip is exact up to the file's decimal digits).
    auto near = [](double decoded, double expected, double lsb, const char* what) {
      EXPECT_NEAR(decoded, expected, 0.5 * lsb + 1e-12 * std::abs(expected)) << what;
    };
    const SubframeReader& s1 = sf[0];
    EXPECT_EQ(static_cast<int>(s1.bits(3, 1, 10)), toe.week % 1024);
    EXPECT_EQ(static_cast<int>(s1.bits(3, 17, 6)), eph.health & 0x3F);
    EXPECT_EQ(static_cast<int>((s1.bits(3, 23, 2) << 8) | s1.bits(8, 1, 8)), eph.iodc);
    near(std::ldexp(static_cast<double>(s1.signed_bits(7, 17, 8)), -31), eph.group_delays.tgd_s, std::ldexp(1.0, -31), "TGD");
    near(static_cast<double>(s1.bits(8, 9, 16)) * 16.0, eph.toc.to_week_tow(TimeScale::kGpst).tow_s, 16.0, "toc");
    near(std::ldexp(static_cast<double>(s1.signed_bits(9, 1, 8)), -55), eph.af2_s_per_s2, std::ldexp(1.0, -55), "af2");
    near(std::ldexp(static_cast<double>(s1.signed_bits(9, 9, 16)), -43), eph.af1_s_per_s, std::ldexp(1.0, -43), "af1");
    near(std::ldexp(static_cast<double>(s1.signed_bits(10, 1, 22)), -31), eph.af0_s, std::ldexp(1.0, -31), "af0");
    const SubframeReader& s2 = sf[1];
    EXPECT_EQ(static_cast<int>(s2.bits(3, 1, 8)), eph.iode);
    near(std::ldexp(static_cast<double>(s2.signed_bits(3, 9, 16)), -5), eph.crs_m, std::ldexp(1.0, -5), "Crs");
    near(std::ldexp(static_cast<double>(s2.signed_bits(4, 1, 16)), -43) * pi, eph.delta_n_rad_per_s,
         std::ldexp(1.0, -43) * pi, "delta n");
    near(std::ldexp(static_cast<double>(SubframeReader::to_signed(s2.split(4, 17, 8, 32), 32)), -31) * pi, eph.m0_rad,
         std::ldexp(1.0, -31) * pi, "M0");
    near(std::ldexp(static_cast<double>(s2.signed_bits(6, 1, 16)), -29), eph.cuc_rad, std::ldexp(1.0, -29), "Cuc");
    near(std::ldexp(static_cast<double>(s2.split(6, 17, 8, 32)), -33), eph.eccentricity, std::ldexp(1.0, -33), "e");
    near(std::ldexp(static_cast<double>(s2.signed_bits(8, 1, 16)), -29), eph.cus_rad, std::ldexp(1.0, -29), "Cus");
    near(std::ldexp(static_cast<double>(s2.split(8, 17, 8, 32)), -19), eph.sqrt_a_sqrtm, std::ldexp(1.0, -19), "sqrt A");
    near(static_cast<double>(s2.bits(10, 1, 16)) * 16.0, eph.toe_sow, 16.0, "toe");
    const SubframeReader& s3 = sf[2];
    near(std::ldexp(static_cast<double>(s3.signed_bits(3, 1, 16)), -29), eph.cic_rad, std::ldexp(1.0, -29), "Cic");
    near(std::ldexp(static_cast<double>(SubframeReader::to_signed(s3.split(3, 17, 8, 32), 32)), -31) * pi,
         eph.omega0_rad, std::ldexp(1.0, -31) * pi, "Omega0");
    near(std::ldexp(static_cast<double>(s3.signed_bits(5, 1, 16)), -29), eph.cis_rad, std::ldexp(1.0, -29), "Cis");
    near(std::ldexp(static_cast<double>(SubframeReader::to_signed(s3.split(5, 17, 8, 32), 32)), -31) * pi, eph.i0_rad,
         std::ldexp(1.0, -31) * pi, "i0");
    near(std::ldexp(static_cast<double>(s3.signed_bits(7, 1, 16)), -5), eph.crc_m, std::ldexp(1.0, -5), "Crc");
    near(std::ldexp(static_cast<double>(SubframeReader::to_signed(s3.split(7, 17, 8, 32), 32)), -31) * pi,
         eph.omega_rad, std::ldexp(1.0, -31) * pi, "omega");
    near(std::ldexp(static_cast<double>(s3.signed_bits(9, 1, 24)), -43) * pi, eph.omega_dot_rad_per_s,
         std::ldexp(1.0, -43) * pi, "Omega dot");
    EXPECT_EQ(static_cast<int>(s3.bits(10, 1, 8)), eph.iode);
    near(std::ldexp(static_cast<double>(s3.signed_bits(10, 9, 14)), -43) * pi, eph.idot_rad_per_s,
         std::ldexp(1.0, -43) * pi, "IDOT");
  }
  EXPECT_GE(checked, 12);
  // Subframe 4 page 18 (frames 18 and 43 of the 25): the ionosphere, SV ID 56.
  ASSERT_TRUE(nav->ionosphere.gps.has_value());
  LnavCommon common;
  common.ionosphere = nav->ionosphere.gps;
  const int page18_sow = 17 * 30 + 18;  // frame 18 (page 18), subframe 4
  const SubframeReader s4(lnav_subframe(nav->kepler.front(), common, 2111, page18_sow));
  EXPECT_TRUE(s4.parity_ok());
  EXPECT_EQ(s4.bits(3, 3, 6), 56u);
  EXPECT_NEAR(std::ldexp(static_cast<double>(s4.signed_bits(3, 9, 8)), -30), nav->ionosphere.gps->alpha[0], std::ldexp(1.0, -31));
  EXPECT_NEAR(std::ldexp(static_cast<double>(s4.signed_bits(5, 17, 8)), 16), nav->ionosphere.gps->beta[3], std::ldexp(1.0, 15));
}

// A correlator of this test over samples of one satellite without data: the prompt sums per
// millisecond with the code and carrier the test expects, and one with another PRN for the noise.
TEST(BasebandSynthesizer, CorrelatorMeasuresTheCn0CodeDelayAndCarrierItWasGiven) {
  constexpr double fs = 4.092e6;  // not a multiple of the chip rate's 1 ms: blocks of 4092 samples
  constexpr double kCn0_dbhz = 44.0;
  constexpr double kPseudorange0_m = 21'234'567.8;
  constexpr double kDoppler_hz = -1234.5;
  const double wavelength_m = constants::kSpeedOfLight_mps / 1575.42e6;
  SynthesizerSettings settings;
  settings.sample_rate_hz = fs;
  settings.format = SampleFormat::kGrComplex;
  settings.start = GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0);
  settings.seed = 3;
  BasebandSynthesizer synthesizer(settings, make_gps_l1ca_signals({}, 2111, nullptr));
  // A constant Doppler: the range falls at -D lambda; the phase in cycles follows the range.
  auto arrival_at = [&](double t) {
    Arrival a;
    a.id = 5;
    a.pseudorange_m = kPseudorange0_m - kDoppler_hz * wavelength_m * t;
    a.carrier_phase_cycles = a.pseudorange_m / wavelength_m + 0.3;
    a.doppler_hz = kDoppler_hz;
    a.antenna_cn0_dbhz = kCn0_dbhz;
    return a;
  };
  std::string bytes;
  ASSERT_TRUE(synthesizer.add_instant(0.0, {arrival_at(0.0)}, bytes));
  ASSERT_TRUE(synthesizer.add_instant(0.5, {arrival_at(0.5)}, bytes));
  const size_t samples = bytes.size() / 8;
  ASSERT_EQ(samples, static_cast<size_t>(0.5 * fs));
  std::vector<std::complex<float>> x(samples);
  std::memcpy(x.data(), bytes.data(), bytes.size());

  const auto code = *gps_ca_code(5);
  const auto other = *gps_ca_code(17);
  const double start_ms = 345600.0 * 1000.0;
  // Replica at a code offset (chips) from the expected one; sums per ms.
  auto correlate = [&](const std::array<std::int8_t, kCaCodeLength>& c, double offset_chips) {
    std::vector<std::complex<double>> sums;
    const auto per_ms = static_cast<size_t>(fs / 1000.0);
    for (size_t m = 0; m + per_ms <= samples; m += per_ms) {
      std::complex<double> sum = 0.0;
      for (size_t k = m; k < m + per_ms; ++k) {
        const double t = static_cast<double>(k) / fs;
        const Arrival a = arrival_at(t);
        const double tx_ms = (t - a.pseudorange_m / constants::kSpeedOfLight_mps) * 1000.0 + start_ms;
        double chip = (tx_ms - std::floor(tx_ms)) * kCaCodeLength + offset_chips;
        chip -= kCaCodeLength * std::floor(chip / kCaCodeLength);
        const double phase = -2.0 * std::numbers::pi * a.carrier_phase_cycles;
        sum += std::complex<double>(x[k]) * static_cast<double>(c[static_cast<size_t>(chip)]) *
               std::polar(1.0, -phase);
      }
      sums.push_back(sum);
    }
    return sums;
  };
  auto mean_power = [](const std::vector<std::complex<double>>& v) {
    double p = 0.0;
    for (const auto& s : v) p += std::norm(s);
    return p / static_cast<double>(v.size());
  };
  const auto prompt = correlate(code, 0.0);
  const double noise = mean_power(correlate(other, 0.0));
  const double measured_dbhz = 10.0 * std::log10((mean_power(prompt) - noise) / noise / 1e-3);
  EXPECT_NEAR(measured_dbhz, kCn0_dbhz, 0.5);
  // One chip off, the code no longer correlates; half a chip off, half the amplitude.
  EXPECT_LT(mean_power(correlate(code, 1.0)) - noise, 0.02 * (mean_power(prompt) - noise));
  const double half = std::sqrt((mean_power(correlate(code, 0.5)) - noise) / (mean_power(prompt) - noise));
  EXPECT_NEAR(half, 0.5, 0.08);
  // The carrier: the prompt's phase stays where the replica puts it (no Doppler left, no offset).
  std::complex<double> total = 0.0;
  for (const auto& s : prompt) total += s;
  EXPECT_LT(std::abs(std::arg(total)), 0.05);
  EXPECT_GT(std::abs(total) / static_cast<double>(prompt.size()), 0.9 * std::sqrt(mean_power(prompt) - noise));
}

TEST(BasebandSynthesizer, FormatsScaleTheSameNoise) {
  for (const char* name : {"sc8", "sc16", "gr_complex"}) {
    auto format = parse_sample_format(name);
    ASSERT_TRUE(format);
    SynthesizerSettings settings;
    settings.format = *format;
    BasebandSynthesizer synthesizer(settings, make_gps_l1ca_signals({}, 2111, nullptr));
    std::string bytes;
    ASSERT_TRUE(synthesizer.add_instant(0.0, {}, bytes));
    ASSERT_TRUE(synthesizer.add_instant(0.01, {}, bytes));
    ASSERT_EQ(bytes.size(), static_cast<size_t>(40000 * bytes_per_sample(*format)));
    double sum2 = 0.0;
    const size_t n = 2 * 40000;
    for (size_t i = 0; i < n; ++i) {
      double v = 0.0;
      if (*format == SampleFormat::kSc8) v = static_cast<std::int8_t>(bytes[i]);
      if (*format == SampleFormat::kSc16) {
        std::int16_t s = 0;
        std::memcpy(&s, bytes.data() + 2 * i, 2);
        v = s;
      }
      if (*format == SampleFormat::kGrComplex) {
        float f = 0.0F;
        std::memcpy(&f, bytes.data() + 4 * i, 4);
        v = f;
      }
      sum2 += v * v;
    }
    EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(n)) / synthesizer.noise_sigma(), 1.0, 0.02) << name;
  }
  EXPECT_FALSE(parse_sample_format("sc4"));
}

}  // namespace
}  // namespace skytrace::baseband

namespace skytrace::baseband {
namespace {

// GLONASS L1OF: the ranging code's first chips and period, the strings' Hamming code as a receiver
// checks it, the fields read back, and the symbols decoded as receivers undo relative code and
// meander (GNSS-SDR checks the same end to end in tests/integration/test_iq_gnss_sdr.cpp).
TEST(GlonassL1of, RangingCodeStartsWithTheIcdChipsAndIsAnMSequence) {
  const auto& code = glonass_ranging_code();
  // ICD GLONASS 5.1, 3.3.1.2: the code read at the 7th stage starts 111111100.
  std::string first;
  for (int i = 0; i < 9; ++i) first += code[static_cast<size_t>(i)] < 0 ? '1' : '0';
  EXPECT_EQ(first, "111111100");
  // An m-sequence of degree 9: 256 ones, 255 zeros, autocorrelation -1 off the peak.
  int ones = 0;
  for (auto c : code) ones += c < 0 ? 1 : 0;
  EXPECT_EQ(ones, 256);
  for (int lag = 1; lag < kGlonassCodeLength; lag += 17) {
    int r = 0;
    for (int i = 0; i < kGlonassCodeLength; ++i) {
      r += code[static_cast<size_t>(i)] * code[static_cast<size_t>((i + lag) % kGlonassCodeLength)];
    }
    EXPECT_EQ(r, -1) << "lag " << lag;
  }
}

// The ICD's check (4.7): C1..C7 and C_sigma all zero for a string received without error; one
// flipped data bit gives a syndrome.
bool gnav_checks_pass(const std::array<std::uint8_t, kGlonassStringBits>& bits) {
  auto b = [&](int number) { return static_cast<int>(bits[static_cast<size_t>(kGlonassStringBits - number)]); };
  std::array<std::uint8_t, kGlonassStringBits> recomputed = bits;
  set_gnav_hamming(recomputed);
  int sum_all = 0;
  for (int n = 1; n <= kGlonassStringBits; ++n) sum_all ^= b(n);
  return recomputed == bits && sum_all == 0;
}

TEST(GlonassL1of, StringsCarryTheRecordAndTheirHammingCode) {
  orbits::GlonassEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGlonass, 9};
  e.toe = GnssTime::from_calendar(CalendarTime{2020, 6, 25, 0, 15, 0.0}, TimeScale::kUtc);
  e.position_m = {-11836194.33594, 11848921.38672, 19227001.46484};
  e.velocity_mps = {-2571.640014648, 555.4933547974, -1933.672904968};
  e.acceleration_mps2 = {-9.313225746155e-7, -1.862645149231e-6, -9.313225746155e-7};
  e.minus_tau_n_s = 1.398939639330e-4;
  e.gamma_n = 1.818989403546e-12;
  e.frequency_channel = -2;
  const GnavCommon common{1.5e-8, -2.0e-9};
  const int frame_start = 3 * 3600 + 15 * 60 + 30;  // 03:15:30 MT
  std::array<std::array<std::uint8_t, kGlonassStringBits>, 6> s{};
  for (int n = 1; n <= 5; ++n) s[static_cast<size_t>(n)] = gnav_string(e, common, n, frame_start, 177, 7);
  auto field = [&](int string, int first, int n) {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 1) | s[static_cast<size_t>(string)][static_cast<size_t>(kGlonassStringBits - (first - i))];
    return v;
  };
  auto signed_field = [&](int string, int first, int n) {
    const double magnitude = static_cast<double>(field(string, first - 1, n - 1));
    return field(string, first, 1) != 0 ? -magnitude : magnitude;
  };
  for (int n = 1; n <= 5; ++n) {
    SCOPED_TRACE("string " + std::to_string(n));
    EXPECT_EQ(s[static_cast<size_t>(n)][0], 0);  // the idle bit
    EXPECT_EQ(field(n, 84, 4), static_cast<std::uint64_t>(n));
    EXPECT_TRUE(gnav_checks_pass(s[static_cast<size_t>(n)]));
    auto flipped = s[static_cast<size_t>(n)];
    flipped[30] ^= 1U;
    EXPECT_FALSE(gnav_checks_pass(flipped));
  }
  EXPECT_EQ(field(1, 76, 5), 3u);   // t_k hours
  EXPECT_EQ(field(1, 71, 6), 15u);  // minutes
  EXPECT_EQ(field(1, 65, 1), 1u);   // + 30 s
  EXPECT_NEAR(signed_field(1, 35, 27) * std::ldexp(1.0, -11) * 1e3, e.position_m.x(), 0.25);
  EXPECT_NEAR(signed_field(2, 64, 24) * std::ldexp(1.0, -20) * 1e3, e.velocity_mps.y(), 1e-3);
  EXPECT_NEAR(signed_field(3, 40, 5) * std::ldexp(1.0, -30) * 1e3, e.acceleration_mps2.z(), 1e-6);
  // t_b: 00:15 UTC is 03:15 MT, the 13th quarter hour.
  EXPECT_EQ(field(2, 76, 7), 13u);
  EXPECT_NEAR(signed_field(3, 79, 11) * std::ldexp(1.0, -40), e.gamma_n, std::ldexp(1.0, -41));
  EXPECT_NEAR(signed_field(4, 80, 22) * std::ldexp(1.0, -30), -e.minus_tau_n_s, std::ldexp(1.0, -31));
  EXPECT_EQ(field(4, 26, 11), 177u);  // N_T
  EXPECT_EQ(field(4, 15, 5), 9u);     // slot
  EXPECT_EQ(field(5, 36, 5), 7u);     // N_4: 2020-2023
  EXPECT_NEAR(signed_field(5, 69, 32) * std::ldexp(1.0, -31), common.tau_c_s, std::ldexp(1.0, -32));
}

TEST(GlonassL1of, SymbolsUndoneAsReceiversDoGiveTheStringBack) {
  orbits::GlonassEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kGlonass, 3};
  e.toe = GnssTime::from_calendar(CalendarTime{2020, 6, 25, 0, 15, 0.0}, TimeScale::kUtc);
  e.position_m = {1.2e7, -1.5e7, 1.9e7};
  const auto bits = gnav_string(e, GnavCommon{}, 1, 0, 177, 7);
  const auto symbols = gnav_symbols(bits);
  // The time mark closes the string.
  const std::string mark = "111110001101110101000010010110";
  for (size_t k = 0; k < mark.size(); ++k) EXPECT_EQ(symbols[170 + k], mark[k] == '1' ? 1 : -1);
  // Meander pairs (1, 0) mean relative 1, (0, 1) relative 0; data = relative xor the one before.
  std::array<int, kGlonassStringBits> relative{};
  for (int i = 0; i < kGlonassStringBits; ++i) {
    const int a = symbols[static_cast<size_t>(2 * i)];
    const int b = symbols[static_cast<size_t>(2 * i + 1)];
    ASSERT_EQ(a, -b) << "symbol pair " << i << " is not a meander";
    relative[static_cast<size_t>(i)] = a > 0 ? 1 : 0;
  }
  for (int i = 1; i < kGlonassStringBits; ++i) {
    EXPECT_EQ(relative[static_cast<size_t>(i - 1)] ^ relative[static_cast<size_t>(i)], bits[static_cast<size_t>(i)]) << i;
  }
}

}  // namespace
}  // namespace skytrace::baseband

namespace skytrace::baseband {
namespace {

// BeiDou B1I: the codes of PRN 1-37 from the ICD's G2 tap pairs (BDS-SIS-ICD-B1I Table 4-1), built
// here with a register of this test; the BCH(15,11) words; a D1 subframe read back.
TEST(BeidouB1i, CodesFollowTheIcdTapPairs) {
  const std::array<std::pair<int, int>, 37> taps = {{{1, 3}, {1, 4}, {1, 5}, {1, 6}, {1, 8}, {1, 9}, {1, 10}, {1, 11},
                                                    {2, 7}, {3, 4}, {3, 5}, {3, 6}, {3, 8}, {3, 9}, {3, 10}, {3, 11},
                                                    {4, 5}, {4, 6}, {4, 8}, {4, 9}, {4, 10}, {4, 11}, {5, 6}, {5, 8},
                                                    {5, 9}, {5, 10}, {5, 11}, {6, 8}, {6, 9}, {6, 10}, {6, 11}, {8, 9},
                                                    {8, 10}, {8, 11}, {9, 10}, {9, 11}, {10, 11}}};
  // Registers as strings of stages 1..11, 01010101010 at the start.
  for (int prn = 1; prn <= 37; ++prn) {
    std::array<int, 12> g1{}, g2{};
    for (int s = 1; s <= 11; ++s) g1[static_cast<size_t>(s)] = g2[static_cast<size_t>(s)] = (s % 2 == 0) ? 1 : 0;
    auto code = beidou_b1i_code(prn);
    ASSERT_TRUE(code);
    const auto [a, b] = taps[static_cast<size_t>(prn - 1)];
    for (int n = 0; n < kB1iCodeLength; ++n) {
      const int chip = g1[11] ^ g2[static_cast<size_t>(a)] ^ g2[static_cast<size_t>(b)];
      ASSERT_EQ((*code)[static_cast<size_t>(n)], chip == 0 ? 1 : -1) << "PRN " << prn << " chip " << n;
      const int f1 = g1[1] ^ g1[7] ^ g1[8] ^ g1[9] ^ g1[10] ^ g1[11];
      const int f2 = g2[1] ^ g2[2] ^ g2[3] ^ g2[4] ^ g2[5] ^ g2[8] ^ g2[9] ^ g2[11];
      for (int s = 11; s > 1; --s) {
        g1[static_cast<size_t>(s)] = g1[static_cast<size_t>(s - 1)];
        g2[static_cast<size_t>(s)] = g2[static_cast<size_t>(s - 1)];
      }
      g1[1] = f1;
      g2[1] = f2;
    }
  }
  EXPECT_TRUE(beidou_geo_prn(1) && beidou_geo_prn(5) && beidou_geo_prn(60) && !beidou_geo_prn(19));
  EXPECT_FALSE(beidou_b1i_code(64));
}

std::uint32_t bch_remainder(std::uint32_t word15) {
  for (int bit = 14; bit >= 4; --bit) {
    if ((word15 >> bit) & 1U) word15 ^= 0x13U << (bit - 4);
  }
  return word15 & 0xF;
}

TEST(BeidouB1i, BchWordsAreMultiplesOfTheGeneratorAndDetectEveryOneBitError) {
  for (std::uint32_t info = 0; info < 2048; info += 7) {
    const std::uint32_t word = (info << 4) | bch15_11_parity(info);
    EXPECT_EQ(bch_remainder(word), 0u) << info;
    for (int bit = 0; bit < 15; ++bit) EXPECT_NE(bch_remainder(word ^ (1U << bit)), 0u);
  }
}

// The information bits of a D1 or D2 subframe as a receiver recovers them: word 1's first 15 bits,
// then each BCH word checked and its information bits taken (words 2-10 de-interleaved).
std::array<int, 300> information_bits(const std::array<std::uint8_t, 300>& bits) {
  std::array<int, 300> data{};
  for (int i = 0; i < 30; ++i) data[static_cast<size_t>(i)] = bits[static_cast<size_t>(i)];
  std::uint32_t w1 = 0;
  for (int i = 15; i < 30; ++i) w1 = (w1 << 1) | bits[static_cast<size_t>(i)];
  EXPECT_EQ(bch_remainder(w1), 0u);
  for (int w = 1; w < 10; ++w) {
    std::uint32_t a = 0, b = 0;
    for (int c = 0; c < 15; ++c) {
      a = (a << 1) | bits[static_cast<size_t>(30 * w + 2 * c)];
      b = (b << 1) | bits[static_cast<size_t>(30 * w + 2 * c + 1)];
    }
    EXPECT_EQ(bch_remainder(a), 0u) << "word " << w + 1;
    EXPECT_EQ(bch_remainder(b), 0u) << "word " << w + 1;
    for (int i = 0; i < 11; ++i) {
      data[static_cast<size_t>(30 * w + i)] = static_cast<int>((a >> (14 - i)) & 1U);
      data[static_cast<size_t>(30 * w + 11 + i)] = static_cast<int>((b >> (14 - i)) & 1U);
    }
  }
  return data;
}

// A field of the information bits (1-based first bit and length of each part, MSB first).
std::uint64_t field_of(const std::array<int, 300>& data, std::initializer_list<std::pair<int, int>> parts) {
  std::uint64_t v = 0;
  for (auto [first, n] : parts) {
    for (int i = 0; i < n; ++i) v = (v << 1) | static_cast<std::uint64_t>(data[static_cast<size_t>(first - 1 + i)]);
  }
  return v;
}

// Two's complement of `bits` bits.
std::int64_t signed_of(std::uint64_t raw, int bits) {
  return ((raw >> (bits - 1)) & 1U) != 0 ? static_cast<std::int64_t>(raw) - (std::int64_t{1} << bits)
                                         : static_cast<std::int64_t>(raw);
}

TEST(BeidouB1i, D1SubframesReadBack) {
  orbits::KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kBeiDou, 19};
  e.sqrt_a_sqrtm = 5282.62580490112;
  e.toe_sow = 345600.0;
  e.eccentricity = 0.00123456;
  e.iode = 1;
  for (const int start : {345606, 345612}) {  // subframes 2 and 3: (start / 6) % 5 + 1
    const std::array<int, 300> data = information_bits(d1_subframe(e, {}, 758, start));
    auto field = [&](std::initializer_list<std::pair<int, int>> parts) { return field_of(data, parts); };
    EXPECT_EQ(field({{1, 11}}), 0b11100010010u);
    const auto subframe = static_cast<int>(field({{16, 3}}));
    EXPECT_EQ(static_cast<int>(field({{19, 8}, {31, 12}})), start);
    if (subframe == 2) {
      EXPECT_NEAR(static_cast<double>(field({{251, 12}, {271, 20}})) * std::ldexp(1.0, -19), e.sqrt_a_sqrtm, std::ldexp(1.0, -20));
      EXPECT_NEAR(static_cast<double>(field({{133, 10}, {151, 22}})) * std::ldexp(1.0, -33), e.eccentricity, std::ldexp(1.0, -34));
      EXPECT_EQ(field({{291, 2}}), (345600u / 8u) >> 15);
    } else {
      EXPECT_EQ(subframe, 3);
      EXPECT_EQ(field({{43, 10}, {61, 5}}), (345600u / 8u) & 0x7FFFu);
    }
  }
}

// D2 of a GEO satellite: the ten pages of subframe 1 (one per 3 s frame) read back with the bit
// table of BDS-SIS-ICD-B1I-3.0 5.3.2 give the record, the fields split over two pages included
// (negative values among them, whose two's complement crosses the page boundary).
TEST(BeidouB1i, D2PagesReadBackToTheRecord) {
  orbits::KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kBeiDou, 3};
  e.sqrt_a_sqrtm = 6493.40234375;
  e.toe_sow = 345600.0;
  e.toc = GnssTime::from_week_tow(TimeScale::kBdt, 758, 345600.0);
  e.eccentricity = 0.000512345;
  e.i0_rad = 0.0412;
  e.omega0_rad = -2.87;
  e.omega_rad = -1.234;
  e.m0_rad = 2.5;
  e.delta_n_rad_per_s = 2.1e-9;
  e.omega_dot_rad_per_s = -3.2e-9;
  e.idot_rad_per_s = -4.5e-10;
  e.cuc_rad = -7.3e-6;
  e.cus_rad = 1.1e-5;
  e.cic_rad = -3.4e-8;
  e.cis_rad = 2.2e-8;
  e.crc_m = -412.5;
  e.crs_m = 120.25;
  e.af0_s = -4.3e-4;
  e.af1_s_per_s = -3.9e-11;
  e.iode = 17;
  e.iodc = 9;
  e.group_delays.tgd1_s = -2.5e-9;
  e.group_delays.tgd2_s = 7.1e-9;
  const double pi = constants::kPi;
  std::map<int, std::array<int, 300>> pages;
  for (int k = 0; k < 10; ++k) {
    const int frame_sow = 345600 + 3 * k;
    const std::array<int, 300> data = information_bits(d2_subframe(e, {}, 758, frame_sow, 1));
    EXPECT_EQ(field_of(data, {{1, 11}}), 0b11100010010u);
    EXPECT_EQ(field_of(data, {{16, 3}}), 1u);
    EXPECT_EQ(static_cast<int>(field_of(data, {{19, 8}, {31, 12}})), frame_sow);
    pages[static_cast<int>(field_of(data, {{43, 4}}))] = data;
  }
  ASSERT_EQ(pages.size(), 10u);
  ASSERT_EQ(pages.begin()->first, 1);
  const auto get = [&](int page, std::initializer_list<std::pair<int, int>> parts) { return field_of(pages[page], parts); };
  // A field sent as its high bits on one page and its low bits on the next, as a signed value.
  const auto joined = [&](int page, std::initializer_list<std::pair<int, int>> high,
                          std::initializer_list<std::pair<int, int>> low, int low_bits, int bits) {
    return signed_of((get(page, high) << low_bits) | get(page + 1, low), bits);
  };
  const auto near = [](std::int64_t raw, double lsb, double value) { EXPECT_NEAR(static_cast<double>(raw) * lsb, value, lsb / 2); };
  EXPECT_EQ(get(1, {{47, 1}}), 0u);
  EXPECT_EQ(get(1, {{48, 5}}), 9u);
  EXPECT_EQ(get(1, {{65, 13}}), 758u);
  EXPECT_EQ(get(1, {{78, 5}, {91, 12}}), 345600u / 8u);
  EXPECT_EQ(signed_of(get(1, {{103, 10}}), 10), -25);
  EXPECT_EQ(signed_of(get(1, {{121, 10}}), 10), 71);
  near(signed_of(get(3, {{101, 12}, {121, 12}}), 24), std::ldexp(1.0, -33), e.af0_s);
  near(joined(3, {{133, 4}}, {{47, 6}, {61, 12}}, 18, 22), std::ldexp(1.0, -50), e.af1_s_per_s);
  EXPECT_EQ(get(4, {{92, 5}}), 17u);
  near(signed_of(get(4, {{97, 16}}), 16), std::ldexp(pi, -43), e.delta_n_rad_per_s);
  near(joined(4, {{121, 14}}, {{47, 4}}, 4, 18), std::ldexp(1.0, -31), e.cuc_rad);
  near(signed_of(get(5, {{51, 2}, {61, 22}, {91, 8}}), 32), std::ldexp(pi, -31), e.m0_rad);
  near(signed_of(get(5, {{99, 14}, {121, 4}}), 18), std::ldexp(1.0, -31), e.cus_rad);
  near(static_cast<std::int64_t>((get(5, {{125, 10}}) << 22) | get(6, {{47, 6}, {61, 16}})), std::ldexp(1.0, -33), e.eccentricity);
  near(static_cast<std::int64_t>(get(6, {{77, 6}, {91, 22}, {121, 4}})), std::ldexp(1.0, -19), e.sqrt_a_sqrtm);
  near(joined(6, {{125, 10}}, {{47, 6}, {61, 2}}, 8, 18), std::ldexp(1.0, -31), e.cic_rad);
  near(signed_of(get(7, {{63, 18}}), 18), std::ldexp(1.0, -31), e.cis_rad);
  EXPECT_EQ(get(7, {{81, 2}, {91, 15}}) * 8u, 345600u);
  near(joined(7, {{106, 7}, {121, 14}}, {{47, 6}, {61, 5}}, 11, 32), std::ldexp(pi, -31), e.i0_rad);
  near(signed_of(get(8, {{66, 17}, {91, 1}}), 18), std::ldexp(1.0, -6), e.crc_m);
  near(signed_of(get(8, {{92, 18}}), 18), std::ldexp(1.0, -6), e.crs_m);
  near(joined(8, {{110, 3}, {121, 16}}, {{47, 5}}, 5, 24), std::ldexp(pi, -43), e.omega_dot_rad_per_s);
  near(signed_of(get(9, {{52, 1}, {61, 22}, {91, 9}}), 32), std::ldexp(pi, -31), e.omega0_rad);
  near(joined(9, {{100, 13}, {121, 14}}, {{47, 5}}, 5, 32), std::ldexp(pi, -31), e.omega_rad);
  near(signed_of(get(10, {{52, 1}, {61, 13}}), 14), std::ldexp(pi, -43), e.idot_rad_per_s);
  // Subframes 2-5 of a frame: their number, the frame's SOW and a page number.
  for (int id = 2; id <= 5; ++id) {
    const std::array<int, 300> data = information_bits(d2_subframe(e, {}, 758, 345603, id));
    EXPECT_EQ(field_of(data, {{16, 3}}), static_cast<std::uint64_t>(id));
    EXPECT_EQ(field_of(data, {{19, 8}, {31, 12}}), 345603u);
    if (id == 5) {
      EXPECT_EQ(field_of(data, {{44, 7}}), 115201u % 120u + 1u);
    } else {
      EXPECT_EQ(field_of(data, {{43, 4}}), 115201u % 6u + 1u);
    }
  }
}

// A GEO satellite's samples carry D2: 2 ms bits (two code periods) without the Neumann-Hoffman
// code, subframe k of a frame starting (k - 1) * 0.6 s after it; a MEO one D1's 20 ms bits with it.
TEST(BeidouB1i, GeoSatellitesSendD2AtFiveHundredBitsPerSecond) {
  orbits::KeplerEphemeris e;
  e.satellite = SatelliteId{GnssSystem::kBeiDou, 3};
  e.sqrt_a_sqrtm = 6493.4;
  e.toe_sow = 345600.0;
  e.iode = 5;
  const int gps_week = 758 + 1356;
  auto signals = make_beidou_b1i_signals({}, gps_week, [&](int, const GnssTime&) { return &e; });
  ASSERT_TRUE(signals->code(3, 0));
  ASSERT_TRUE(signals->code(19, 0));
  // Milliseconds since the GPS week's start of BDT second 345603 (BDT = GPST - 14 s).
  const std::int64_t frame_ms = (345603 + 14) * 1000LL;
  for (int id = 1; id <= 5; ++id) {
    const auto bits = d2_subframe(e, {}, 758, 345603, id);
    const std::int64_t start_ms = frame_ms + (id - 1) * 600;
    int wrong = 0;
    for (int b = 0; b < 300; ++b) {
      const int expected = bits[static_cast<size_t>(b)] != 0 ? -1 : 1;
      wrong += signals->sign(3, start_ms + 2 * b) != expected ? 1 : 0;
      wrong += signals->sign(3, start_ms + 2 * b + 1) != expected ? 1 : 0;
    }
    EXPECT_EQ(wrong, 0) << "subframe " << id;
  }
  // C19 (MEO): within one D1 bit the signs follow the Neumann-Hoffman code.
  const std::int64_t d1_bit_ms = (345606 + 14) * 1000LL;
  const int first = signals->sign(19, d1_bit_ms);
  for (int chip = 0; chip < 20; ++chip) {
    EXPECT_EQ(signals->sign(19, d1_bit_ms + chip),
              first * beidou_nh_code()[static_cast<size_t>(chip)] * beidou_nh_code()[0]);
  }
}

}  // namespace
}  // namespace skytrace::baseband
