#include "gz_bridge.hpp"
#include "gz_module.hpp"

#include <fmt/format.h>
#include <ignition/msgs/clock.pb.h>
#include <ignition/msgs/navsat.pb.h>
#include <ignition/msgs/pose_v.pb.h>
#include <ignition/msgs/stringmsg.pb.h>
#include <ignition/transport/Node.hh>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <mutex>
#include <set>

#include "skytrace/core/cancellation.hpp"
#include "skytrace/sim/live.hpp"
#include "skytrace/sim/live_outputs.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::gz {
namespace {

namespace im = ignition::msgs;

double seconds(const im::Time& t) { return static_cast<double>(t.sec()) + 1e-9 * static_cast<double>(t.nsec()); }

void set_time(im::Time& t, double s) {
  const double whole = std::floor(s);
  t.set_sec(static_cast<std::int64_t>(whole));
  t.set_nsec(static_cast<std::int32_t>(std::lround((s - whole) * 1e9)));
}

Eigen::Isometry3d to_isometry(const im::Pose& p) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(p.position().x(), p.position().y(), p.position().z());
  if (p.has_orientation()) {
    const Eigen::Quaterniond q(p.orientation().w(), p.orientation().x(), p.orientation().y(), p.orientation().z());
    if (q.norm() > 1e-9) pose.linear() = q.normalized().toRotationMatrix();
  }
  return pose;
}

// A warning at most every `period` per key: a stream of bad poses must not flood the log.
class Throttle {
 public:
  bool allow(const std::string& key, std::chrono::seconds period = std::chrono::seconds(5)) {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard lock(mutex_);
    auto it = last_.find(key);
    if (it != last_.end() && now - it->second < period) return false;
    last_[key] = now;
    return true;
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::chrono::steady_clock::time_point> last_;
};

nlohmann::json observations_json(const sim::SinkEpoch& epoch, double sim_time_s) {
  const WeekTow wt = epoch.observations->receiver_time.to_week_tow(TimeScale::kGpst);
  nlohmann::json j;
  j["sim_time_s"] = sim_time_s;
  j["gps_week"] = wt.week;
  j["gps_tow_s"] = wt.tow_s;
  j["restarted"] = epoch.restarted;
  j["pose_stale"] = epoch.pose_stale;
  if (epoch.fix) {
    const auto& f = *epoch.fix;
    j["fix"] = {{"type", std::string(positioning::to_string(f.type))},
                {"latitude_deg", f.position.latitude_deg},
                {"longitude_deg", f.position.longitude_deg},
                {"height_m", f.position.height_m},
                {"satellites_used", f.satellites_used},
                {"hdop", f.hdop},
                {"vdop", f.vdop}};
  }
  nlohmann::json satellites = nlohmann::json::array();
  for (const auto& sat : epoch.observations->satellites) {
    if (sat.status == receiver::SatelliteStatus::kNoEphemeris || sat.direction.elevation_deg < 0.0) continue;
    nlohmann::json s = {{"id", sat.satellite.to_string()},
                        {"status", std::string(receiver::to_string(sat.status))},
                        {"azimuth_deg", sat.direction.azimuth_deg},
                        {"elevation_deg", sat.direction.elevation_deg},
                        {"vegetation_path_m", sat.vegetation_path_m}};
    if (!sat.detail.empty()) s["detail"] = sat.detail;
    nlohmann::json signals = nlohmann::json::array();
    for (const auto& m : sat.signals) {
      signals.push_back({{"code", m.signal.code()},
                         {"pseudorange_m", m.pseudorange_m},
                         {"carrier_phase_cycles", m.carrier_phase_cycles},
                         {"doppler_hz", m.doppler_hz},
                         {"cn0_dbhz", m.cn0_dbhz},
                         {"loss_of_lock", m.loss_of_lock},
                         {"lock_time_s", m.lock_time_s}});
    }
    s["signals"] = std::move(signals);
    satellites.push_back(std::move(s));
  }
  j["satellites"] = std::move(satellites);
  return j;
}

class Bridge {
 public:
  Bridge(const BridgeOptions& options, std::unique_ptr<sim::LiveSession> session, const GnssTime& start)
      : options_(options), session_(std::move(session)), start_(start) {}

