// Models that move through the world between epochs (scenario key world.moving): other robots,
// vehicles. A CSV gives the pose of the model frame in the world frame over time.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {

struct ModelPoseSample {
  GnssTime time;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // model frame origin, world frame
  double yaw_deg = 0.0;  // about the world z axis, from the world x axis
};

// Poses interpolated linearly between samples (yaw along the shorter arc); before the first sample
// the model stands at the first pose, after the last at the last.
class ModelTrajectory {
 public:
  // Reads the CSV (docs/scenario.md): an optional header line, then rows of a time (ISO 8601 in the
  // setting's time scale, or seconds since `start`), x_m, y_m, z_m and yaw_deg. Errors name the
  // file and line.
  [[nodiscard]] static Result<ModelTrajectory> read_csv(const MovingModelSetting& setting,
                                                        const GnssTime& start);
  // At least one sample, times strictly increasing, finite values.
  [[nodiscard]] static Result<ModelTrajectory> create(std::vector<ModelPoseSample> samples,
                                                      const std::string& name);

  // The model frame in the world frame at `t`: translation, then rotation about z by the yaw.
  [[nodiscard]] Eigen::Isometry3d at(const GnssTime& t) const;
  [[nodiscard]] const std::vector<ModelPoseSample>& samples() const { return samples_; }

 private:
  explicit ModelTrajectory(std::vector<ModelPoseSample> samples) : samples_(std::move(samples)) {}
  std::vector<ModelPoseSample> samples_;
};

}  // namespace skytrace::sim
