// skytrace_ros_node: a simulated GNSS receiver on ROS 1 (docs/ros.md). One sim::LiveSession stepped
// at ~rate_hz on the ROS clock (the Gazebo clock under /use_sim_time), the antenna where the
// scenario, tf, an odometry or a pose topic puts it; publishes the fix, the velocity, the raw
// observations, NMEA, the sky and the rays for RViz. Bad input from ROS (NaN poses, missing
// transforms, stale poses, time jumps) is reported with throttled warnings, never a crash.
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <tf2_ros/transform_listener.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <unistd.h>

#include <csignal>
#include <cmath>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "latency_report.hpp"
#include "live_receiver.hpp"
#include "ros_messages.hpp"

namespace skytrace::ros_node {
namespace {

// Exit codes of the skytrace CLI (README "Exit codes").
constexpr int kExitUsage = 2;
constexpr int kExitInput = 3;
constexpr int kExitOutput = 5;

enum class PoseSource { kScenario, kTf, kOdometry, kPose };

struct Config {
  std::string scenario;
  PoseSource pose_source = PoseSource::kScenario;
  std::string world_frame = "world";
  std::string antenna_frame = "gnss_antenna";
  std::string frame_id;  // of the fix and velocity; the antenna frame by default
  std::string pose_topic = "antenna_pose";
  std::string odom_topic = "odom";
  Eigen::Vector3d antenna_offset_m = Eigen::Vector3d::Zero();  // in the body frame of pose/odometry
  // A moving base's antenna (the receiver's rtk.moving_base), in the same body frame (tf: the
  // antenna frame's); none: it follows the antenna at the scenario's baseline.
  std::optional<Eigen::Vector3d> base_antenna_offset_m;
  double rate_hz = 1.0;
  std::string start_time;  // ISO 8601 in start_time_scale; empty: the scenario's start
  std::string start_time_scale = "GPST";
  double pose_timeout_s = 1.0;
  double ray_length_m = 100.0;
  std::vector<std::string> moving_models;  // tf frames of movable world models
  // The files of live::Receiver::file_parameters() ("rinex_out", "nmea_out", ...) and their paths.
  std::vector<std::pair<std::string, std::string>> file_outputs;
  std::string latency_report;
  std::string receiver;  // one receiver of a scenario with several; empty: the first
  std::string rtk_base;  // RTK: HOST:PORT or ntrip://... of a base's RTCM 3 stream
};

// Reads and checks the private parameters; an error names the parameter and what was expected.
std::optional<std::string> read_config(const ros::NodeHandle& pnh, Config& c) {
  if (!pnh.getParam("scenario", c.scenario) || c.scenario.empty()) {
    return "~scenario is required: the path of a skytrace scenario file (YAML)";
  }
  std::string source = "scenario";
  pnh.param<std::string>("pose_source", source, source);
  if (source == "scenario") {
    c.pose_source = PoseSource::kScenario;
  } else if (source == "tf") {
    c.pose_source = PoseSource::kTf;
  } else if (source == "odometry") {
    c.pose_source = PoseSource::kOdometry;
  } else if (source == "pose") {
    c.pose_source = PoseSource::kPose;
  } else {
    return fmt::format("~pose_source '{}': expected scenario, tf, odometry or pose", source);
  }
  pnh.param<std::string>("world_frame", c.world_frame, c.world_frame);
  pnh.param<std::string>("antenna_frame", c.antenna_frame, c.antenna_frame);
  pnh.param<std::string>("frame_id", c.frame_id, c.antenna_frame);
  pnh.param<std::string>("pose_topic", c.pose_topic, c.pose_topic);
  pnh.param<std::string>("odom_topic", c.odom_topic, c.odom_topic);
  pnh.param("rate_hz", c.rate_hz, c.rate_hz);
  if (!(c.rate_hz > 0.0 && c.rate_hz <= 100.0)) {
    return fmt::format("~rate_hz {}: expected a rate in (0, 100] Hz", c.rate_hz);
  }
  pnh.param("pose_timeout_s", c.pose_timeout_s, c.pose_timeout_s);
  if (!(c.pose_timeout_s > 0.0)) return fmt::format("~pose_timeout_s {}: expected a positive duration", c.pose_timeout_s);
  pnh.param("ray_length_m", c.ray_length_m, c.ray_length_m);
  if (!(c.ray_length_m > 0.0)) return fmt::format("~ray_length_m {}: expected a positive length", c.ray_length_m);
  pnh.param<std::string>("start_time", c.start_time, c.start_time);
  pnh.param<std::string>("start_time_scale", c.start_time_scale, c.start_time_scale);
  // A lever arm: a list of three numbers (rosparam or a launch file: `_name:=[..]` on the command
  // line is a string in ROS 1, refused here rather than ignored).
  const auto lever_arm = [&](const char* name) -> std::optional<std::optional<Eigen::Vector3d>> {
    if (!pnh.hasParam(name)) return std::optional<Eigen::Vector3d>{};
    std::vector<double> v;
    if (!pnh.getParam(name, v) || v.size() != 3) return std::nullopt;
    return std::optional<Eigen::Vector3d>(Eigen::Vector3d(v[0], v[1], v[2]));
  };
  const auto offset = lever_arm("antenna_offset_m");
  if (!offset) return "~antenna_offset_m: expected a list [x, y, z] in metres in the robot's body frame (rosparam or launch file)";
  if (*offset) c.antenna_offset_m = **offset;
  const auto base_offset = lever_arm("base_antenna_offset_m");
  if (!base_offset) {
    return "~base_antenna_offset_m: expected a list [x, y, z] in metres in the robot's body frame (rosparam or launch file)";
  }
  c.base_antenna_offset_m = *base_offset;
  pnh.param("moving_models", c.moving_models, c.moving_models);
  for (const auto& [parameter, description] : live::Receiver::file_parameters()) {
    std::string path;
    pnh.param<std::string>(parameter, path, path);
    c.file_outputs.emplace_back(parameter, path);
  }
  pnh.param<std::string>("latency_report", c.latency_report, c.latency_report);
  pnh.param<std::string>("receiver", c.receiver, c.receiver);
  pnh.param<std::string>("rtk_base", c.rtk_base, c.rtk_base);
  return std::nullopt;
}

Eigen::Quaterniond to_eigen(const geometry_msgs::Quaternion& q) { return {q.w, q.x, q.y, q.z}; }

class Node {
 public:
  Node(Config config, std::unique_ptr<live::Receiver> receiver)
      : config_(std::move(config)), receiver_(std::move(receiver)), pnh_("~") {
    period_s_ = 1.0 / config_.rate_hz;
    fix_pub_ = pnh_.advertise<sensor_msgs::NavSatFix>("fix", 10);
    velocity_pub_ = pnh_.advertise<geometry_msgs::TwistWithCovarianceStamped>("velocity", 10);
    observations_pub_ = pnh_.advertise<skytrace_msgs::Observations>("observations", 10);
    nmea_pub_ = pnh_.advertise<std_msgs::String>("nmea", 100);
    sky_pub_ = pnh_.advertise<skytrace_msgs::Sky>("sky", 10);
    rays_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("rays", 10);
    if (config_.pose_source == PoseSource::kTf || !config_.moving_models.empty()) {
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
    }
    if (config_.pose_source == PoseSource::kPose) {
      pose_sub_ = nh_.subscribe(config_.pose_topic, 20, &Node::on_pose, this);
    } else if (config_.pose_source == PoseSource::kOdometry) {
      pose_sub_ = nh_.subscribe(config_.odom_topic, 20, &Node::on_odometry, this);
    }
  }

