// skytrace_ros2_node: a simulated GNSS receiver on ROS 2 without a ROS 2 install (docs/ros2.md).
// The ROS 1 node's behaviour and parameters (apps/ros/skytrace_ros_node.cpp) over DDS: Cyclone DDS
// participant, ROS 2 topic and type names, CDR payloads from skytrace/ros2/messages.hpp, the QoS
// profiles of rclcpp, and the graph information (ros_discovery_info) that makes `ros2 node list`
// and `ros2 topic info` show it. One live::Receiver stepped at ~rate_hz on the ROS clock (/clock
// under use_sim_time), the antenna where the scenario, tf, an odometry or a pose topic puts it.
// Bad input (NaN or stale poses, unknown frames, the clock going back, incompatible QoS) is
// reported with throttled warnings, never a crash.
#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "dds.hpp"
#include "latency_report.hpp"
#include "live_receiver.hpp"
#include "log.hpp"
#include "params.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/io/rosbag2.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/ros2/messages.hpp"
#include "skytrace/sim/live.hpp"
#include "skytrace/sim/live_outputs.hpp"
#include "skytrace/sim/ros2_topics.hpp"
#include "skytrace/sim/streams.hpp"
#include "tf_buffer.hpp"

namespace skytrace::ros2_node {
namespace {

// Exit codes of the skytrace CLI (README "Exit codes").
constexpr int kExitUsage = 2;
constexpr int kExitInput = 3;
constexpr int kExitOutput = 5;
constexpr int kExitNetwork = 6;

constexpr const char* kUsage = R"(usage: skytrace_ros2_node [--ros-args] [--params-file FILE]... [-p NAME:=VALUE]...
                          [-r __ns:=/NAMESPACE] [-r __node:=NAME] [-r FROM:=TO]...

A simulated GNSS receiver on ROS 2 (DDS, no ROS 2 install needed). Parameters (docs/ros2.md):
  scenario (required), pose_source (scenario|tf|odometry|pose), world_frame, antenna_frame,
  frame_id, pose_topic, odom_topic, antenna_offset_m, base_antenna_offset_m, rate_hz, start_time, start_time_scale,
  pose_timeout_s, ray_length_m, moving_models, rinex_out, nmea_out, fix_csv_out, rtcm_out, bag_out,
  bag_compression (lz4|zstd|none),
  latency_report, use_sim_time, ros_distro (humble|jazzy), rtcm3, gnss_comm, receiver, rtk_base_topic,
  rtk_base.
Environment: ROS_DOMAIN_ID, ROS_LOCALHOST_ONLY, ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS,
  CYCLONEDDS_URI.
)";

enum class PoseSource { kScenario, kTf, kOdometry, kPose };

struct Config {
  std::string scenario;
  PoseSource pose_source = PoseSource::kScenario;
  std::string world_frame = "world";
  std::string antenna_frame = "gnss_antenna";
  std::string frame_id;  // of the fix and velocity; the antenna frame by default
  // Absolute by default: the names ROS 1's node resolves its defaults to.
  std::string pose_topic = "/antenna_pose";
  std::string odom_topic = "/odom";
  Eigen::Vector3d antenna_offset_m = Eigen::Vector3d::Zero();  // in the body frame of pose/odometry
  // A moving base's antenna (the receiver's rtk.moving_base), in the same body frame (tf: the
  // antenna frame's); none: it follows the antenna at the scenario's baseline.
  std::optional<Eigen::Vector3d> base_antenna_offset_m;
  double rate_hz = 1.0;
  std::string start_time;
  std::string start_time_scale = "GPST";
  double pose_timeout_s = 1.0;
  double ray_length_m = 100.0;
  std::vector<std::string> moving_models;  // tf frames of movable world models
  // The files of live::Receiver::file_parameters() ("rinex_out", "nmea_out", ...) and their paths.
  std::vector<std::pair<std::string, std::string>> file_outputs;
  std::string bag_out;                 // a rosbag2 folder of the published topics, written at the end
  std::string bag_compression = "lz4";
  std::string latency_report;
  std::string receiver;        // one receiver of a scenario with several; empty: the first
  std::string rtk_base_topic;  // RTK: a base's rtcm_msgs/Message topic; empty: no RTK
  std::string rtk_base;        // RTK: HOST:PORT or ntrip://... of a base's RTCM 3 stream
  bool use_sim_time = false;
  ros2::RosDistro distro = ros2::RosDistro::kJazzy;
  bool rtcm3 = true;
  bool gnss_comm = true;
};

#define SKYTRACE_READ(expr, target) \
  do {                              \
    auto value_ = (expr);           \
    if (!value_) return value_.error(); \
    target = *value_;               \
  } while (false)

// A lever arm [x, y, z] in metres in the robot's body frame; nullopt when the parameter is absent.
Result<std::optional<Eigen::Vector3d>> read_lever_arm(const Parameters& p, const std::string& name) {
  auto values = p.get_doubles(name);
  if (!values) return values.error();
  if (!p.has(name)) return std::optional<Eigen::Vector3d>{};
  if (values->size() != 3) {
    return Error{ErrorCode::kInvalidArgument,
                 "parameter " + name + ": expected [x, y, z] in metres in the robot's body frame"};
  }
  return std::optional<Eigen::Vector3d>(Eigen::Vector3d((*values)[0], (*values)[1], (*values)[2]));
}

Result<Config> read_config(const Parameters& p) {
  Config c;
  SKYTRACE_READ(p.get_string("scenario", ""), c.scenario);
  if (c.scenario.empty()) {
    return Error{ErrorCode::kInvalidArgument, "parameter scenario is required: the path of a skytrace scenario file (YAML)"};
  }
  std::string source;
  SKYTRACE_READ(p.get_string("pose_source", "scenario"), source);
  if (source == "scenario") {
    c.pose_source = PoseSource::kScenario;
  } else if (source == "tf") {
    c.pose_source = PoseSource::kTf;
  } else if (source == "odometry") {
    c.pose_source = PoseSource::kOdometry;
  } else if (source == "pose") {
    c.pose_source = PoseSource::kPose;
  } else {
    return Error{ErrorCode::kInvalidArgument, fmt::format("parameter pose_source '{}': expected scenario, tf, odometry or pose", source)};
  }
  SKYTRACE_READ(p.get_string("world_frame", c.world_frame), c.world_frame);
  SKYTRACE_READ(p.get_string("antenna_frame", c.antenna_frame), c.antenna_frame);
  SKYTRACE_READ(p.get_string("frame_id", c.antenna_frame), c.frame_id);
  SKYTRACE_READ(p.get_string("pose_topic", c.pose_topic), c.pose_topic);
  SKYTRACE_READ(p.get_string("odom_topic", c.odom_topic), c.odom_topic);
  SKYTRACE_READ(p.get_double("rate_hz", c.rate_hz), c.rate_hz);
  if (!(c.rate_hz > 0.0 && c.rate_hz <= 100.0)) {
    return Error{ErrorCode::kInvalidArgument, fmt::format("parameter rate_hz {}: expected a rate in (0, 100] Hz", c.rate_hz)};
  }
  SKYTRACE_READ(p.get_double("pose_timeout_s", c.pose_timeout_s), c.pose_timeout_s);
  if (!(c.pose_timeout_s > 0.0)) {
    return Error{ErrorCode::kInvalidArgument, fmt::format("parameter pose_timeout_s {}: expected a positive duration", c.pose_timeout_s)};
  }
  SKYTRACE_READ(p.get_double("ray_length_m", c.ray_length_m), c.ray_length_m);
  if (!(c.ray_length_m > 0.0)) {
    return Error{ErrorCode::kInvalidArgument, fmt::format("parameter ray_length_m {}: expected a positive length", c.ray_length_m)};
  }
  SKYTRACE_READ(p.get_string("start_time", c.start_time), c.start_time);
  SKYTRACE_READ(p.get_string("start_time_scale", c.start_time_scale), c.start_time_scale);
  std::optional<Eigen::Vector3d> offset;
  SKYTRACE_READ(read_lever_arm(p, "antenna_offset_m"), offset);
  if (offset) c.antenna_offset_m = *offset;
  SKYTRACE_READ(read_lever_arm(p, "base_antenna_offset_m"), c.base_antenna_offset_m);
  SKYTRACE_READ(p.get_strings("moving_models"), c.moving_models);
  for (const auto& [parameter, description] : live::Receiver::file_parameters()) {
    std::string path;
    SKYTRACE_READ(p.get_string(parameter, path), path);
    c.file_outputs.emplace_back(parameter, path);
  }
  SKYTRACE_READ(p.get_string("bag_out", c.bag_out), c.bag_out);
  SKYTRACE_READ(p.get_string("bag_compression", c.bag_compression), c.bag_compression);
  if (c.bag_compression != "lz4" && c.bag_compression != "zstd" && c.bag_compression != "none") {
    return Error{ErrorCode::kInvalidArgument,
                 fmt::format("parameter bag_compression '{}': expected lz4, zstd or none", c.bag_compression)};
  }
  SKYTRACE_READ(p.get_string("latency_report", c.latency_report), c.latency_report);
  SKYTRACE_READ(p.get_string("receiver", c.receiver), c.receiver);
  SKYTRACE_READ(p.get_string("rtk_base_topic", c.rtk_base_topic), c.rtk_base_topic);
  SKYTRACE_READ(p.get_string("rtk_base", c.rtk_base), c.rtk_base);
  if (!c.rtk_base.empty() && !c.rtk_base_topic.empty()) {
    return Error{ErrorCode::kInvalidArgument, "parameters rtk_base and rtk_base_topic: give one of them"};
  }
  SKYTRACE_READ(p.get_bool("use_sim_time", c.use_sim_time), c.use_sim_time);
  std::string distro;
  SKYTRACE_READ(p.get_string("ros_distro", "jazzy"), distro);
  auto parsed = ros2::parse_ros_distro(distro);
  if (!parsed) return Error{ErrorCode::kInvalidArgument, "parameter ros_distro: " + parsed.error().message};
  c.distro = *parsed;
  SKYTRACE_READ(p.get_bool("rtcm3", c.rtcm3), c.rtcm3);
  SKYTRACE_READ(p.get_bool("gnss_comm", c.gnss_comm), c.gnss_comm);
  return c;
}

#undef SKYTRACE_READ

Eigen::Quaterniond to_eigen(const ros2::Quaternion& q) { return {q.w, q.x, q.y, q.z}; }

// ROS time in nanoseconds (builtin_interfaces/Time); the clock's zero means "not started".
std::int64_t to_ns(const ros2::Time& t) { return t.nanoseconds(); }
ros2::Time from_ns(std::int64_t ns) {
  ros2::Time t;
  t.sec = static_cast<std::int32_t>(ns / 1000000000);
  t.nanosec = static_cast<std::uint32_t>(ns % 1000000000);
  return t;
}

// A topic's writer: messages are serialised only when someone listens (a transient-local writer
// always writes, for the late joiners).
struct Output {
  std::unique_ptr<DdsWriter> writer;
  bool always = false;
  std::string name;  // the resolved ROS name ("/skytrace/fix")
  std::string type;
  sim::Ros2Qos qos = sim::Ros2Qos::kDefault;
  std::optional<std::uint16_t> bag_topic;  // its id in the bag being recorded
  [[nodiscard]] bool wanted() const { return writer && (always || writer->matched_readers() > 0); }
};

// The QoS of a topic of sim::ros2_receiver_topics() (REP 2003, see there).
QosProfile topic_qos(const sim::Ros2Topic& topic) {
  QosProfile qos = topic.qos == sim::Ros2Qos::kSensorData ? QosProfile::sensor_data()
                   : topic.qos == sim::Ros2Qos::kLatched  ? QosProfile::default_profile().transient_local()
                                                          : QosProfile::default_profile();
  return qos.keep_last(topic.depth);
}

class Node {
 public:
  Node(Config config, CommandLine command_line, std::unique_ptr<live::Receiver> receiver, Log& log)
      : config_(std::move(config)), command_line_(std::move(command_line)), receiver_(std::move(receiver)), log_(log) {
    period_s_ = 1.0 / config_.rate_hz;
  }
  ~Node() {
    if (bag_) drop_bag();  // not finished: nothing is left
  }
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  // The messages of an epoch, as the bag sink of `skytrace run` makes them (an error: the
  // scenario's receiver profile).
  Status make_builder() {
    const sim::LiveSession& session = receiver_->session();
    auto profile = receiver::load_profile(session.receiver().profile, session.scenario().source.parent_path());
    if (!profile) return profile.error();
    sim::Ros2TopicSettings settings;
    settings.frame_id = config_.frame_id;
    settings.world_frame = config_.world_frame;
    settings.ray_length_m = config_.ray_length_m;
    settings.rtcm = config_.rtcm3;
    builder_ = std::make_unique<sim::Ros2EpochBuilder>(*session.resources().ephemerides, std::move(*profile),
                                                        session.world_frame(),
                                                        sim::rtcm_station(session.marker_ecef_m(), session.receiver()), settings);
    return Ok{};
  }

