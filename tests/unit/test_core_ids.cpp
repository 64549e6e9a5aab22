// Satellite identifiers, signal catalogue and frames.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"

namespace skytrace {
namespace {

TEST(SatelliteId, ParseAndFormat) {
  EXPECT_EQ(SatelliteId::parse("G05").value().to_string(), "G05");
  EXPECT_EQ(SatelliteId::parse("G 5").value().to_string(), "G05");
  EXPECT_EQ(SatelliteId::parse("S127").value().to_string(), "S27");
  EXPECT_EQ(SatelliteId::parse("S27").value().prn(), 127);
  EXPECT_EQ(SatelliteId::parse("J193").value().to_string(), "J01");
  EXPECT_EQ(SatelliteId::parse("C59").value().system, GnssSystem::kBeiDou);
  EXPECT_EQ(SatelliteId::parse("C59").value().to_string(), "C59");
  EXPECT_EQ(SatelliteId::parse("R10").value().to_string(), "R10");
  EXPECT_EQ((SatelliteId{GnssSystem::kGps, 0}).to_string(), "G00");       // as printf's %c%02d
  EXPECT_EQ((SatelliteId{GnssSystem::kSbas, 158}).to_string(), "S158");
  EXPECT_FALSE(SatelliteId::parse("X01").ok());
  EXPECT_FALSE(SatelliteId::parse("G33").ok());
  EXPECT_FALSE(SatelliteId::parse("G").ok());
  const auto bad = SatelliteId::parse("Q07");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("'Q'"), std::string::npos);
}

TEST(SignalCatalogue, FrequenciesAndWavelengths) {
  const SignalInfo* l1 = find_signal_info(Signal::parse("G1C").value());
  ASSERT_NE(l1, nullptr);
  EXPECT_DOUBLE_EQ(l1->carrier_frequency_hz(), 1575.42e6);
  EXPECT_NEAR(299792458.0 / l1->carrier_frequency_hz(), 0.190293672798, 1e-12);
  EXPECT_DOUBLE_EQ(l1->chip_rate_hz, 1.023e6);
  // GLONASS FDMA: G1 = 1602 + k * 0.5625 MHz, G2 = 1246 + k * 0.4375 MHz.
  const SignalInfo* g1 = find_signal_info(Signal::parse("R1C").value());
  ASSERT_NE(g1, nullptr);
  EXPECT_TRUE(g1->is_fdma());
  EXPECT_DOUBLE_EQ(g1->carrier_frequency_hz(-7), 1598.0625e6);
  EXPECT_DOUBLE_EQ(g1->carrier_frequency_hz(6), 1605.375e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("R2C").value())->carrier_frequency_hz(1), 1246.4375e6);
  // BeiDou B1I, B2I vs B2b, B3I; Galileo E5 AltBOC; NavIC S.
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("C2I").value())->carrier_hz, 1561.098e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("C7I").value())->chip_rate_hz, 2.046e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("C7D").value())->chip_rate_hz, 10.23e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("C6I").value())->carrier_hz, 1268.52e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("E8Q").value())->carrier_hz, 1191.795e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("I9A").value())->carrier_hz, 2492.028e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("J6L").value())->carrier_hz, 1278.75e6);
  EXPECT_DOUBLE_EQ(find_signal_info(Signal::parse("S5I").value())->carrier_hz, 1176.45e6);
}

TEST(SignalCatalogue, RejectsSignalsASystemDoesNotHave) {
  EXPECT_FALSE(Signal::parse("G7Q").ok());  // GPS has no band 7
  EXPECT_FALSE(Signal::parse("E2C").ok());  // Galileo has no band 2
  EXPECT_FALSE(Signal::parse("R5Q").ok());
  EXPECT_FALSE(Signal::parse("G1").ok());
  const auto r = Signal::parse("E2C");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("Galileo"), std::string::npos);
  // Every catalogue entry parses back to itself.
  for (const auto& info : all_signals()) {
    EXPECT_EQ(Signal::parse(info.signal.to_string()).value(), info.signal) << info.signal.to_string();
  }
}