  // The outputs, each a sink of the receiver's epochs: this node's topics, then the files asked for.
  [[nodiscard]] bool open_outputs() {
    if (auto problem = receiver_->open_outputs(config_.file_outputs, period_s_); !problem.empty()) {
      ROS_FATAL("%s", problem.c_str());
      return false;
    }
    receiver_->add_publisher([this](const live::EpochView& e) { publish(e); });
    return true;
  }

  void run() {
    ros::CallbackQueue& queue = *ros::getGlobalCallbackQueue();
    const double wait_s = std::min(0.01, period_s_ / 4.0);
    if (!ros::Time::isSimTime()) origin_ = ros::Time::now();  // node start maps to ~start_time
    while (ros::ok() && !live::stop_requested()) {
      queue.callAvailable(ros::WallDuration(wait_s));
      const ros::Time now = ros::Time::now();
      if (now.isZero()) {
        ROS_WARN_THROTTLE(10.0, "waiting for the clock (/use_sim_time is set and /clock has not started)");
        continue;
      }
      const double elapsed_s = (now - origin_).toSec();
      if (elapsed_s < 0.0) continue;
      const auto k = static_cast<std::int64_t>(std::floor(elapsed_s * config_.rate_hz + 1e-6));
      if (last_k_) {
        if (k == *last_k_) continue;
        if (k < *last_k_) {
          ROS_WARN("time went back %.3f s (simulation reset?): the receiver restarts tracking",
                   static_cast<double>(*last_k_ - k) * period_s_);
        } else if (k - *last_k_ > std::max<std::int64_t>(2, static_cast<std::int64_t>(2.0 * config_.rate_hz))) {
          ROS_WARN("time jumped %.3f s forward: %lld epochs skipped", static_cast<double>(k - *last_k_) * period_s_,
                   static_cast<long long>(k - *last_k_ - 1));
        }
      }
      last_k_ = k;
      epoch(k);
    }
  }

