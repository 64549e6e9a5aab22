// skytrace_ros_node against a roscore of the test's own: the contract's acceptance (a fix near
// ESBC's antenna and every tracked satellite on /skytrace/observations, checked against a
// LiveSession run in-process at the same epochs), and the antenna moved by a pose topic.
#include <gtest/gtest.h>

#include "live_receiver.hpp"
#include "process.hpp"
#include "test_support.hpp"

#if SKYTRACE_HAVE_ROS
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/NavSatFix.h>
#include <std_msgs/String.h>
#include <skytrace_msgs/Observations.h>
#include <sys/prctl.h>

#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <set>

#include "child_process.hpp"
#endif

namespace skytrace {
namespace {

#if SKYTRACE_HAVE_ROS

using namespace std::chrono_literals;

std::filesystem::path contract_scenario() {
  return test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
}

double distance_m(const live::Vec3& a, const live::Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// The receiver of the contract scenario, run in-process: the expected values, and the world frame
// (east-north-up at ESBC's marker) the node uses too.
std::unique_ptr<live::Receiver> contract_receiver() {
  live::ReceiverOptions options;
  options.scenario_path = contract_scenario().string();
  std::string error;
  auto receiver = live::Receiver::create(options, error);
  EXPECT_TRUE(receiver) << error;
  return receiver;
}

live::Vec3 fix_world_m(const live::Receiver& receiver, const sensor_msgs::NavSatFix& fix) {
  return receiver.world_from_geodetic(fix.latitude, fix.longitude, fix.altitude);
}

// One roscore for the test process: roscpp is initialised once per process, with one master.
class RosMaster {
 public:
  static RosMaster& instance() {
    static RosMaster master;
    return master;
  }
  [[nodiscard]] const std::string& problem() const { return problem_; }
  [[nodiscard]] std::map<std::string, std::string> environment() const {
    return {{"ROS_MASTER_URI", uri_}, {"ROS_HOSTNAME", "localhost"}, {"ROS_HOME", home_.string()}};
  }
  [[nodiscard]] const std::filesystem::path& home() const { return home_; }
  ~RosMaster() {
    if (ros::isInitialized()) ros::shutdown();
  }

 private:
  RosMaster() {
    home_ = test::make_temp_dir("ros_master");
    const int port = test::free_tcp_port();
    uri_ = "http://localhost:" + std::to_string(port);
    for (const auto& [key, value] : environment()) setenv(key.c_str(), value.c_str(), 1);
    // The tests' main ends by std::quick_exit, without this object's destructor: stop roscore
    // (and its rosmaster and rosout) there.
    std::at_quick_exit([] { (void)instance().roscore_.stop(); });
    int argc = 0;
    ros::init(argc, nullptr, "skytrace_test", ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
    // A NodeHandle blocks until the master answers: wait for it first. roslaunch gives up when its
    // master takes more than 10 s to come up ("could not contact master"), as happened on the
    // 2-core machine under the IQ tests' load: then start it again.
    for (int attempt = 0; attempt < 3; ++attempt) {
      if (!roscore_.start({"roscore", "-p", std::to_string(port)}, environment(), home_ / "roscore.log")) {
        problem_ = "cannot start roscore";
        return;
      }
      const bool answered = test::wait_until([this] { return ros::master::check() || !roscore_.running(); }, 60s) &&
                            ros::master::check();
      if (answered) {
        problem_.clear();
        return;
      }
      problem_ = "roscore did not answer on " + uri_ + ":\n" + roscore_.log_text();
      (void)roscore_.stop();
    }
  }
  test::ChildProcess roscore_;
  std::filesystem::path home_;
  std::string uri_;
  std::string problem_;
};

class RosNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!test::program_available("roscore")) GTEST_SKIP() << "roscore not installed (python3-roslaunch)";
    if (!std::filesystem::exists(contract_scenario()) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
    }
    ASSERT_TRUE(RosMaster::instance().problem().empty()) << RosMaster::instance().problem();
    receiver_ = contract_receiver();
    ASSERT_TRUE(receiver_);
  }
  void TearDown() override {
    if (node_.running()) {
      const int status = node_.stop();
      // Asked to stop with SIGINT, the node finishes its outputs and exits 0.
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "node log:\n" << node_.log_text();
    }
  }

