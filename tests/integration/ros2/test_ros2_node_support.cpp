// The ROS 2 node's parts that need no DDS: its command line and parameters files as rcl reads
// them, topic name resolution, the tf buffer, the discovery environment and the Cyclone DDS
// configuration for ROS_LOCALHOST_ONLY.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "dds.hpp"
#include "params.hpp"
#include "test_support.hpp"
#include "tf_buffer.hpp"

namespace skytrace::ros2_node {
namespace {

Result<CommandLine> parse(std::vector<const char*> args) {
  args.insert(args.begin(), "skytrace_ros2_node");
  return parse_command_line(static_cast<int>(args.size()), args.data());
}

TEST(Ros2CommandLine, RosArgumentsSetNamespaceNameParametersAndRemappings) {
  auto c = parse({"--ros-args", "-r", "__ns:=/robot1", "-r", "__node:=gnss", "-p", "rate_hz:=10", "--params-file", "a.yaml",
                  "-r", "fix:=/gps/fix", "-r", "~/sky:=sky_view"});
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->node_namespace, "/robot1");
  EXPECT_EQ(c->node_name, "gnss");
  ASSERT_EQ(c->param_overrides.size(), 1U);
  EXPECT_EQ(c->param_overrides[0].first, "rate_hz");
  EXPECT_EQ(c->params_files, std::vector<std::string>{"a.yaml"});
  EXPECT_EQ(*resolve_topic_name("fix", *c), "/gps/fix");
  EXPECT_EQ(*resolve_topic_name("velocity", *c), "/robot1/velocity");
  EXPECT_EQ(*resolve_topic_name("/tf", *c), "/tf");
  EXPECT_EQ(*resolve_topic_name("~/sky", *c), "/robot1/sky_view");
  EXPECT_EQ(*resolve_topic_name("~/rays", *c), "/robot1/gnss/rays");
  EXPECT_EQ(*resolve_topic_name("gnss/measurements", *c), "/robot1/gnss/measurements");
}

TEST(Ros2CommandLine, DefaultsPublishWhereTheRos1NodeDoes) {
  auto c = parse({});
  ASSERT_TRUE(c);
  EXPECT_EQ(*resolve_topic_name("fix", *c), "/skytrace/fix");
  auto root = parse({"--ros-args", "-r", "__ns:=/"});
  ASSERT_TRUE(root);
  EXPECT_EQ(*resolve_topic_name("fix", *root), "/fix");
}

TEST(Ros2CommandLine, MalformedArgumentsAreRefused) {
  EXPECT_FALSE(parse({"--params-file"}));
  EXPECT_FALSE(parse({"-p", "rate_hz"}));
  EXPECT_FALSE(parse({"--unknown"}));
  EXPECT_FALSE(parse({"-r", "__ns:=/bad name"}));
  EXPECT_FALSE(parse({"-r", "__node:=a/b"}));
  auto c = parse({});
  ASSERT_TRUE(c);
  EXPECT_FALSE(resolve_topic_name("a//b", *c));
  EXPECT_FALSE(resolve_topic_name("x~", *c));
  EXPECT_FALSE(resolve_topic_name("", *c));
}

TEST(Ros2Parameters, FilesMatchTheNodeWildcardsAndNestedNamespacesLaterSourcesWin) {
  const auto dir = test::make_temp_dir("ros2_params");
  const auto file = dir / "params.yaml";
  std::ofstream(file) << R"(/**:
  ros__parameters:
    rate_hz: 2.0
    moving_models: [door, crane]
other_node:
  ros__parameters:
    rate_hz: 99.0
robot1:
  gnss:
    ros__parameters:
      antenna_offset_m: [0.1, 0.0, 1.2]
      nested:
        depth: 3
/robot1/gnss:
  ros__parameters:
    rate_hz: 5.0
)";
  auto c = parse({"--ros-args", "-r", "__ns:=/robot1", "-r", "__node:=gnss", "--params-file", file.c_str(), "-p",
                  "use_sim_time:=true"});
  ASSERT_TRUE(c);
  auto values = load_parameters(*c);
  ASSERT_TRUE(values) << values.error().message;
  const Parameters p(std::move(*values));
  EXPECT_DOUBLE_EQ(*p.get_double("rate_hz", 1.0), 5.0);
  EXPECT_TRUE(*p.get_bool("use_sim_time", false));
  EXPECT_EQ(*p.get_strings("moving_models"), (std::vector<std::string>{"door", "crane"}));
  EXPECT_EQ(p.get_doubles("antenna_offset_m")->size(), 3U);
  EXPECT_EQ(p.unread(), std::vector<std::string>{"nested.depth"});
  EXPECT_EQ(*p.get_string("frame_id", "gnss_antenna"), "gnss_antenna");
  EXPECT_FALSE(p.get_double("moving_models", 0.0));  // a list where a number is expected
}

TEST(Ros2Parameters, FilesWithoutTheNodeOrBrokenAreErrorsNamingTheFile) {
  const auto dir = test::make_temp_dir("ros2_params_bad");
  std::ofstream(dir / "other.yaml") << "other:\n  ros__parameters:\n    a: 1\n";
  std::ofstream(dir / "broken.yaml") << "skytrace:\n  ros__parameters: [1, 2\n";
  for (const char* name : {"other.yaml", "broken.yaml", "missing.yaml"}) {
    const std::string path = (dir / name).string();
    auto c = parse({"--params-file", path.c_str()});
    ASSERT_TRUE(c);
    auto values = load_parameters(*c);
    ASSERT_FALSE(values) << name;
    EXPECT_NE(values.error().message.find(path), std::string::npos) << values.error().message;
  }
}

