#include "skytrace/world/world_model.hpp"

#include <limits>

namespace skytrace::world {

std::pair<Eigen::Vector3d, Eigen::Vector3d> world_bounds(const WorldModel& world) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d high = -low;
  bool any = false;
  for (const auto& object : world.objects) {
    for (const auto& v : object.mesh.vertices_m) {
      const Eigen::Vector3d p = object.pose * v.cast<double>();
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
      any = true;
    }
  }
  if (!any) return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  return {low, high};
}

}  // namespace skytrace::world