  // Creates the DDS entities; errors name the topic.
  Status open(const DiscoveryOptions& discovery) {
    auto participant = DdsParticipant::create(discovery, [this](const std::string& text) {
      log_.throttled(LogLevel::kWarn, 10.0, text.substr(0, text.find(':')), text);
    });
    if (!participant) return participant.error();
    dds_ = std::move(*participant);

    const QosProfile sensor = QosProfile::sensor_data();
    const QosProfile reliable = QosProfile::default_profile();
    for (const auto& topic : sim::ros2_receiver_topics()) {
      if (topic.name == "rtcm" && !config_.rtcm3) continue;
      if (topic.name.rfind("gnss/", 0) == 0 && !config_.gnss_comm) continue;
      const QosProfile qos = topic_qos(topic);
      auto name = resolve_topic_name(std::string(topic.name), command_line_);
      if (!name) return name.error();
      auto writer = dds_->create_writer("rt" + *name, ros2::dds_type_name(topic.type), qos);
      if (!writer) return writer.error();
      writer_gids_.push_back((*writer)->guid());
      outputs_[std::string(topic.name)] = Output{std::move(*writer), qos.durability == QosProfile::Durability::kTransientLocal,
                                                 *name, std::string(topic.type), topic.qos, std::nullopt};
    }

    // rclcpp's QoS for what the node reads: the clock and poses best effort (they match either
    // kind of publisher), tf2_ros's listener profiles for /tf and /tf_static.
    if (config_.use_sim_time) {
      if (auto st = subscribe(clock_, "/clock", ros2::Clock::kType, sensor.keep_last(1)); !st) return st;
    }
    if (config_.pose_source == PoseSource::kTf || !config_.moving_models.empty()) {
      if (auto st = subscribe(tf_, "/tf", ros2::TFMessage::kType, reliable.keep_last(100)); !st) return st;
      if (auto st = subscribe(tf_static_, "/tf_static", ros2::TFMessage::kType, reliable.keep_last(100).transient_local()); !st) {
        return st;
      }
    }
    // RTK corrections best effort too: they match the reliable publishers of ntrip_client and of
    // another skytrace node as well as best-effort ones; a deep history keeps a burst of messages.
    if (!config_.rtk_base_topic.empty()) {
      if (auto st = subscribe(rtk_base_, config_.rtk_base_topic, ros2::RtcmMessage::kType, sensor.keep_last(200)); !st) return st;
    }
    if (config_.pose_source == PoseSource::kPose) {
      if (auto st = subscribe(pose_, config_.pose_topic, ros2::PoseStamped::kType, sensor); !st) return st;
    } else if (config_.pose_source == PoseSource::kOdometry) {
      if (auto st = subscribe(pose_, config_.odom_topic, ros2::Odometry::kType, sensor); !st) return st;
    }
    return announce();
  }

