// The world as loaded from SDF, meshes or OpenStreetMap: named objects made of triangle meshes in
// the world frame (ENU metres of the world origin), each with a material, plus the world's
// geographic origin. Loaders fill it; the scene (Embree) is built from it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"

namespace skytrace::world {

struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices_m;   // in the object's own frame
  std::vector<Eigen::Vector3i> triangles;    // indices into vertices_m, counter-clockwise outward
};

// kSurroundings: the city beyond the model's extent (world.surroundings_height_m), which blocks
// rays but neither reflects nor diffracts.
enum class ObjectKind : std::uint8_t { kBuilding, kTree, kGround, kOther, kSurroundings };

struct WorldObject {
  std::string name;  // "model/link/collision" for SDF, "way/123" for OSM, the file for meshes
  ObjectKind kind = ObjectKind::kOther;
  Material material;
  TriangleMesh mesh;
  // Pose of the object frame in the world frame; objects that move between epochs (other robots,
  // vehicles) get new poses through the scene without rebuilding it.
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  bool is_static = true;
};

// Ties the world frame to the Earth exactly as Gazebo's <spherical_coordinates> does: the origin's
// latitude, longitude and elevation, and the heading of the world x axis counter-clockwise from east.
using GeoOrigin = LocalFrame;

struct WorldModel {
  std::string name;
  std::optional<GeoOrigin> geo_origin;
  std::vector<WorldObject> objects;
  std::vector<std::string> warnings;  // what was skipped and why (missing models, bad meshes)
  // World poses of the top-level models by name (SDF models and includes, placed mesh files): the
  // frame a moving model's new pose refers to; its objects follow it rigidly.
  std::map<std::string, Eigen::Isometry3d> model_poses;
};

// Axis-aligned bounds of all objects in the world frame (min, max); zero box when empty.
[[nodiscard]] std::pair<Eigen::Vector3d, Eigen::Vector3d> world_bounds(const WorldModel& world);

// Moves an object's vertices around their horizontal centre, the pose carrying that offset (z
// stays): float vertices stay precise however far the object is from the world origin.
void centre_mesh_horizontally(WorldObject& object);

// An object seen from above: the convex hull of its vertices on the world frame's x-y plane
// (counter-clockwise; empty for an object without vertices). For maps, not for geometry.
struct Footprint {
  ObjectKind kind = ObjectKind::kOther;
  std::vector<Eigen::Vector2d> outline_m;
};
[[nodiscard]] Footprint footprint(const WorldObject& object);

}  // namespace skytrace::world
