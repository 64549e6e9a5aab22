// rosbag2 bags of skytrace's ROS 2 messages checked by the libraries Foxglove's viewer reads them
// with (tests/clients/mcap/check_bag.mjs: @mcap/core with CRC checks, @mcap/support's
// decompressors, @foxglove/rosmsg, @foxglove/rosmsg2-serialization): every message decodes, encodes
// again to the same bytes with Foxglove's MessageWriter, metadata.yaml agrees with the MCAP file,
// and decoded values equal what was written. Runs for each chunk compression ("mcap/..." names).
// Skips only when the npm packages are not installed (scripts/setup installs them).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "process.hpp"
#include "skytrace/io/rosbag2.hpp"
#include "skytrace/ros2/messages.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

using nlohmann::json;
using io::QosProfileKind;

std::filesystem::path client_dir() { return test::source_dir() / "tests" / "clients" / "mcap"; }

json stamp_json(const ros2::Time& t) { return {{"sec", t.sec}, {"nanosec", t.nanosec}}; }
json header_json(const ros2::Header& h) { return {{"stamp", stamp_json(h.stamp)}, {"frame_id", h.frame_id}}; }

// Writes messages of any skytrace ROS 2 type and collects what check_bag.mjs must find.
class BagBuilder {
 public:
  explicit BagBuilder(io::Rosbag2Writer& writer) : writer_(writer) {}

  template <typename Message>
  void topic(const std::string& name, QosProfileKind qos) {
    const std::string type(Message::kType);
    const std::string definition = ros2::message_definition(type);
    ASSERT_FALSE(definition.empty()) << type;
    auto id = writer_.add_topic(name, type, definition, qos);
    ASSERT_TRUE(id.ok()) << id.error().message;
    ids_[name] = *id;
    expect_["topics"][name] = {{"type", type}, {"count", 0}};
    expect_["messages"][name] = json::array();
  }

  template <typename Message>
  void write(const std::string& name, std::uint64_t stamp_ns, const Message& message, json values = json::object()) {
    const auto bytes = ros2::serialize(message);
    const Status status = writer_.write(ids_.at(name), stamp_ns, bytes);
    ASSERT_TRUE(status.ok()) << status.error().message;
    expect_["topics"][name]["count"] = expect_["topics"][name]["count"].get<int>() + 1;
    expect_["messages"][name].push_back(std::move(values));
  }

  [[nodiscard]] const json& expectations() const { return expect_; }

 private:
  io::Rosbag2Writer& writer_;
  std::map<std::string, std::uint16_t> ids_;
  json expect_ = json::object();
};