TEST(Frames, GeodeticRoundTripAndKnownPoint) {
  // ESBC00DNK marker (IGS): about 55.4936 N, 8.4568 E.
  const Eigen::Vector3d esbc(3582105.2910, 532589.7313, 5232754.8054);
  const Geodetic g = ecef_to_geodetic(esbc);
  EXPECT_NEAR(g.latitude_deg, 55.4936, 1e-3);
  EXPECT_NEAR(g.longitude_deg, 8.4568, 1e-3);
  EXPECT_NEAR((geodetic_to_ecef(g) - esbc).norm(), 0.0, 1e-6);
  // Azimuth/elevation of a point straight up and straight north.
  const Eigen::Vector3d up = enu_to_ecef(Eigen::Vector3d(0, 0, 1000), g);
  EXPECT_NEAR(azimuth_elevation(esbc, g, up).elevation_deg, 90.0, 1e-6);
  const Eigen::Vector3d north = enu_to_ecef(Eigen::Vector3d(0, 1000, 0), g);
  const AzimuthElevation ae = azimuth_elevation(esbc, g, north);
  EXPECT_NEAR(std::remainder(ae.azimuth_deg, 360.0), 0.0, 1e-6);
  EXPECT_NEAR(ae.elevation_deg, 0.0, 1e-6);
  const Eigen::Vector3d east = enu_to_ecef(Eigen::Vector3d(1000, 0, 0), g);
  EXPECT_NEAR(azimuth_elevation(esbc, g, east).azimuth_deg, 90.0, 1e-6);
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// The small-angle series against libm's sine and cosine, across the angles of flight times
// (0 to 0.3 s of Earth rotation) and beyond, where the function falls back to libm.
TEST(Frames, EarthRotationOverTheFlightTimeMatchesSineAndCosine) {
  const Eigen::Vector3d satellite_m(-13.1e6, 19.7e6, 10.4e6);
  for (const double flight_s : {0.0, 1e-9, 0.06, 0.0673, 0.0871, 0.14, 0.3, 13.7, 20.0, 3600.0}) {
    for (const double sign : {1.0, -1.0}) {
      const double angle_rad = sign * 7.2921151467e-5 * flight_s;
      const Eigen::Vector3d expected(std::cos(angle_rad) * satellite_m.x() + std::sin(angle_rad) * satellite_m.y(),
                                     -std::sin(angle_rad) * satellite_m.x() + std::cos(angle_rad) * satellite_m.y(),
                                     satellite_m.z());
      const Eigen::Vector3d rotated = rotate_earth_frame(satellite_m, angle_rad);
      // 2.6e7 m at double precision: a few ulp are ~1e-8 m.
      EXPECT_LT((rotated - expected).norm(), 2e-8) << "angle " << angle_rad << " rad";
      EXPECT_NEAR(rotated.norm(), satellite_m.norm(), 2e-8);
    }
  }
  // A quarter turn (no series): x goes to -y.
  const Eigen::Vector3d turned = rotate_earth_frame(Eigen::Vector3d(1.0, 0.0, 0.5), M_PI / 2.0);
  EXPECT_NEAR(turned.x(), 0.0, 1e-15);
  EXPECT_NEAR(turned.y(), -1.0, 1e-15);
  EXPECT_EQ(turned.z(), 0.5);
}

TEST(LocalFrame, HeadingTurnsTheXAxisCounterClockwiseFromEast) {
  const LocalFrame east_x{Geodetic{55.49357, 8.45683, 59.5}, 0.0};
  const LocalFrame north_x{Geodetic{55.49357, 8.45683, 59.5}, 90.0};
  const Geodetic origin = east_x.origin;
  // heading 0: local x is east; heading 90: local x is north, local y is west.
  EXPECT_NEAR((ecef_to_enu(east_x.to_ecef({10, 0, 0}), origin) - Eigen::Vector3d(10, 0, 0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR((ecef_to_enu(north_x.to_ecef({10, 0, 0}), origin) - Eigen::Vector3d(0, 10, 0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR((ecef_to_enu(north_x.to_ecef({0, 10, 0}), origin) - Eigen::Vector3d(-10, 0, 0)).norm(), 0.0, 1e-6);
  const Eigen::Vector3d p(3.0, -4.0, 5.0);
  EXPECT_NEAR((north_x.from_ecef(north_x.to_ecef(p)) - p).norm(), 0.0, 1e-6);
}

}  // namespace
}  // namespace skytrace
