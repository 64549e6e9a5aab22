#include "skytrace/sim/live.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <mutex>

#include "skytrace/core/constants.hpp"
#include "skytrace/sim/streams.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {
namespace {

// The antenna where the outside world last put it, falling back to the scenario's own kinematics
// until the first pose arrives. Poses arrive from another thread (ROS callbacks, UDP).
class ExternalPose final : public receiver::KinematicsSource {
 public:
  ExternalPose(std::shared_ptr<const receiver::KinematicsSource> fallback, double timeout_s)
      : fallback_(std::move(fallback)), timeout_s_(timeout_s) {}

  void set(const GnssTime& time, const Eigen::Vector3d& position_m, const std::optional<Eigen::Vector3d>& velocity_mps) {
    std::lock_guard lock(mutex_);
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
    if (velocity_mps) {
      velocity = *velocity_mps;
    } else if (pose_) {
      // Velocity from successive poses, when they are close enough in time to mean it.
      const double dt_s = time - pose_->time;
      if (dt_s > 1e-3 && dt_s <= 2.0 * timeout_s_) velocity = (position_m - pose_->position_m) / dt_s;
      if (velocity.norm() > kMaxAntennaSpeed_mps) velocity = Eigen::Vector3d::Zero();  // a jump, not a motion
    }
    pose_ = Pose{time, position_m, velocity};
  }

  [[nodiscard]] bool has_pose() const {
    std::lock_guard lock(mutex_);
    return pose_.has_value();
  }
  // Whether the last pose is older than the timeout at time t.
  [[nodiscard]] bool stale(const GnssTime& t) const {
    std::lock_guard lock(mutex_);
    return pose_ && (t - pose_->time) > timeout_s_;
  }

  [[nodiscard]] Result<receiver::Kinematics> at(const GnssTime& t) const override {
    std::optional<Pose> pose;
    {
      std::lock_guard lock(mutex_);
      pose = pose_;
    }
    if (!pose) return fallback_->at(t);
    // Extrapolate with the pose's velocity, but not beyond the timeout: a robot whose pose stopped
    // arriving is held where it was, at rest.
    const double dt_s = t - pose->time;
    if (std::abs(dt_s) > timeout_s_) {
      const double held_s = std::clamp(dt_s, -timeout_s_, timeout_s_);
      return receiver::Kinematics{pose->position_m + pose->velocity_mps * held_s, Eigen::Vector3d::Zero()};
    }
    return receiver::Kinematics{pose->position_m + pose->velocity_mps * dt_s, pose->velocity_mps};
  }

 private:
  struct Pose {
    GnssTime time;
    Eigen::Vector3d position_m;
    Eigen::Vector3d velocity_mps;
  };
  std::shared_ptr<const receiver::KinematicsSource> fallback_;
  double timeout_s_;
  mutable std::mutex mutex_;
  std::optional<Pose> pose_;
};

// A moving base's antenna before anyone places it: where the rover's external pose puts the body,
// offset by the scenario's baseline at the start (a body that translates); before the first pose,
// the base's own scenario kinematics.
class BaseFollowsRover final : public receiver::KinematicsSource {
 public:
  BaseFollowsRover(std::shared_ptr<const ExternalPose> rover, std::shared_ptr<const receiver::KinematicsSource> own,
                   const Eigen::Vector3d& baseline_ecef_m)
      : rover_(std::move(rover)), own_(std::move(own)), baseline_ecef_m_(baseline_ecef_m) {}
  [[nodiscard]] Result<receiver::Kinematics> at(const GnssTime& t) const override {
    if (!rover_->has_pose()) return own_->at(t);
    auto k = rover_->at(t);
    if (!k) return k.error();
    k->position_m += baseline_ecef_m_;
    return k;
  }

 private:
  std::shared_ptr<const ExternalPose> rover_;
  std::shared_ptr<const receiver::KinematicsSource> own_;
  Eigen::Vector3d baseline_ecef_m_;
};

}  // namespace

