#include "skytrace/receiver/stages/geometry.hpp"

#include <Eigen/Geometry>

namespace skytrace::receiver::stages {

namespace {
constexpr double kC = constants::kSpeedOfLight_mps;
}  // namespace

LightTime solve_light_time(const orbits::SatelliteState& at_guess, double guess_s, const Eigen::Vector3d& receiver_m,
                           const Eigen::Vector3d& receiver_velocity_mps) {
  LightTime out;
  out.state = at_guess;
  const Eigen::Vector3d& r0 = at_guess.position_m;
  const Eigen::Vector3d& v0 = at_guess.velocity_mps;
  // Acceleration in the Earth-fixed frame: gravity, Coriolis and centrifugal terms.
  const Eigen::Vector3d omega(0.0, 0.0, kEarthRotation_radps);
  const Eigen::Vector3d a0 = -constants::kGmGps_m3ps2 / std::pow(r0.norm(), 3) * r0 - 2.0 * omega.cross(v0) -
                             omega.cross(omega.cross(r0));
  double flight_time_s = guess_s;
  Eigen::Vector3d sat_position_m;
  double range_m = 0.0;
  double step_s = 0.0;  // transmission time minus evaluation time
  // Four passes at most; once the flight time repeats exactly, further passes would repeat too.
  for (int iteration = 0; iteration < 4; ++iteration) {
    step_s = guess_s - flight_time_s;
    const Eigen::Vector3d r = r0 + v0 * step_s + 0.5 * a0 * step_s * step_s;
    sat_position_m = rotate_earth_frame(r, kEarthRotation_radps * flight_time_s);
    range_m = (sat_position_m - receiver_m).norm();
    const double previous_s = flight_time_s;
    flight_time_s = range_m / kC;
    if (flight_time_s == previous_s) break;
  }
  step_s = guess_s - flight_time_s;
  out.state.clock_bias_s += at_guess.clock_drift_s_per_s * step_s;
  out.state.relativistic_s += at_guess.relativistic_drift_s_per_s * step_s;
  out.state.velocity_mps = v0 + a0 * step_s;
  const double rotation_rad = kEarthRotation_radps * flight_time_s;
  const Eigen::Vector3d sat_velocity_mps = rotate_earth_frame(out.state.velocity_mps, rotation_rad);
  const Eigen::Vector3d line_of_sight = (sat_position_m - receiver_m) / range_m;
  // d(range)/dt with the flight time changing too: the satellite term is scaled by (1 - d tau/dt)
  // and the Sagnac rotation angle grows with d tau/dt (d R(theta) r / d theta = (y, -x, 0)).
  const double sat_term = line_of_sight.dot(sat_velocity_mps);
  const Eigen::Vector3d rotation_derivative(sat_position_m.y(), -sat_position_m.x(), 0.0);
  const double sagnac_term = kEarthRotation_radps * line_of_sight.dot(rotation_derivative);
  out.range_rate_mps = (sat_term - line_of_sight.dot(receiver_velocity_mps)) / (1.0 + (sat_term - sagnac_term) / kC);
  out.position_m = sat_position_m;
  out.velocity_mps = sat_velocity_mps;
  out.line_of_sight = line_of_sight;
  out.flight_time_s = flight_time_s;
  out.range_m = range_m;
  return out;
}

}  // namespace skytrace::receiver::stages
