// The parts of the DDS transport that need no DDS library: QoS text, the discovery environment
// and the Cyclone DDS configuration it asks for.
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>

#include "dds.hpp"

namespace skytrace::ros2_node {
namespace {

std::vector<std::string> split(std::string_view text, char separator) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(separator, start), text.size());
    std::string item(text.substr(start, end - start));
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (!item.empty()) out.push_back(std::move(item));
    start = end + 1;
  }
  return out;
}

std::string environment(const char* name) {
  const char* value = std::getenv(name);
  return value == nullptr ? std::string() : std::string(value);
}

}  // namespace

std::string QosProfile::to_string() const {
  return fmt::format("{}, {}, {}", reliability == Reliability::kReliable ? "reliable" : "best effort",
                     durability == Durability::kTransientLocal ? "transient local" : "volatile",
                     history == History::kKeepAll ? std::string("keep all") : fmt::format("keep last {}", depth));
}

Result<DiscoveryOptions> read_discovery_environment() {
  DiscoveryOptions options;
  if (const std::string id = environment("ROS_DOMAIN_ID"); !id.empty()) {
    char* end = nullptr;
    const long value = std::strtol(id.c_str(), &end, 10);
    // 232 is the last domain whose RTPS ports fit in 16 bits.
    if (end == id.c_str() || *end != '\0' || value < 0 || value > 232) {
      return Error{ErrorCode::kInvalidArgument, fmt::format("ROS_DOMAIN_ID '{}': expected an integer in 0-232", id)};
    }
    options.domain_id = static_cast<int>(value);
  }
  options.localhost_only = environment("ROS_LOCALHOST_ONLY") == "1";
  if (const std::string range = environment("ROS_AUTOMATIC_DISCOVERY_RANGE"); !range.empty()) {
    if (range == "LOCALHOST") {
      options.localhost_only = true;
    } else if (range != "SUBNET" && range != "SYSTEM_DEFAULT") {
      return Error{ErrorCode::kInvalidArgument,
                   fmt::format("ROS_AUTOMATIC_DISCOVERY_RANGE '{}': expected LOCALHOST, SUBNET or SYSTEM_DEFAULT", range)};
    }
  }
  options.static_peers = split(environment("ROS_STATIC_PEERS"), ';');
  return options;
}

std::string cyclone_config(const DiscoveryOptions& options) {
  if (!options.localhost_only && options.static_peers.empty()) return {};
  std::string config = "<CycloneDDS><Domain>";
  if (options.localhost_only) {
    // The loopback interface only, and no multicast (Linux's lo has none): peers on this host are
    // found by unicast to the ports of the first participant indices, as rmw_cyclonedds does.
    config += "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
              "<AllowMulticast>false</AllowMulticast></General>";
  }
  config += "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>";
  config += "<Peers>";
  if (options.localhost_only) config += "<Peer address=\"localhost\"/>";
  for (const auto& peer : options.static_peers) config += fmt::format("<Peer address=\"{}\"/>", peer);
  config += "</Peers></Discovery></Domain></CycloneDDS>";
  return config;
}

}  // namespace skytrace::ros2_node
