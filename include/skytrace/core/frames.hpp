// Earth frames: ECEF (WGS84), geodetic latitude/longitude/height, local east-north-up.
#pragma once

#include <Eigen/Core>

#include <cmath>

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

// Coordinates in the Earth-fixed frame at reception of a vector given in the frame at
// transmission, the Earth having turned by `angle_rad` in between (Sagnac). The angle is
// microradians for a signal's flight time: there the series below equals sine and cosine to
// double rounding, at a fraction of libm's cost (the generator rotates every satellite several
// times an epoch).
[[nodiscard]] inline Eigen::Vector3d rotate_earth_frame(const Eigen::Vector3d& v, double angle_rad) {
  double c = 0.0;
  double s = 0.0;
  if (std::abs(angle_rad) <= 1e-3) {
    const double a2 = angle_rad * angle_rad;  // next terms below 1e-30 relative
    s = angle_rad * (1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0)));
    c = 1.0 - a2 / 2.0 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0));
  } else {
    c = std::cos(angle_rad);
    s = std::sin(angle_rad);
  }
  return {c * v.x() + s * v.y(), -s * v.x() + c * v.y(), v.z()};
}

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
