#include "skytrace/sim/world_setup.hpp"

#include <cmath>
#include <map>
#include <numbers>

#include "skytrace/world/loaders.hpp"
#include "skytrace/world/propagation.hpp"
#include "skytrace/world/scene.hpp"

namespace skytrace::sim {

Result<std::optional<LoadedWorld>> load_world(const Scenario& s) {
  if (!s.world.sdf) return std::optional<LoadedWorld>{};
  world::SdfLoadOptions options;
  options.model_paths = s.world.model_paths;
  if (s.world.latitude_deg && s.world.longitude_deg) {
    options.geo_origin = LocalFrame{Geodetic{*s.world.latitude_deg, *s.world.longitude_deg, s.world.elevation_m.value_or(0.0)},
                                    s.world.heading_deg.value_or(0.0)};
  }
  auto model = world::load_sdf_world(*s.world.sdf, options);
  if (!model) return model.error();
  if (!model->geo_origin) {
    return make_error(ErrorCode::kInvalidArgument,
                      s.world.sdf->string() + ": the world has no <spherical_coordinates>; give world.latitude_deg "
                                              "and world.longitude_deg (and elevation_m, heading_deg) in the scenario");
  }
  auto scene = world::EmbreeScene::build(*model);
  if (!scene) return scene.error().with_context(s.world.sdf->string());
  LoadedWorld loaded;
  loaded.name = model->name;
  loaded.frame = *model->geo_origin;
  const world::WorldSummary summary = world::summarize_world(*model);
  loaded.objects = model->objects.size();
  loaded.buildings = summary.buildings;
  loaded.trees = summary.trees;
  loaded.triangles = (*scene)->stats().triangles;
  loaded.warnings = model->warnings;
  std::shared_ptr<world::EmbreeScene> shared_scene(std::move(*scene));
  loaded.move_object = [shared_scene](const std::string& name, const Eigen::Isometry3d& pose) {
    return shared_scene->set_object_pose(name, pose);
  };
  loaded.scene = std::move(shared_scene);
  if (s.models.multipath) {
    // Reflections and diffraction off the static objects; the Embree scene still casts every ray.
    auto propagation = world::PropagationScene::build(*model, loaded.scene);
    if (!propagation) return propagation.error().with_context(s.world.sdf->string());
    loaded.scene = std::shared_ptr<const PathQuery>(std::move(*propagation));
  }
  return std::optional<LoadedWorld>(std::move(loaded));
}

Status set_object_pose(LoadedWorld& world, const std::string& name, const Eigen::Isometry3d& pose_world) {
  if (!world.move_object) return make_error(ErrorCode::kInvalidArgument, "the world '" + world.name + "' has no movable objects");
  if (auto moved = world.move_object(name, pose_world); !moved) return moved.error().with_context("world '" + world.name + "'");
  return Ok{};
}

Status check_outside_objects(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m, const std::string& receiver_name) {
  // 26 directions: the faces, edges and corners of a cube.
  std::vector<Eigen::Vector3d> directions;
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        if (x != 0 || y != 0 || z != 0) directions.push_back(Eigen::Vector3d(x, y, z).normalized());
      }
    }
  }
  const Eigen::Vector3d origin = world.frame.from_ecef(position_ecef_m);
  const auto outcomes = world.scene->trace(origin, directions);
  std::map<std::string, int> inside_hits;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const RayOutcome& o = outcomes[i];
    // Leaving a closed object, the first surface met is seen from behind.
    if (o.blocked && o.blocking_normal.dot(directions[i]) > 0.0) ++inside_hits[o.blocking_object];
  }
  for (const auto& [object, hits] : inside_hits) {
    if (hits >= 24) {
      return make_error(ErrorCode::kInvalidArgument,
                        "receiver '" + receiver_name + "' is inside the object '" + object + "' of the world (world frame " +
                            std::to_string(origin.x()) + ", " + std::to_string(origin.y()) + ", " + std::to_string(origin.z()) +
                            " m)");
    }
  }
  return Ok{};
}

Result<std::vector<double>> world_sky_mask_deg(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m,
                                               double azimuth_step_deg) {
  // The sky mask is drawn in the receiver's azimuths; the world frame's x axis is `heading` from east.
  auto mask = world::sky_mask_elevation_deg(*world.scene, world.frame.from_ecef(position_ecef_m), azimuth_step_deg);
  if (!mask || world.frame.heading_deg == 0.0) return mask;
  // Rotate: world-frame azimuths are measured from the world's y axis; shift to north.
  const auto n = static_cast<long>(mask->size());
  std::vector<double> rotated(mask->size());
  const long shift = std::lround(-world.frame.heading_deg / azimuth_step_deg);
  for (long i = 0; i < n; ++i) rotated[static_cast<size_t>(((i + shift) % n + n) % n)] = (*mask)[static_cast<size_t>(i)];
  return rotated;
}

}  // namespace skytrace::sim
