#include "skytrace/io/rosbag2.hpp"

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <system_error>
#include <utility>

#include "skytrace/core/output_file.hpp"

namespace skytrace::io {
namespace {

// Bag metadata version 9 (ROS 2 Jazzy): QoS policies as names, offered_qos_profiles as a YAML
// list in metadata.yaml, ros_distro and type_description_hash present.
constexpr int kBagMetadataVersion = 9;
// What DDS discovery reports for an unset deadline, lifespan or lease duration
// (RMW_DURATION_INFINITE); rosbag2 stores the publisher's offer as discovered.
constexpr std::int64_t kInfiniteSec = 9223372036;
constexpr std::int64_t kInfiniteNsec = 854775807;

YAML::Node infinite_duration() {
  YAML::Node node;
  node["sec"] = kInfiniteSec;
  node["nsec"] = kInfiniteNsec;
  return node;
}

// One profile in the key order of rosbag2's encoder (rmw_qos_profile_t's field order).
YAML::Node qos_profile_node(QosProfileKind qos) {
  int depth = 10;
  std::string reliability = "reliable";
  std::string durability = "volatile";
  switch (qos) {
    case QosProfileKind::kSensorData:
      depth = 5;
      reliability = "best_effort";
      break;
    case QosProfileKind::kDefault:
      break;
    case QosProfileKind::kTransientLocal:
      depth = 1;
      durability = "transient_local";
      break;
  }
  YAML::Node node;
  node["history"] = "keep_last";
  node["depth"] = depth;
  node["reliability"] = reliability;
  node["durability"] = durability;
  node["deadline"] = infinite_duration();
  node["lifespan"] = infinite_duration();
  node["liveliness"] = "automatic";
  node["liveliness_lease_duration"] = infinite_duration();
  node["avoid_ros_namespace_conventions"] = false;
  return node;
}

YAML::Node qos_list_node(QosProfileKind qos) {
  YAML::Node list(YAML::NodeType::Sequence);
  list.push_back(qos_profile_node(qos));
  return list;
}

YAML::Node nanoseconds_node(const char* key, std::int64_t value) {
  YAML::Node node;
  node[key] = value;
  return node;
}

struct Topic {
  std::string name, type, type_description_hash;
  QosProfileKind qos = QosProfileKind::kDefault;
};

Error output_error(const std::filesystem::path& path, const std::string& what) {
  return make_error(ErrorCode::kOutput, path.string() + ": " + what);
}

}  // namespace

std::string rosbag2_offered_qos_yaml(QosProfileKind qos) { return YAML::Dump(qos_list_node(qos)); }

struct Rosbag2Writer::State {
  std::filesystem::path folder, mcap_path;
  std::string file_name;  // relative to the folder
  Rosbag2Options options;
  std::unique_ptr<McapWriter> mcap;
  std::vector<Topic> topics;  // index = MCAP channel id - 1
  bool closed = false;
  std::optional<Error> close_error;

  // rosbag2's BagMetadata as its YAML encoder lays it out (key order included).
  [[nodiscard]] YAML::Node bag_metadata() const {
    const McapStatistics& stats = mcap->statistics();
    // As rosbag2's writer: without messages the start is the largest time point and the
    // duration zero.
    const std::int64_t starting_time = stats.message_count == 0 ? std::numeric_limits<std::int64_t>::max()
                                                                : static_cast<std::int64_t>(stats.message_start_time_ns);
    const std::int64_t duration =
        stats.message_count == 0 ? 0 : static_cast<std::int64_t>(stats.message_end_time_ns - stats.message_start_time_ns);
    YAML::Node node;
    node["version"] = kBagMetadataVersion;
    node["storage_identifier"] = "mcap";
    node["duration"] = nanoseconds_node("nanoseconds", duration);
    node["starting_time"] = nanoseconds_node("nanoseconds_since_epoch", starting_time);
    node["message_count"] = stats.message_count;
    YAML::Node topic_list(YAML::NodeType::Sequence);
    for (size_t id = 0; id < topics.size(); ++id) {
      const Topic& topic = topics[id];
      YAML::Node metadata;
      metadata["name"] = topic.name;
      metadata["type"] = topic.type;
      metadata["serialization_format"] = "cdr";
      metadata["offered_qos_profiles"] = qos_list_node(topic.qos);
      metadata["type_description_hash"] = topic.type_description_hash;
      YAML::Node entry;
      entry["topic_metadata"] = metadata;
      const auto count = stats.channel_message_counts.find(static_cast<std::uint16_t>(id + 1));
      entry["message_count"] = count == stats.channel_message_counts.end() ? std::uint64_t{0} : count->second;
      topic_list.push_back(entry);
    }
    node["topics_with_message_count"] = topic_list;
    node["compression_format"] = "";  // MCAP chunks carry their own compression
    node["compression_mode"] = "";
    YAML::Node paths(YAML::NodeType::Sequence);
    paths.push_back(file_name);
    node["relative_file_paths"] = paths;
    YAML::Node file;
    file["path"] = file_name;
    file["starting_time"] = nanoseconds_node("nanoseconds_since_epoch", starting_time);
    file["duration"] = nanoseconds_node("nanoseconds", duration);
    file["message_count"] = stats.message_count;
    YAML::Node files(YAML::NodeType::Sequence);
    files.push_back(file);
    node["files"] = files;
    node["custom_data"] = YAML::Node();  // rosbag2 writes an empty map as null (~)
    node["ros_distro"] = options.ros_distro;
    return node;
  }

