// skytrace_ros_sink: subscribes to every topic the node publishes and counts the messages, so that
// the node's latency benchmark serialises and sends everything as with real consumers
// (docs/performance.md). Usage: skytrace_ros_sink [NODE_NAMESPACE=/skytrace] [DURATION_S=60]
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/NavSatFix.h>
#include <skytrace_msgs/Observations.h>
#include <skytrace_msgs/Sky.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

int main(int argc, char** argv) {
  ros::init(argc, argv, "skytrace_sink", ros::init_options::AnonymousName);
  const std::string ns = argc > 1 ? argv[1] : "/skytrace";
  const double duration_s = argc > 2 ? std::atof(argv[2]) : 60.0;
  if (!(duration_s > 0.0)) {
    std::fprintf(stderr, "skytrace_ros_sink: DURATION_S must be a positive number of seconds\n");
    return 2;
  }
  ros::NodeHandle nh;
  std::map<std::string, long> counts;
  auto count = [&counts](const std::string& topic) { return [&counts, topic](const auto&) { ++counts[topic]; }; };
  const auto fix = nh.subscribe<sensor_msgs::NavSatFix>(ns + "/fix", 100, count("fix"));
  const auto velocity = nh.subscribe<geometry_msgs::TwistWithCovarianceStamped>(ns + "/velocity", 100, count("velocity"));
  const auto observations = nh.subscribe<skytrace_msgs::Observations>(ns + "/observations", 100, count("observations"));
  const auto nmea = nh.subscribe<std_msgs::String>(ns + "/nmea", 1000, count("nmea"));
  const auto sky = nh.subscribe<skytrace_msgs::Sky>(ns + "/sky", 100, count("sky"));
  const auto rays = nh.subscribe<visualization_msgs::MarkerArray>(ns + "/rays", 100, count("rays"));
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(duration_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  for (const auto& [topic, n] : counts) std::printf("%s/%s %ld\n", ns.c_str(), topic.c_str(), n);
  return 0;
}
