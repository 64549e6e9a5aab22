// The reference scene (every triangle, double precision) and the checks both scenes share.
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

#include "skytrace/world/scene.hpp"

namespace skytrace::world {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::string format_vector(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << '(' << v.x() << ", " << v.y() << ", " << v.z() << ')';
  return out.str();
}

// Moller-Trumbore without back-face culling; returns the distance along the unit direction or a
// negative value for a miss. A ray parallel to the triangle's plane misses it.
double intersect_triangle(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, const Eigen::Vector3d& a,
                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a;
  const Eigen::Vector3d e2 = c - a;
  const Eigen::Vector3d p = direction.cross(e2);
  const double det = e1.dot(p);
  // |det| = |cos(angle between ray and normal)| * 2 area: parallel within 1e-12 rad counts as a miss.
  if (std::abs(det) <= 1e-12 * e1.cross(e2).norm()) return -1.0;
  const double inv_det = 1.0 / det;
  const Eigen::Vector3d s = origin - a;
  const double u = s.dot(p) * inv_det;
  if (u < 0.0 || u > 1.0) return -1.0;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = direction.dot(q) * inv_det;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  const double t = e2.dot(q) * inv_det;
  return t >= 0.0 ? t : -1.0;
}

// Generalised winding number of a closed triangle mesh around a point (Van Oosterom-Strackee solid
// angles): +-1 inside, 0 outside, whatever the ray directions; the sign follows the winding.
double winding_number(const std::vector<Eigen::Vector3d>& vertices, const std::vector<Eigen::Vector3i>& triangles,
                      const Eigen::Vector3d& point) {
  double total_sr = 0.0;
  for (const auto& tri : triangles) {
    const Eigen::Vector3d a = vertices[static_cast<std::size_t>(tri[0])] - point;
    const Eigen::Vector3d b = vertices[static_cast<std::size_t>(tri[1])] - point;
    const Eigen::Vector3d c = vertices[static_cast<std::size_t>(tri[2])] - point;
    const double la = a.norm();
    const double lb = b.norm();
    const double lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    total_sr += 2.0 * std::atan2(numerator, denominator);
  }
  return total_sr / (4.0 * std::numbers::pi);
}

// Normalises the direction of a valid ray; false for a non-finite origin or direction or a zero one.
bool normalise_ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Eigen::Vector3d& unit) {
  if (!origin.allFinite() || !direction.allFinite()) return false;
  const double norm = direction.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  unit = direction / norm;
  return true;
}

RayOutcome invalid_ray_outcome() {
  RayOutcome outcome;
  outcome.blocked = true;
  outcome.blocking_object = kInvalidRayObject;
  return outcome;
}

}  // namespace

bool triangle_is_degenerate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a;
  const Eigen::Vector3d e2 = c - a;
  const double scale_m2 = std::max({e1.squaredNorm(), e2.squaredNorm(), (c - b).squaredNorm()});
  // Twice the area against the longest edge squared: zero for repeated or collinear vertices up to
  // double rounding.
  return !(e1.cross(e2).norm() > 1e-12 * scale_m2);
}