  // The outputs, each a sink of the receiver's epochs: the bridge's topics, then the files asked for.
  Status open_outputs() {
    auto outputs = sim::LiveOutputs::open(*session_, options_.file_outputs, 1.0 / options_.rate_hz);
    if (!outputs) return outputs.error();
    outputs_ = std::move(*outputs);
    outputs_->add_publisher(std::make_unique<sim::CallbackSink>([this](const sim::SinkEpoch& e) {
      publish(e);
      return Status(Ok{});
    }));
    return Ok{};
  }

  // Completes the files; the first error is returned (every one is logged).
  Status finish_outputs() {
    const auto finished = outputs_->finish();
    for (const auto& written : finished.written) spdlog::info("skytrace gz: written: {}", written);
    for (const auto& error : finished.errors) spdlog::error("skytrace gz: {}", error);
    if (!finished.errors.empty()) return make_error(ErrorCode::kOutput, finished.errors.front());
    return Ok{};
  }

  Status connect() {
    navsat_pub_ = node_.Advertise<im::NavSat>(navsat_topic(options_));
    if (!navsat_pub_) return make_error(ErrorCode::kInvalidArgument, "cannot advertise " + navsat_topic(options_));
    observations_pub_ = node_.Advertise<im::StringMsg>(observations_topic(options_));
    if (!observations_pub_) return make_error(ErrorCode::kInvalidArgument, "cannot advertise " + observations_topic(options_));
    if (!node_.Subscribe(pose_topic(options_), &Bridge::on_poses, this)) {
      return make_error(ErrorCode::kInvalidArgument, "cannot subscribe to " + pose_topic(options_));
    }
    if (!node_.Subscribe(clock_topic(options_), &Bridge::on_clock, this)) {
      return make_error(ErrorCode::kInvalidArgument, "cannot subscribe to " + clock_topic(options_));
    }
    return Ok{};
  }

  void run() {
    const double period_s = 1.0 / options_.rate_hz;
    std::optional<std::int64_t> last_k;
    while (!cancellation_requested()) {
      double sim_time_s = 0.0;
      std::map<std::string, Eigen::Isometry3d> objects;
      {
        std::unique_lock lock(mutex_);
        cv_.wait_for(lock, std::chrono::milliseconds(100));
        if (!sim_time_s_) continue;
        sim_time_s = *sim_time_s_;
        const auto k = static_cast<std::int64_t>(std::floor(sim_time_s * options_.rate_hz + 1e-6));
        if (last_k && k == *last_k) continue;
        if (last_k && k < *last_k) {
          spdlog::warn("simulation time went back to {:.3f} s (reset): the receiver restarts tracking", sim_time_s);
        }
        last_k = k;
        sim_time_s = static_cast<double>(k) * period_s;
        objects.swap(pending_objects_);
      }
      for (const auto& [name, pose] : objects) {
        if (unmovable_.count(name) > 0) continue;
        // Pose_V carries every entity (links, visuals...): names that are not movable models of
        // the scenario's world are remembered and skipped from then on.
        if (!session_->set_object_pose(name, pose)) unmovable_.insert(name);
      }
      epoch(sim_time_s);
    }
  }

 private:
  void on_clock(const im::Clock& msg) {
    if (!msg.has_sim()) return;
    {
      std::lock_guard lock(mutex_);
      sim_time_s_ = seconds(msg.sim());
    }
    cv_.notify_one();
  }