  // The outputs, each a sink of the receiver's epochs: this node's topics (and the bag of them),
  // then the files asked for.
  [[nodiscard]] bool open_outputs() {
    if (auto problem = receiver_->open_outputs(config_.file_outputs, period_s_); !problem.empty()) {
      log_.fatal("{}", problem);
      return false;
    }
    receiver_->add_publisher(std::make_unique<sim::CallbackSink>([this](const sim::SinkEpoch& e) {
      publish_epoch(e);
      return Status(Ok{});
    }));
    return true;
  }

  // bag_out: a rosbag2 folder of every published topic, recorded into a hidden sibling folder and
  // renamed to bag_out when the node stops, so that a bag that cannot be finished leaves nothing.
  [[nodiscard]] bool open_bag() {
    if (config_.bag_out.empty()) return true;
    const std::filesystem::path target = std::filesystem::absolute(config_.bag_out).lexically_normal();
    std::error_code ec;
    if (std::filesystem::exists(target, ec)) {
      log_.fatal("parameter bag_out {}: exists (a bag is never written over)", config_.bag_out);
      return false;
    }
    bag_target_ = target;
    bag_partial_ = target.parent_path() / fmt::format(".{}.partial-{}", target.filename().string(), ::getpid());
    io::Rosbag2Options options;
    options.mcap.compression = config_.bag_compression == "none" ? "" : config_.bag_compression;
    options.file_stem = target.filename().string();
    options.ros_distro = config_.distro == ros2::RosDistro::kHumble ? "humble" : "jazzy";
    auto bag = io::Rosbag2Writer::open(bag_partial_, options);
    if (!bag) {
      log_.fatal("parameter bag_out {}: {}", config_.bag_out, bag.error().message);
      return false;
    }
    bag_ = std::move(*bag);
    for (auto& [relative, output] : outputs_) {
      const io::QosProfileKind kind = output.qos == sim::Ros2Qos::kLatched      ? io::QosProfileKind::kTransientLocal
                                      : output.qos == sim::Ros2Qos::kSensorData ? io::QosProfileKind::kSensorData
                                                                                : io::QosProfileKind::kDefault;
      auto id = bag_->add_topic(output.name, output.type, ros2::message_definition(output.type), kind);
      if (!id) {
        log_.fatal("parameter bag_out {}: {}", config_.bag_out, id.error().message);
        drop_bag();
        return false;
      }
      output.bag_topic = *id;
    }
    return true;
  }

