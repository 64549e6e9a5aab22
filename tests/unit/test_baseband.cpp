// GPS L1 C/A at the signal level: the Gold codes against IS-GPS-200's table, the LNAV parity
// against the decoders' mask form of the same equations, subframes decoded back by an independent
// reader of this test into the record they came from, and the samples' power, code phase and
// carrier measured with a correlator written here.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <numbers>
#include <random>

#include "skytrace/baseband/gps_l1ca.hpp"
#include "skytrace/baseband/l1ca_synthesizer.hpp"
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
TEST(L1caSynthesizer, CorrelatorMeasuresTheCn0CodeDelayAndCarrierItWasGiven) {
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
  L1caSynthesizer synthesizer(settings);
  // A constant Doppler: the range falls at -D lambda; the phase in cycles follows the range.
  auto arrival_at = [&](double t) {
    L1caArrival a;
    a.prn = 5;
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
        const L1caArrival a = arrival_at(t);
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

TEST(L1caSynthesizer, FormatsScaleTheSameNoise) {
  for (const char* name : {"sc8", "sc16", "gr_complex"}) {
    auto format = parse_sample_format(name);
    ASSERT_TRUE(format);
    SynthesizerSettings settings;
    settings.format = *format;
    L1caSynthesizer synthesizer(settings);
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
