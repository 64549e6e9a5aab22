// Meshes of primitive shapes (SDF geometries, city-model prisms, ground planes) and the conversion
// between a world's frame and geodetic coordinates: the parts of the SDF loader that need no SDF
// library, shared by every loader and by the simulation's setup.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "skytrace/world/loaders.hpp"

namespace skytrace::world {

// -------------------------------------------------------------------------------------------------
// Primitives

namespace {

// Surface of revolution around z from a profile of (radius, z) points going from top to bottom;
// entries of zero radius are poles (one vertex). x and y are scaled to make ellipsoids.
TriangleMesh lathe(const std::vector<std::pair<double, double>>& profile, int segments,
                   double scale_x, double scale_y) {
  TriangleMesh mesh;
  std::vector<std::vector<int>> rings;  // vertex indices per profile entry (one for a pole)
  for (const auto& [radius, z] : profile) {
    std::vector<int> ring;
    if (radius == 0.0) {
      ring.push_back(static_cast<int>(mesh.vertices_m.size()));
      mesh.vertices_m.emplace_back(0.0F, 0.0F, static_cast<float>(z));
    } else {
      for (int j = 0; j < segments; ++j) {
        const double phi = 2.0 * std::numbers::pi * j / segments;
        ring.push_back(static_cast<int>(mesh.vertices_m.size()));
        mesh.vertices_m.emplace_back(static_cast<float>(scale_x * radius * std::cos(phi)),
                                     static_cast<float>(scale_y * radius * std::sin(phi)),
                                     static_cast<float>(z));
      }
    }
    rings.push_back(std::move(ring));
  }
  for (std::size_t k = 0; k + 1 < rings.size(); ++k) {
    const auto& upper = rings[k];
    const auto& lower = rings[k + 1];
    for (int j = 0; j < segments; ++j) {
      const auto j0 = static_cast<std::size_t>(j);
      const auto j1 = static_cast<std::size_t>((j + 1) % segments);
      if (upper.size() == 1 && lower.size() == 1) continue;
      if (upper.size() == 1) {
        mesh.triangles.emplace_back(upper[0], lower[j0], lower[j1]);
      } else if (lower.size() == 1) {
        mesh.triangles.emplace_back(upper[j0], lower[0], upper[j1]);
      } else {
        mesh.triangles.emplace_back(upper[j0], lower[j0], lower[j1]);
        mesh.triangles.emplace_back(upper[j0], lower[j1], upper[j1]);
      }
    }
  }
  return mesh;
}

}  // namespace

TriangleMesh make_box(const Eigen::Vector3d& size_m) {
  TriangleMesh mesh;
  const Eigen::Vector3d half = 0.5 * size_m;
  for (int i = 0; i < 8; ++i) {  // bit 0: +x, bit 1: +y, bit 2: +z
    mesh.vertices_m.emplace_back(static_cast<float>((i & 1) != 0 ? half.x() : -half.x()),
                                 static_cast<float>((i & 2) != 0 ? half.y() : -half.y()),
                                 static_cast<float>((i & 4) != 0 ? half.z() : -half.z()));
  }
  // Each face counter-clockwise seen from outside.
  constexpr int kQuads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3},
                                {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : kQuads) {
    mesh.triangles.emplace_back(q[0], q[1], q[2]);
    mesh.triangles.emplace_back(q[0], q[2], q[3]);
  }
  return mesh;
}

TriangleMesh make_cylinder(double radius_m, double length_m, int segments) {
  segments = std::max(segments, 3);
  const double half = 0.5 * length_m;
  return lathe({{0.0, half}, {radius_m, half}, {radius_m, -half}, {0.0, -half}}, segments, 1.0,
               1.0);
}

TriangleMesh make_ellipsoid(const Eigen::Vector3d& radii_m, int segments, int rings) {
  segments = std::max(segments, 3);
  rings = std::max(rings, 2);
  std::vector<std::pair<double, double>> profile;
  for (int k = 0; k <= rings; ++k) {
    const double theta = std::numbers::pi * k / rings;
    profile.emplace_back(k == 0 || k == rings ? 0.0 : std::sin(theta),
                         radii_m.z() * std::cos(theta));
  }
  return lathe(profile, segments, radii_m.x(), radii_m.y());
}

