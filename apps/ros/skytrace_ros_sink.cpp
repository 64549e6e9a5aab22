// skytrace_ros_sink: subscribes to every topic the node publishes and counts the messages, so that
// the node's latency benchmark serialises and sends everything as with real consumers
// (docs/performance.md). With a third argument, a pose topic, it also plays a careless robot for
// the soak test (scripts/soak-ros-node): geometry_msgs/PoseStamped at 50 Hz, valid poses on a
// circle mixed with NaN, absurd positions, a wrong frame, a zero quaternion and stamps going back.
// Usage: skytrace_ros_sink [NODE_NAMESPACE=/skytrace] [DURATION_S=60] [HOSTILE_POSE_TOPIC]
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/NavSatFix.h>
#include <skytrace_msgs/Observations.h>
#include <skytrace_msgs/Sky.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstdio>
#include <limits>
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
  ros::Publisher poses;
  if (argc > 3) poses = nh.advertise<geometry_msgs::PoseStamped>(argv[3], 50);
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(duration_s);
  ros::WallTime next_pose = ros::WallTime::now();
  long sent = 0;
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (argc > 3 && ros::WallTime::now() >= next_pose) {
      next_pose += ros::WallDuration(0.02);
      geometry_msgs::PoseStamped pose;
      pose.header.stamp = ros::Time::now();
      pose.header.frame_id = "world";
      const double angle = 0.01 * static_cast<double>(sent);
      pose.pose.position.x = 20.0 * std::cos(angle);
      pose.pose.position.y = 20.0 * std::sin(angle);
      pose.pose.position.z = 1.5;
      pose.pose.orientation.w = 1.0;
      switch (sent % 10) {
        case 3: pose.pose.position.x = std::numeric_limits<double>::quiet_NaN(); break;
        case 5: pose.pose.position.y = 1e18; break;
        case 6: pose.header.frame_id = "elsewhere"; break;
        case 7: pose.pose.orientation.w = 0.0; break;
        case 8: pose.header.stamp = ros::Time::now() - ros::Duration(30.0); break;
        default: break;
      }
      poses.publish(pose);
      ++sent;
    }
    ros::WallDuration(0.002).sleep();
  }
  if (argc > 3) std::printf("poses sent %ld\n", sent);
  for (const auto& [topic, n] : counts) std::printf("%s/%s %ld\n", ns.c_str(), topic.c_str(), n);
  return 0;
}