  void finish() {
    const auto finished = receiver_->finish_outputs();
    for (const auto& error : finished.errors) ROS_ERROR("%s", error.c_str());
    for (const auto& written : finished.written) ROS_INFO("written: %s", written.c_str());
    report_latency();
  }

 private:
  // Receiver time (seconds after the start time) of a ROS time (stamps of poses and transforms).
  [[nodiscard]] double receiver_time_s(const ros::Time& stamp) const { return (stamp - origin_).toSec(); }

  void set_pose(const ros::Time& stamp, const Eigen::Vector3d& position_world_m,
                const std::optional<Eigen::Vector3d>& velocity_world_mps, const char* source) {
    if (!position_world_m.allFinite() || (velocity_world_mps && !velocity_world_mps->allFinite())) {
      ROS_WARN_THROTTLE(5.0, "%s: antenna pose with NaN or infinite values ignored", source);
      return;
    }
    const ros::Time when = stamp.isZero() ? ros::Time::now() : stamp;
    std::optional<live::Vec3> velocity;
    if (velocity_world_mps) velocity = live::Vec3{velocity_world_mps->x(), velocity_world_mps->y(), velocity_world_mps->z()};
    const live::Vec3 position{position_world_m.x(), position_world_m.y(), position_world_m.z()};
    if (auto problem = receiver_->set_antenna_pose_world(receiver_time_s(when), position, velocity); !problem.empty()) {
      ROS_WARN_THROTTLE(5.0, "%s: %s", source, problem.c_str());
    }
  }

  // The antenna point of a body pose: the body's position plus the lever arm turned by its attitude.
  [[nodiscard]] std::optional<Eigen::Vector3d> antenna_point(const geometry_msgs::Pose& pose, const char* source) const {
    Eigen::Vector3d p(pose.position.x, pose.position.y, pose.position.z);
    if (config_.antenna_offset_m.isZero()) return p;
    const Eigen::Quaterniond q = to_eigen(pose.orientation);
    if (!q.coeffs().allFinite() || q.norm() < 1e-6) {
      ROS_WARN_THROTTLE(5.0, "%s: orientation missing or not finite; ~antenna_offset_m needs it, pose ignored", source);
      return std::nullopt;
    }
    return p + q.normalized() * config_.antenna_offset_m;
  }

