// skytrace_ros2_sink: subscribes to every topic skytrace_ros2_node publishes (with each topic's
// QoS) and counts the samples, so that the node's latency benchmark serialises and sends
// everything as with real consumers (docs/performance.md, scripts/bench-ros2-latency).
// Usage: skytrace_ros2_sink [NAMESPACE=/skytrace] [DURATION_S=60]; ROS_DOMAIN_ID and
// ROS_LOCALHOST_ONLY as for the node.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
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
    std::fprintf(stderr, "usage: skytrace_ros2_sink [NAMESPACE=/skytrace] [DURATION_S=60]\n");
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
  // SIGINT and SIGTERM end the count early; the counts are printed either way.
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(duration_s);
  while (!g_stop && std::chrono::steady_clock::now() < end) {
    (*participant)->wait_for_data(0.05);
    for (auto& [name, reader] : readers) counts[name] += static_cast<long>(reader->take(100000).size());
  }
  for (const auto& [name, n] : counts) std::printf("%s %ld\n", name.c_str(), n);
  return 0;
}
