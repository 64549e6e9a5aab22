// `skytrace gz` on a Gazebo transport partition of the test's own: the test plays Gazebo (clock and
// world pose messages), the bridge answers with NavSat fixes that follow the robot, raw
// observations as JSON, and the `ign topic` tool sees them.
#include <gtest/gtest.h>

#include <fstream>

#include "live_receiver.hpp"
#include "process.hpp"
#include "test_support.hpp"

#if SKYTRACE_HAVE_GZ
#include <ignition/msgs/clock.pb.h>
#include <ignition/msgs/navsat.pb.h>
#include <ignition/msgs/pose_v.pb.h>
#include <ignition/msgs/stringmsg.pb.h>
#include <ignition/transport/Node.hh>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <mutex>
#include <thread>
#include <optional>
#include <random>

#include "child_process.hpp"
#endif

namespace skytrace {
namespace {

#if SKYTRACE_HAVE_GZ

using namespace std::chrono_literals;
namespace im = ignition::msgs;

std::filesystem::path contract_scenario() {
  return test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
}

double distance_m(const live::Vec3& a, const live::Vec3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// The ign topic tool of Debian's ignition-transport-cli (the `ign` front end is a Ruby script).
std::optional<std::filesystem::path> ign_topic_tool() {
  for (const char* p : {"/usr/libexec/ignition/transport11/ign-transport-topic",
                        "/usr/lib/x86_64-linux-gnu/ignition/transport11/ign-transport-topic"}) {
    if (std::filesystem::exists(p)) return std::filesystem::path(p);
  }
  return std::nullopt;
}

TEST(GzBridgeTest, PosesMoveTheReceiverAndNavSatComesBack) {
  if (!std::filesystem::exists(contract_scenario()) ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  }
  // A partition of this test only, on the loopback interface.
  std::random_device seed;
  const std::string partition = "skytrace_test_" + std::to_string(getpid()) + "_" + std::to_string(seed());
  setenv("IGN_IP", "127.0.0.1", 1);
  setenv("IGN_PARTITION", partition.c_str(), 1);
  const std::map<std::string, std::string> env = {{"IGN_IP", "127.0.0.1"}, {"IGN_PARTITION", partition}};

  live::ReceiverOptions options;
  options.scenario_path = contract_scenario().string();
  std::string error;
  auto receiver = live::Receiver::create(options, error);
  ASSERT_TRUE(receiver) << error;

  const std::string world = "skytrace_test_world";
  const std::string prefix = "/world/" + world;
  ignition::transport::Node node;
  auto clock_pub = node.Advertise<im::Clock>(prefix + "/clock");
  auto pose_pub = node.Advertise<im::Pose_V>(prefix + "/pose/info");
  ASSERT_TRUE(clock_pub && pose_pub);
  std::mutex mutex;
  std::optional<im::NavSat> last_fix;
  std::optional<std::string> last_observations;
  const std::string navsat_topic = prefix + "/model/rover/skytrace/navsat";
  std::function<void(const im::NavSat&)> on_fix = [&](const im::NavSat& m) {
    std::lock_guard lock(mutex);
    last_fix = m;
  };
  std::function<void(const im::StringMsg&)> on_observations = [&](const im::StringMsg& m) {
    std::lock_guard lock(mutex);
    last_observations = m.data();
  };
  ASSERT_TRUE(node.Subscribe(navsat_topic, on_fix));
  ASSERT_TRUE(node.Subscribe(prefix + "/model/rover/skytrace/observations", on_observations));

  test::ChildProcess bridge;
  const auto dir = test::make_temp_dir("gz_bridge");
  const auto log = dir / "bridge.log";
  ASSERT_TRUE(bridge.start({test::skytrace_executable().string(), "gz", "--scenario", contract_scenario().string(),
                            "--world-name", world, "--model", "rover", "--link", "gnss", "--rate-hz", "5",
                            "--nmea-out", (dir / "rover.nmea").string()},
                           env, log));

  // Gazebo's part: the clock and the world's poses 20 times a second. The rover's origin is at
  // `base`, its antenna link 0.5 m above it; another model stands elsewhere.
  double sim_time_s = 0.0;
  const auto publish = [&](const live::Vec3& base) {
    sim_time_s += 0.05;
    im::Clock clock;
    clock.mutable_sim()->set_sec(static_cast<std::int64_t>(std::floor(sim_time_s)));
    clock.mutable_sim()->set_nsec(static_cast<std::int32_t>(std::lround((sim_time_s - std::floor(sim_time_s)) * 1e9)));
    clock_pub.Publish(clock);
    im::Pose_V poses;
    *poses.mutable_header()->mutable_stamp() = clock.sim();
    im::Pose* other = poses.add_pose();
    other->set_name("box");
    other->mutable_position()->set_x(5.0);
    im::Pose* rover = poses.add_pose();
    rover->set_name("rover");
    rover->mutable_position()->set_x(base[0]);
    rover->mutable_position()->set_y(base[1]);
    rover->mutable_position()->set_z(base[2]);
    rover->mutable_orientation()->set_w(1.0);
    im::Pose* link = poses.add_pose();
    link->set_name("gnss");
    link->mutable_position()->set_z(0.5);
    link->mutable_orientation()->set_w(1.0);
    pose_pub.Publish(poses);
  };
  const auto fix_near = [&](const live::Vec3& antenna) {
    std::lock_guard lock(mutex);
    if (!last_fix) return false;
    const live::Vec3 p = receiver->world_from_geodetic(last_fix->latitude_deg(), last_fix->longitude_deg(), last_fix->altitude());
    return distance_m(p, antenna) < 0.2;  // noise-free: centimetres; the link offset is 0.5 m
  };
  const auto drive_to = [&](const live::Vec3& base) {
    const live::Vec3 antenna{base[0], base[1], base[2] + 0.5};
    const bool reached = test::wait_until(
        [&] {
          publish(base);
          return fix_near(antenna) || !bridge.running();
        },
        45s);
    ASSERT_TRUE(reached && fix_near(antenna)) << "no NavSat near the antenna; bridge log:\n" << bridge.log_text();
  };

  drive_to({30.0, -20.0, 1.0});
  {
    std::lock_guard lock(mutex);
    EXPECT_EQ(last_fix->frame_id(), "rover::gnss");
    ASSERT_TRUE(last_observations.has_value());
    const auto j = nlohmann::json::parse(*last_observations);
    EXPECT_EQ(j.at("fix").at("type"), "3d");
    int tracked = 0;
    for (const auto& s : j.at("satellites")) {
      if (s.at("status") == "tracked") {
        ++tracked;
        EXPECT_FALSE(s.at("signals").empty()) << s.dump();
      }
    }
    EXPECT_GE(tracked, 20) << *last_observations;
  }
  drive_to({-400.0, 250.0, 12.0});

  // The `ign topic` tool reads the bridge's NavSat like any Gazebo topic.
  if (auto tool = ign_topic_tool()) {
    std::string command = "IGN_IP=127.0.0.1 IGN_PARTITION=" + test::shell_quote(partition) + " timeout 20 " +
                          test::shell_quote(tool->string()) + " -e -n 1 -t " + test::shell_quote(navsat_topic);
    std::atomic<bool> echo_done{false};
    test::ProcessResult echoed;
    std::thread echo([&] {
      echoed = test::run_command(command);
      echo_done = true;
    });
    test::wait_until(
        [&] {
          publish({-400.0, 250.0, 12.0});
          return echo_done.load();
        },
        30s);
    echo.join();
    EXPECT_NE(echoed.output.find("latitude_deg"), std::string::npos) << echoed.output;
  }
  EXPECT_TRUE(bridge.running()) << bridge.log_text();
  EXPECT_FALSE(std::filesystem::exists(dir / "rover.nmea"));
  const int status = bridge.stop();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << bridge.log_text();
  // The NMEA file of the receiver's fixes appears when the bridge stops.
  std::ifstream nmea(dir / "rover.nmea");
  int gga = 0;
  for (std::string line; std::getline(nmea, line);) gga += line.find("GGA,") != std::string::npos ? 1 : 0;
  EXPECT_GE(gga, 1) << bridge.log_text();
}

// A robot with two GNSS antennas (the scenario's rover has rtk.moving_base): --link and --base-link
// name the model's two antenna links; the bridge places both, and the heading of the baseline comes
// as NMEA HDT. The scenario's baseline points at 30 degrees; the robot faces east (yaw 0) with its
// antennas 0.7 m ahead of and behind its origin: 90 degrees.
TEST(GzBridgeTest, MovingBaseHeadingFromTheModelsTwoAntennaLinks) {
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  if (!std::filesystem::exists(nav)) GTEST_SKIP() << "ESBC navigation file absent";
  std::random_device seed;
  const std::string partition = "skytrace_test_" + std::to_string(getpid()) + "_" + std::to_string(seed());
  setenv("IGN_IP", "127.0.0.1", 1);
  setenv("IGN_PARTITION", partition.c_str(), 1);
  const std::map<std::string, std::string> env = {{"IGN_IP", "127.0.0.1"}, {"IGN_PARTITION", partition}};
  const auto dir = test::make_temp_dir("gz_bridge_heading");
  std::ofstream(dir / "heading.yaml") << test::moving_base_scenario_yaml(nav, "0.7, 1.2124356, 1.5", 600);
  const std::string world = "skytrace_heading_world";
  const std::string prefix = "/world/" + world;
  ignition::transport::Node node;
  auto clock_pub = node.Advertise<im::Clock>(prefix + "/clock");
  auto pose_pub = node.Advertise<im::Pose_V>(prefix + "/pose/info");
  ASSERT_TRUE(clock_pub && pose_pub);
  test::ChildProcess bridge;
  ASSERT_TRUE(bridge.start({test::skytrace_executable().string(), "gz", "--scenario", (dir / "heading.yaml").string(),
                            "--world-name", world, "--model", "robot", "--receiver", "ANT2", "--link", "gnss_front",
                            "--base-link", "gnss_rear", "--rate-hz", "5", "--nmea-out", (dir / "robot.nmea").string()},
                           env, dir / "bridge.log"));
  // Gazebo's part: 40 s of simulation time at 20 poses a second, as fast as the bridge takes them.
  for (int k = 1; k <= 800 && bridge.running(); ++k) {
    const double t = 0.05 * k;
    im::Clock clock;
    clock.mutable_sim()->set_sec(static_cast<std::int64_t>(std::floor(t)));
    clock.mutable_sim()->set_nsec(static_cast<std::int32_t>(std::lround((t - std::floor(t)) * 1e9)));
    clock_pub.Publish(clock);
    im::Pose_V poses;
    *poses.mutable_header()->mutable_stamp() = clock.sim();
    im::Pose* robot = poses.add_pose();
    robot->set_name("robot");
    robot->mutable_position()->set_z(1.0);
    robot->mutable_orientation()->set_w(1.0);  // facing east (the world frame is east-north-up)
    for (const auto& [name, x] : {std::pair{"gnss_front", 0.7}, std::pair{"gnss_rear", -0.7}}) {
      im::Pose* link = poses.add_pose();
      link->set_name(name);
      link->mutable_position()->set_x(x);
      link->mutable_position()->set_z(0.5);
      link->mutable_orientation()->set_w(1.0);
    }
    pose_pub.Publish(poses);
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_TRUE(bridge.running()) << bridge.log_text();
  const int status = bridge.stop();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << bridge.log_text();
  std::ifstream nmea(dir / "robot.nmea");
  std::vector<double> headings;
  for (std::string line; std::getline(nmea, line);) {
    const auto at = line.find("HDT,");
    if (at != std::string::npos) headings.push_back(std::stod(line.substr(at + 4)));
  }
  ASSERT_GT(headings.size(), 20u) << bridge.log_text();
  EXPECT_NEAR(headings.back(), 90.0, 0.5) << bridge.log_text();
  // A bridge whose receiver has no moving base refuses --base-link.
  const auto refused = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " gz --scenario " +
                                         test::shell_quote((dir / "heading.yaml").string()) + " --world-name " + world +
                                         " --model robot --receiver ANT1 --base-link gnss_rear 2>&1");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.output.find("--base-link gnss_rear: the receiver has no moving base"), std::string::npos) << refused.output;
}

#else

TEST(GzBridgeTest, PosesMoveTheReceiverAndNavSatComesBack) {
  GTEST_SKIP() << "built without Gazebo transport (ignition-transport 11); scripts/setup installs it";
}

#endif

}  // namespace
}  // namespace skytrace
