// The pieces of the ROS 2 topics of a receiver: gnss_comm numbering (its sat_no and RTKLIB's
// code table), RTCM frame splitting, NavSatFix status and covariance, UTC stamps.
#include <gtest/gtest.h>

#include <cmath>

#include "skytrace/sim/ros2_topics.hpp"

namespace skytrace::sim {
namespace {

SatelliteId sat(const char* text) { return SatelliteId::parse(text).value(); }

TEST(Ros2Topics, GnssCommNumbersSatellitesAsItsSatNo) {
  EXPECT_EQ(gnss_comm_satellite(sat("G01")), 1u);
  EXPECT_EQ(gnss_comm_satellite(sat("G32")), 32u);
  EXPECT_EQ(gnss_comm_satellite(sat("R01")), 33u);
  EXPECT_EQ(gnss_comm_satellite(sat("E01")), 60u);
  EXPECT_EQ(gnss_comm_satellite(sat("C01")), 98u);
  EXPECT_EQ(gnss_comm_satellite(sat("C63")), 160u);
  EXPECT_EQ(gnss_comm_satellite(sat("J01")), 0u);  // gnss_comm has no QZSS
  EXPECT_EQ(gnss_comm_satellite(sat("S27")), 0u);
}

TEST(Ros2Topics, GnssCommCodesAreRtklibs) {
  EXPECT_EQ(gnss_comm_code(Signal::from_code(GnssSystem::kGps, "1C").value()), 1);
  EXPECT_EQ(gnss_comm_code(Signal::from_code(GnssSystem::kGps, "2W").value()), 20);
  EXPECT_EQ(gnss_comm_code(Signal::from_code(GnssSystem::kGalileo, "5Q").value()), 25);
  EXPECT_EQ(gnss_comm_code(Signal::from_code(GnssSystem::kBeiDou, "2I").value()), 40);
}

TEST(Ros2Topics, RtcmStreamsSplitIntoFrames) {
  // Two frames of 2 and 0 payload bytes, garbage in between.
  const std::vector<std::uint8_t> stream = {0xD3, 0x00, 0x02, 0xAA, 0xBB, 1, 2, 3, 0x55,
                                            0xD3, 0x00, 0x00, 4,    5,    6};
  const auto frames = split_rtcm3_frames(stream);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].size(), 8u);
  EXPECT_EQ(frames[1].size(), 6u);
  EXPECT_EQ(frames[1][0], 0xD3);
}

TEST(Ros2Topics, NavSatFixStatusFollowsTheSolutionType) {
  const ros2::Header header{ros2::Time{5, 0}, "gnss"};
  const auto none = to_navsat_fix(nullptr, header);
  EXPECT_EQ(none.status.status, ros2::NavSatStatus::kStatusNoFix);
  EXPECT_TRUE(std::isnan(none.latitude));
  positioning::PositionFix fix;
  fix.type = positioning::FixType::kFix3D;
  fix.position = Geodetic{48.0, 11.0, 500.0};
  fix.covariance_enu_m2 << 4, 0.5, 0, 0.5, 9, 0, 0, 0, 16;
  positioning::SatelliteUse g, e, c;
  g.satellite = sat("G05");
  e.satellite = sat("E11");
  c.satellite = sat("C30");
  g.used = e.used = true;  // C30 not used
  fix.satellites = {g, e, c};
  const auto single = to_navsat_fix(&fix, header);
  EXPECT_EQ(single.status.status, ros2::NavSatStatus::kStatusFix);
  EXPECT_EQ(single.status.service, ros2::NavSatStatus::kServiceGps | ros2::NavSatStatus::kServiceGalileo);
  EXPECT_EQ(single.position_covariance[1], 0.5);
  EXPECT_EQ(single.position_covariance[8], 16.0);
  EXPECT_EQ(single.position_covariance_type, ros2::NavSatFix::kCovarianceKnown);
  fix.type = positioning::FixType::kRtkFixed;
  EXPECT_EQ(to_navsat_fix(&fix, header).status.status, ros2::NavSatStatus::kStatusGbasFix);
}

TEST(Ros2Topics, UtcStampsCountLeapSeconds) {
  // 2020-06-25T00:00:18 GPST is 00:00:00 UTC (18 leap seconds): Unix 1593043200.
  const GnssTime t = GnssTime::parse_iso8601("2020-06-25T00:00:18.25", TimeScale::kGpst).value();
  const ros2::Time utc = unix_utc_time(t);
  EXPECT_EQ(utc.sec, 1593043200);
  EXPECT_EQ(utc.nanosec, 250000000u);
}

}  // namespace
}  // namespace skytrace::sim