  void run() {
    const double wait_s = std::min(0.01, period_s_ / 4.0);
    if (!config_.use_sim_time) origin_ns_ = system_now_ns();  // node start maps to start_time
    while (!cancellation_requested()) {
      dds_->wait_for_data(wait_s);
      take_inputs();
      const std::int64_t now_ns = ros_now_ns();
      if (now_ns == 0) {
        log_.throttled(LogLevel::kWarn, 10.0, "clock", "waiting for the clock (use_sim_time is set and /clock has not started)");
        continue;
      }
      const double elapsed_s = 1e-9 * static_cast<double>(now_ns - origin_ns_);
      if (elapsed_s < 0.0) continue;
      const auto k = static_cast<std::int64_t>(std::floor(elapsed_s * config_.rate_hz + 1e-6));
      if (last_k_) {
        if (k == *last_k_) continue;
        if (k < *last_k_) {
          log_.warn("time went back {:.3f} s (simulation reset?): the receiver restarts tracking",
                    static_cast<double>(*last_k_ - k) * period_s_);
          tf_buffer_.clear();  // as tf2 does when time jumps back
        } else if (k - *last_k_ > std::max<std::int64_t>(2, static_cast<std::int64_t>(2.0 * config_.rate_hz))) {
          log_.warn("time jumped {:.3f} s forward: {} epochs skipped", static_cast<double>(k - *last_k_) * period_s_,
                    k - *last_k_ - 1);
        }
      }
      last_k_ = k;
      epoch(k);
    }
  }

  void finish() {
    if (bag_) {
      if (auto st = bag_->close(); !st) {
        log_.error("parameter bag_out {}: {}; nothing written", config_.bag_out, st.error().message);
        drop_bag();
      } else {
        std::error_code ec;
        std::filesystem::rename(bag_partial_, bag_target_, ec);
        if (ec) {
          log_.error("parameter bag_out {}: cannot move the bag into place ({}); nothing written", config_.bag_out, ec.message());
          drop_bag();
        } else {
          log_.info("rosbag2 bag written to {}", bag_target_.string());
          bag_.reset();
        }
      }
    }
    const auto finished = receiver_->finish_outputs();
    for (const auto& error : finished.errors) log_.error("{}", error);
    for (const auto& written : finished.written) log_.info("written: {}", written);
    report_latency();
  }

 private:
  static std::int64_t system_now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  }
  [[nodiscard]] std::int64_t ros_now_ns() const { return config_.use_sim_time ? sim_now_ns_ : system_now_ns(); }
  // Receiver time (seconds after the start time) of a ROS time.
  [[nodiscard]] double receiver_time_s(std::int64_t stamp_ns) const {
    return 1e-9 * static_cast<double>(stamp_ns - origin_ns_);
  }