struct LiveSession::Impl {
  Scenario scenario;
  LiveOptions options;
  ScenarioResources resources;
  Eigen::Vector3d marker_m = Eigen::Vector3d::Zero();
  LocalFrame frame;
  std::shared_ptr<ExternalPose> pose;
  std::unique_ptr<receiver::ObservationGenerator> generator;
  std::optional<positioning::SinglePointSolver> solver;
  std::optional<positioning::RtkEngine> rtk;
  std::deque<positioning::BaseEpoch> base_epochs;  // newest last, about a minute
  // A moving base (the receiver's rtk.moving_base): the base antenna's receiver of the scenario,
  // simulated beside the rover; its own single-point fix is the base position of each epoch.
  std::optional<size_t> base_index;
  std::shared_ptr<ExternalPose> base_pose;
  std::unique_ptr<receiver::ObservationGenerator> base_generator;
  std::optional<positioning::SinglePointSolver> base_solver;
  io::ObservationHeader header;
  std::unique_ptr<RinexRecordMaker> records;
  std::optional<GnssTime> last_tag;

  [[nodiscard]] positioning::SolverSettings solver_settings() const {
    if (options.solver) return *options.solver;
    return default_solver_settings(scenario.receivers[options.receiver_index], *resources.ephemerides);
  }
  Status restart() {
    auto generator_made = make_generator(scenario, resources, options.receiver_index, pose);
    if (!generator_made) return generator_made.error();
    generator = std::move(*generator_made);
    if (base_index) {
      auto base_made = make_generator(scenario, resources, *base_index, base_pose);
      if (!base_made) return base_made.error();
      base_generator = std::move(*base_made);
      base_solver.emplace(*resources.ephemerides,
                          default_solver_settings(scenario.receivers[*base_index], *resources.ephemerides),
                          resources.ephemerides->data().ionosphere.gps);
    }
    if (options.solve_position) {
      solver.emplace(*resources.ephemerides, solver_settings(), resources.ephemerides->data().ionosphere.gps);
      if (options.rtk) {
        // A moving base of the scenario is a known receiver (its profile decides GLONASS); a
        // stream's base is not.
        auto settings = base_index ? rtk_settings(scenario, options.receiver_index, *resources.ephemerides)
                                   : rtk_settings_without_base(scenario.receivers[options.receiver_index], scenario,
                                                               *resources.ephemerides);
        if (!settings) return settings.error();
        rtk.emplace(*resources.ephemerides, std::move(*settings), resources.ephemerides->data().ionosphere.gps);
      }
    }
    return Ok{};
  }
};

LiveSession::LiveSession(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LiveSession::~LiveSession() = default;

Result<std::unique_ptr<LiveSession>> LiveSession::create(const Scenario& scenario, const LiveOptions& options) {
  if (options.receiver_index >= scenario.receivers.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("{}: the scenario has {} receivers, receiver {} was asked for", scenario.source.string(),
                                  scenario.receivers.size(), options.receiver_index));
  }
  if (!(options.pose_timeout_s > 0.0)) {
    return make_error(ErrorCode::kInvalidArgument, "the pose timeout must be positive");
  }
  auto impl = std::make_unique<Impl>();
  impl->scenario = scenario;
  impl->options = options;
  auto resources = prepare_resources(impl->scenario);
  if (!resources) return resources.error();
  impl->resources = std::move(*resources);
  const ReceiverSettings& rx = impl->scenario.receivers[options.receiver_index];
  const std::optional<LocalFrame> origin = world_origin(impl->scenario, impl->resources.world);
  auto kinematics = make_kinematics(impl->scenario, rx, origin, impl->marker_m);
  if (!kinematics) return kinematics.error();
  impl->frame = origin.value_or(LocalFrame{ecef_to_geodetic(impl->marker_m), 0.0});
  impl->pose = std::make_shared<ExternalPose>(*kinematics, options.pose_timeout_s);
  if (rx.rtk && rx.rtk->moving_base) {
    const auto base = std::find_if(impl->scenario.receivers.begin(), impl->scenario.receivers.end(),
                                   [&](const ReceiverSettings& r) { return r.name == rx.rtk->base; });
    if (base == impl->scenario.receivers.end()) {
      return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: receiver '{}': rtk.base '{}' is not a receiver of the scenario",
                                                                 impl->scenario.source.string(), rx.name, rx.rtk->base));
    }
    impl->base_index = static_cast<size_t>(base - impl->scenario.receivers.begin());
    Eigen::Vector3d base_marker_m = Eigen::Vector3d::Zero();
    auto base_kinematics = make_kinematics(impl->scenario, *base, origin, base_marker_m);
    if (!base_kinematics) return base_kinematics.error();
    const GnssTime start = impl->scenario.time.start;
    auto rover_at_start = (*kinematics)->at(start);
    auto base_at_start = (*base_kinematics)->at(start);
    if (!rover_at_start) return rover_at_start.error();
    if (!base_at_start) return base_at_start.error();
    auto follows = std::make_shared<BaseFollowsRover>(impl->pose, *base_kinematics,
                                                      base_at_start->position_m - rover_at_start->position_m);
    impl->base_pose = std::make_shared<ExternalPose>(std::move(follows), options.pose_timeout_s);
    impl->options.rtk = true;
  }
  if (auto st = impl->restart(); !st) return st.error();
  impl->header = make_observation_header(impl->scenario, rx, impl->marker_m, *impl->resources.ephemerides,
                                         impl->resources.left_out_systems,
                                         impl->generator->settings().profile.antenna_rinex_type);
  impl->records = std::make_unique<RinexRecordMaker>(impl->header);
  return std::unique_ptr<LiveSession>(new LiveSession(std::move(impl)));
}

