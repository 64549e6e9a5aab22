// Receiver trajectories: a static point, or a CSV of time and position interpolated with C1
// continuity (cubic Hermite with Catmull-Rom tangents) so that velocity is continuous.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include "skytrace/core/frames.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {

using StaticPosition = receiver::StaticPosition;

struct TrajectorySample {
  GnssTime time;
  Eigen::Vector3d position_m;  // ECEF
};

class InterpolatedTrajectory final : public receiver::KinematicsSource {
 public:
  // At least two samples in increasing time.
  [[nodiscard]] static Result<std::shared_ptr<InterpolatedTrajectory>> create(std::vector<TrajectorySample> samples,
                                                                              std::string name);
  [[nodiscard]] Result<receiver::Kinematics> at(const GnssTime& t) const override;
  [[nodiscard]] const std::vector<TrajectorySample>& samples() const { return samples_; }

 private:
  InterpolatedTrajectory(std::vector<TrajectorySample> samples, std::string name)
      : samples_(std::move(samples)), name_(std::move(name)) {}
  std::vector<TrajectorySample> samples_;
  std::string name_;
};

// Converts a position setting to ECEF; world ENU needs the world origin (a geodetic point and the
// heading of the world's x axis from east, counter-clockwise, as Gazebo defines it).
using WorldOrigin = LocalFrame;
[[nodiscard]] Eigen::Vector3d world_enu_to_ecef(const Eigen::Vector3d& world_m, const WorldOrigin& origin);
[[nodiscard]] Result<Eigen::Vector3d> position_to_ecef(const PositionSetting& position,
                                                       const std::optional<WorldOrigin>& world);

// Reads a trajectory CSV (see docs/scenario.md): a header line naming the columns, then rows of a
// time (ISO 8601 in the setting's time scale, or seconds since `start`) and three coordinates.
// Consecutive samples may be at most kMaxAntennaSpeed_mps apart.
[[nodiscard]] Result<std::vector<TrajectorySample>> read_trajectory_csv(const TrajectorySetting& setting,
                                                                         const GnssTime& start,
                                                                         const std::optional<WorldOrigin>& world);

}  // namespace skytrace::sim