  void on_poses(const im::Pose_V& msg) {
    double stamp_s = 0.0;
    bool stamped = msg.has_header() && msg.header().has_stamp();
    if (stamped) stamp_s = seconds(msg.header().stamp());
    // The model's pose is in the world frame; its links follow it in the message (depth-first),
    // with poses relative to the model.
    std::optional<Eigen::Isometry3d> antenna;
    std::optional<Eigen::Vector3d> base_antenna_m;  // a moving base's link (options_.base_link)
    std::map<std::string, Eigen::Isometry3d> others;
    // A link of the model at index i (its pose follows the model's in the message) into `pose`.
    const auto link_pose = [&](int i, const Eigen::Isometry3d& model, const std::string& link, Eigen::Isometry3d& pose) {
      for (int j = i + 1; j < msg.pose_size(); ++j) {
        if (msg.pose(j).name() == link) {
          pose = model * to_isometry(msg.pose(j));
          return true;
        }
      }
      return false;
    };
    for (int i = 0; i < msg.pose_size(); ++i) {
      const im::Pose& p = msg.pose(i);
      if (p.name() == options_.model && !antenna) {
        const Eigen::Isometry3d model = to_isometry(p);
        antenna = model;
        Eigen::Isometry3d link = Eigen::Isometry3d::Identity();
        if (!options_.link.empty()) {
          if (link_pose(i, model, options_.link, link)) {
            antenna = link;
          } else if (throttle_.allow("link")) {
            spdlog::warn("{}: model '{}' has no link '{}' after it; its origin is used", pose_topic(options_),
                         options_.model, options_.link);
          }
        }
        if (!options_.base_link.empty()) {
          if (link_pose(i, model, options_.base_link, link)) {
            base_antenna_m = link.translation();
          } else if (throttle_.allow("base_link")) {
            spdlog::warn("{}: model '{}' has no link '{}' after it; the base antenna keeps the scenario's baseline",
                         pose_topic(options_), options_.model, options_.base_link);
          }
        }
      } else if (!p.name().empty()) {
        others[p.name()] = to_isometry(p);
      }
    }
    std::optional<double> now_s;
    {
      std::lock_guard lock(mutex_);
      if (stamped && (!sim_time_s_ || stamp_s > *sim_time_s_)) sim_time_s_ = stamp_s;
      now_s = sim_time_s_;
      for (auto& [name, pose] : others) pending_objects_[name] = pose;
    }
    cv_.notify_one();
    if (!antenna) {
      if (throttle_.allow("model")) {
        spdlog::warn("{}: no pose of model '{}' (the antenna stays where it was)", pose_topic(options_), options_.model);
      }
      return;
    }
    const Eigen::Vector3d position = antenna->translation();
    if (!position.allFinite()) {
      if (throttle_.allow("nan")) spdlog::warn("{}: pose of '{}' with NaN values ignored", pose_topic(options_), options_.model);
      return;
    }
    const double time_s = stamped ? stamp_s : now_s.value_or(0.0);
    if (auto st = session_->set_antenna_pose_world(start_ + time_s, position); !st && throttle_.allow("pose")) {
      spdlog::warn("{}: {}", pose_topic(options_), st.error().message);
    }
    if (base_antenna_m) {
      if (auto st = session_->set_base_antenna_pose_world(start_ + time_s, *base_antenna_m);
          !st && throttle_.allow("base_pose")) {
        spdlog::warn("{}: moving base: {}", pose_topic(options_), st.error().message);
      }
    }
  }

  void epoch(double sim_time_s) {
    auto result = session_->step(start_ + sim_time_s);
    if (!result) {
      if (throttle_.allow("step", std::chrono::seconds(10))) {
        spdlog::error("epoch at simulation time {:.3f} s: {}", sim_time_s, result.error().message);
      }
      return;
    }
    sim_time_s_of_epoch_ = sim_time_s;
    for (const auto& note : outputs_->add(*result)) {
      if (throttle_.allow("outputs", std::chrono::seconds(10))) spdlog::warn("skytrace gz: {}", note);
    }
  }

  // The bridge's topics of one epoch (its publisher in the receiver's outputs).
  void publish(const sim::SinkEpoch& e) {
    const double sim_time_s = sim_time_s_of_epoch_;
    if (e.pose_stale && throttle_.allow("stale")) {
      spdlog::warn("no pose of '{}' for {:.1f} s: the receiver is held where it was", options_.model, options_.pose_timeout_s);
    }
    if (e.fix != nullptr && e.fix->type != positioning::FixType::kNone) {
      im::NavSat navsat;
      set_time(*navsat.mutable_header()->mutable_stamp(), sim_time_s);
      navsat.set_frame_id(options_.link.empty() ? options_.model : options_.model + "::" + options_.link);
      navsat.set_latitude_deg(e.fix->position.latitude_deg);
      navsat.set_longitude_deg(e.fix->position.longitude_deg);
      navsat.set_altitude(e.fix->position.height_m);
      navsat.set_velocity_east(e.fix->velocity_enu_mps.x());
      navsat.set_velocity_north(e.fix->velocity_enu_mps.y());
      navsat.set_velocity_up(e.fix->velocity_enu_mps.z());
      navsat_pub_.Publish(navsat);
    } else if (throttle_.allow("nofix")) {
      spdlog::warn("no fix at simulation time {:.3f} s: {}", sim_time_s, e.fix ? e.fix->message : "");
    }
    im::StringMsg observations;
    set_time(*observations.mutable_header()->mutable_stamp(), sim_time_s);
    observations.set_data(observations_json(e, sim_time_s).dump());
    observations_pub_.Publish(observations);
  }