TriangleMesh make_capsule(double radius_m, double length_m, int segments, int rings) {
  segments = std::max(segments, 3);
  const int half_rings = std::max(rings / 2, 1);
  const double half = 0.5 * length_m;
  std::vector<std::pair<double, double>> profile;
  for (int k = 0; k <= half_rings; ++k) {  // top hemisphere, pole to equator
    const double theta = 0.5 * std::numbers::pi * k / half_rings;
    profile.emplace_back(k == 0 ? 0.0 : radius_m * std::sin(theta),
                         half + radius_m * std::cos(theta));
  }
  for (int k = 0; k <= half_rings; ++k) {  // bottom hemisphere, equator to pole
    const double theta = 0.5 * std::numbers::pi + 0.5 * std::numbers::pi * k / half_rings;
    profile.emplace_back(k == half_rings ? 0.0 : radius_m * std::sin(theta),
                         -half + radius_m * std::cos(theta));
  }
  return lathe(profile, segments, 1.0, 1.0);
}

TriangleMesh make_plane(const Eigen::Vector3d& normal, const Eigen::Vector2d& size_m) {
  const Eigen::Vector3d n =
      normal.norm() > 0.0 ? Eigen::Vector3d(normal.normalized()) : Eigen::Vector3d::UnitZ();
  Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX() - n * n.x();
  if (x_axis.norm() < 1e-6) x_axis = Eigen::Vector3d::UnitY() - n * n.y();
  x_axis.normalize();
  const Eigen::Vector3d y_axis = n.cross(x_axis);
  TriangleMesh mesh;
  for (const auto& [sx, sy] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
    mesh.vertices_m.push_back(
        (0.5 * sx * size_m.x() * x_axis + 0.5 * sy * size_m.y() * y_axis).cast<float>());
  }
  mesh.triangles.emplace_back(0, 1, 2);
  mesh.triangles.emplace_back(0, 2, 3);
  return mesh;
}

Result<TriangleMesh> make_height_grid(const std::vector<double>& heights_m, int rows, int columns,
                                      double size_x_m, double size_y_m) {
  if (rows < 2 || columns < 2 ||
      heights_m.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(columns)) {
    return make_error(ErrorCode::kInvalidArgument,
                      "height grid: need at least 2 x 2 heights, rows * columns of them");
  }
  TriangleMesh mesh;
  mesh.vertices_m.reserve(heights_m.size());
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const double x = -0.5 * size_x_m + size_x_m * c / (columns - 1);
      const double y = 0.5 * size_y_m - size_y_m * r / (rows - 1);
      mesh.vertices_m.emplace_back(
          static_cast<float>(x), static_cast<float>(y),
          static_cast<float>(
              heights_m[static_cast<std::size_t>(r) * static_cast<std::size_t>(columns) +
                        static_cast<std::size_t>(c)]));
    }
  }
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < columns; ++c) {
      const int v00 = r * columns + c;
      const int v01 = v00 + 1;
      const int v10 = v00 + columns;
      const int v11 = v10 + 1;
      mesh.triangles.emplace_back(v00, v10, v11);  // counter-clockwise seen from above
      mesh.triangles.emplace_back(v00, v11, v01);
    }
  }
  return mesh;
}

// -------------------------------------------------------------------------------------------------
// Geographic origin (gz-math SphericalCoordinates, LOCAL2: x = east cos h + north sin h)

Geodetic world_point_to_geodetic(const GeoOrigin& origin, const Eigen::Vector3d& world_m) {
  const double h = origin.heading_deg * std::numbers::pi / 180.0;
  const Eigen::Vector3d enu(world_m.x() * std::cos(h) - world_m.y() * std::sin(h),
                            world_m.x() * std::sin(h) + world_m.y() * std::cos(h), world_m.z());
  return ecef_to_geodetic(enu_to_ecef(enu, origin.origin));
}

Eigen::Vector3d geodetic_to_world_point(const GeoOrigin& origin, const Geodetic& point) {
  const double h = origin.heading_deg * std::numbers::pi / 180.0;
  const Eigen::Vector3d enu = ecef_to_enu(geodetic_to_ecef(point), origin.origin);
  return {enu.x() * std::cos(h) + enu.y() * std::sin(h),
          -enu.x() * std::sin(h) + enu.y() * std::cos(h), enu.z()};
}

}  // namespace skytrace::world