  Status finish() {
    const YAML::Node metadata = bag_metadata();
    // rosbag2's MCAP storage keeps the bag metadata in the file as well, so that the MCAP file
    // alone is a bag for `ros2 bag info`.
    if (auto status = mcap->add_metadata("rosbag2", {{"serialized_metadata", YAML::Dump(metadata)}}); !status.ok()) {
      return status;
    }
    if (auto status = mcap->close(); !status.ok()) return status;
    YAML::Node root;
    root["rosbag2_bagfile_information"] = metadata;
    YAML::Emitter emitter;
    emitter << root;  // no final newline, as rosbag2's `fout << node`
    return write_file_atomically(folder / "metadata.yaml", emitter.c_str());
  }
};

Rosbag2Writer::Rosbag2Writer(std::unique_ptr<State> state) : state_(std::move(state)) {}
Rosbag2Writer::~Rosbag2Writer() = default;

Result<std::unique_ptr<Rosbag2Writer>> Rosbag2Writer::open(const std::filesystem::path& folder, McapOptions mcap) {
  Rosbag2Options options;
  options.mcap = std::move(mcap);
  return open(folder, std::move(options));
}

Result<std::unique_ptr<Rosbag2Writer>> Rosbag2Writer::open(const std::filesystem::path& requested,
                                                           Rosbag2Options options) {
  std::filesystem::path folder = requested;
  if (!folder.has_filename()) folder = folder.parent_path();  // "bag/" names the folder "bag"
  if (folder.empty()) return make_error(ErrorCode::kInvalidArgument, "rosbag2 output: empty folder name");
  std::error_code error;
  const auto status = std::filesystem::symlink_status(folder, error);
  if (std::filesystem::exists(status)) {
    if (!std::filesystem::is_directory(status)) return output_error(folder, "exists and is not a folder");
    if (!std::filesystem::is_empty(folder, error) || error) {
      return output_error(folder, "bag folder exists and is not empty");
    }
  } else if (!std::filesystem::create_directory(folder, error) || error) {
    return output_error(folder, "cannot create the bag folder (" + error.message() + ")");
  }

  auto state = std::make_unique<State>();
  state->folder = folder;
  const std::string stem = options.file_stem.empty() ? folder.filename().string() : options.file_stem;
  state->file_name = stem + "_0.mcap";
  state->mcap_path = folder / state->file_name;
  state->options = std::move(options);
  state->options.mcap.profile = "ros2";
  auto mcap = McapWriter::open(state->mcap_path, state->options.mcap);
  if (!mcap.ok()) return mcap.error();
  state->mcap = std::move(*mcap);
  return std::unique_ptr<Rosbag2Writer>(new Rosbag2Writer(std::move(state)));
}

Result<std::uint16_t> Rosbag2Writer::add_topic(const std::string& topic, const std::string& ros_type,
                                               const std::string& definition, QosProfileKind qos,
                                               const std::string& type_description_hash) {
  State& s = *state_;
  for (const Topic& existing : s.topics) {
    if (existing.name == topic) {
      return make_error(ErrorCode::kInvalidArgument, s.folder.string() + ": topic " + topic + " added twice");
    }
  }
  auto schema = s.mcap->add_schema(ros_type, "ros2msg", definition);
  if (!schema.ok()) return schema.error();
  auto channel = s.mcap->add_channel(
      *schema, topic, "cdr",
      {{"offered_qos_profiles", rosbag2_offered_qos_yaml(qos)}, {"topic_type_hash", type_description_hash}});
  if (!channel.ok()) return channel.error();
  s.topics.push_back({topic, ros_type, type_description_hash, qos});
  return *channel;
}

Status Rosbag2Writer::write(std::uint16_t topic_id, std::uint64_t stamp_ns, std::span<const std::uint8_t> cdr) {
  return state_->mcap->write(topic_id, stamp_ns, stamp_ns, cdr);
}

Status Rosbag2Writer::close() {
  State& s = *state_;
  if (!s.closed) {
    s.closed = true;
    if (auto status = s.finish(); !status.ok()) s.close_error = status.error();
  }
  if (s.close_error) return *s.close_error;
  return Ok{};
}

const std::filesystem::path& Rosbag2Writer::folder() const { return state_->folder; }
const std::filesystem::path& Rosbag2Writer::mcap_path() const { return state_->mcap_path; }

std::vector<Rosbag2TopicSummary> Rosbag2Writer::topics() const {
  std::vector<Rosbag2TopicSummary> out;
  const McapStatistics& stats = state_->mcap->statistics();
  for (size_t id = 0; id < state_->topics.size(); ++id) {
    const auto count = stats.channel_message_counts.find(static_cast<std::uint16_t>(id + 1));
    out.push_back({state_->topics[id].name, state_->topics[id].type,
                   count == stats.channel_message_counts.end() ? 0 : count->second});
  }
  return out;
}

}  // namespace skytrace::io