  BridgeOptions options_;
  std::unique_ptr<sim::LiveSession> session_;
  GnssTime start_;
  ignition::transport::Node node_;
  ignition::transport::Node::Publisher navsat_pub_;
  ignition::transport::Node::Publisher observations_pub_;
  std::unique_ptr<sim::LiveOutputs> outputs_;
  double sim_time_s_of_epoch_ = 0.0;  // the simulation time of the epoch being published
  std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<double> sim_time_s_;
  std::map<std::string, Eigen::Isometry3d> pending_objects_;
  std::set<std::string> unmovable_;
  Throttle throttle_;
};

}  // namespace

std::string pose_topic(const BridgeOptions& options) { return "/world/" + options.world_name + "/pose/info"; }
std::string clock_topic(const BridgeOptions& options) { return "/world/" + options.world_name + "/clock"; }
std::string navsat_topic(const BridgeOptions& options) {
  return "/world/" + options.world_name + "/model/" + options.model + "/skytrace/navsat";
}
std::string observations_topic(const BridgeOptions& options) {
  return "/world/" + options.world_name + "/model/" + options.model + "/skytrace/observations";
}

namespace {

Status run_bridge_here(const BridgeOptions& options) {
  if (options.world_name.empty() || options.model.empty()) {
    return make_error(ErrorCode::kInvalidArgument, "--world-name and --model must not be empty");
  }
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100.0)) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("--rate-hz {}: expected a rate in (0, 100] Hz", options.rate_hz));
  }
  auto scenario = sim::load_scenario(options.scenario);
  if (!scenario) return scenario.error();
  GnssTime start = scenario->time.start;
  if (options.start_time) {
    auto t = GnssTime::parse_iso8601(*options.start_time, TimeScale::kGpst);
    if (!t) {
      return make_error(ErrorCode::kInvalidArgument,
                        fmt::format("--start-time '{}': expected YYYY-MM-DDThh:mm:ss[.fff] GPST", *options.start_time));
    }
    start = *t;
  }
  sim::LiveOptions live_options;
  live_options.pose_timeout_s = options.pose_timeout_s;
  if (!options.receiver.empty()) {
    const auto& receivers = scenario->receivers;
    const auto it = std::find_if(receivers.begin(), receivers.end(),
                                 [&](const sim::ReceiverSettings& r) { return r.name == options.receiver; });
    if (it == receivers.end()) {
      return make_error(ErrorCode::kInvalidArgument,
                        "--receiver " + options.receiver + ": no such receiver in " + options.scenario.string());
    }
    live_options.receiver_index = static_cast<size_t>(it - receivers.begin());
  }
  auto session = sim::LiveSession::create(*scenario, live_options);
  if (!session) return session.error();
  if (!options.base_link.empty() && !(*session)->has_moving_base()) {
    return make_error(ErrorCode::kInvalidArgument,
                      "--base-link " + options.base_link + ": the receiver has no moving base (rtk.moving_base with rtk.base)");
  }
  for (const auto& warning : (*session)->resources().warnings) spdlog::warn("skytrace gz: {}", warning);
  Bridge bridge(options, std::move(*session), start);
  if (auto st = bridge.open_outputs(); !st) return st;
  if (auto st = bridge.connect(); !st) return st;
  if (!options.quiet) {
    spdlog::info("skytrace gz: world '{}', model '{}'{}; poses from {}, time from {}; NavSat on {}", options.world_name,
                 options.model, options.link.empty() ? "" : " link '" + options.link + "'", pose_topic(options),
                 clock_topic(options), navsat_topic(options));
  }
  bridge.run();
  disarm_stop_watchdog();  // the loop ended in time: no forced exit while the files are finished
  return bridge.finish_outputs();
}

}  // namespace

}  // namespace skytrace::gz

// The entry of the module skytrace-gz.so (gz_module.hpp).
extern "C" __attribute__((visibility("default"))) const skytrace::gz::GzBackend* skytrace_gz_backend() {
  using namespace skytrace::gz;
  static const GzBackend table{kGzBackendRevision, gz_backend_layout(), &run_bridge_here};
  return &table;
}
