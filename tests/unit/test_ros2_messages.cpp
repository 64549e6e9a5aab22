// ROS 2 messages: CDR layout (alignment from the end of the encapsulation header), round trips,
// malformed payloads, names on the wire and rosbag2 definition texts. The byte-for-byte check
// against an independent CDR implementation is done by tests/clients (Foxglove's MessageWriter)
// and the Fast DDS peer (Fast CDR).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "skytrace/ros2/messages.hpp"

namespace skytrace::ros2 {
namespace {

TEST(Ros2Cdr, HeaderBytesAreThoseOfTheSpecification) {
  Header header;
  header.stamp = Time{1, 2};
  header.frame_id = "ab";
  const std::vector<std::uint8_t> expected = {0x00, 0x01, 0x00, 0x00,  // CDR_LE
                                              1, 0, 0, 0, 2, 0, 0, 0,  // sec, nanosec
                                              3, 0, 0, 0, 'a', 'b', 0};  // length with NUL
  EXPECT_EQ(serialize(header), expected);
}

TEST(Ros2Cdr, NavSatFixAlignsDoublesToEightBytesAfterTheHeader) {
  NavSatFix fix;
  fix.header.frame_id = "gps";  // header: 4 + 4 + 4 + 4 bytes
  fix.status.status = NavSatStatus::kStatusFix;
  fix.status.service = NavSatStatus::kServiceGps | NavSatStatus::kServiceGalileo;
  fix.latitude = 48.1;
  fix.position_covariance_type = NavSatFix::kCovarianceKnown;
  const auto bytes = serialize(fix);
  // status int8 at 16, one byte of padding, service at 18, latitude aligned to 24.
  ASSERT_EQ(bytes.size(), 4u + 24 + 3 * 8 + 9 * 8 + 1);
  EXPECT_EQ(bytes[4 + 16], 0);
  EXPECT_EQ(bytes[4 + 18], 9);
  double latitude = 0;
  std::memcpy(&latitude, bytes.data() + 4 + 24, 8);
  EXPECT_EQ(latitude, 48.1);
  EXPECT_EQ(bytes.back(), 3);
}

TEST(Ros2Cdr, EveryMessageRoundTrips) {
  Marker marker;
  marker.header.frame_id = "world";
  marker.ns = "rays";
  marker.type = Marker::kLineList;
  marker.points = {{1, 2, 3}, {4, 5, 6}};
  marker.colors = {{1, 0, 0, 1}, {0, 1, 0, 1}};
  marker.texture.data = {1, 2, 3};
  marker.uv_coordinates = {{0.5f, 0.25f}};
  marker.mesh_file.filename = "x.dae";
  MarkerArray markers;
  markers.markers = {marker, marker};
  auto decoded = deserialize<MarkerArray>(serialize(markers));
  ASSERT_TRUE(decoded.ok()) << decoded.error().message;
  EXPECT_EQ(serialize(*decoded), serialize(markers));
  ASSERT_EQ(decoded->markers.size(), 2u);
  EXPECT_EQ(decoded->markers[1].points[1].z, 6.0);
  EXPECT_EQ(decoded->markers[0].uv_coordinates[0].v, 0.25f);

  GnssMeasMsg meas;
  GnssObsMsg obs;
  obs.time = {2111, 345600.5};
  obs.sat = 7;
  obs.freqs = {1575.42e6, 1227.6e6};
  obs.psr = {2.1e7, 2.1e7 + 3};
  obs.lli = {0, 1};
  obs.status = {1, 3};
  meas.meas = {obs, obs};
  auto meas_back = deserialize<GnssMeasMsg>(serialize(meas));
  ASSERT_TRUE(meas_back.ok());
  EXPECT_EQ(meas_back->meas[1].psr[1], 2.1e7 + 3);
  EXPECT_EQ(meas_back->meas[0].time.tow, 345600.5);

  TFMessage tf;
  TransformStamped t;
  t.header.frame_id = "odom";
  t.child_frame_id = "base_link";
  t.transform.rotation.w = 0.5;
  tf.transforms = {t};
  auto tf_back = deserialize<TFMessage>(serialize(tf));
  ASSERT_TRUE(tf_back.ok());
  EXPECT_EQ(tf_back->transforms[0].child_frame_id, "base_link");
  EXPECT_EQ(tf_back->transforms[0].transform.rotation.w, 0.5);

  Observations observations;
  observations.gps_week = 2111;
  Observation o;
  o.satellite = "E11";
  o.nlos = true;
  o.cn0_dbhz = 41.5;
  observations.observations = {o};
  auto obs_back = deserialize<Observations>(serialize(observations));
  ASSERT_TRUE(obs_back.ok());
  EXPECT_TRUE(obs_back->observations[0].nlos);
  EXPECT_EQ(obs_back->observations[0].cn0_dbhz, 41.5);
}

TEST(Ros2Cdr, MalformedPayloadsAreErrorsNotCrashes) {
  NavSatFix fix;
  fix.header.frame_id = "gps";
  auto bytes = serialize(fix);
  for (size_t cut = 0; cut < bytes.size(); ++cut) {
    auto truncated = deserialize<NavSatFix>(std::span<const std::uint8_t>(bytes.data(), cut));
    EXPECT_FALSE(truncated.ok()) << cut;
  }
  // A sequence claiming four billion elements in a short message.
  std::vector<std::uint8_t> huge = {0x00, 0x01, 0x00, 0x00, 0xff, 0xff, 0xff, 0xff};
  auto tf = deserialize<TFMessage>(huge);
  ASSERT_FALSE(tf.ok());
  EXPECT_NE(tf.error().message.find("sequence"), std::string::npos);
  // Representations ROS 2 does not use.
  std::vector<std::uint8_t> pl_cdr = {0x00, 0x03, 0x00, 0x00, 0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_FALSE(deserialize<Clock>(pl_cdr).ok());
  // A boolean of 2.
  Observations observations;
  observations.restarted = true;
  auto flags = serialize(observations);
  flags[4 + 32] = 2;  // stamp 0-7, frame id 8-12, padding, week 16-19, padding, tow 24-31, restarted
  EXPECT_FALSE(deserialize<Observations>(flags).ok());
}

TEST(Ros2Cdr, BigEndianPayloadsAreRead) {
  const std::vector<std::uint8_t> clock = {0x00, 0x00, 0x00, 0x00, 0, 0, 0, 5, 0, 0, 0, 7};
  auto decoded = deserialize<Clock>(clock);
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded->clock.sec, 5);
  EXPECT_EQ(decoded->clock.nanosec, 7u);
}

TEST(Ros2Cdr, TimeFromSecondsRoundsToTheNanosecond) {
  EXPECT_EQ(Time::from_seconds(1.5).sec, 1);
  EXPECT_EQ(Time::from_seconds(1.5).nanosec, 500000000u);
  const Time almost = Time::from_seconds(2.9999999999);
  EXPECT_EQ(almost.sec, 3);
  EXPECT_EQ(almost.nanosec, 0u);
  EXPECT_EQ(Time::from_seconds(-0.25).sec, -1);
  EXPECT_EQ(Time::from_seconds(-0.25).nanosec, 750000000u);
}

TEST(Ros2Names, DdsTypeNamesAreThoseRmwUses) {
  EXPECT_EQ(dds_type_name(NavSatFix::kType), "sensor_msgs::msg::dds_::NavSatFix_");
  EXPECT_EQ(dds_type_name(ParticipantEntitiesInfo::kType), "rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_");
}

TEST(Ros2Names, GidIsTwentyFourBytesInHumbleAndSixteenInJazzy) {
  ParticipantEntitiesInfo info;
  info.gid.data[0] = 0x01;
  info.gid.data[15] = 0x0f;
  NodeEntitiesInfo node;
  node.node_name = "skytrace";
  node.node_namespace = "/";
  node.writer_gid_seq.resize(2);
  info.node_entities_info_seq = {node};
  const auto humble = serialize(info, RosDistro::kHumble);
  const auto jazzy = serialize(info, RosDistro::kJazzy);
  EXPECT_EQ(humble.size() - jazzy.size(), 3u * 8);
  auto back = deserialize_participant_info(jazzy, RosDistro::kJazzy);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->gid.data[15], 0x0f);
  EXPECT_EQ(back->node_entities_info_seq[0].node_name, "skytrace");
  EXPECT_EQ(back->node_entities_info_seq[0].writer_gid_seq.size(), 2u);
  EXPECT_FALSE(parse_ros_distro("noetic").ok());
}

TEST(Ros2Definitions, NavSatFixCarriesEveryTypeItUsesOnce) {
  const std::string text = message_definition(NavSatFix::kType);
  EXPECT_EQ(text.rfind("std_msgs/Header header\nNavSatStatus status\n", 0), 0u) << text;
  for (const char* dependency : {"MSG: std_msgs/Header\n", "MSG: builtin_interfaces/Time\n",
                                 "MSG: sensor_msgs/NavSatStatus\n"}) {
    const size_t first = text.find(dependency);
    ASSERT_NE(first, std::string::npos) << dependency;
    EXPECT_EQ(text.find(dependency, first + 1), std::string::npos) << dependency;
  }
  EXPECT_NE(text.find("uint8 COVARIANCE_TYPE_KNOWN = 3"), std::string::npos);
  EXPECT_NE(text.find(std::string(80, '=') + "\nMSG: "), std::string::npos);
  // The gnss_comm types refer to each other without a package.
  EXPECT_NE(message_definition(GnssMeasMsg::kType).find("MSG: gnss_comm/GnssTimeMsg"), std::string::npos);
  EXPECT_TRUE(message_definition("no_msgs/msg/Nothing").empty());
}

}  // namespace
}  // namespace skytrace::ros2
