// The scenario's 3D world: loaded, turned into a scene, tied to the Earth.
#pragma once

#include <Eigen/Core>

#include <Eigen/Geometry>

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/sim/moving_models.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/world/world_model.hpp"

namespace skytrace::sim {

struct LoadedWorld {
  std::string name;
  LocalFrame frame;                     // world frame on the Earth (scenario keys override the file)
  std::shared_ptr<const PathQuery> scene;
  std::size_t objects = 0, buildings = 0, trees = 0, triangles = 0;
  std::vector<std::string> warnings;    // what the loader skipped
  // Every object but the ground seen from above (world frame x-y), for the report's map.
  std::vector<world::Footprint> footprints;
  // Bounds of every object but the ground in the world frame (min, max; zero without objects).
  Eigen::Vector3d low_m = Eigen::Vector3d::Zero(), high_m = Eigen::Vector3d::Zero();
  bool has_objects = false;
  // Moves a movable (non-static) object of the scene; not concurrently with tracing.
  std::function<Status(const std::string& name, const Eigen::Isometry3d& pose_world)> move_object;

  // Movable models (non-static SDF models, models listed in world.moving): their objects with
  // their poses in the model frame, so that a model moves as one rigid body.
  struct ModelPart {
    std::string object;
    Eigen::Isometry3d pose_in_model = Eigen::Isometry3d::Identity();
  };
  std::map<std::string, std::vector<ModelPart>> movable_models;
  // world.moving: each model with its trajectory (moved by move_models_to).
  std::vector<std::pair<std::string, ModelTrajectory>> moving;
};

// Moves a movable model (its frame: the model's <pose>, or a mesh's placement) or a single movable
// object (by its object name) to a pose in the world frame, between epochs.
[[nodiscard]] Status set_object_pose(LoadedWorld& world, const std::string& name, const Eigen::Isometry3d& pose_world);

// Puts every model of world.moving where its trajectory says at `time` (an epoch's time tag).
[[nodiscard]] Status move_models_to(LoadedWorld& world, const GnssTime& time);

// Loads the scenario's world (nullopt without one): world.sdf, world.osm and world.meshes in one
// world frame, with world.materials rules and world.moving trajectories. The frame is the scenario's
// origin keys, else the SDF's <spherical_coordinates>, else the OSM extract's centre. Errors name the
// file (and line) or the key.
[[nodiscard]] Result<std::optional<LoadedWorld>> load_world(const Scenario& scenario);

// Refuses a receiver position inside a closed opaque object (nearly every ray from it leaves
// through the inside of one surface), naming the object.
[[nodiscard]] Status check_outside_objects(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m,
                                           const std::string& receiver_name);

// The obstruction elevation per azimuth (0, step, 2 step, ... degrees) seen from a point.
[[nodiscard]] Result<std::vector<double>> world_sky_mask_deg(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m,
                                                             double azimuth_step_deg);

}  // namespace skytrace::sim
