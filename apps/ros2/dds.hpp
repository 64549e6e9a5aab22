// DDS transport of the ROS 2 node: a Cyclone DDS participant whose writers and readers carry
// messages as CDR bytes already serialised (skytrace/ros2/messages.hpp), under the topic and type
// names ROS 2 uses. Cyclone's headers stay in dds.cpp (docs/adr/0003-ros2-over-dds.md).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace::ros2_node {

// The QoS policies ROS 2 exposes (rmw_qos_profile_t), the rest at rmw's defaults.
struct QosProfile {
  enum class Reliability { kBestEffort, kReliable };
  enum class Durability { kVolatile, kTransientLocal };
  enum class History { kKeepLast, kKeepAll };
  Reliability reliability = Reliability::kReliable;
  Durability durability = Durability::kVolatile;
  History history = History::kKeepLast;
  int depth = 10;

  // rmw_qos_profile_sensor_data: best effort, volatile, keep last 5.
  [[nodiscard]] static QosProfile sensor_data() {
    return {Reliability::kBestEffort, Durability::kVolatile, History::kKeepLast, 5};
  }
  // rmw_qos_profile_default: reliable, volatile, keep last 10.
  [[nodiscard]] static QosProfile default_profile() { return {}; }
  [[nodiscard]] QosProfile keep_last(int new_depth) const {
    QosProfile q = *this;
    q.history = History::kKeepLast;
    q.depth = new_depth;
    return q;
  }
  [[nodiscard]] QosProfile transient_local() const {
    QosProfile q = *this;
    q.durability = Durability::kTransientLocal;
    return q;
  }
  [[nodiscard]] QosProfile reliable() const {
    QosProfile q = *this;
    q.reliability = Reliability::kReliable;
    return q;
  }
  [[nodiscard]] std::string to_string() const;
};

// Where the participant looks for peers: ROS_DOMAIN_ID, ROS_LOCALHOST_ONLY and the rest of the
// environment rmw reads (read_discovery_environment).
struct DiscoveryOptions {
  int domain_id = 0;
  bool localhost_only = false;
  std::vector<std::string> static_peers;  // ROS_STATIC_PEERS (Jazzy and later)
  std::string enclave = "/";              // participant USER_DATA "enclave=/;" as rmw sets it
};

// From ROS_DOMAIN_ID (0-232, default 0), ROS_LOCALHOST_ONLY=1 (Humble), or
// ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and ROS_STATIC_PEERS (Jazzy). Errors name the variable.
[[nodiscard]] Result<DiscoveryOptions> read_discovery_environment();

// The Cyclone DDS configuration fragment for the options (empty when Cyclone's defaults apply);
// CYCLONEDDS_URI, when set, is appended by the participant as rmw_cyclonedds does.
[[nodiscard]] std::string cyclone_config(const DiscoveryOptions& options);

using Guid = std::array<std::uint8_t, 16>;
// Warnings from DDS listeners (incompatible QoS), called on Cyclone's threads.
using DdsWarning = std::function<void(const std::string& text)>;

class DdsWriter {
 public:
  virtual ~DdsWriter() = default;
  // One sample: CDR bytes starting with the 4-byte encapsulation header.
  [[nodiscard]] virtual Status write(std::span<const std::uint8_t> cdr) = 0;
  [[nodiscard]] virtual Guid guid() const = 0;
  [[nodiscard]] virtual int matched_readers() const = 0;
};

class DdsReader {
 public:
  virtual ~DdsReader() = default;
  // The samples received since the last call (up to `max_samples`), oldest first, each with its
  // encapsulation header; the writer's padding may follow the data.
  [[nodiscard]] virtual std::vector<std::vector<std::uint8_t>> take(size_t max_samples = 256) = 0;
  [[nodiscard]] virtual Guid guid() const = 0;
  [[nodiscard]] virtual int matched_writers() const = 0;
};

class DdsParticipant {
 public:
  [[nodiscard]] static Result<std::unique_ptr<DdsParticipant>> create(const DiscoveryOptions& options,
                                                                      DdsWarning warning);
  virtual ~DdsParticipant() = default;
  // `topic` and `type` as they appear on the wire ("rt/skytrace/fix",
  // "sensor_msgs::msg::dds_::NavSatFix_"); `ignore_local`: not from this participant's writers.
  [[nodiscard]] virtual Result<std::unique_ptr<DdsWriter>> create_writer(const std::string& topic, const std::string& type,
                                                                         const QosProfile& qos) = 0;
  [[nodiscard]] virtual Result<std::unique_ptr<DdsReader>> create_reader(const std::string& topic, const std::string& type,
                                                                         const QosProfile& qos,
                                                                         bool ignore_local = false) = 0;
  [[nodiscard]] virtual Guid guid() const = 0;
  // Blocks until a reader has data or `timeout_s` passes (the node's loop waits here).
  virtual void wait_for_data(double timeout_s) = 0;
};

}  // namespace skytrace::ros2_node
