#include "skytrace/core/frames.hpp"

#include <GeographicLib/Geocentric.hpp>

#include <cmath>
#include <numbers>

namespace skytrace {
namespace {

const GeographicLib::Geocentric& wgs84() {
  static const GeographicLib::Geocentric earth = GeographicLib::Geocentric::WGS84();
  return earth;
}

constexpr double kDegToRad = std::numbers::pi / 180.0;

}  // namespace

Geodetic ecef_to_geodetic(const Eigen::Vector3d& ecef_m) {
  Geodetic g;
  wgs84().Reverse(ecef_m.x(), ecef_m.y(), ecef_m.z(), g.latitude_deg, g.longitude_deg, g.height_m);
  return g;
}

Eigen::Vector3d geodetic_to_ecef(const Geodetic& g) {
  Eigen::Vector3d ecef;
  wgs84().Forward(g.latitude_deg, g.longitude_deg, g.height_m, ecef.x(), ecef.y(), ecef.z());
  return ecef;
}

Eigen::Matrix3d ecef_to_enu_rotation(const Geodetic& origin) {
  const double lat = origin.latitude_deg * kDegToRad;
  const double lon = origin.longitude_deg * kDegToRad;
  const double sin_lat = std::sin(lat), cos_lat = std::cos(lat);
  const double sin_lon = std::sin(lon), cos_lon = std::cos(lon);
  Eigen::Matrix3d r;
  r << -sin_lon, cos_lon, 0.0,                              //
      -sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat,      //
      cos_lat * cos_lon, cos_lat * sin_lon, sin_lat;
  return r;
}

Eigen::Vector3d ecef_to_enu(const Eigen::Vector3d& ecef_m, const Geodetic& origin) {
  return ecef_to_enu_rotation(origin) * (ecef_m - geodetic_to_ecef(origin));
}

Eigen::Vector3d enu_to_ecef(const Eigen::Vector3d& enu_m, const Geodetic& origin) {
  return geodetic_to_ecef(origin) + ecef_to_enu_rotation(origin).transpose() * enu_m;
}

AzimuthElevation azimuth_elevation(const Eigen::Vector3d& observer_ecef_m, const Geodetic& observer,
                                   const Eigen::Vector3d& target_ecef_m) {
  const Eigen::Vector3d enu = ecef_to_enu_rotation(observer) * (target_ecef_m - observer_ecef_m);
  const double horizontal = std::hypot(enu.x(), enu.y());
  AzimuthElevation ae;
  ae.elevation_deg = std::atan2(enu.z(), horizontal) / kDegToRad;
  double az = std::atan2(enu.x(), enu.y()) / kDegToRad;
  if (az < 0.0) az += 360.0;
  ae.azimuth_deg = az;
  return ae;
}

Eigen::Matrix3d LocalFrame::ecef_to_local_rotation() const {
  // ENU -> local: rotate by -heading about up (the local x axis is `heading` from east).
  const double h = heading_deg * kDegToRad;
  Eigen::Matrix3d enu_to_local;
  enu_to_local << std::cos(h), std::sin(h), 0.0,  //
      -std::sin(h), std::cos(h), 0.0,               //
      0.0, 0.0, 1.0;
  return enu_to_local * ecef_to_enu_rotation(origin);
}

Eigen::Vector3d LocalFrame::to_ecef(const Eigen::Vector3d& local_m) const {
  return geodetic_to_ecef(origin) + ecef_to_local_rotation().transpose() * local_m;
}

Eigen::Vector3d LocalFrame::from_ecef(const Eigen::Vector3d& ecef_m) const {
  return ecef_to_local_rotation() * (ecef_m - geodetic_to_ecef(origin));
}

}  // namespace skytrace