namespace {

// Non-finite values, a position far from the Earth's surface or a speed no vehicle has: a unit or
// frame mistake or garbage (and extrapolated over a second it would put the antenna anywhere).
Status check_antenna_pose(const Eigen::Vector3d& position_ecef_m, const std::optional<Eigen::Vector3d>& velocity_ecef_mps) {
  if (!position_ecef_m.allFinite() || (velocity_ecef_mps && !velocity_ecef_mps->allFinite())) {
    return make_error(ErrorCode::kInvalidArgument, "antenna pose with non-finite values ignored");
  }
  // Between 1,000 km below and 100,000 km above the surface.
  const double radius_m = position_ecef_m.norm();
  if (radius_m < 5.3e6 || radius_m > 1.1e8) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("antenna pose {:.1f} km from the Earth's centre ignored (not near the Earth)", radius_m / 1e3));
  }
  if (velocity_ecef_mps && velocity_ecef_mps->norm() > kMaxAntennaSpeed_mps) {
    return make_error(ErrorCode::kInvalidArgument,
                      fmt::format("antenna velocity {:.3g} m/s ignored (more than 20 km/s)", velocity_ecef_mps->norm()));
  }
  return Ok{};
}

}  // namespace

Status LiveSession::set_antenna_pose_ecef(const GnssTime& time, const Eigen::Vector3d& position_ecef_m,
                                          const std::optional<Eigen::Vector3d>& velocity_ecef_mps) {
  if (auto st = check_antenna_pose(position_ecef_m, velocity_ecef_mps); !st) return st;
  impl_->pose->set(time, position_ecef_m, velocity_ecef_mps);
  return Ok{};
}

namespace {

// A pose in a world frame as ECEF position and velocity; an error for non-finite values.
Result<std::pair<Eigen::Vector3d, std::optional<Eigen::Vector3d>>> world_pose_to_ecef(
    const LocalFrame& frame, const Eigen::Vector3d& position_world_m, const std::optional<Eigen::Vector3d>& velocity_world_mps) {
  if (!position_world_m.allFinite() || (velocity_world_mps && !velocity_world_mps->allFinite())) {
    return make_error(ErrorCode::kInvalidArgument, "antenna pose with non-finite values ignored");
  }
  std::optional<Eigen::Vector3d> velocity_ecef;
  if (velocity_world_mps) velocity_ecef = frame.ecef_to_local_rotation().transpose() * *velocity_world_mps;
  return std::make_pair(frame.to_ecef(position_world_m), velocity_ecef);
}

}  // namespace

Status LiveSession::set_antenna_pose_world(const GnssTime& time, const Eigen::Vector3d& position_world_m,
                                           const std::optional<Eigen::Vector3d>& velocity_world_mps) {
  auto ecef = world_pose_to_ecef(impl_->frame, position_world_m, velocity_world_mps);
  if (!ecef) return ecef.error();
  return set_antenna_pose_ecef(time, ecef->first, ecef->second);
}

Status LiveSession::set_base_antenna_pose_ecef(const GnssTime& time, const Eigen::Vector3d& position_ecef_m,
                                               const std::optional<Eigen::Vector3d>& velocity_ecef_mps) {
  if (!impl_->base_pose) {
    return make_error(ErrorCode::kInvalidArgument, "receiver '" + receiver().name + "' has no moving base (rtk.moving_base)");
  }
  if (auto st = check_antenna_pose(position_ecef_m, velocity_ecef_mps); !st) return st;
  impl_->base_pose->set(time, position_ecef_m, velocity_ecef_mps);
  return Ok{};
}

