// UNB3m + Niell troposphere: hand-computed values from the published tables, limits of the
// mapping functions, hemispheres, and agreement with the reference Saastamoinen where the two
// models should agree.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "skytrace/atmosphere/models.hpp"

namespace skytrace::atmosphere {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

TEST(Troposphere, MappingFunctionsAreOneAtZenithAndNearCosecantHigh) {
  for (double lat : {-80.0, -45.0, 0.0, 20.0, 45.0, 52.5, 79.0}) {
    EXPECT_NEAR(niell_hydrostatic_mapping(lat, 0.0, 90.0, 100.0), 1.0, 1e-12) << lat;
    EXPECT_NEAR(niell_wet_mapping(lat, 90.0), 1.0, 1e-12) << lat;
    // Above 30 degrees the Earth's curvature hardly matters: within 0.5 % of 1/sin(el).
    EXPECT_NEAR(niell_hydrostatic_mapping(lat, 0.0, 30.0, 100.0), 2.0, 0.01) << lat;
  }
}

TEST(Troposphere, NiellAtFiveDegreesByHand) {
  // 45 N, day 28 (winter peak: coefficients = average - amplitude), sea level.
  const double a = 1.2465397e-3 - 2.6523662e-5, b = 2.9288445e-3 - 3.0160779e-5, c = 63.721774e-3 - 4.3497037e-5;
  const double s = std::sin(5.0 * kDegToRad);
  const double expected = (1.0 + a / (1.0 + b / (1.0 + c))) / (s + a / (s + b / (s + c)));
  EXPECT_NEAR(niell_hydrostatic_mapping(45.0, 0.0, 5.0, 28.0), expected, 1e-12);
  EXPECT_GT(expected, 10.0);  // the curvature keeps it below 1/sin(5 deg) = 11.47
  EXPECT_LT(expected, 10.5);
  // The wet mapping function rises faster toward the horizon than the hydrostatic one.
  EXPECT_GT(niell_wet_mapping(45.0, 5.0), expected);
}

TEST(Troposphere, HeightCorrectionRaisesTheHydrostaticMapping) {
  const double at_sea = niell_hydrostatic_mapping(45.0, 0.0, 10.0, 200.0);
  const double at_2km = niell_hydrostatic_mapping(45.0, 2000.0, 10.0, 200.0);
  const double s = std::sin(10.0 * kDegToRad);
  const double a = 2.53e-5, b = 5.49e-3, c = 1.14e-3;
  const double height_term = (1.0 / s - (1.0 + a / (1.0 + b / (1.0 + c))) / (s + a / (s + b / (s + c)))) * 2.0;
  EXPECT_NEAR(at_2km - at_sea, height_term, 1e-12);
  EXPECT_GT(height_term, 0.0);
}

TEST(Troposphere, Unb3mZenithHydrostaticDelayByHand) {
  // 45 N on day 28: P0 = 1015.75 - (-2.25) = 1018.00 hPa at sea level; Saastamoinen/Davis
  // ZHD = 0.0022768 P / (1 - 0.00266 cos(2 phi_geocentric)).
  const auto d = unb3m_delay(Geodetic{45.0, 10.0, 0.0}, 90.0, 28.0);
  ASSERT_TRUE(d.has_value());
  const double geocentric = std::atan((1.0 - 6.6943799901413e-3) * std::tan(45.0 * kDegToRad));
  const double expected_m = 1e-6 * 77.604 * (8314.34 / 28.9644) * 1018.0 / (9.784 * (1.0 - 2.66e-3 * std::cos(2.0 * geocentric)));
  EXPECT_NEAR(d->zenith_hydrostatic_m, expected_m, 1e-9);
  EXPECT_NEAR(d->zenith_hydrostatic_m, 2.318, 0.002);
  // Winter at 45 N: a few centimetres of wet delay.
  EXPECT_GT(d->zenith_wet_m, 0.03);
  EXPECT_LT(d->zenith_wet_m, 0.15);
  EXPECT_NEAR(d->slant_m(), d->zenith_hydrostatic_m + d->zenith_wet_m, 1e-12);
}

TEST(Troposphere, Unb3mTropicalWetDelayIsLargerThanPolar) {
  const auto tropics = unb3m_delay(Geodetic{10.0, 0.0, 0.0}, 90.0, 180.0);
  const auto arctic = unb3m_delay(Geodetic{79.0, 12.0, 0.0}, 90.0, 180.0);
  ASSERT_TRUE(tropics && arctic);
  EXPECT_GT(tropics->zenith_wet_m, 0.2);
  EXPECT_LT(arctic->zenith_wet_m, 0.1);
}

TEST(Troposphere, SouthernHemisphereIsHalfAYearApart) {
  const auto north = unb3m_delay(Geodetic{40.0, 0.0, 100.0}, 20.0, 28.0);
  const auto south = unb3m_delay(Geodetic{-40.0, 0.0, 100.0}, 20.0, 28.0 - 182.625);
  ASSERT_TRUE(north && south);
  EXPECT_NEAR(north->slant_m(), south->slant_m(), 1e-9);
  // Summer and winter differ.
  const auto summer = unb3m_delay(Geodetic{40.0, 0.0, 100.0}, 20.0, 28.0 + 182.625);
  EXPECT_GT(std::abs(summer->zenith_wet_m - north->zenith_wet_m), 0.02);
}

TEST(Troposphere, Unb3mPressureFallsWithHeight) {
  const auto sea = unb3m_delay(Geodetic{45.0, 0.0, 0.0}, 90.0, 150.0);
  const auto high = unb3m_delay(Geodetic{45.0, 0.0, 2000.0}, 90.0, 150.0);
  ASSERT_TRUE(sea && high);
  // About 79 % of the sea-level pressure at 2 km (standard lapse).
  EXPECT_NEAR(high->zenith_hydrostatic_m / sea->zenith_hydrostatic_m, 0.785, 0.01);
  EXPECT_FALSE(unb3m_delay(Geodetic{45.0, 0.0, 20000.0}, 90.0, 150.0).has_value());
  EXPECT_FALSE(unb3m_delay(Geodetic{45.0, 0.0, 0.0}, -1.0, 150.0).has_value());
}

TEST(Troposphere, AgreesWithTheReferenceSaastamoinenWithinCentimetresAboveThirtyDegrees) {
  // Both are Saastamoinen-type zenith delays; they differ by meteorology and mapping: a few cm at
  // 30 degrees, more toward the horizon where 1/sin(el) overestimates.
  for (double el : {90.0, 60.0, 30.0}) {
    const double reference = *saastamoinen_delay_m(Geodetic{55.5, 8.5, 60.0}, el);
    const double unb3m = unb3m_delay(Geodetic{55.5, 8.5, 60.0}, el, 177.0)->slant_m();
    EXPECT_NEAR(unb3m, reference, 0.05 / std::sin(el * kDegToRad)) << el;
  }
  const double reference_5 = *saastamoinen_delay_m(Geodetic{55.5, 8.5, 60.0}, 5.0);
  const double unb3m_5 = unb3m_delay(Geodetic{55.5, 8.5, 60.0}, 5.0, 177.0)->slant_m();
  EXPECT_LT(unb3m_5, reference_5);
}

}  // namespace
}  // namespace skytrace::atmosphere