TEST(Ros2TfBuffer, ChainsThroughParentsAndReportsUnknownAndDisconnectedFrames) {
  TfBuffer tf;
  const Eigen::Quaterniond yaw_90(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  ASSERT_TRUE(tf.set("map", "odom", {10.0, 0.0, 0.0}, Eigen::Quaterniond::Identity(), 0.0, true));
  ASSERT_TRUE(tf.set("odom", "base_link", {1.0, 2.0, 0.0}, yaw_90, 100.0, false));
  ASSERT_TRUE(tf.set("/base_link", "gnss_antenna", {0.5, 0.0, 1.0}, Eigen::Quaterniond::Identity(), 0.0, true));
  auto t = tf.lookup("map", "gnss_antenna");
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_TRUE(t->transform.translation().isApprox(Eigen::Vector3d(11.0, 2.5, 1.0), 1e-12));
  EXPECT_FALSE(t->is_static);
  EXPECT_DOUBLE_EQ(t->stamp_s, 100.0);
  // The inverse direction.
  auto back = tf.lookup("gnss_antenna", "map");
  ASSERT_TRUE(back);
  EXPECT_TRUE((back->transform * t->transform).isApprox(Eigen::Isometry3d::Identity(), 1e-12));

  auto unknown = tf.lookup("map", "mars");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("'mars' does not exist"), std::string::npos);
  ASSERT_TRUE(tf.set("world", "other", {0.0, 0.0, 0.0}, Eigen::Quaterniond::Identity(), 0.0, true));
  auto apart = tf.lookup("map", "other");
  ASSERT_FALSE(apart);
  EXPECT_NE(apart.error().message.find("not connected"), std::string::npos);

  EXPECT_FALSE(tf.set("map", "x", {NAN, 0.0, 0.0}, Eigen::Quaterniond::Identity(), 0.0, false));
  EXPECT_FALSE(tf.set("map", "x", {0.0, 0.0, 0.0}, Eigen::Quaterniond(0, 0, 0, 0), 0.0, false));
  EXPECT_FALSE(tf.set("map", "map", {0.0, 0.0, 0.0}, Eigen::Quaterniond::Identity(), 0.0, false));
  // A loop does not hang the lookup.
  ASSERT_TRUE(tf.set("gnss_antenna", "map", {0.0, 0.0, 0.0}, Eigen::Quaterniond::Identity(), 0.0, true));
  EXPECT_FALSE(tf.lookup("map", "gnss_antenna"));
}

TEST(Ros2Discovery, EnvironmentAndLocalhostConfiguration) {
  setenv("ROS_DOMAIN_ID", "42", 1);
  setenv("ROS_LOCALHOST_ONLY", "1", 1);
  unsetenv("ROS_AUTOMATIC_DISCOVERY_RANGE");
  setenv("ROS_STATIC_PEERS", "192.168.1.7; robot2.local", 1);
  auto d = read_discovery_environment();
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(d->domain_id, 42);
  EXPECT_TRUE(d->localhost_only);
  EXPECT_EQ(d->static_peers, (std::vector<std::string>{"192.168.1.7", "robot2.local"}));
  const std::string config = cyclone_config(*d);
  EXPECT_NE(config.find("<NetworkInterface address=\"127.0.0.1\"/>"), std::string::npos) << config;
  EXPECT_NE(config.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(config.find("<Peer address=\"localhost\"/>"), std::string::npos);
  EXPECT_NE(config.find("<Peer address=\"robot2.local\"/>"), std::string::npos);

  setenv("ROS_DOMAIN_ID", "233", 1);
  EXPECT_FALSE(read_discovery_environment());
  setenv("ROS_DOMAIN_ID", "7x", 1);
  EXPECT_FALSE(read_discovery_environment());
  unsetenv("ROS_DOMAIN_ID");
  unsetenv("ROS_LOCALHOST_ONLY");
  unsetenv("ROS_STATIC_PEERS");
  setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST", 1);
  d = read_discovery_environment();
  ASSERT_TRUE(d);
  EXPECT_EQ(d->domain_id, 0);
  EXPECT_TRUE(d->localhost_only);
  setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "EVERYWHERE", 1);
  EXPECT_FALSE(read_discovery_environment());
  unsetenv("ROS_AUTOMATIC_DISCOVERY_RANGE");
  d = read_discovery_environment();
  ASSERT_TRUE(d);
  EXPECT_TRUE(cyclone_config(*d).empty());  // Cyclone's own defaults (and CYCLONEDDS_URI)
}

TEST(Ros2Qos, ProfilesAreRclcpps) {
  EXPECT_EQ(QosProfile::sensor_data().to_string(), "best effort, volatile, keep last 5");
  EXPECT_EQ(QosProfile::default_profile().to_string(), "reliable, volatile, keep last 10");
  EXPECT_EQ(QosProfile::default_profile().keep_last(1).transient_local().to_string(), "reliable, transient local, keep last 1");
}

}  // namespace
}  // namespace skytrace::ros2_node
