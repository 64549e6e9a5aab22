#include "ros_messages.hpp"

#include <algorithm>
#include <limits>

namespace skytrace::ros_node {
namespace {

using live::SkyStatus;

std::uint16_t navsat_service(char system) {
  switch (system) {
    case 'G':
    case 'J':  // QZSS ranges as a GPS augmentation
    case 'S':
      return sensor_msgs::NavSatStatus::SERVICE_GPS;
    case 'R': return sensor_msgs::NavSatStatus::SERVICE_GLONASS;
    case 'C': return sensor_msgs::NavSatStatus::SERVICE_COMPASS;
    case 'E': return sensor_msgs::NavSatStatus::SERVICE_GALILEO;
    default: return 0;  // NavIC: NavSatStatus has no bit for it
  }
}

std::uint8_t sky_status(SkyStatus status) {
  switch (status) {
    case SkyStatus::kTracked: return skytrace_msgs::SatelliteSky::TRACKED;
    case SkyStatus::kBelowMask: return skytrace_msgs::SatelliteSky::BELOW_MASK;
    case SkyStatus::kNoEphemeris: return skytrace_msgs::SatelliteSky::NO_EPHEMERIS;
    case SkyStatus::kNoSignal: return skytrace_msgs::SatelliteSky::NO_SIGNAL;
    case SkyStatus::kBlocked: return skytrace_msgs::SatelliteSky::BLOCKED;
    case SkyStatus::kAttenuated: return skytrace_msgs::SatelliteSky::ATTENUATED;
  }
  return skytrace_msgs::SatelliteSky::NO_SIGNAL;
}

std_msgs::ColorRGBA rgba(float r, float g, float b) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = 1.0F;
  return c;
}

geometry_msgs::Point point(const live::Vec3& v) {
  geometry_msgs::Point p;
  p.x = v[0];
  p.y = v[1];
  p.z = v[2];
  return p;
}

}  // namespace

sensor_msgs::NavSatFix to_navsat_fix(const live::FixView& fix, const std_msgs::Header& header) {
  sensor_msgs::NavSatFix msg;
  msg.header = header;
  if (fix.type == 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    msg.status.status = sensor_msgs::NavSatStatus::STATUS_NO_FIX;
    msg.latitude = msg.longitude = msg.altitude = nan;
    msg.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_UNKNOWN;
    return msg;
  }
  // GBAS_FIX: corrections of a base station in the solution (DGNSS, RTK float or fixed), as ROS
  // GNSS drivers report RTK.
  msg.status.status = fix.differential ? sensor_msgs::NavSatStatus::STATUS_GBAS_FIX : sensor_msgs::NavSatStatus::STATUS_FIX;
  for (char system : fix.systems_used) msg.status.service |= navsat_service(system);
  msg.latitude = fix.latitude_deg;
  msg.longitude = fix.longitude_deg;
  msg.altitude = fix.height_m;  // above the WGS84 ellipsoid, as NavSatFix defines it
  std::copy(fix.covariance_enu_m2.begin(), fix.covariance_enu_m2.end(), msg.position_covariance.begin());
  msg.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_KNOWN;
  return msg;
}

geometry_msgs::TwistWithCovarianceStamped to_velocity(const live::FixView& fix, const std_msgs::Header& header) {
  geometry_msgs::TwistWithCovarianceStamped msg;
  msg.header = header;
  msg.twist.twist.linear.x = fix.velocity_enu_mps[0];
  msg.twist.twist.linear.y = fix.velocity_enu_mps[1];
  msg.twist.twist.linear.z = fix.velocity_enu_mps[2];
  for (size_t r = 0; r < 3; ++r) {
    for (size_t c = 0; c < 3; ++c) msg.twist.covariance[6 * r + c] = fix.velocity_covariance_enu_m2ps2[3 * r + c];
  }
  for (size_t k = 3; k < 6; ++k) msg.twist.covariance[6 * k + k] = 1e9;  // GNSS gives no angular rate
  return msg;
}

