// skytrace_ros2_sink: subscribes to every topic skytrace_ros2_node publishes (with each topic's
// QoS) and counts the samples, so that the node's latency benchmark serialises and sends
// everything as with real consumers (docs/performance.md, scripts/bench-ros2-latency). With a
// third argument, a pose topic, it also plays a careless robot for the soak test
// (scripts/soak-ros2-node): geometry_msgs/PoseStamped at 50 Hz, valid poses on a 20 m circle
// between NaN, 1e18 m, a wrong frame, a zero quaternion and a stamp 30 s back.
// Usage: skytrace_ros2_sink [NAMESPACE=/skytrace] [DURATION_S=60] [POSE_TOPIC]; ROS_DOMAIN_ID and
// ROS_LOCALHOST_ONLY as for the node.
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "dds.hpp"
#include "skytrace/ros2/messages.hpp"
#include "skytrace/sim/ros2_topics.hpp"

namespace {
std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  using namespace skytrace;
  using namespace skytrace::ros2_node;
  std::string ns = argc > 1 ? argv[1] : "/skytrace";
  while (ns.size() > 1 && ns.back() == '/') ns.pop_back();
  const double duration_s = argc > 2 ? std::atof(argv[2]) : 60.0;
  if (!(duration_s > 0.0) || ns.empty() || ns.front() != '/') {
    std::fprintf(stderr, "usage: skytrace_ros2_sink [NAMESPACE=/skytrace] [DURATION_S=60] [POSE_TOPIC]\n");
    return 2;
  }
  auto discovery = read_discovery_environment();
  if (!discovery) {
    std::fprintf(stderr, "skytrace_ros2_sink: %s\n", discovery.error().message.c_str());
    return 2;
  }
  auto participant = DdsParticipant::create(*discovery, [](const std::string& text) {
    std::fprintf(stderr, "skytrace_ros2_sink: %s\n", text.c_str());
  });
  if (!participant) {
    std::fprintf(stderr, "skytrace_ros2_sink: %s\n", participant.error().message.c_str());
    return 6;
  }
  std::map<std::string, std::unique_ptr<DdsReader>> readers;
  std::map<std::string, long> counts;
  for (const auto& topic : sim::ros2_receiver_topics()) {
    // Best effort takes what either kind of writer sends; a deep history keeps the bursts.
    QosProfile qos = QosProfile::sensor_data().keep_last(1000);
    if (topic.name.find("ephemeris") != std::string_view::npos) qos = qos.reliable().transient_local();
    const std::string name = (ns == "/" ? "" : ns) + "/" + std::string(topic.name);
    auto reader = (*participant)->create_reader("rt" + name, ros2::dds_type_name(topic.type), qos);
    if (!reader) {
      std::fprintf(stderr, "skytrace_ros2_sink: %s\n", reader.error().message.c_str());
      return 6;
    }
    readers[name] = std::move(*reader);
    counts[name] = 0;
  }
  std::unique_ptr<DdsWriter> poses;
  if (argc > 3) {
    const std::string topic = argv[3];
    auto writer = (*participant)->create_writer("rt" + topic, ros2::dds_type_name(ros2::PoseStamped::kType),
                                                QosProfile::default_profile());
    if (!writer) {
      std::fprintf(stderr, "skytrace_ros2_sink: %s\n", writer.error().message.c_str());
      return 6;
    }
    poses = std::move(*writer);
  }
  // SIGINT and SIGTERM end the count early; the counts are printed either way.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
  auto next_pose = std::chrono::steady_clock::now();
  long sent = 0;
  while (!g_stop && std::chrono::steady_clock::now() < end) {
    (*participant)->wait_for_data(poses ? 0.002 : 0.05);
    for (auto& [name, reader] : readers) counts[name] += static_cast<long>(reader->take(100000).size());
    if (poses && std::chrono::steady_clock::now() >= next_pose) {
      next_pose += std::chrono::milliseconds(20);
      const double now_s = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
      ros2::PoseStamped pose;
      pose.header.stamp = ros2::Time::from_seconds(now_s);
      pose.header.frame_id = "world";
      const double angle = 0.01 * static_cast<double>(sent);
      pose.pose.position = {20.0 * std::cos(angle), 20.0 * std::sin(angle), 1.5};
      switch (sent % 10) {
        case 3: pose.pose.position.x = std::numeric_limits<double>::quiet_NaN(); break;
        case 5: pose.pose.position.y = 1e18; break;
        case 6: pose.header.frame_id = "elsewhere"; break;
        case 7: pose.pose.orientation.w = 0.0; break;
        case 8: pose.header.stamp = ros2::Time::from_seconds(now_s - 30.0); break;
        default: break;
      }
      (void)poses->write(ros2::serialize(pose));
      ++sent;
    }
  }
  if (poses) std::printf("poses sent %ld\n", sent);
  for (const auto& [name, n] : counts) std::printf("%s %ld\n", name.c_str(), n);
  return 0;
}
