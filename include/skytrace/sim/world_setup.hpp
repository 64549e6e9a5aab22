// The scenario's 3D world: loaded, turned into a scene, tied to the Earth.
#pragma once

#include <Eigen/Core>

#include <Eigen/Geometry>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/sim/scenario.hpp"

namespace skytrace::sim {

struct LoadedWorld {
  std::string name;
  LocalFrame frame;                     // world frame on the Earth (scenario keys override the file)
  std::shared_ptr<const PathQuery> scene;
  std::size_t objects = 0, buildings = 0, trees = 0, triangles = 0;
  std::vector<std::string> warnings;    // what the loader skipped
  // Moves a movable (non-static) model of the scene; not concurrently with tracing.
  std::function<Status(const std::string& name, const Eigen::Isometry3d& pose_world)> move_object;
};

// Moves a movable model of the world (e.g. another robot) to a pose in the world frame between epochs.
[[nodiscard]] Status set_object_pose(LoadedWorld& world, const std::string& name, const Eigen::Isometry3d& pose_world);

// Loads world.sdf when the scenario has one (nullopt otherwise). Errors name the file; a world
// without <spherical_coordinates> needs world.latitude_deg and world.longitude_deg.
[[nodiscard]] Result<std::optional<LoadedWorld>> load_world(const Scenario& scenario);

// Refuses a receiver position inside a closed opaque object (nearly every ray from it leaves
// through the inside of one surface), naming the object.
[[nodiscard]] Status check_outside_objects(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m,
                                           const std::string& receiver_name);

// The obstruction elevation per azimuth (0, step, 2 step, ... degrees) seen from a point.
[[nodiscard]] Result<std::vector<double>> world_sky_mask_deg(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m,
                                                             double azimuth_step_deg);

}  // namespace skytrace::sim