ros2::Header header_at(std::uint64_t stamp_ns, const std::string& frame) {
  ros2::Header header;
  header.stamp.sec = static_cast<std::int32_t>(stamp_ns / 1'000'000'000);
  header.stamp.nanosec = static_cast<std::uint32_t>(stamp_ns % 1'000'000'000);
  header.frame_id = frame;
  return header;
}

// One message of every type skytrace publishes, over `epochs` epochs at 10 Hz (the gnss_comm
// topics optionally).
void write_every_type(BagBuilder& bag, int epochs, bool gnss_comm = false) {
  bag.topic<ros2::NavSatFix>("/gnss/fix", QosProfileKind::kSensorData);
  bag.topic<ros2::TwistWithCovarianceStamped>("/gnss/vel", QosProfileKind::kSensorData);
  bag.topic<ros2::TimeReference>("/gnss/time_reference", QosProfileKind::kSensorData);
  bag.topic<ros2::NmeaSentence>("/nmea_sentence", QosProfileKind::kDefault);
  bag.topic<ros2::RtcmMessage>("/rtcm", QosProfileKind::kDefault);
  bag.topic<ros2::Observations>("/gnss/observations", QosProfileKind::kSensorData);
  bag.topic<ros2::Sky>("/gnss/sky", QosProfileKind::kDefault);
  if (gnss_comm) {
    bag.topic<ros2::GnssMeasMsg>("/ublox_driver/range_meas", QosProfileKind::kDefault);
    bag.topic<ros2::GnssEphemMsg>("/ublox_driver/ephem", QosProfileKind::kDefault);
    bag.topic<ros2::GnssGloEphemMsg>("/ublox_driver/glo_ephem", QosProfileKind::kDefault);
  }
  bag.topic<ros2::Odometry>("/gnss/odom", QosProfileKind::kDefault);
  bag.topic<ros2::PoseStamped>("/gnss/pose", QosProfileKind::kDefault);
  bag.topic<ros2::TFMessage>("/tf", QosProfileKind::kDefault);
  bag.topic<ros2::Clock>("/clock", QosProfileKind::kDefault);
  bag.topic<ros2::MarkerArray>("/world/markers", QosProfileKind::kTransientLocal);
  if (testing::Test::HasFatalFailure()) return;

  const std::uint64_t t0 = 1'593'302'418'000'000'000ULL;  // 2020-06-28, the ESBC recording's day
  {
    ros2::MarkerArray markers;
    ros2::Marker marker;
    marker.header = header_at(t0, "map");
    marker.ns = "buildings";
    marker.id = 7;
    marker.type = ros2::Marker::kLineList;
    marker.pose.orientation.w = 1;
    marker.scale.x = 0.1;
    marker.color = {0.2f, 0.4f, 0.6f, 1.0f};
    marker.points = {{0, 0, 0}, {10.5, -3.25, 20}};
    marker.colors = {{1, 0, 0, 1}, {0, 1, 0, 1}};
    marker.text = "block";
    marker.mesh_file.filename = "a.dae";
    marker.mesh_file.data = {1, 2, 3};
    markers.markers = {marker, marker};
    markers.markers[1].action = ros2::Marker::kActionDeleteAll;
    bag.write("/world/markers", t0, markers,
              {{"markers", {{{"ns", "buildings"}, {"id", 7}, {"type", 5}, {"text", "block"},
                             {"points", {{{"x", 0.0}}, {{"x", 10.5}, {"y", -3.25}, {"z", 20.0}}}},
                             {"color", {{"r", 0.2f}, {"b", 0.6f}}}, {"mesh_file", {{"data", {1, 2, 3}}}}},
                            {{"action", 3}}}}});
  }
  for (int e = 0; e < epochs; ++e) {
    const std::uint64_t t = t0 + static_cast<std::uint64_t>(e) * 100'000'000;
    const ros2::Header header = header_at(t, "gnss");

    ros2::NavSatFix fix;
    fix.header = header;
    fix.status.status = e % 5 == 4 ? ros2::NavSatStatus::kStatusNoFix : ros2::NavSatStatus::kStatusFix;
    fix.status.service = ros2::NavSatStatus::kServiceGps | ros2::NavSatStatus::kServiceGalileo;
    fix.latitude = 39.0213 + 1e-7 * e;
    fix.longitude = -76.8270 - 1e-7 * e;
    fix.altitude = 45.678 + 0.01 * e;
    for (int i = 0; i < 9; ++i) fix.position_covariance[static_cast<size_t>(i)] = i % 4 == 0 ? 1.5 + e : 0.0;
    fix.position_covariance_type = ros2::NavSatFix::kCovarianceDiagonalKnown;
    json covariance = json::array();
    for (double c : fix.position_covariance) covariance.push_back(c);
    bag.write("/gnss/fix", t, fix,
              {{"header", header_json(header)},
               {"status", {{"status", fix.status.status}, {"service", fix.status.service}}},
               {"latitude", fix.latitude}, {"longitude", fix.longitude}, {"altitude", fix.altitude},
               {"position_covariance", covariance}, {"position_covariance_type", 2}});

    ros2::TwistWithCovarianceStamped velocity;
    velocity.header = header;
    velocity.twist.twist.linear = {1.25, -0.5, 0.01 * e};
    velocity.twist.covariance[0] = 0.04;
    bag.write("/gnss/vel", t, velocity, {{"twist", {{"twist", {{"linear", {{"x", 1.25}, {"y", -0.5}}}}}}}});

    ros2::TimeReference time_reference;
    time_reference.header = header;
    time_reference.time_ref = ros2::Time{1'593'302'400 + e, 500};
    time_reference.source = "gps";
    bag.write("/gnss/time_reference", t, time_reference,
              {{"time_ref", stamp_json(time_reference.time_ref)}, {"source", "gps"}});

    ros2::NmeaSentence nmea;
    nmea.header = header;
    nmea.sentence = "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47" + std::string(e % 3, ' ');
    bag.write("/nmea_sentence", t, nmea, {{"sentence", nmea.sentence}});

    ros2::RtcmMessage rtcm;
    rtcm.header = header;
    rtcm.message.assign(static_cast<size_t>(5 + e % 7), static_cast<std::uint8_t>(0xD3));
    json rtcm_bytes = json::array();
    for (auto b : rtcm.message) rtcm_bytes.push_back(b);
    bag.write("/rtcm", t, rtcm, {{"message", rtcm_bytes}});

    ros2::Observations observations;
    observations.header = header;
    observations.gps_week = 2111;
    observations.gps_tow_s = 18.0 + 0.1 * e;
    observations.pose_stale = e == 2;
    for (int s = 0; s < 3 + e % 2; ++s) {
      ros2::Observation o;
      o.satellite = s == 2 ? std::string("R05") : std::to_string(10 + s).insert(0, 1, 'G');
      o.system = s == 2 ? "GLONASS" : "GPS";
      o.prn = static_cast<std::uint16_t>(10 + s);
      o.glonass_channel = s == 2 ? -4 : 0;
      o.signal = "1C";
      o.carrier_frequency_hz = s == 2 ? 1.602e9 - 4 * 562500.0 : 1575.42e6;
      o.pseudorange_m = 2.1e7 + 1000.0 * s + 0.25 * e;
      o.carrier_phase_cycles = 1.1e8 + s;
      o.doppler_hz = -1234.5 + s;
      o.cn0_dbhz = 42.0 + s;
      o.loss_of_lock = e == 0;
      o.lock_time_s = 0.1 * e;
      o.azimuth_deg = 120.0 + 10 * s;
      o.elevation_deg = 35.0 + s;
      o.los = s != 1;
      o.nlos = s == 1;
      o.vegetation = s == 0;
      o.vegetation_path_m = s == 0 ? 3.5 : 0.0;
      o.vegetation_attenuation_db = s == 0 ? 2.25 : 0.0;
      observations.observations.push_back(o);
    }
    // A list compares by length and element by element: an empty object matches any element.
    json expected_observations = json::array();
    for (size_t s = 0; s < observations.observations.size(); ++s) expected_observations.push_back(json::object());
    expected_observations[0] = {{"satellite", "G10"}, {"pseudorange_m", observations.observations[0].pseudorange_m},
                                {"vegetation_path_m", 3.5}, {"loss_of_lock", e == 0}};
    expected_observations[1] = {{"nlos", true}, {"los", false}};
    expected_observations[2] = {{"satellite", "R05"}, {"glonass_channel", -4}, {"prn", 12}};
    bag.write("/gnss/observations", t, observations,
              {{"gps_week", 2111}, {"gps_tow_s", observations.gps_tow_s}, {"pose_stale", e == 2},
               {"observations", expected_observations}});

    ros2::Sky sky;
    sky.header = header;
    sky.gps_week = 2111;
    sky.gps_tow_s = observations.gps_tow_s;
    ros2::SatelliteSky satellite;
    satellite.satellite = "E11";
    satellite.system = "Galileo";
    satellite.prn = 11;
    satellite.azimuth_deg = 300.5;
    satellite.elevation_deg = 12.25;
    satellite.status = ros2::SatelliteSky::kBlocked;
    satellite.detail = "building 3";
    sky.satellites = {satellite, satellite};
    sky.satellites[1].status = ros2::SatelliteSky::kTracked;
    sky.satellites[1].used_in_fix = true;
    bag.write("/gnss/sky", t, sky,
              {{"satellites", {{{"status", 4}, {"detail", "building 3"}}, {{"status", 0}, {"used_in_fix", true}}}}});

    if (gnss_comm) {
      ros2::GnssMeasMsg meas;
      ros2::GnssObsMsg obs;
      obs.time = {2111, 18.0 + 0.1 * e};
      obs.sat = 10;
      obs.freqs = {1575.42e6, 1227.6e6};
      obs.cn0 = {44, 38};
      obs.lli = {0, 1};
      obs.code = {1, 14};
      obs.psr = {2.1e7, 2.1e7 + 2.5};
      obs.psr_std = {0.3, 0.6};
      obs.cp = {1.1e8, 8.6e7};
      obs.cp_std = {0.004, 0.008};
      obs.dopp = {-1234.5, -962.1};
      obs.dopp_std = {0.1, 0.2};
      obs.status = {0x0F, 0x07};
      meas.meas = {obs};
      bag.write("/ublox_driver/range_meas", t, meas,
                {{"meas", {{{"sat", 10}, {"time", {{"week", 2111}, {"tow", obs.time.tow}}}, {"lli", {0, 1}},
                            {"psr", {2.1e7, 2.1e7 + 2.5}}, {"status", {15, 7}}}}}});

      if (e % 10 == 0) {
        ros2::GnssEphemMsg ephem;
        ephem.sat = 10;
        ephem.toe = {2111, 21600};
        ephem.week = 2111;
        ephem.a = 26559700.5;
        ephem.e = 0.0123;
        ephem.af0 = -1.2e-5;
        bag.write("/ublox_driver/ephem", t, ephem, {{"sat", 10}, {"a", ephem.a}, {"af0", ephem.af0}});
        ros2::GnssGloEphemMsg glo;
        glo.sat = 65;
        glo.freqo = -4;
        glo.pos_x = 1.2e7;
        glo.tau_n = 3.5e-5;
        bag.write("/ublox_driver/glo_ephem", t, glo, {{"freqo", -4}, {"tau_n", glo.tau_n}});
      }
    }

    ros2::Odometry odom;
    odom.header = header_at(t, "map");
    odom.child_frame_id = "gnss_antenna";
    odom.pose.pose.position = {100.5, -20.25, 3.0};
    odom.pose.covariance[35] = 9.0;
    bag.write("/gnss/odom", t, odom, {{"child_frame_id", "gnss_antenna"}, {"pose", {{"pose", {{"position", {{"x", 100.5}}}}}}}});

    ros2::PoseStamped pose;
    pose.header = header_at(t, "map");
    pose.pose.orientation = {0, 0, 0.7071067811865476, 0.7071067811865476};
    bag.write("/gnss/pose", t, pose, {{"pose", {{"orientation", {{"z", 0.7071067811865476}}}}}});

    ros2::TFMessage tf;
    ros2::TransformStamped transform;
    transform.header = header_at(t, "map");
    transform.child_frame_id = "base_link";
    transform.transform.translation = {1, 2, 3};
    tf.transforms = {transform};
    bag.write("/tf", t, tf, {{"transforms", {{{"child_frame_id", "base_link"}}}}});

    ros2::Clock clock;
    clock.clock = header.stamp;
    bag.write("/clock", t, clock, {{"clock", stamp_json(header.stamp)}});
  }
}

class FoxgloveBagCheck : public testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(client_dir() / "node_modules" / "@mcap" / "core")) {
      GTEST_SKIP() << "npm packages not installed in " << client_dir() << " (run scripts/setup)";
    }
  }

  // Runs check_bag.mjs; returns its JSON summary.
  json check(const std::filesystem::path& bag, const json& expectations) {
    const auto expect_file = bag.parent_path() / (bag.filename().string() + ".expect.json");
    std::ofstream(expect_file) << expectations.dump(1);
    const auto result = test::run_command("node " + test::shell_quote((client_dir() / "check_bag.mjs").string()) + " " +
                                          test::shell_quote(bag.string()) + " --expect " +
                                          test::shell_quote(expect_file.string()) + " 2>&1");
    EXPECT_EQ(result.exit_code, 0) << result.output;
    const auto start = result.output.find('{');
    if (start == std::string::npos) {
      ADD_FAILURE() << "no JSON from check_bag.mjs: " << result.output;
      return json::object();
    }
    try {
      return json::parse(result.output.substr(start));
    } catch (const json::exception& error) {
      ADD_FAILURE() << error.what() << "\n" << result.output;
      return json::object();
    }
  }
};