  struct Subscription {
    std::string topic;  // resolved ROS name, for messages
    std::unique_ptr<DdsReader> reader;
  };
  Status subscribe(Subscription& subscription, const std::string& name, std::string_view type, const QosProfile& qos) {
    auto topic = resolve_topic_name(name, command_line_);
    if (!topic) return topic.error();
    auto reader = dds_->create_reader("rt" + *topic, ros2::dds_type_name(type), qos);
    if (!reader) return reader.error();
    reader_gids_.push_back((*reader)->guid());
    subscription = Subscription{*topic, std::move(*reader)};
    return Ok{};
  }

  // The node on ros_discovery_info, as rmw_dds_common's graph cache expects it: the participant's
  // GID and, for this node, the GIDs of its readers and writers.
  Status announce() {
    auto writer = dds_->create_writer("ros_discovery_info", ros2::dds_type_name(ros2::ParticipantEntitiesInfo::kType),
                                      QosProfile::default_profile().keep_last(1).transient_local());
    if (!writer) return writer.error();
    discovery_ = std::move(*writer);
    const auto gid = [](const Guid& guid) {
      ros2::Gid g;
      std::copy(guid.begin(), guid.end(), g.data.begin());
      return g;
    };
    ros2::ParticipantEntitiesInfo info;
    info.gid = gid(dds_->guid());
    ros2::NodeEntitiesInfo node;
    node.node_namespace = command_line_.node_namespace;
    node.node_name = command_line_.node_name;
    for (const auto& g : reader_gids_) node.reader_gid_seq.push_back(gid(g));
    for (const auto& g : writer_gids_) node.writer_gid_seq.push_back(gid(g));
    info.node_entities_info_seq.push_back(std::move(node));
    return discovery_->write(ros2::serialize(info, config_.distro));
  }

  template <typename Message>
  std::optional<Message> decode(const std::vector<std::uint8_t>& bytes, const std::string& topic) {
    auto message = ros2::deserialize<Message>(bytes);
    if (!message) {
      log_.throttled(LogLevel::kWarn, 5.0, topic + "/decode", fmt::format("{}: message not decoded: {}", topic, message.error().message));
      return std::nullopt;
    }
    return std::move(*message);
  }

  void take_inputs() {
    if (rtk_base_.reader) {
      for (const auto& bytes : rtk_base_.reader->take()) {
        auto message = decode<ros2::RtcmMessage>(bytes, rtk_base_.topic);
        if (!message) continue;
        if (auto note = receiver_->add_base_rtcm3(message->message.data(), message->message.size()); !note.empty()) {
          log_.throttled(LogLevel::kWarn, 10.0, "rtk_base", fmt::format("{}: {}", rtk_base_.topic, note));
        }
      }
    }
    if (clock_.reader) {
      for (const auto& bytes : clock_.reader->take()) {
        if (auto clock = decode<ros2::Clock>(bytes, clock_.topic)) sim_now_ns_ = to_ns(clock->clock);
      }
    }
    if (tf_.reader) {
      for (const auto& bytes : tf_static_.reader->take()) {
        if (auto tf = decode<ros2::TFMessage>(bytes, tf_static_.topic)) add_transforms(*tf, true);
      }
      for (const auto& bytes : tf_.reader->take()) {
        if (auto tf = decode<ros2::TFMessage>(bytes, tf_.topic)) add_transforms(*tf, false);
      }
    }
    if (pose_.reader) {
      for (const auto& bytes : pose_.reader->take()) {
        if (config_.pose_source == PoseSource::kPose) {
          if (auto pose = decode<ros2::PoseStamped>(bytes, pose_.topic)) on_pose(*pose);
        } else if (auto odom = decode<ros2::Odometry>(bytes, pose_.topic)) {
          on_odometry(*odom);
        }
      }
    }
  }

  void add_transforms(const ros2::TFMessage& message, bool is_static) {
    for (const auto& t : message.transforms) {
      const auto& tr = t.transform.translation;
      const auto st = tf_buffer_.set(t.header.frame_id, t.child_frame_id, Eigen::Vector3d(tr.x, tr.y, tr.z),
                                     to_eigen(t.transform.rotation), 1e-9 * static_cast<double>(to_ns(t.header.stamp)), is_static);
      if (!st) log_.throttled(LogLevel::kWarn, 5.0, "tf/" + t.child_frame_id, (is_static ? "/tf_static: " : "/tf: ") + st.error().message);
    }
  }

  void set_pose(std::int64_t stamp_ns, const Eigen::Vector3d& position_world_m,
                const std::optional<Eigen::Vector3d>& velocity_world_mps, const std::string& source) {
    if (!position_world_m.allFinite() || (velocity_world_mps && !velocity_world_mps->allFinite())) {
      log_.throttled(LogLevel::kWarn, 5.0, source + "/nan", fmt::format("{}: antenna pose with NaN or infinite values ignored", source));
      return;
    }
    const std::int64_t when_ns = stamp_ns == 0 ? ros_now_ns() : stamp_ns;
    std::optional<live::Vec3> velocity;
    if (velocity_world_mps) velocity = live::Vec3{velocity_world_mps->x(), velocity_world_mps->y(), velocity_world_mps->z()};
    const live::Vec3 position{position_world_m.x(), position_world_m.y(), position_world_m.z()};
    if (auto problem = receiver_->set_antenna_pose_world(receiver_time_s(when_ns), position, velocity); !problem.empty()) {
      log_.throttled(LogLevel::kWarn, 5.0, source + "/pose", fmt::format("{}: {}", source, problem));
    }
  }

