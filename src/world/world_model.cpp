#include "skytrace/world/world_model.hpp"

#include <algorithm>
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

void centre_mesh_horizontally(WorldObject& object) {
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f high = -low;
  for (const auto& v : object.mesh.vertices_m) {
    low = low.cwiseMin(v);
    high = high.cwiseMax(v);
  }
  if (!low.allFinite() || !high.allFinite()) return;
  Eigen::Vector3f centre = 0.5F * (low + high);
  centre.z() = 0.0F;
  for (auto& v : object.mesh.vertices_m) v -= centre;
  object.pose = Eigen::Translation3d(centre.cast<double>()) * object.pose;
}

Footprint footprint(const WorldObject& object) {
  Footprint f;
  f.kind = object.kind;
  std::vector<Eigen::Vector2d> points;
  points.reserve(object.mesh.vertices_m.size());
  for (const auto& v : object.mesh.vertices_m) {
    const Eigen::Vector3d p = object.pose * v.cast<double>();
    if (p.allFinite()) points.emplace_back(p.x(), p.y());
  }
  std::sort(points.begin(), points.end(),
            [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() < 3) {
    f.outline_m = points;
    return f;
  }
  // Andrew's monotone chain: lower hull, then upper hull.
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  size_t k = 0;
  for (const auto& p : points) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
    hull[k++] = p;
  }
  for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);  // the last point repeats the first
  f.outline_m = std::move(hull);
  return f;
}

}  // namespace skytrace::world