Status validate_world_for_scene(const WorldModel& world) {
  std::set<std::string> movable_names;
  for (const auto& object : world.objects) {
    const std::string where = "world object '" + object.name + "'";
    if (!object.pose.matrix().allFinite()) {
      return make_error(ErrorCode::kInvalidArgument, where + ": pose is not finite");
    }
    if (object.material.is_vegetation() &&
        !(std::isfinite(object.material.attenuation_db_per_m) && object.material.attenuation_db_per_m >= 0.0)) {
      return make_error(ErrorCode::kInvalidArgument,
                        where + ": vegetation attenuation_db_per_m must be finite and >= 0, got " +
                            std::to_string(object.material.attenuation_db_per_m));
    }
    const auto& mesh = object.mesh;
    for (std::size_t i = 0; i < mesh.vertices_m.size(); ++i) {
      if (!mesh.vertices_m[i].allFinite()) {
        return make_error(ErrorCode::kInvalidArgument,
                          where + ": vertex " + std::to_string(i) + " is not finite " +
                              format_vector(mesh.vertices_m[i].cast<double>()));
      }
    }
    const auto vertex_count = static_cast<long long>(mesh.vertices_m.size());
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        const int index = mesh.triangles[i][k];
        if (index < 0 || index >= vertex_count) {
          return make_error(ErrorCode::kInvalidArgument,
                            where + ": triangle " + std::to_string(i) + " vertex index " + std::to_string(index) +
                                " outside 0.." + std::to_string(vertex_count - 1));
        }
      }
    }
    if (!object.is_static && !movable_names.insert(object.name).second) {
      return make_error(ErrorCode::kInvalidArgument,
                        where + ": two movable objects share this name, so poses could not be set by name");
    }
  }
  return Ok{};
}

Result<std::vector<RayOutcome>> trace_checked(const PathQuery& query, const Eigen::Vector3d& origin_m,
                                              const std::vector<Eigen::Vector3d>& directions) {
  if (!origin_m.allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, "ray origin is not finite " + format_vector(origin_m));
  }
  for (std::size_t i = 0; i < directions.size(); ++i) {
    Eigen::Vector3d unit;
    if (!normalise_ray(origin_m, directions[i], unit)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "ray direction " + std::to_string(i) + " is not a finite non-zero vector " +
                            format_vector(directions[i]));
    }
  }
  return query.trace(origin_m, directions);
}

Eigen::Vector3d enu_direction(double azimuth_deg, double elevation_deg) {
  const double azimuth_rad = azimuth_deg * std::numbers::pi / 180.0;
  const double elevation_rad = elevation_deg * std::numbers::pi / 180.0;
  return {std::sin(azimuth_rad) * std::cos(elevation_rad), std::cos(azimuth_rad) * std::cos(elevation_rad),
          std::sin(elevation_rad)};
}

Result<BruteForceScene> BruteForceScene::build(const WorldModel& world) {
  if (auto status = validate_world_for_scene(world); !status.ok()) return status.error();
  BruteForceScene scene;
  for (const auto& source : world.objects) {
    Object object;
    object.name = source.name;
    object.material = source.material;
    object.is_static = source.is_static;
    object.pose = source.pose;
    for (const auto& v : source.mesh.vertices_m) object.local_vertices_m.push_back(v.cast<double>());
    for (const auto& v : object.local_vertices_m) object.world_vertices_m.push_back(object.pose * v);
    for (const auto& tri : source.mesh.triangles) {
      const auto& w = object.world_vertices_m;
      if (triangle_is_degenerate(w[static_cast<std::size_t>(tri[0])], w[static_cast<std::size_t>(tri[1])],
                                 w[static_cast<std::size_t>(tri[2])])) {
        ++scene.stats_.degenerate_triangles;
        continue;
      }
      object.triangles.push_back(tri);
    }
    ++scene.stats_.objects;
    if (!object.is_static) ++scene.stats_.movable_objects;
    if (object.material.is_vegetation()) ++scene.stats_.vegetation_objects;
    scene.stats_.triangles += object.triangles.size();
    scene.objects_.push_back(std::move(object));
  }
  return scene;
}

Status BruteForceScene::set_object_pose(const std::string& name, const Eigen::Isometry3d& pose) {
  if (!pose.matrix().allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, "pose of world object '" + name + "' is not finite");
  }
  for (auto& object : objects_) {
    if (object.name != name || object.is_static) continue;
    object.pose = pose;
    for (std::size_t i = 0; i < object.local_vertices_m.size(); ++i) {
      object.world_vertices_m[i] = pose * object.local_vertices_m[i];
    }
    return Ok{};
  }
  const bool exists = std::any_of(objects_.begin(), objects_.end(), [&](const Object& o) { return o.name == name; });
  return make_error(exists ? ErrorCode::kInvalidArgument : ErrorCode::kNotFound,
                    exists ? "world object '" + name + "' is static and cannot be moved"
                           : "no world object named '" + name + "'");
}