skytrace_msgs::Observations to_observations(const live::EpochView& epoch, const std_msgs::Header& header) {
  skytrace_msgs::Observations msg;
  msg.header = header;
  msg.gps_week = static_cast<std::uint32_t>(epoch.gps_week);
  msg.gps_tow_s = epoch.gps_tow_s;
  msg.restarted = epoch.restarted;
  msg.pose_stale = epoch.pose_stale;
  for (const auto& sat : epoch.satellites) {
    if (sat.status != SkyStatus::kTracked) continue;
    const bool vegetation = sat.vegetation_path_m > 0.0;
    for (const auto& m : sat.signals) {
      skytrace_msgs::Observation o;
      o.satellite = sat.id;
      o.system = std::string(1, sat.system);
      o.prn = static_cast<std::uint16_t>(sat.prn);
      o.glonass_channel = static_cast<std::int8_t>(sat.glonass_channel);
      o.signal = m.code;
      o.carrier_frequency_hz = m.carrier_hz;
      o.pseudorange_m = m.pseudorange_m;
      o.carrier_phase_cycles = m.carrier_phase_cycles;
      o.doppler_hz = m.doppler_hz;
      o.cn0_dbhz = m.cn0_dbhz;
      o.loss_of_lock = m.loss_of_lock;
      o.half_cycle_unresolved = m.half_cycle_unresolved;
      o.lock_time_s = m.lock_time_s;
      o.azimuth_deg = sat.azimuth_deg;
      o.elevation_deg = sat.elevation_deg;
      o.los = !vegetation && !sat.nlos;
      o.nlos = sat.nlos;  // reflected or diffracted paths only (models.multipath)
      o.vegetation = vegetation;
      o.blocked = false;  // blocked satellites are not tracked (they are on /skytrace/sky)
      o.vegetation_path_m = sat.vegetation_path_m;
      o.vegetation_attenuation_db = sat.vegetation_attenuation_db;
      msg.observations.push_back(std::move(o));
    }
  }
  return msg;
}

skytrace_msgs::Sky to_sky(const live::EpochView& epoch, const std_msgs::Header& header) {
  skytrace_msgs::Sky msg;
  msg.header = header;
  msg.gps_week = static_cast<std::uint32_t>(epoch.gps_week);
  msg.gps_tow_s = epoch.gps_tow_s;
  for (const auto& sat : epoch.satellites) {
    // Satellites without a position (no ephemeris) or below the horizon are not in the sky.
    if (sat.status == SkyStatus::kNoEphemeris || sat.elevation_deg < 0.0) continue;
    skytrace_msgs::SatelliteSky s;
    s.satellite = sat.id;
    s.system = std::string(1, sat.system);
    s.prn = static_cast<std::uint16_t>(sat.prn);
    s.azimuth_deg = sat.azimuth_deg;
    s.elevation_deg = sat.elevation_deg;
    s.status = sky_status(sat.status);
    s.used_in_fix = sat.used_in_fix;
    for (const auto& m : sat.signals) s.cn0_dbhz = std::max(s.cn0_dbhz, m.cn0_dbhz);
    s.vegetation_path_m = sat.vegetation_path_m;
    s.vegetation_attenuation_db = sat.vegetation_attenuation_db;
    s.detail = sat.detail;
    msg.satellites.push_back(std::move(s));
  }
  return msg;
}

visualization_msgs::MarkerArray to_rays(const live::EpochView& epoch, const std_msgs::Header& header, double length_m) {
  visualization_msgs::Marker marker;
  marker.header = header;
  marker.ns = "skytrace_rays";
  marker.id = 0;
  marker.type = visualization_msgs::Marker::LINE_LIST;
  marker.pose.orientation.w = 1.0;
  marker.scale.x = 0.05;  // line width, m
  const geometry_msgs::Point from = point(epoch.antenna_world_m);
  for (const auto& sat : epoch.satellites) {
    if (sat.status == SkyStatus::kNoEphemeris || sat.status == SkyStatus::kNoSignal || sat.elevation_deg < 0.0) continue;
    std_msgs::ColorRGBA colour;
    switch (sat.status) {
      case SkyStatus::kTracked:
        colour = sat.vegetation_path_m > 0.0 ? rgba(0.9F, 0.8F, 0.1F) : rgba(0.1F, 0.8F, 0.2F);
        break;
      case SkyStatus::kAttenuated: colour = rgba(0.9F, 0.45F, 0.1F); break;
      case SkyStatus::kBlocked: colour = rgba(0.9F, 0.1F, 0.1F); break;
      default: colour = rgba(0.5F, 0.5F, 0.5F); break;
    }
    live::Vec3 end{};
    for (size_t i = 0; i < 3; ++i) end[i] = epoch.antenna_world_m[i] + length_m * sat.direction_world[i];
    marker.points.push_back(from);
    marker.points.push_back(point(end));
    marker.colors.push_back(colour);
    marker.colors.push_back(colour);
  }
  marker.action = marker.points.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
  visualization_msgs::MarkerArray msg;
  msg.markers.push_back(std::move(marker));
  return msg;
}

}  // namespace skytrace::ros_node