  // The antenna point of a body pose: the body's position plus the lever arm turned by its attitude.
  [[nodiscard]] std::optional<Eigen::Vector3d> antenna_point(const ros2::Pose& pose, const std::string& source) {
    const Eigen::Vector3d p(pose.position.x, pose.position.y, pose.position.z);
    if (config_.antenna_offset_m.isZero()) return p;
    const Eigen::Quaterniond q = to_eigen(pose.orientation);
    if (!q.coeffs().allFinite() || q.norm() < 1e-6) {
      log_.throttled(LogLevel::kWarn, 5.0, source + "/orientation",
                     fmt::format("{}: orientation missing or not finite; antenna_offset_m needs it, pose ignored", source));
      return std::nullopt;
    }
    return p + q.normalized() * config_.antenna_offset_m;
  }

  void check_frame(const std::string& frame_id, const std::string& source) {
    if (!frame_id.empty() && frame_id != config_.world_frame) {
      log_.throttled(LogLevel::kWarn, 10.0, source + "/frame",
                     fmt::format("{}: pose in frame '{}', expected world_frame '{}'; used as world coordinates", source,
                                 frame_id, config_.world_frame));
    }
  }

  // A moving base's antenna on the body (base_antenna_offset_m), from the body's position and attitude.
  void set_base_pose(std::int64_t stamp_ns, const Eigen::Vector3d& body_m, const Eigen::Quaterniond& attitude,
                     const std::optional<Eigen::Vector3d>& velocity_world_mps, const std::string& source) {
    if (!config_.base_antenna_offset_m) return;
    if (!attitude.coeffs().allFinite() || attitude.norm() < 1e-6) {
      log_.throttled(LogLevel::kWarn, 5.0, source + "/base", fmt::format("{}: orientation missing; base_antenna_offset_m needs it", source));
      return;
    }
    const Eigen::Vector3d p = body_m + attitude.normalized() * *config_.base_antenna_offset_m;
    std::optional<live::Vec3> velocity;
    if (velocity_world_mps) velocity = live::Vec3{velocity_world_mps->x(), velocity_world_mps->y(), velocity_world_mps->z()};
    const std::int64_t when_ns = stamp_ns == 0 ? ros_now_ns() : stamp_ns;
    if (auto problem = receiver_->set_base_antenna_pose_world(receiver_time_s(when_ns), {p.x(), p.y(), p.z()}, velocity);
        !problem.empty()) {
      log_.throttled(LogLevel::kWarn, 5.0, source + "/base", fmt::format("{}: moving base: {}", source, problem));
    }
  }

  void on_pose(const ros2::PoseStamped& msg) {
    check_frame(msg.header.frame_id, pose_.topic);
    auto p = antenna_point(msg.pose, pose_.topic);
    if (!p) return;
    set_pose(to_ns(msg.header.stamp), *p, std::nullopt, pose_.topic);
    const auto& b = msg.pose.position;
    set_base_pose(to_ns(msg.header.stamp), Eigen::Vector3d(b.x, b.y, b.z), to_eigen(msg.pose.orientation), std::nullopt,
                  pose_.topic);
  }

  void on_odometry(const ros2::Odometry& msg) {
    check_frame(msg.header.frame_id, pose_.topic);
    auto p = antenna_point(msg.pose.pose, pose_.topic);
    if (!p) return;
    // The twist is in the child (body) frame: turned into the world frame by the attitude.
    const auto& v = msg.twist.twist.linear;
    const Eigen::Quaterniond q = to_eigen(msg.pose.pose.orientation);
    std::optional<Eigen::Vector3d> v_world;
    if (q.coeffs().allFinite() && q.norm() > 1e-6) v_world = q.normalized() * Eigen::Vector3d(v.x, v.y, v.z);
    set_pose(to_ns(msg.header.stamp), *p, v_world, pose_.topic);
    const auto& b = msg.pose.pose.position;
    set_base_pose(to_ns(msg.header.stamp), Eigen::Vector3d(b.x, b.y, b.z), q, v_world, pose_.topic);
  }

  // world_frame <- frame, if tf has it and it is usable.
  std::optional<StampedTransform> lookup(const std::string& frame) {
    auto t = tf_buffer_.lookup(config_.world_frame, frame);
    if (!t) {
      log_.throttled(LogLevel::kWarn, 5.0, "lookup/" + frame,
                     fmt::format("no transform {} -> {}: {}", config_.world_frame, frame, t.error().message));
      return std::nullopt;
    }
    return *t;
  }

