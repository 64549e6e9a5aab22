// Stage 1 of the observation model: geometry and light time. From the satellite's state near the
// transmission time (its reference record or the precise products) to the state at transmission,
// rotated into the Earth-fixed frame at reception (Sagnac), the geometric range and its rate, the
// direction seen by the receiver, and the satellite clock and relativistic terms at transmission.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <numbers>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/receiver/antex.hpp"

namespace skytrace::receiver::stages {

// Sagnac: the Earth turns during the signal's flight (WGS84 rate for every system: it is physics,
// not a parameter of any one navigation message).
inline constexpr double kEarthRotation_radps = constants::kEarthRotationRateGps_radps;

// The flight time assumed before a satellite's first epoch (s).
inline constexpr double kFirstFlightTimeGuess_s = 0.075;

struct LightTime {
  // The satellite state at transmission: clock, relativistic term and velocity moved from the
  // evaluation instant to the transmission (Earth-fixed frame of transmission); the position is
  // left at the evaluation instant (position_m below is the one at transmission).
  orbits::SatelliteState state;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();     // at transmission, frame at reception
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();   // at transmission, frame at reception
  Eigen::Vector3d line_of_sight = Eigen::Vector3d::Zero();  // unit, receiver to satellite (ECEF)
  double flight_time_s = 0.0;
  double range_m = 0.0;         // geometric, transmission to reception, Sagnac included
  double range_rate_mps = 0.0;  // d range / d reception time, the flight time changing too
};

// Light-time solution for a receiver at `receiver_m` (velocity `receiver_velocity_mps`, ECEF, at
// the true reception time) from the satellite's state `at_guess` evaluated `guess_s` before the
// reception time (a guess of the flight time, e.g. the last epoch's). The record is evaluated once;
// the iteration moves along the second-order expansion of the orbit and clock around it: the step
// is microseconds after the first epoch, and below 12 ms even then, where the expansion is exact to
// 1e-10 m.
[[nodiscard]] LightTime solve_light_time(const orbits::SatelliteState& at_guess, double guess_s,
                                         const Eigen::Vector3d& receiver_m,
                                         const Eigen::Vector3d& receiver_velocity_mps);

// Azimuth (clockwise from north, [0, 360)) and elevation of a local east-north-up vector.
[[nodiscard]] inline AzimuthElevation local_direction(const Eigen::Vector3d& enu) {
  AzimuthElevation d;
  d.elevation_deg = std::atan2(enu.z(), std::hypot(enu.x(), enu.y())) * 180.0 / std::numbers::pi;
  const double azimuth_deg = std::atan2(enu.x(), enu.y()) * 180.0 / std::numbers::pi;
  d.azimuth_deg = azimuth_deg < 0.0 ? azimuth_deg + 360.0 : azimuth_deg;
  return d;
}

// The receiver-side geometric term of a signal: its frequency's phase centre (ANTEX PCO and PCV)
// seen from the direction of the satellite at the antenna reference point (0 without a model).
// The geometric range stays the one to the reference point; this term goes into the observables.
[[nodiscard]] inline double antenna_phase_centre_m(const AntennaPhaseCentre* model, const Signal& signal,
                                                   const AzimuthElevation& direction) {
  return model != nullptr ? model->range_correction_m(signal, direction) : 0.0;
}

}  // namespace skytrace::receiver::stages
