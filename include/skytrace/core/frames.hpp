// Earth frames: ECEF (WGS84), geodetic latitude/longitude/height, local east-north-up.
#pragma once

#include <Eigen/Core>

namespace skytrace {

struct Geodetic {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;  // above the WGS84 ellipsoid
};

struct AzimuthElevation {
  double azimuth_deg = 0.0;    // clockwise from north, [0, 360)
  double elevation_deg = 0.0;  // above the local horizon (ellipsoid normal)
};

[[nodiscard]] Geodetic ecef_to_geodetic(const Eigen::Vector3d& ecef_m);
[[nodiscard]] Eigen::Vector3d geodetic_to_ecef(const Geodetic& geodetic);

// Rotation taking ECEF vectors into the local east-north-up frame at the given point.
[[nodiscard]] Eigen::Matrix3d ecef_to_enu_rotation(const Geodetic& origin);
[[nodiscard]] Eigen::Vector3d ecef_to_enu(const Eigen::Vector3d& ecef_m, const Geodetic& origin);
[[nodiscard]] Eigen::Vector3d enu_to_ecef(const Eigen::Vector3d& enu_m, const Geodetic& origin);

// Direction of `target` seen from `observer`, both in ECEF.
[[nodiscard]] AzimuthElevation azimuth_elevation(const Eigen::Vector3d& observer_ecef_m,
                                                 const Geodetic& observer,
                                                 const Eigen::Vector3d& target_ecef_m);

// A local Cartesian frame tied to the Earth the way Gazebo ties a world to it
// (<spherical_coordinates>): origin at a geodetic point, z up along the ellipsoid normal, and the
// x axis `heading_deg` counter-clockwise from east (0: x east, y north).
struct LocalFrame {
  Geodetic origin;
  double heading_deg = 0.0;

  // Rotation from ECEF vectors to local vectors.
  [[nodiscard]] Eigen::Matrix3d ecef_to_local_rotation() const;
  [[nodiscard]] Eigen::Vector3d to_ecef(const Eigen::Vector3d& local_m) const;
  [[nodiscard]] Eigen::Vector3d from_ecef(const Eigen::Vector3d& ecef_m) const;
};

}  // namespace skytrace