  void check_frame(const std::string& frame_id, const char* source) const {
    if (!frame_id.empty() && frame_id != config_.world_frame) {
      ROS_WARN_THROTTLE(10.0, "%s: pose in frame '%s', expected ~world_frame '%s'; used as world coordinates", source,
                        frame_id.c_str(), config_.world_frame.c_str());
    }
  }

  // A moving base's antenna on the body (~base_antenna_offset_m), from the body's position and attitude.
  void set_base_pose(const ros::Time& stamp, const Eigen::Vector3d& body_m, const Eigen::Quaterniond& attitude,
                     const std::optional<Eigen::Vector3d>& velocity_world_mps, const char* source) {
    if (!config_.base_antenna_offset_m) return;
    if (!attitude.coeffs().allFinite() || attitude.norm() < 1e-6) {
      ROS_WARN_THROTTLE(5.0, "%s: orientation missing; ~base_antenna_offset_m needs it", source);
      return;
    }
    const Eigen::Vector3d p = body_m + attitude.normalized() * *config_.base_antenna_offset_m;
    std::optional<live::Vec3> velocity;
    if (velocity_world_mps) velocity = live::Vec3{velocity_world_mps->x(), velocity_world_mps->y(), velocity_world_mps->z()};
    const ros::Time when = stamp.isZero() ? ros::Time::now() : stamp;
    if (auto problem = receiver_->set_base_antenna_pose_world(receiver_time_s(when), {p.x(), p.y(), p.z()}, velocity);
        !problem.empty()) {
      ROS_WARN_THROTTLE(5.0, "%s: moving base: %s", source, problem.c_str());
    }
  }

  void on_pose(const geometry_msgs::PoseStamped::ConstPtr& msg) {
    check_frame(msg->header.frame_id, config_.pose_topic.c_str());
    if (auto p = antenna_point(msg->pose, config_.pose_topic.c_str())) {
      set_pose(msg->header.stamp, *p, std::nullopt, config_.pose_topic.c_str());
      const auto& b = msg->pose.position;
      set_base_pose(msg->header.stamp, Eigen::Vector3d(b.x, b.y, b.z), to_eigen(msg->pose.orientation), std::nullopt,
                    config_.pose_topic.c_str());
    }
  }

  void on_odometry(const nav_msgs::Odometry::ConstPtr& msg) {
    check_frame(msg->header.frame_id, config_.odom_topic.c_str());
    auto p = antenna_point(msg->pose.pose, config_.odom_topic.c_str());
    if (!p) return;
    // The twist is in the child (body) frame: turned into the world frame by the attitude.
    const Eigen::Vector3d v_body(msg->twist.twist.linear.x, msg->twist.twist.linear.y, msg->twist.twist.linear.z);
    const Eigen::Quaterniond q = to_eigen(msg->pose.pose.orientation);
    std::optional<Eigen::Vector3d> v_world;
    if (q.coeffs().allFinite() && q.norm() > 1e-6) v_world = q.normalized() * v_body;
    set_pose(msg->header.stamp, *p, v_world, config_.odom_topic.c_str());
    const auto& b = msg->pose.pose.position;
    set_base_pose(msg->header.stamp, Eigen::Vector3d(b.x, b.y, b.z), q, v_world, config_.odom_topic.c_str());
  }

  // A transform world_frame <- frame, if tf has it and it is usable.
  std::optional<geometry_msgs::TransformStamped> lookup(const std::string& frame) {
    try {
      auto t = tf_buffer_->lookupTransform(config_.world_frame, frame, ros::Time(0));
      const auto& tr = t.transform.translation;
      if (!std::isfinite(tr.x) || !std::isfinite(tr.y) || !std::isfinite(tr.z)) {
        ROS_WARN_THROTTLE(5.0, "tf %s -> %s has NaN or infinite values; ignored", config_.world_frame.c_str(), frame.c_str());
        return std::nullopt;
      }
      return t;
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(5.0, "no transform %s -> %s: %s", config_.world_frame.c_str(), frame.c_str(), e.what());
      return std::nullopt;
    }
  }