  void start_node(std::vector<std::string> args, const std::string& name) {
    args.insert(args.begin(), (test::binary_dir() / "bin" / "skytrace_ros_node").string());
    args.push_back("_scenario:=" + contract_scenario().string());
    ASSERT_TRUE(node_.start(args, RosMaster::instance().environment(), RosMaster::instance().home() / (name + ".log")));
  }

  // Spins until `condition` holds; fails with the node's log otherwise.
  template <typename F>
  void spin_until(F condition, const std::string& what) {
    const bool ok = test::wait_until(
        [&] {
          ros::spinOnce();
          return condition() || !node_.running();
        },
        45s);
    ASSERT_TRUE(ok && condition()) << what << "; node " << (node_.running() ? "running" : "exited") << ", log:\n"
                                   << node_.log_text();
  }

  std::unique_ptr<live::Receiver> receiver_;
  test::ChildProcess node_;
};

TEST_F(RosNodeTest, PublishesAFixAtTheStationAndEveryTrackedSatellite) {
  ros::NodeHandle nh;
  std::vector<sensor_msgs::NavSatFix> fixes;
  std::vector<skytrace_msgs::Observations> observations;
  auto fix_sub = nh.subscribe<sensor_msgs::NavSatFix>("/skytrace/fix", 10, [&](const auto& m) { fixes.push_back(*m); });
  auto obs_sub = nh.subscribe<skytrace_msgs::Observations>("/skytrace/observations", 10,
                                                          [&](const auto& m) { observations.push_back(*m); });
  const auto files = test::make_temp_dir("ros_node_files");
  start_node({"_pose_source:=scenario", "_rate_hz:=2", "_rinex_out:=" + (files / "node.obs").string(),
              "_nmea_out:=" + (files / "node.nmea").string()},
             "node_scenario");
  spin_until([&] { return !fixes.empty() && !observations.empty(); }, "no fix and observations from the node");

  const sensor_msgs::NavSatFix& fix = fixes.front();
  ASSERT_EQ(fix.status.status, sensor_msgs::NavSatStatus::STATUS_FIX);
  EXPECT_NE(fix.status.service & sensor_msgs::NavSatStatus::SERVICE_GPS, 0);
  EXPECT_NE(fix.status.service & sensor_msgs::NavSatStatus::SERVICE_GALILEO, 0);
  // ESBC's antenna reference point: 0.2160 m above the marker, the origin of the world frame.
  const live::Vec3 esbc_antenna_world{0.0, 0.0, 0.2160};
  EXPECT_LT(distance_m(fix_world_m(*receiver_, fix), esbc_antenna_world), 15.0);
  EXPECT_EQ(fix.position_covariance_type, sensor_msgs::NavSatFix::COVARIANCE_TYPE_KNOWN);
  EXPECT_GT(fix.position_covariance[8], 0.0);  // up variance

  // The same scenario stepped in-process at the node's epochs (2 Hz from the scenario's start).
  const skytrace_msgs::Observations& published = observations.front();
  const double since_start_s = receiver_->time_s_of_gps(static_cast<int>(published.gps_week), published.gps_tow_s);
  ASSERT_GE(since_start_s, 0.0);
  ASSERT_LT(since_start_s, 3600.0);
  live::EpochView expected;
  for (int k = 0; k <= static_cast<int>(std::lround(since_start_s * 2.0)); ++k) {
    std::string error;
    ASSERT_TRUE(receiver_->step(0.5 * k, expected, error)) << error;
  }
  ASSERT_EQ(expected.gps_week, static_cast<int>(published.gps_week));
  ASSERT_NEAR(expected.gps_tow_s, published.gps_tow_s, 1e-9);

  std::map<std::pair<std::string, std::string>, const skytrace_msgs::Observation*> by_signal;
  std::set<std::string> published_satellites;
  for (const auto& o : published.observations) {
    by_signal[{o.satellite, o.signal}] = &o;
    published_satellites.insert(o.satellite);
    EXPECT_TRUE(o.los) << o.satellite;  // open sky
    EXPECT_FALSE(o.vegetation || o.blocked || o.nlos) << o.satellite;
  }
  std::set<std::string> tracked;
  size_t signals = 0;
  for (const auto& sat : expected.satellites) {
    if (sat.status != live::SkyStatus::kTracked) continue;
    tracked.insert(sat.id);
    for (const auto& m : sat.signals) {
      ++signals;
      const auto it = by_signal.find({sat.id, m.code});
      ASSERT_NE(it, by_signal.end()) << sat.id << " " << m.code << " not published";
      const skytrace_msgs::Observation& o = *it->second;
      EXPECT_NEAR(o.pseudorange_m, m.pseudorange_m, 1e-6) << o.satellite << o.signal;
      EXPECT_NEAR(o.carrier_phase_cycles, m.carrier_phase_cycles, 1e-6) << o.satellite << o.signal;
      EXPECT_NEAR(o.doppler_hz, m.doppler_hz, 1e-6) << o.satellite << o.signal;
      EXPECT_NEAR(o.cn0_dbhz, m.cn0_dbhz, 1e-6) << o.satellite << o.signal;
      EXPECT_NEAR(o.elevation_deg, sat.elevation_deg, 1e-9);
    }
  }
  EXPECT_EQ(published_satellites, tracked);
  EXPECT_EQ(published.observations.size(), signals);
  EXPECT_GE(tracked.size(), 20U);  // GPS, Galileo, GLONASS, BeiDou and QZSS over Esbjerg

  // The files the parameters asked for appear when the node stops, with every epoch in both.
  EXPECT_FALSE(std::filesystem::exists(files / "node.obs"));
  const int status = node_.stop();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << node_.log_text();
  const auto count_lines = [](const std::filesystem::path& path, const std::string& start) {
    std::ifstream in(path);
    int n = 0;
    for (std::string line; std::getline(in, line);) n += line.rfind(start, 0) == 0 ? 1 : 0;
    return n;
  };
  const int epochs = count_lines(files / "node.obs", "> ");
  EXPECT_GE(epochs, 1) << node_.log_text();
  EXPECT_EQ(count_lines(files / "node.nmea", "$GNGGA") + count_lines(files / "node.nmea", "$GPGGA"), epochs);
}

// What docs/ros.md tells users to run: rostopic echo shows the fix, and with the generated Python
// messages (PYTHONPATH=<build>/apps/ros/gen/python) skytrace's own observations and sky.
TEST_F(RosNodeTest, RostopicEchoShowsTheFixAndTheObservations) {
  if (!test::program_available("rostopic")) GTEST_SKIP() << "rostopic not installed (python3-rostopic, scripts/setup)";
  start_node({"_pose_source:=scenario", "_rate_hz:=2"}, "node_rostopic");
  std::string environment;
  for (const auto& [key, value] : RosMaster::instance().environment()) environment += key + "=" + test::shell_quote(value) + " ";
  environment += "PYTHONPATH=" + test::shell_quote((test::binary_dir() / "apps/ros/gen/python").string()) + " ";
  const auto echo = [&](const std::string& topic) {
    return test::run_command(environment + "timeout 60 rostopic echo -n 1 " + topic + " 2>&1");
  };
  const auto fix = echo("/skytrace/fix");
  ASSERT_EQ(fix.exit_code, 0) << fix.output << node_.log_text();
  EXPECT_NE(fix.output.find("latitude: 55.49"), std::string::npos) << fix.output;
  EXPECT_NE(fix.output.find("status: 0"), std::string::npos) << fix.output;  // STATUS_FIX
  const auto observations = echo("/skytrace/observations");
  ASSERT_EQ(observations.exit_code, 0) << observations.output;
  EXPECT_NE(observations.output.find("pseudorange_m: "), std::string::npos) << observations.output;
  EXPECT_NE(observations.output.find("signal: \"1C\""), std::string::npos) << observations.output;
  const auto sky = echo("/skytrace/sky");
  ASSERT_EQ(sky.exit_code, 0) << sky.output;
  EXPECT_NE(sky.output.find("azimuth_deg: "), std::string::npos) << sky.output;
}

TEST_F(RosNodeTest, PoseTopicMovesTheFixAndBadPosesAreIgnored) {
  ros::NodeHandle nh;
  std::optional<sensor_msgs::NavSatFix> last_fix;
  auto fix_sub = nh.subscribe<sensor_msgs::NavSatFix>("/skytrace/fix", 10, [&](const auto& m) { last_fix = *m; });
  ros::Publisher pose_pub = nh.advertise<geometry_msgs::PoseStamped>("/test/antenna_pose", 10);
  start_node({"_pose_source:=pose", "_pose_topic:=/test/antenna_pose", "_rate_hz:=5", "_world_frame:=map"}, "node_pose");

  const auto publish = [&](const live::Vec3& p) {
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = ros::Time::now();
    pose.header.frame_id = "map";
    pose.pose.position.x = p[0];
    pose.pose.position.y = p[1];
    pose.pose.position.z = p[2];
    pose.pose.orientation.w = 1.0;
    pose_pub.publish(pose);
  };
  const auto fix_near = [&](const live::Vec3& p) {
    if (!last_fix || last_fix->status.status < 0) return false;
    return distance_m(fix_world_m(*receiver_, *last_fix), p) < 1.0;
  };
  // Poses ten times a second, as a robot's localisation would send them, until the fix follows.
  const auto drive_to = [&](const live::Vec3& p) {
    auto last_sent = std::chrono::steady_clock::now() - 1s;
    spin_until(
        [&] {
          if (std::chrono::steady_clock::now() - last_sent > 100ms) {
            publish(p);
            last_sent = std::chrono::steady_clock::now();
          }
          return fix_near(p);
        },
        "the fix did not follow the pose topic");
  };
  const live::Vec3 a{120.0, -40.0, 2.0};
  drive_to(a);
  for (int k = 0; k < 5; ++k) publish(live::Vec3{NAN, 0.0, 0.0});  // refused with a warning
  const live::Vec3 b{-350.0, 410.0, 15.0};
  drive_to(b);
  EXPECT_GT(distance_m(a, b), 500.0);
  EXPECT_TRUE(node_.running());
  EXPECT_NE(node_.log_text().find("NaN"), std::string::npos) << node_.log_text();
}

#else

TEST(RosNodeTest, PublishesAFixAtTheStationAndEveryTrackedSatellite) {
  GTEST_SKIP() << "built without ROS 1 (roscpp); scripts/setup installs it";
}
TEST(RosNodeTest, PoseTopicMovesTheFixAndBadPosesAreIgnored) {
  GTEST_SKIP() << "built without ROS 1 (roscpp); scripts/setup installs it";
}

#endif

// RTK on ROS 1: the node of the pair's rover takes the base's RTCM 3 stream from `skytrace serve`
// over TCP (~rtk_base) and publishes GBAS_FIX at the rover.
TEST_F(RosNodeTest, RoverNodeFixesFromABaseStreamOverTcp) {
  const auto pair = test::shared_data_dir().parent_path() / "contract" / "rtk-pair.yaml";
  if (!std::filesystem::exists(pair)) GTEST_SKIP() << "contract rtk-pair.yaml absent";
  const auto dir = test::make_temp_dir("ros_node_rtk");
  const int base_port = test::free_tcp_port();
  test::ChildProcess base;
  ASSERT_TRUE(base.start({test::skytrace_executable().string(), "serve", pair.string(), "--receiver", "BASE", "--rate-hz", "2",
                          "--duration-s", "60", "--rtcm-tcp", "127.0.0.1:" + std::to_string(base_port)},
                         {}, dir / "base.log"));
  ros::NodeHandle nh;
  std::vector<sensor_msgs::NavSatFix> rtk;
  auto fix_sub = nh.subscribe<sensor_msgs::NavSatFix>("/skytrace/fix", 10, [&](const auto& m) {
    if (m->status.status == sensor_msgs::NavSatStatus::STATUS_GBAS_FIX) rtk.push_back(*m);
  });
  std::vector<std::string> args = {(test::binary_dir() / "bin" / "skytrace_ros_node").string(), "_scenario:=" + pair.string(),
                                   "_receiver:=ROVR", "_rate_hz:=2", "_rtk_base:=127.0.0.1:" + std::to_string(base_port)};
  ASSERT_TRUE(node_.start(args, RosMaster::instance().environment(), RosMaster::instance().home() / "node_rtk.log"));
  spin_until([&] { return rtk.size() >= 3; }, "no GBAS_FIX from the rover node");
  for (const auto& m : rtk) {
    // The rover of the pair: 55.4935 N, 8.4880 E, 75 m (metres while float, centimetres once fixed).
    EXPECT_NEAR(m.latitude, 55.4935, 2e-5);
    EXPECT_NEAR(m.longitude, 8.4880, 3e-5);
    EXPECT_NEAR(m.altitude, 75.0, 2.0);
  }
}

// Two antennas on one body on ROS 1 (the scenario's rtk.moving_base): the pose topic's attitude
// places both antennas by ~antenna_offset_m and ~base_antenna_offset_m; the heading of the
// baseline comes as NMEA HDT on ~nmea. The scenario's body faces north; the poses turn it east.
TEST_F(RosNodeTest, MovingBaseGivesTheHeadingOfTheBody) {
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  const auto dir = test::make_temp_dir("ros_node_heading");
  const auto scenario = dir / "heading.yaml";
  std::ofstream(scenario) << test::moving_base_scenario_yaml(nav, "0.0, 1.4, 1.5", 600);
  ros::NodeHandle nh;
  std::optional<double> heading;
  std::string last_sentence;
  auto nmea_sub = nh.subscribe<std_msgs::String>("/skytrace/nmea", 100, [&](const auto& m) {
    last_sentence = m->data;
    if (m->data.size() > 7 && m->data.compare(3, 4, "HDT,") == 0) heading = std::stod(m->data.substr(7));
  });
  ros::Publisher pose_pub = nh.advertise<geometry_msgs::PoseStamped>("/test/body_pose", 10);
  // Lists go on the parameter server (a `_name:=[...]` argument is a string in ROS 1).
  ros::param::set("/skytrace/antenna_offset_m", std::vector<double>{1.4, 0.0, 0.0});
  ros::param::set("/skytrace/base_antenna_offset_m", std::vector<double>{0.0, 0.0, 0.0});
  std::vector<std::string> args = {(test::binary_dir() / "bin" / "skytrace_ros_node").string(), "_scenario:=" + scenario.string(),
                                   "_receiver:=ANT2", "_rate_hz:=5", "_pose_source:=pose", "_pose_topic:=/test/body_pose"};
  ASSERT_TRUE(node_.start(args, RosMaster::instance().environment(), RosMaster::instance().home() / "node_heading.log"));
  auto last_sent = std::chrono::steady_clock::now() - 1s;
  const bool turned = test::wait_until(
      [&] {
        ros::spinOnce();
        if (std::chrono::steady_clock::now() - last_sent > 100ms) {
          geometry_msgs::PoseStamped pose;  // facing east: identity attitude
          pose.header.stamp = ros::Time::now();
          pose.header.frame_id = "world";
          pose.pose.position.z = 1.5;
          pose.pose.orientation.w = 1.0;
          pose_pub.publish(pose);
          last_sent = std::chrono::steady_clock::now();
        }
        return heading && std::abs(*heading - 90.0) < 1.0;
      },
      45s);
  EXPECT_TRUE(turned) << "no HDT near 90 degrees: last heading " << heading.value_or(-1.0) << ", last sentence "
                      << last_sentence << "; node log:\n"
                      << node_.log_text();
  ros::param::del("/skytrace/antenna_offset_m");
  ros::param::del("/skytrace/base_antenna_offset_m");
}

}  // namespace
}  // namespace skytrace