Status LiveSession::set_base_antenna_pose_world(const GnssTime& time, const Eigen::Vector3d& position_world_m,
                                               const std::optional<Eigen::Vector3d>& velocity_world_mps) {
  auto ecef = world_pose_to_ecef(impl_->frame, position_world_m, velocity_world_mps);
  if (!ecef) return ecef.error();
  return set_base_antenna_pose_ecef(time, ecef->first, ecef->second);
}

bool LiveSession::has_moving_base() const { return impl_->base_index.has_value(); }

Status LiveSession::set_object_pose(const std::string& name, const Eigen::Isometry3d& pose_world) {
  if (!impl_->resources.world) {
    return make_error(ErrorCode::kInvalidArgument, "cannot move '" + name + "': the scenario has no world");
  }
  if (!pose_world.matrix().allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, "pose of '" + name + "' with non-finite values ignored");
  }
  if (pose_world.translation().norm() > kMaxWorldDistance_m) {
    return make_error(ErrorCode::kInvalidArgument, "pose of '" + name + "' more than 1000 km from the world origin ignored");
  }
  return sim::set_object_pose(*impl_->resources.world, name, pose_world);
}

Result<LiveEpoch> LiveSession::step(const GnssTime& tag) {
  LiveEpoch out;
  if (impl_->last_tag && !(*impl_->last_tag < tag)) {
    if (auto st = impl_->restart(); !st) return st.error();
    out.restarted = true;
  }
  impl_->last_tag = tag;
  out.pose_stale = impl_->pose->stale(tag);
  auto observations = impl_->generator->observe(tag);
  if (!observations) return observations.error();
  out.observations = std::move(*observations);
  // A moving base: its antenna observed at the same tag, its own fix its position.
  std::optional<positioning::BaseEpoch> moving;
  if (impl_->base_generator) {
    auto base_observations = impl_->base_generator->observe(tag);
    if (!base_observations) return base_observations.error().with_context("moving base");
    positioning::EpochMeasurements base_measurements = to_measurements(*base_observations);
    auto base_fix = impl_->base_solver->solve(base_measurements);
    if (!base_fix) return base_fix.error().with_context("moving base");
    if (base_fix->type != positioning::FixType::kNone) {
      moving = positioning::BaseEpoch{std::move(base_measurements), base_fix->position_ecef_m};
    }
  }
  if (impl_->rtk) {
    const positioning::BaseEpoch* base = moving ? &*moving : nullptr;
    for (auto it = impl_->base_epochs.rbegin(); !impl_->base_generator && it != impl_->base_epochs.rend(); ++it) {
      if (it->measurements.receiver_time - out.observations.receiver_time <= 1e-3) {
        base = &*it;
        break;
      }
    }
    auto fix = impl_->rtk->solve(to_measurements(out.observations), base);
    if (!fix) return fix.error();
    if (moving) positioning::add_baseline_heading(*fix);
    out.fix = std::move(*fix);
  } else if (impl_->solver) {
    auto fix = impl_->solver->solve(to_measurements(out.observations));
    if (!fix) return fix.error();
    out.fix = std::move(*fix);
  }
  return out;
}

void LiveSession::add_base_epoch(positioning::BaseEpoch base) {
  constexpr double kKept_s = 60.0;
  auto& epochs = impl_->base_epochs;
  // In time order (a stream may repeat or reorder an epoch: the later copy wins).
  while (!epochs.empty() && !(epochs.back().measurements.receiver_time < base.measurements.receiver_time)) {
    epochs.pop_back();
  }
  epochs.push_back(std::move(base));
  while (epochs.back().measurements.receiver_time - epochs.front().measurements.receiver_time > kKept_s) {
    epochs.pop_front();
  }
}

const Scenario& LiveSession::scenario() const { return impl_->scenario; }
const ScenarioResources& LiveSession::resources() const { return impl_->resources; }
const ReceiverSettings& LiveSession::receiver() const { return impl_->scenario.receivers[impl_->options.receiver_index]; }
const LocalFrame& LiveSession::world_frame() const { return impl_->frame; }
const Eigen::Vector3d& LiveSession::marker_ecef_m() const { return impl_->marker_m; }
const io::ObservationHeader& LiveSession::observation_header() const { return impl_->header; }
const RinexRecordMaker& LiveSession::rinex_records() const { return *impl_->records; }

}  // namespace skytrace::sim
