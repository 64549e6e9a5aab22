// The independent peer of the ROS 2 node's tests: a Fast DDS 2.9 participant acting as a ROS 2
// node on the other middleware would (rmw_fastrtps): topics "rt/<name>", DDS type names
// "pkg::msg::dds_::Type_", payloads as raw CDR (decoded with Fast CDR in ros2_wire.hpp, never with
// skytrace's code), ROS_LOCALHOST_ONLY as rmw_fastrtps does it (UDPv4 on 127.0.0.1 only).
#pragma once

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace skytrace::test::ros2_peer {

using Bytes = std::vector<std::uint8_t>;
using Guid = std::array<std::uint8_t, 16>;

struct Qos {
  bool reliable = true;
  bool transient_local = false;
  int depth = 10;
  [[nodiscard]] static Qos sensor_data() { return {false, false, 5}; }
  [[nodiscard]] static Qos default_profile() { return {true, false, 10}; }
};

// An endpoint another participant announced (SEDP).
struct RemoteEndpoint {
  std::string topic;
  std::string type;
  Guid guid{};
  bool reliable = false;
  bool transient_local = false;
};

class Subscription {
 public:
  virtual ~Subscription() = default;
  // Everything received so far (kept), and a wait for at least `count` samples.
  [[nodiscard]] virtual std::vector<Bytes> samples() const = 0;
  virtual bool wait_for(size_t count, std::chrono::milliseconds timeout) const = 0;
  [[nodiscard]] virtual size_t incompatible_qos_count() const = 0;
};

class Publication {
 public:
  virtual ~Publication() = default;
  virtual bool write(const Bytes& cdr) = 0;
  [[nodiscard]] virtual int matched() const = 0;
};

class Peer {
 public:
  // A participant on `domain_id`, on the loopback interface only.
  [[nodiscard]] static std::unique_ptr<Peer> create(int domain_id);
  virtual ~Peer() = default;
  // `topic` and `type` as on the wire ("rt/skytrace/fix", "sensor_msgs::msg::dds_::NavSatFix_").
  virtual Subscription& subscribe(const std::string& topic, const std::string& type, const Qos& qos) = 0;
  virtual Publication& advertise(const std::string& topic, const std::string& type, const Qos& qos) = 0;
  [[nodiscard]] virtual std::vector<RemoteEndpoint> remote_writers() const = 0;
  [[nodiscard]] virtual std::vector<RemoteEndpoint> remote_readers() const = 0;
  // GUID prefixes (12 bytes) of the participants discovered.
  [[nodiscard]] virtual std::vector<Guid> remote_participants() const = 0;
};

}  // namespace skytrace::test::ros2_peer