  void update_from_tf(const ros::Time& epoch_stamp) {
    if (config_.pose_source == PoseSource::kTf) {
      if (auto t = lookup(config_.antenna_frame)) {
        // A static transform (stamp 0) holds at every time.
        const ros::Time stamp = t->header.stamp.isZero() ? epoch_stamp : t->header.stamp;
        if ((epoch_stamp - stamp).toSec() > config_.pose_timeout_s) {
          ROS_WARN_THROTTLE(5.0, "tf %s -> %s is %.1f s old (stale)", config_.world_frame.c_str(),
                            config_.antenna_frame.c_str(), (epoch_stamp - stamp).toSec());
        }
        const auto& tr = t->transform.translation;
        set_pose(stamp, Eigen::Vector3d(tr.x, tr.y, tr.z), std::nullopt, "tf");
        set_base_pose(stamp, Eigen::Vector3d(tr.x, tr.y, tr.z), to_eigen(t->transform.rotation), std::nullopt, "tf");
      }
    }
    for (const auto& model : config_.moving_models) {
      auto t = lookup(model);
      if (!t) continue;
      const auto& tr = t->transform.translation;
      const auto& q = t->transform.rotation;
      if (auto problem = receiver_->set_object_pose(model, {tr.x, tr.y, tr.z}, {q.w, q.x, q.y, q.z}); !problem.empty()) {
        ROS_WARN_THROTTLE(10.0, "moving model '%s': %s", model.c_str(), problem.c_str());
      }
    }
  }

