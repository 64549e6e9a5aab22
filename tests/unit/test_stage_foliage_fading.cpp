// Foliage fading (receiver/stages/foliage_fading.hpp): the Rician K factor of a canopy, the
// envelope statistics of a thick canopy against Rayleigh's, the level-crossing rate against the
// theory for the Doppler spread, phase and range rate consistent with each other, fades that break
// or lose the phase lock by their length, and the same field for the same seed.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "skytrace/core/constants.hpp"
#include "skytrace/receiver/stages/foliage_fading.hpp"

namespace skytrace::receiver::stages {
namespace {

const GnssTime kStart = GnssTime::from_week_tow(TimeScale::kGpst, 2200, 3600.0);
const Eigen::Vector3d kZenith = Eigen::Vector3d::UnitZ();
constexpr double kL1_hz = 1575.42e6;

FoliageFading fading(double wind_hz, std::uint64_t seed = 7, int receiver = 0) {
  FoliageFadingSettings s;
  s.enabled = true;
  s.wind_spread_hz = wind_hz;
  return FoliageFading(seed, receiver, s);
}

// Every sample of `epochs` one-second epochs of satellite `sat`'s L1 field under `attenuation_db`.
std::vector<double> power_samples(FoliageFading& f, const SatelliteId& sat, double attenuation_db, int epochs,
                                  const Eigen::Vector3d& velocity = Eigen::Vector3d::Zero()) {
  std::vector<double> out;
  std::optional<GnssTime> previous;
  for (int k = 0; k < epochs; ++k) {
    const GnssTime t = kStart + static_cast<double>(k);
    const FoliageComposite& c = f.composite(sat, '1', kL1_hz, attenuation_db, 10.0, velocity, kZenith, t, previous);
    out.insert(out.end(), c.power.begin(), c.power.end());
    previous = t;
  }
  return out;
}

TEST(FoliageFading, KFactorFromTheCanopysAttenuation) {
  EXPECT_TRUE(std::isinf(foliage_k_factor(0.0, -12.0)));
  // 3 dB: mean 0.501 = coherent + 0.0631 (1 - coherent).
  const double mean = std::pow(10.0, -0.3), diffuse_max = std::pow(10.0, -1.2);
  const double coherent = (mean - diffuse_max) / (1.0 - diffuse_max);
  EXPECT_NEAR(foliage_k_factor(3.0, -12.0), coherent / (mean - coherent), 1e-9);
  EXPECT_GT(foliage_k_factor(3.0, -12.0), 10.0);
  // Thicker than the diffuse level: nothing coherent left (Rayleigh).
  EXPECT_EQ(foliage_k_factor(15.0, -12.0), 0.0);
  EXPECT_GT(foliage_k_factor(15.0, -20.0), 0.5);
}

TEST(FoliageFading, ThickCanopyFadesLikeRayleighAroundTheMeanPower) {
  FoliageFading f = fading(1.0);
  std::vector<double> all;
  for (std::uint8_t prn = 1; prn <= 8; ++prn) {
    const auto samples = power_samples(f, SatelliteId{GnssSystem::kGps, prn}, 25.0, 300);
    all.insert(all.end(), samples.begin(), samples.end());
  }
  double sum = 0.0;
  int below_tenth = 0, below_hundredth = 0;
  for (const double p : all) {
    sum += p;
    below_tenth += p < 0.1;
    below_hundredth += p < 0.01;
  }
  const double n = static_cast<double>(all.size());
  EXPECT_NEAR(sum / n, 1.0, 0.05);  // the link budget's mean is kept
  // Rayleigh: P(power < x) = 1 - exp(-x).
  EXPECT_NEAR(below_tenth / n, 1.0 - std::exp(-0.1), 0.025);
  EXPECT_NEAR(below_hundredth / n, 1.0 - std::exp(-0.01), 0.006);
}

TEST(FoliageFading, ThinCanopyKeepsItsCoherentWave) {
  FoliageFading f = fading(1.0);
  const auto samples = power_samples(f, SatelliteId{GnssSystem::kGps, 3}, 2.0, 300);
  for (const double p : samples) {
    ASSERT_GT(p, 0.2);
    ASSERT_LT(p, 2.5);
  }
}

// Level crossings per second of power 0.1 (rho^2) for a Doppler spectrum of rms width s:
// 2 sqrt(pi) s rho exp(-rho^2) (Rice; Clarke's spectrum, s = f_max / sqrt(2), gives the familiar
// sqrt(2 pi) f_max rho exp(-rho^2)).
double crossings_per_s(double wind_hz) {
  FoliageFading f = fading(wind_hz);
  int crossings = 0;
  double seconds = 0.0;
  for (std::uint8_t prn = 1; prn <= 24; ++prn) {
    const auto samples = power_samples(f, SatelliteId{GnssSystem::kGalileo, prn}, 30.0, 400);
    for (size_t k = 1; k < samples.size(); ++k) crossings += samples[k - 1] >= 0.1 && samples[k] < 0.1;
    seconds += 400.0;
  }
  return crossings / seconds;
}

TEST(FoliageFading, FadesComeAsOftenAsTheDopplerSpreadSays) {
  const double rho2 = 0.1;
  for (const double wind_hz : {0.5, 2.0}) {
    const double theory = 2.0 * std::sqrt(std::numbers::pi) * wind_hz * std::sqrt(rho2) * std::exp(-rho2);
    EXPECT_NEAR(crossings_per_s(wind_hz) / theory, 1.0, 0.3) << wind_hz << " Hz";
  }
}

TEST(FoliageFading, AStillCanopyFadesOnlyWhenTheAntennaMoves) {
  FoliageFading still = fading(0.0);
  const auto standing = power_samples(still, SatelliteId{GnssSystem::kGps, 5}, 25.0, 20);
  for (const double p : standing) ASSERT_NEAR(p, standing.front(), 1e-9);
  FoliageFading walking = fading(0.0);
  const auto moving = power_samples(walking, SatelliteId{GnssSystem::kGps, 5}, 25.0, 20, Eigen::Vector3d(1.0, 0.0, 0.0));
  double lowest = 1e9, highest = 0.0;
  for (const double p : moving) {
    lowest = std::min(lowest, p);
    highest = std::max(highest, p);
  }
  EXPECT_GT(highest / lowest, 10.0);  // walking 20 m through the standing waves under the crown
}

TEST(FoliageFading, RangeRateIsThePhaseErrorsRate) {
  FoliageFading f = fading(2.0);
  const SatelliteId sat{GnssSystem::kGps, 9};
  std::optional<GnssTime> previous;
  double previous_phase_m = 0.0;
  int checked = 0;
  for (int k = 0; k < 500; ++k) {
    const GnssTime t = kStart + 0.01 * k;  // one sample per epoch
    const FoliageComposite& c = f.composite(sat, '1', kL1_hz, 6.0, 4.0, Eigen::Vector3d::Zero(), kZenith, t, previous);
    if (previous) {
      ASSERT_EQ(c.power.size(), 1u);
      EXPECT_NEAR(c.range_rate_error_mps, (c.phase_error_m - previous_phase_m) / 0.01, 1e-6);
      ++checked;
    }
    previous_phase_m = c.phase_error_m;
    previous = t;
  }
  EXPECT_EQ(checked, 499);
}

TEST(FoliageFading, TheLoopSlipsOrLosesTheSignalByTheFadesLength) {
  FoliageComposite c;
  c.step_s = 0.01;
  c.power.assign(100, 1.0);
  // Mean 35 dB-Hz, threshold 20: below means power < 10^-1.5.
  EXPECT_FALSE(c.for_signal(35.0, 20.0, 0.05).slipped);
  for (int k = 40; k < 43; ++k) c.power[k] = 0.01;  // 30 ms: the loop holds
  FoliageFade short_fade = c.for_signal(35.0, 20.0, 0.05);
  EXPECT_FALSE(short_fade.slipped);
  EXPECT_FALSE(short_fade.faded_out);
  for (int k = 40; k < 47; ++k) c.power[k] = 0.01;  // 70 ms: lock lost, regained
  FoliageFade long_fade = c.for_signal(35.0, 20.0, 0.05);
  EXPECT_TRUE(long_fade.slipped);
  EXPECT_FALSE(long_fade.faded_out);
  for (int k = 94; k < 100; ++k) c.power[k] = 0.01;  // still in the fade at the epoch
  EXPECT_TRUE(c.for_signal(35.0, 20.0, 0.05).faded_out);
  // The reported C/N0: the mean power over the last second.
  double sum = 0.0;
  for (const double p : c.power) sum += p;
  EXPECT_NEAR(c.for_signal(35.0, 20.0, 0.05).cn0_change_db, 10.0 * std::log10(sum / 100.0), 1e-12);
}

TEST(FoliageFading, SameSeedSameFieldOtherReceiverAnother) {
  FoliageFading a = fading(1.0, 7, 0), b = fading(1.0, 7, 0), c = fading(1.0, 7, 1);
  const SatelliteId sat{GnssSystem::kBeiDou, 20};
  EXPECT_EQ(power_samples(a, sat, 20.0, 5), power_samples(b, sat, 20.0, 5));
  EXPECT_NE(power_samples(a, sat, 20.0, 5), power_samples(c, sat, 20.0, 5));
}

}  // namespace
}  // namespace skytrace::receiver::stages
