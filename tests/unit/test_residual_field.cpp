// Atmosphere residual fields: the difference between two places d apart has a standard deviation
// of ppm 1e-6 d (the gradient the scenario asks for), independent places are uncorrelated, the
// field changes slowly within its correlation time, one seed gives one field, and the ionosphere
// residual rides on the model's delay at the pierce point.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "skytrace/atmosphere/residual_field.hpp"

namespace skytrace::atmosphere {
namespace {

double std_dev(const std::vector<double>& v) {
  double mean = 0.0, sum = 0.0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  for (double x : v) sum += (x - mean) * (x - mean);
  return std::sqrt(sum / static_cast<double>(v.size() - 1));
}

TEST(ResidualField, DifferencesGrowWithDistanceAsTheGradientSays) {
  const GnssTime t0 = GnssTime::parse_iso8601("2020-06-25T06:00:00", TimeScale::kGpst).value();
  std::mt19937 random(3);
  std::uniform_real_distribution<double> lat(40.0, 60.0), lon(0.0, 20.0), angle(0.0, 2 * M_PI);
  for (const double ppm : {0.5, 2.0}) {
    std::vector<double> diff_10km;
    // Many independent fields (seeds), places and directions.
    for (int seed = 1; seed <= 40; ++seed) {
      const ResidualField field(ResidualField::for_gradient_ppm(ppm, 300e3, 600.0, static_cast<std::uint64_t>(seed)));
      for (int k = 0; k < 50; ++k) {
        const double la = lat(random), lo = lon(random), a = angle(random);
        const double dlat = 10e3 * std::cos(a) / 111195.0, dlon = 10e3 * std::sin(a) / (111195.0 * std::cos(la * M_PI / 180));
        diff_10km.push_back(field.value_m(la + dlat, lo + dlon, t0) - field.value_m(la, lo, t0));
      }
    }
    EXPECT_NEAR(std_dev(diff_10km) / 10e3 * 1e6, ppm, 0.15 * ppm) << ppm;
  }
}

TEST(ResidualField, SlowInTimeAndOneFieldPerSeed) {
  const GnssTime t0 = GnssTime::parse_iso8601("2020-06-25T06:00:00", TimeScale::kGpst).value();
  const auto settings = ResidualField::for_gradient_ppm(1.0, 300e3, 600.0, 5);
  const ResidualField a(settings), b(settings);
  EXPECT_EQ(a.value_m(55.0, 8.0, t0), b.value_m(55.0, 8.0, t0));
  EXPECT_NE(a.value_m(55.0, 8.0, t0), ResidualField(ResidualField::for_gradient_ppm(1.0, 300e3, 600.0, 6)).value_m(55.0, 8.0, t0));
  // One second apart the field hardly changes; its own size is sigma = ppm 1e-6 L = 0.3 m.
  std::vector<double> values, steps;
  for (int k = 0; k < 600; ++k) {
    values.push_back(a.value_m(55.0 + 0.1 * k, 8.0, t0 + 10.0 * k));
    steps.push_back(a.value_m(55.0, 8.0, t0 + k + 1.0) - a.value_m(55.0, 8.0, t0 + k));
  }
  EXPECT_NEAR(std_dev(values), 0.3, 0.12);
  EXPECT_LT(std_dev(steps), 0.01);
  // Zero: no field at all.
  EXPECT_EQ(ResidualField(ResidualField::Settings{}).value_m(55.0, 8.0, t0), 0.0);
}

TEST(ResidualField, IonosphereResidualAddsToTheModelAtThePiercePoint) {
  const GnssTime t0 = GnssTime::parse_iso8601("2020-06-25T06:00:00", TimeScale::kGpst).value();
  const Geodetic receiver{55.49, 8.49, 75.0};
  const IonosphereWithResidual residual_only(nullptr, ResidualField(ResidualField::for_gradient_ppm(5.0, 300e3, 600.0, 9)));
  const AzimuthElevation zenith{0.0, 90.0}, low{180.0, 10.0};
  // At the zenith the pierce point is above the receiver and the mapping 1; low, the mapping is about 2.6.
  const double at_zenith = residual_only.residual_l1_m(t0, receiver, zenith);
  EXPECT_NE(at_zenith, 0.0);
  const auto delay = residual_only.delay_l1_m(t0, receiver, zenith);
  ASSERT_TRUE(delay.ok());
  EXPECT_DOUBLE_EQ(**delay, std::max(0.0, at_zenith));
  const auto below = residual_only.delay_l1_m(t0, receiver, AzimuthElevation{0.0, -5.0});
  ASSERT_TRUE(below.ok());
  EXPECT_FALSE(below->has_value());
  EXPECT_NE(residual_only.residual_l1_m(t0, receiver, low), at_zenith);
}

}  // namespace
}  // namespace skytrace::atmosphere