  void update_from_tf(std::int64_t epoch_ns) {
    if (config_.pose_source == PoseSource::kTf) {
      if (auto t = lookup(config_.antenna_frame)) {
        // A static chain holds at every time.
        const std::int64_t stamp_ns = t->is_static ? epoch_ns : static_cast<std::int64_t>(std::llround(t->stamp_s * 1e9));
        const double age_s = 1e-9 * static_cast<double>(epoch_ns - stamp_ns);
        if (age_s > config_.pose_timeout_s) {
          log_.throttled(LogLevel::kWarn, 5.0, "tf/stale",
                         fmt::format("tf {} -> {} is {:.1f} s old (stale)", config_.world_frame, config_.antenna_frame, age_s));
        }
        set_pose(stamp_ns, t->transform.translation(), std::nullopt, "tf");
        set_base_pose(stamp_ns, t->transform.translation(), Eigen::Quaterniond(t->transform.rotation()), std::nullopt, "tf");
      }
    }
    for (const auto& model : config_.moving_models) {
      auto t = lookup(model);
      if (!t) continue;
      const Eigen::Vector3d p = t->transform.translation();
      const Eigen::Quaterniond q(t->transform.rotation());
      if (auto problem = receiver_->set_object_pose(model, {p.x(), p.y(), p.z()}, {q.w(), q.x(), q.y(), q.z()}); !problem.empty()) {
        log_.throttled(LogLevel::kWarn, 10.0, "model/" + model, fmt::format("moving model '{}': {}", model, problem));
      }
    }
  }

  // A bag that cannot be written is given up (the node goes on) and removed.
  void drop_bag() {
    bag_.reset();
    std::error_code ignored;
    std::filesystem::remove_all(bag_partial_, ignored);
    for (auto& [relative, output] : outputs_) output.bag_topic.reset();
  }

  // Writes a message to the topic `name` when someone listens, and into the bag being recorded.
  template <typename Message>
  void publish(std::string_view name, const Message& message) {
    const auto it = outputs_.find(name);
    if (it == outputs_.end()) return;
    const bool wanted = it->second.wanted();
    const bool recorded = bag_ && it->second.bag_topic;
    if (!wanted && !recorded) return;
    ros2::serialize_into(message, cdr_);
    if (wanted) {
      if (auto st = it->second.writer->write(cdr_); !st) {
        log_.throttled(LogLevel::kWarn, 10.0, std::string(name), fmt::format("{}: {}", name, st.error().message));
      }
    }
    if (recorded) {
      if (auto st = bag_->write(*it->second.bag_topic, static_cast<std::uint64_t>(stamp_ns_), cdr_); !st) {
        log_.error("parameter bag_out {}: {}; recording stopped, nothing kept", config_.bag_out, st.error().message);
        drop_bag();
      }
    }
  }

