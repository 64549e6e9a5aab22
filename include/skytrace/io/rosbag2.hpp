// A rosbag2 bag as `ros2 bag record -s mcap` of ROS 2 Jazzy leaves it (bag metadata version 9):
//
//   <folder>/metadata.yaml         rosbag2_bagfile_information: topics, counts, times, files
//   <folder>/<name>_0.mcap         profile ros2; one ros2msg schema per type, one cdr channel per
//                                  topic with offered_qos_profiles and topic_type_hash metadata;
//                                  a "rosbag2" Metadata record holding the same bag metadata
//
// so that `ros2 bag info`, `ros2 bag play` and Foxglove open it. Messages are CDR bytes (see
// skytrace/ros2/messages.hpp); log and publish times are the stamps given to write().
// metadata.yaml is written last, by close(): a bag without it is unfinished.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/io/mcap.hpp"

namespace skytrace::io {

// The QoS a topic's publisher offers, as recorded in the bag and used by `ros2 bag play`.
enum class QosProfileKind {
  kSensorData,      // best effort, volatile, keep last 5 (rclcpp::SensorDataQoS)
  kDefault,         // reliable, volatile, keep last 10 (rclcpp::QoS(10))
  kTransientLocal,  // reliable, transient local, keep last 1: latched topics (a map, a world)
};

struct Rosbag2Options {
  McapOptions mcap;
  std::string file_stem;            // the MCAP file is "<file_stem>_0.mcap"; empty: the folder's name
  std::string ros_distro = "jazzy";  // metadata's ros_distro
};

// What the bag holds so far, per topic in the order added.
struct Rosbag2TopicSummary {
  std::string name, type;
  std::uint64_t message_count = 0;
};

class Rosbag2Writer {
 public:
  // Creates `folder` (its parent must exist; the folder must not exist or be empty) and the MCAP
  // file in it.
  [[nodiscard]] static Result<std::unique_ptr<Rosbag2Writer>> open(const std::filesystem::path& folder,
                                                                   Rosbag2Options options = {});
  [[nodiscard]] static Result<std::unique_ptr<Rosbag2Writer>> open(const std::filesystem::path& folder,
                                                                   McapOptions mcap);
  ~Rosbag2Writer();
  Rosbag2Writer(const Rosbag2Writer&) = delete;
  Rosbag2Writer& operator=(const Rosbag2Writer&) = delete;

  // A topic ("/fix") of a ROS type ("sensor_msgs/msg/NavSatFix") whose definition text is
  // `definition` (ros2msg, as skytrace::ros2::message_definition gives it). The type's schema is
  // shared by all its topics. `type_description_hash` ("RIHS01_...") may be empty, as rosbag2
  // leaves it when the publisher does not announce one. Returns the id for write().
  [[nodiscard]] Result<std::uint16_t> add_topic(const std::string& topic, const std::string& ros_type,
                                                const std::string& definition, QosProfileKind qos,
                                                const std::string& type_description_hash = {});
  // One CDR-encoded message received at `stamp_ns` (nanoseconds since the Unix epoch, or the
  // simulation clock's epoch): the MCAP log and publish time.
  [[nodiscard]] Status write(std::uint16_t topic_id, std::uint64_t stamp_ns, std::span<const std::uint8_t> cdr);
  // Finishes the MCAP file, then writes metadata.yaml. Calling it again returns the first outcome.
  [[nodiscard]] Status close();

  [[nodiscard]] const std::filesystem::path& folder() const;
  [[nodiscard]] const std::filesystem::path& mcap_path() const;
  [[nodiscard]] std::vector<Rosbag2TopicSummary> topics() const;

 private:
  struct State;
  explicit Rosbag2Writer(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// The offered_qos_profiles text of a topic as rosbag2 (Jazzy) puts it into the MCAP channel's
// metadata: a YAML list of one profile.
[[nodiscard]] std::string rosbag2_offered_qos_yaml(QosProfileKind qos);

}  // namespace skytrace::io
