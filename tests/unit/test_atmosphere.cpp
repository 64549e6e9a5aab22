// Reference atmosphere models: values from the model equations and their properties.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/signal.hpp"

namespace skytrace::atmosphere {
namespace {

TEST(Saastamoinen, ZenithDelayAtSeaLevel) {
  // Hydrostatic part at 45 deg latitude, sea level: 0.0022768 * 1013.25 = 2.30698 m. The wet part
  // of the standard atmosphere (15 C, 70 %) adds 0.0022770 * (1255/288.16 + 0.05) * e.
  const Geodetic site{45.0, 0.0, 0.0};
  const double t_k = 288.16;
  const double e_hpa = 6.108 * 0.7 * std::exp((17.15 * t_k - 4684.0) / (t_k - 38.45));
  const double expected = 0.0022768 * 1013.25 + 0.002277 * (1255.0 / t_k + 0.05) * e_hpa;
  EXPECT_NEAR(saastamoinen_delay_m(site, 90.0).value(), expected, 1e-9);
  EXPECT_NEAR(expected, 2.43, 0.03);  // the textbook ~2.4 m zenith delay
}

TEST(Saastamoinen, MappingAndLimits) {
  const Geodetic site{55.5, 8.5, 60.0};
  const double zenith = saastamoinen_delay_m(site, 90.0).value();
  EXPECT_NEAR(saastamoinen_delay_m(site, 30.0).value(), 2.0 * zenith, 1e-9);  // 1/sin(30) = 2
  EXPECT_LT(saastamoinen_delay_m(Geodetic{55.5, 8.5, 2000.0}, 90.0).value(), zenith);
  EXPECT_FALSE(saastamoinen_delay_m(site, -1.0).has_value());
  EXPECT_FALSE(saastamoinen_delay_m(Geodetic{0, 0, 20000.0}, 45.0).has_value());
}

orbits::KlobucharCoefficients esbc_2020177() {
  // GPSA/GPSB of ESBC00DNK_R_20201770000_01D_MN.rnx.
  orbits::KlobucharCoefficients k;
  k.alpha = {4.6566e-09, 1.4901e-08, -5.9605e-08, -1.1921e-07};
  k.beta = {8.1920e+04, 9.8304e+04, -6.5536e+04, -5.2429e+05};
  return k;
}

TEST(Klobuchar, NightFloorAtZenith) {
  // At local midnight the model is the 5 ns floor times the slant factor 1 + 16 (0.53 - 0.5)^3.
  const Geodetic site{0.0, 0.0, 0.0};
  const GnssTime midnight = GnssTime::parse_iso8601("2020-06-25T00:00:00", TimeScale::kGpst).value();
  const double expected_m = 299792458.0 * 5e-9 * (1.0 + 16.0 * std::pow(0.03, 3));
  EXPECT_NEAR(klobuchar_delay_l1_m(esbc_2020177(), midnight, site, {0.0, 90.0}).value(), expected_m, 1e-9);
}

TEST(Klobuchar, DaytimeLargerLowElevationLarger) {
  // At 55 N these coefficients give only the night floor (the amplitude polynomial is negative);
  // at 20 N and 14:00 local time the daytime cosine is well above it.
  const Geodetic site{20.0, 0.0, 0.0};
  const GnssTime noon = GnssTime::parse_iso8601("2020-06-25T14:00:00", TimeScale::kGpst).value();
  const double zenith = klobuchar_delay_l1_m(esbc_2020177(), noon, site, {180.0, 90.0}).value();
  const double low = klobuchar_delay_l1_m(esbc_2020177(), noon, site, {180.0, 10.0}).value();
  EXPECT_GT(zenith, 3.0);
  EXPECT_LT(zenith, 15.0);
  EXPECT_GT(low / zenith, 2.0);  // obliquity factor at 10 deg is 2.7, the pierce point moves too
  EXPECT_LT(low / zenith, 4.0);
  EXPECT_FALSE(klobuchar_delay_l1_m(esbc_2020177(), noon, site, {180.0, -0.1}).has_value());
}

TEST(Klobuchar, ScalesWithInverseSquareOfFrequency) {
  // The delay on another carrier is (f_L1/f)^2 times the L1 delay: L2 by 1.6469, E5a by 1.7933.
  const double l1_l2 = std::pow(kFrequencyL1_Hz / kFrequencyL2_Hz, 2);
  const double l1_l5 = std::pow(kFrequencyL1_Hz / kFrequencyL5_Hz, 2);
  EXPECT_NEAR(l1_l2, 1.646944, 1e-6);
  EXPECT_NEAR(l1_l5, 1.793270, 1e-6);
}

}  // namespace
}  // namespace skytrace::atmosphere