SceneStats BruteForceScene::stats() const { return stats_; }

std::vector<RayOutcome> BruteForceScene::trace(const Eigen::Vector3d& origin_m,
                                               const std::vector<Eigen::Vector3d>& directions) const {
  std::vector<RayOutcome> outcomes;
  outcomes.reserve(directions.size());
  std::vector<double> crossings_m;
  for (const auto& raw_direction : directions) {
    Eigen::Vector3d direction;
    if (!normalise_ray(origin_m, raw_direction, direction)) {
      outcomes.push_back(invalid_ray_outcome());
      continue;
    }
    RayOutcome outcome;
    // First opaque hit.
    double nearest_m = kInfinity;
    const Object* nearest_object = nullptr;
    const Eigen::Vector3i* nearest_triangle = nullptr;
    for (const auto& object : objects_) {
      if (object.material.is_vegetation()) continue;
      const auto& w = object.world_vertices_m;
      for (const auto& tri : object.triangles) {
        const double t = intersect_triangle(origin_m, direction, w[static_cast<std::size_t>(tri[0])],
                                            w[static_cast<std::size_t>(tri[1])], w[static_cast<std::size_t>(tri[2])]);
        if (t >= 0.0 && t < nearest_m) {
          nearest_m = t;
          nearest_object = &object;
          nearest_triangle = &tri;
        }
      }
    }
    if (nearest_object != nullptr) {
      const auto& w = nearest_object->world_vertices_m;
      const Eigen::Vector3d& a = w[static_cast<std::size_t>((*nearest_triangle)[0])];
      const Eigen::Vector3d& b = w[static_cast<std::size_t>((*nearest_triangle)[1])];
      const Eigen::Vector3d& c = w[static_cast<std::size_t>((*nearest_triangle)[2])];
      Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
      if (normal.dot(direction) > 0.0) normal = -normal;
      outcome.blocked = true;
      outcome.blocking_distance_m = nearest_m;
      outcome.blocking_object = nearest_object->name;
      outcome.blocking_material = nearest_object->material.material_class;
      outcome.blocking_point_m = origin_m + nearest_m * direction;
      outcome.blocking_normal = normal;
    }
    // Vegetation before the opaque hit: split the ray at every crossing of the volume and keep the
    // pieces whose midpoint lies inside.
    for (const auto& object : objects_) {
      if (!object.material.is_vegetation()) continue;
      const auto& w = object.world_vertices_m;
      crossings_m.assign(1, 0.0);
      for (const auto& tri : object.triangles) {
        const double t = intersect_triangle(origin_m, direction, w[static_cast<std::size_t>(tri[0])],
                                            w[static_cast<std::size_t>(tri[1])], w[static_cast<std::size_t>(tri[2])]);
        if (t >= 0.0 && t < nearest_m) crossings_m.push_back(t);
      }
      // A bounded volume never contains the piece after its last crossing when the ray is free.
      if (std::isfinite(nearest_m)) crossings_m.push_back(nearest_m);
      std::sort(crossings_m.begin(), crossings_m.end());
      double inside_m = 0.0;
      for (std::size_t i = 0; i + 1 < crossings_m.size(); ++i) {
        const double length_m = crossings_m[i + 1] - crossings_m[i];
        if (length_m <= 0.0) continue;
        const Eigen::Vector3d middle = origin_m + 0.5 * (crossings_m[i] + crossings_m[i + 1]) * direction;
        if (std::abs(winding_number(w, object.triangles, middle)) > 0.5) inside_m += length_m;
      }
      outcome.vegetation_path_m += inside_m;
      outcome.vegetation_attenuation_db += inside_m * object.material.attenuation_db_per_m;
    }
    outcomes.push_back(std::move(outcome));
  }
  return outcomes;
}

}  // namespace skytrace::world
