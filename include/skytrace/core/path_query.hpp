// What the world does to a signal: the receiver layer asks, the world layer answers. Defined in
// core so that receiver code (and its tests, with a stub world) never depends on the 3D scene.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace skytrace {

// Electrical class of an opaque surface (for reflections, multipath work) or vegetation.
enum class MaterialClass : std::uint8_t {
  kConcrete, kBrick, kGlass, kMetal, kWood, kGround, kVegetation, kUnknown,
};

struct Material {
  MaterialClass material_class = MaterialClass::kConcrete;
  // Specific attenuation of vegetation along the path (dB per metre); 0 for opaque surfaces.
  double attenuation_db_per_m = 0.0;
  [[nodiscard]] bool is_vegetation() const { return material_class == MaterialClass::kVegetation; }
};

// The fate of one ray from a point towards a direction (to infinity: a satellite).
struct RayOutcome {
  bool blocked = false;
  // When blocked: the first opaque hit.
  double blocking_distance_m = 0.0;
  std::string blocking_object;  // world object name (model/link/collision, building id)
  MaterialClass blocking_material = MaterialClass::kUnknown;
  Eigen::Vector3d blocking_point_m = Eigen::Vector3d::Zero();  // world frame
  Eigen::Vector3d blocking_normal = Eigen::Vector3d::Zero();   // unit, world frame
  // Vegetation crossed before the first opaque hit (or to infinity): total path length and the
  // attenuation it causes.
  double vegetation_path_m = 0.0;
  double vegetation_attenuation_db = 0.0;
};

// Batched line-of-sight queries in the world frame (local ENU metres of the world origin).
class PathQuery {
 public:
  virtual ~PathQuery() = default;
  // One outcome per direction (unit vectors, world frame) from `origin_m`.
  [[nodiscard]] virtual std::vector<RayOutcome> trace(const Eigen::Vector3d& origin_m,
                                                      const std::vector<Eigen::Vector3d>& directions) const = 0;
};

}  // namespace skytrace