TEST_P(FoxgloveBagCheck, EveryMessageOfEveryTypeDecodesAndEncodesToTheSameBytes) {
  const auto bag = test::make_temp_dir("mcap_bag") / "every_type";
  io::Rosbag2Options options;
  options.mcap.compression = GetParam();
  auto writer = io::Rosbag2Writer::open(bag, options);
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  BagBuilder builder(**writer);
  write_every_type(builder, 2);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_TRUE((*writer)->close().ok());

  const json summary = check(bag, builder.expectations());
  EXPECT_EQ(summary.value("ok", false), true) << summary.dump(1);
  EXPECT_EQ(summary.value("profile", ""), "ros2");
  EXPECT_EQ(summary.value("metadata_version", 0), 9);
  EXPECT_EQ(summary.value("ros_distro", ""), "jazzy");
  EXPECT_EQ(summary["compression"], json::array({GetParam()}));
  ASSERT_TRUE(summary.contains("topics"));
  EXPECT_EQ(summary["topics"].size(), 12u);
  for (const auto& topic : summary["topics"]) {
    if (topic["name"] == "/gnss/fix") {
      EXPECT_EQ(topic["qos"]["reliability"], "best_effort");
      EXPECT_EQ(topic["qos"]["depth"], 5);
    }
    if (topic["name"] == "/world/markers") {
      EXPECT_EQ(topic["qos"]["durability"], "transient_local");
    }
  }
}