  void epoch(std::int64_t k) {
    const double time_s = static_cast<double>(k) * period_s_;
    const std::int64_t stamp_ns = origin_ns_ + static_cast<std::int64_t>(std::llround(time_s * 1e9));
    if (tf_.reader) update_from_tf(stamp_ns);
    const auto started = std::chrono::steady_clock::now();
    stamp_ns_ = stamp_ns;
    std::string problem;
    std::vector<std::string> notes;
    if (!receiver_->step_outputs(time_s, problem, notes)) {
      log_.throttled(LogLevel::kError, 10.0, "step", fmt::format("epoch {:.3f} s after the start time: {}", time_s, problem));
      return;
    }
    latencies_.add(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    for (const auto& note : notes) log_.throttled(LogLevel::kWarn, 10.0, "outputs", note);
  }

  // The node's topics of one epoch, stamped stamp_ns_ (its publisher in the receiver's outputs).
  void publish_epoch(const sim::SinkEpoch& e) {
    const double time_s = 1e-9 * static_cast<double>(stamp_ns_ - origin_ns_);
    if (e.restarted) {
      log_.warn("receiver restarted at {} GPST (time went back)", e.observations->receiver_time.to_iso8601(TimeScale::kGpst));
      builder_->reset();
    }
    if (e.pose_stale) {
      log_.throttled(LogLevel::kWarn, 5.0, "stale",
                     fmt::format("antenna pose is stale (none for {:.1f} s): the receiver is held where it was", config_.pose_timeout_s));
    }
    if (auto st = builder_->build_into(messages_, *e.observations, e.fix, from_ns(stamp_ns_), e.restarted, e.pose_stale); !st) {
      log_.throttled(LogLevel::kError, 10.0, "build", fmt::format("epoch {:.3f} s: {}", time_s, st.error().message));
      return;
    }
    (void)sim::visit_messages(messages_, [&](std::string_view topic, const auto& message) -> Status {
      publish(topic, message);  // failures are logged there: the node goes on
      return Ok{};
    });
  }

  void report_latency() {
    if (latencies_.empty()) return;
    const live::LatencySummary summary = latencies_.summary();
    log_.info("per-epoch latency (step and publish): {} epochs, p50 {:.3f} ms, p99 {:.3f} ms, max {:.3f} ms", summary.epochs,
              summary.p50_ms, summary.p99_ms, summary.max_ms);
    if (!config_.latency_report.empty()) {
      std::ofstream out(config_.latency_report);
      out << live::latency_json(config_.scenario, config_.rate_hz, summary);
      if (!out) log_.error("parameter latency_report {}: cannot write", config_.latency_report);
    }
  }

  Config config_;
  CommandLine command_line_;
  std::unique_ptr<live::Receiver> receiver_;
  Log& log_;
  double period_s_ = 1.0;
  std::int64_t origin_ns_ = 0;  // ROS time of the start time: zero under sim time, else the node's start
  std::int64_t sim_now_ns_ = 0;  // the last /clock
  std::optional<std::int64_t> last_k_;
  TfBuffer tf_buffer_;
  live::LatencyRecorder latencies_;  // bounded: the node may run for days
  std::unique_ptr<sim::Ros2EpochBuilder> builder_;
  sim::Ros2Epoch messages_;           // reused from epoch to epoch (storage kept)
  std::vector<std::uint8_t> cdr_;     // one sample's bytes, reused
  std::int64_t stamp_ns_ = 0;         // the ROS time of the epoch being published
  std::unique_ptr<io::Rosbag2Writer> bag_;
  std::filesystem::path bag_target_, bag_partial_;
  // Destroyed after the endpoints below (declared first): the participant owns their entities.
  std::unique_ptr<DdsParticipant> dds_;
  std::vector<Guid> reader_gids_, writer_gids_;
  std::unique_ptr<DdsWriter> discovery_;
  std::map<std::string, Output, std::less<>> outputs_;  // by topic name of sim::ros2_receiver_topics()
  Subscription clock_, tf_, tf_static_, pose_, rtk_base_;
};

int run(int argc, char** argv) {
  Log log;
  auto command_line = parse_command_line(argc, argv);
  if (!command_line) {
    log.fatal("{}", command_line.error().message);
    std::fputs(kUsage, stderr);
    return kExitUsage;
  }
  if (command_line->help) {
    std::fputs(kUsage, stdout);
    return 0;
  }
  log.set_name(command_line->node_namespace == "/" ? command_line->node_name
                                                   : command_line->node_namespace.substr(1) + "." + command_line->node_name);
  auto values = load_parameters(*command_line);
  if (!values) {
    log.fatal("{}", values.error().message);
    return values.error().code == ErrorCode::kInvalidArgument ? kExitUsage : kExitInput;
  }
  const Parameters parameters(std::move(*values));
  auto config = read_config(parameters);
  if (!config) {
    log.fatal("{}", config.error().message);
    return kExitUsage;
  }
  for (const auto& name : parameters.unread()) log.warn("unknown parameter '{}' ignored", name);
  auto discovery = read_discovery_environment();
  if (!discovery) {
    log.fatal("{}", discovery.error().message);
    return kExitUsage;
  }

  // SIGINT and SIGTERM end the loop (a watchdog ends the process should it hang); a write beyond the
  // file size limit fails like a full disk (the bag is given up) instead of killing the node.
  install_live_stop_handlers();
  live::ReceiverOptions options;
  options.scenario_path = config->scenario;
  options.start_time = config->start_time;
  options.start_time_scale = config->start_time_scale;
  options.pose_timeout_s = config->pose_timeout_s;
  options.receiver_name = config->receiver;
  options.rtk = !config->rtk_base_topic.empty();
  options.rtk_base = config->rtk_base;
  options.log = [&log](int level, const std::string& text) {
    if (level == 0) {
      log.info("skytrace: {}", text);
    } else if (level == 1) {
      log.warn("skytrace: {}", text);
    } else {
      log.error("skytrace: {}", text);
    }
  };
  std::string problem;
  auto receiver = live::Receiver::create(options, problem);
  if (!receiver) {
    log.fatal("{} (from parameters scenario, start_time, start_time_scale)", problem);
    return kExitInput;
  }
  for (const auto& warning : receiver->warnings()) log.warn("skytrace: {}", warning);
  if (config->base_antenna_offset_m && !receiver->has_moving_base()) {
    log.fatal("parameter base_antenna_offset_m: the receiver has no moving base (rtk.moving_base with rtk.base in the scenario)");
    return kExitUsage;
  }
  Node node(*config, *command_line, std::move(receiver), log);
  if (auto st = node.make_builder(); !st) {
    log.fatal("{} (from parameter scenario)", st.error().message);
    return kExitInput;
  }
  if (!node.open_outputs()) return kExitOutput;
  if (auto st = node.open(*discovery); !st) {
    log.fatal("{}", st.error().message);
    return st.error().code == ErrorCode::kInvalidArgument ? kExitUsage : kExitNetwork;
  }
  if (!node.open_bag()) return kExitOutput;
  log.info("skytrace: scenario {}, {:.3g} Hz, antenna pose from {}; DDS domain {}{}, {} graph", config->scenario,
           config->rate_hz,
           config->pose_source == PoseSource::kScenario ? "the scenario"
           : config->pose_source == PoseSource::kTf     ? "tf"
           : config->pose_source == PoseSource::kPose   ? config->pose_topic
                                                        : config->odom_topic,
           discovery->domain_id, discovery->localhost_only ? " (localhost only)" : "",
           config->distro == ros2::RosDistro::kHumble ? "Humble" : "Jazzy");
  node.run();
  disarm_stop_watchdog();  // the loop ended in time: no forced exit while the files are finished
  node.finish();
  return 0;
}

}  // namespace
}  // namespace skytrace::ros2_node

int main(int argc, char** argv) {
  try {
    return skytrace::ros2_node::run(argc, argv);
  } catch (const std::exception& e) {
    // A last resort: every expected failure is reported above with its parameter.
    std::fprintf(stderr, "skytrace_ros2_node: %s\n", e.what());
    return 1;
  }
}