  void epoch(std::int64_t k) {
    const double time_s = static_cast<double>(k) * period_s_;
    const ros::Time stamp = origin_ + ros::Duration(time_s);
    if (tf_buffer_) update_from_tf(stamp);
    const auto started = std::chrono::steady_clock::now();
    std::string problem;
    std::vector<std::string> notes;
    if (!receiver_->step_outputs(time_s, problem, notes)) {
      ROS_ERROR_THROTTLE(10.0, "epoch %.3f s after the start time: %s", time_s, problem.c_str());
      return;
    }
    latencies_.add(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    for (const auto& note : notes) ROS_WARN_THROTTLE(10.0, "%s", note.c_str());
  }

  // The node's topics of one epoch (its publisher in the receiver's outputs).
  void publish(const live::EpochView& e) {
    const ros::Time stamp = origin_ + ros::Duration(e.time_s);
    if (e.restarted) ROS_WARN("receiver restarted at %s GPST (time went back)", e.time_iso.c_str());
    if (e.pose_stale) {
      ROS_WARN_THROTTLE(5.0, "antenna pose is stale (none for %.1f s): the receiver is held where it was", config_.pose_timeout_s);
    }
    std_msgs::Header fix_header;
    fix_header.stamp = stamp;
    fix_header.frame_id = config_.frame_id;
    std_msgs::Header world_header;
    world_header.stamp = stamp;
    world_header.frame_id = config_.world_frame;

    fix_pub_.publish(to_navsat_fix(e.fix, fix_header));
    if (e.fix.type != 0 && e.fix.velocity_valid) velocity_pub_.publish(to_velocity(e.fix, fix_header));
    observations_pub_.publish(to_observations(e, fix_header));
    for (const std::string& sentence : e.nmea) {
      std_msgs::String msg;
      msg.data = sentence;
      nmea_pub_.publish(msg);
    }
    sky_pub_.publish(to_sky(e, world_header));
    rays_pub_.publish(to_rays(e, world_header, config_.ray_length_m));
  }

  void report_latency() {
    if (latencies_.empty()) return;
    const live::LatencySummary summary = latencies_.summary();
    ROS_INFO("per-epoch latency (step and publish): %zu epochs, p50 %.3f ms, p99 %.3f ms, max %.3f ms", summary.epochs,
             summary.p50_ms, summary.p99_ms, summary.max_ms);
    if (!config_.latency_report.empty()) {
      std::ofstream out(config_.latency_report);
      out << live::latency_json(config_.scenario, config_.rate_hz, summary);
      if (!out) ROS_ERROR("~latency_report %s: cannot write", config_.latency_report.c_str());
    }
  }

  Config config_;
  std::unique_ptr<live::Receiver> receiver_;
  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  double period_s_ = 1.0;
  ros::Time origin_;  // the ROS time of the start time: zero under sim time, else the node's start
  std::optional<std::int64_t> last_k_;
  ros::Publisher fix_pub_, velocity_pub_, observations_pub_, nmea_pub_, sky_pub_, rays_pub_;
  ros::Subscriber pose_sub_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  live::LatencyRecorder latencies_;  // bounded: the node may run for days
};

int run(int argc, char** argv) {
  ros::init(argc, argv, "skytrace", ros::init_options::NoSigintHandler);
  // SIGINT and SIGTERM end the loop; should it hang (a NodeHandle waiting for a master that never
  // comes, a stuck callback), a watchdog ends the process a second later.
  live::install_stop_handlers();
  ros::NodeHandle pnh("~");
  Config config;
  if (auto problem = read_config(pnh, config)) {
    ROS_FATAL("%s", problem->c_str());
    return kExitUsage;
  }
  live::ReceiverOptions options;
  options.scenario_path = config.scenario;
  options.start_time = config.start_time;
  options.start_time_scale = config.start_time_scale;
  options.pose_timeout_s = config.pose_timeout_s;
  options.receiver_name = config.receiver;
  options.rtk_base = config.rtk_base;
  options.log = [](int level, const std::string& text) {
    if (level == 0) {
      ROS_INFO("skytrace: %s", text.c_str());
    } else if (level == 1) {
      ROS_WARN("skytrace: %s", text.c_str());
    } else {
      ROS_ERROR("skytrace: %s", text.c_str());
    }
  };
  std::string problem;
  auto receiver = live::Receiver::create(options, problem);
  if (!receiver) {
    ROS_FATAL("%s (from ~scenario, ~start_time, ~start_time_scale, ~receiver, ~rtk_base)", problem.c_str());
    return kExitInput;
  }
  for (const auto& warning : receiver->warnings()) ROS_WARN("skytrace: %s", warning.c_str());
  if (config.base_antenna_offset_m && !receiver->has_moving_base()) {
    ROS_FATAL("~base_antenna_offset_m: the receiver has no moving base (rtk.moving_base with rtk.base in the scenario)");
    return kExitUsage;
  }
  Node node(config, std::move(receiver));
  if (!node.open_outputs()) return kExitOutput;
  ROS_INFO("skytrace: scenario %s, %.3g Hz, antenna pose from %s", config.scenario.c_str(), config.rate_hz,
           config.pose_source == PoseSource::kScenario ? "the scenario"
           : config.pose_source == PoseSource::kTf     ? "tf"
           : config.pose_source == PoseSource::kPose   ? config.pose_topic.c_str()
                                                       : config.odom_topic.c_str());
  node.run();
  live::disarm_stop_watchdog();  // the loop ended in time: no forced exit while the files are finished
  node.finish();
  ros::shutdown();
  return 0;
}

}  // namespace
}  // namespace skytrace::ros_node

int main(int argc, char** argv) {
  try {
    return skytrace::ros_node::run(argc, argv);
  } catch (const std::exception& e) {
    // A last resort: every expected failure is reported above with its parameter.
    std::fprintf(stderr, "skytrace_ros_node: %s\n", e.what());
    return 1;
  }
}