TEST_P(FoxgloveBagCheck, ALongRunSpreadOverManyChunksReadsBackInOrder) {
  const auto bag = test::make_temp_dir("mcap_bag") / "long_run";
  io::Rosbag2Options options;
  options.mcap.compression = GetParam();
  options.mcap.chunk_size_bytes = 16 * 1024;
  auto writer = io::Rosbag2Writer::open(bag, options);
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  BagBuilder builder(**writer);
  write_every_type(builder, 200);  // 20 s at 10 Hz
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_TRUE((*writer)->close().ok());

  const json summary = check(bag, builder.expectations());
  EXPECT_EQ(summary.value("ok", false), true) << summary.dump(1);
  EXPECT_GT(summary.value("chunk_count", 0), 20);
  EXPECT_EQ(summary.value("message_count", 0), 1 + 200 * 11);
}

// gnss_comm's messages with their field names in lower case, as ROS 2 requires (messages.hpp).
TEST_P(FoxgloveBagCheck, GnssCommTopicsDecode) {
  const auto bag = test::make_temp_dir("mcap_bag") / "gnss_comm";
  io::Rosbag2Options options;
  options.mcap.compression = GetParam();
  auto writer = io::Rosbag2Writer::open(bag, options);
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  BagBuilder builder(**writer);
  write_every_type(builder, 10, /*gnss_comm=*/true);
  ASSERT_FALSE(HasFatalFailure());
  ASSERT_TRUE((*writer)->close().ok());
  const json summary = check(bag, builder.expectations());
  EXPECT_EQ(summary.value("ok", false), true) << summary.dump(1);
}

std::string compression_name(const testing::TestParamInfo<std::string>& param) {
  return param.param.empty() ? "none" : param.param;
}

INSTANTIATE_TEST_SUITE_P(mcap, FoxgloveBagCheck, testing::Values(std::string("zstd"), std::string("lz4"), std::string()),
                         compression_name);

}  // namespace
}  // namespace skytrace
