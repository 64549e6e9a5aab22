// Stage 1 (geometry and light time) against a direct light-time iteration on an analytic orbit,
// the first-order Sagnac formula, a numerical range rate, and the clock moved to transmission.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>

#include "skytrace/core/constants.hpp"
#include "skytrace/receiver/stages/geometry.hpp"

namespace skytrace::receiver::stages {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;
constexpr double kOmega = constants::kEarthRotationRateGps_radps;

// A circular Keplerian orbit (radius 26560 km, inclination 55 deg) seen in the Earth-fixed frame.
struct CircularOrbit {
  double radius_m = 26560e3;
  double inclination_rad = 55.0 * M_PI / 180.0;
  double node_rad = 0.3;
  double phase_rad = 1.1;
  [[nodiscard]] double mean_motion() const { return std::sqrt(constants::kGmGps_m3ps2 / std::pow(radius_m, 3)); }
  [[nodiscard]] Eigen::Vector3d inertial(double t_s) const {
    const double u = phase_rad + mean_motion() * t_s;
    const Eigen::Vector3d in_plane(radius_m * std::cos(u), radius_m * std::sin(u), 0.0);
    return Eigen::AngleAxisd(node_rad, Eigen::Vector3d::UnitZ()) *
           (Eigen::AngleAxisd(inclination_rad, Eigen::Vector3d::UnitX()) * in_plane);
  }
  // Earth-fixed position and velocity at t (the Earth turned by omega t since t = 0).
  [[nodiscard]] Eigen::Vector3d position(double t_s) const {
    return Eigen::AngleAxisd(-kOmega * t_s, Eigen::Vector3d::UnitZ()) * inertial(t_s);
  }
  [[nodiscard]] Eigen::Vector3d velocity(double t_s) const {
    const double h = 1e-3;
    return (position(t_s + h) - position(t_s - h)) / (2.0 * h);
  }
};

// Direct iteration: the position at t_rx - tau, in the frame at reception (the frame turned by
// omega tau meanwhile: coordinates rotate by -omega tau), exact orbit every time.
double direct_range_m(const CircularOrbit& orbit, double t_rx_s, const Eigen::Vector3d& receiver_m) {
  double tau_s = 0.07;
  double range_m = 0.0;
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d p =
        Eigen::AngleAxisd(-kOmega * tau_s, Eigen::Vector3d::UnitZ()) * orbit.position(t_rx_s - tau_s);
    range_m = (p - receiver_m).norm();
    tau_s = range_m / kC;
  }
  return range_m;
}

orbits::SatelliteState state_at(const CircularOrbit& orbit, double t_s) {
  orbits::SatelliteState s;
  s.position_m = orbit.position(t_s);
  s.velocity_mps = orbit.velocity(t_s);
  s.clock_bias_s = 1e-4;
  s.clock_drift_s_per_s = 2e-11;
  s.relativistic_s = 1e-8;
  s.relativistic_drift_s_per_s = 1e-12;
  return s;
}

const Eigen::Vector3d kReceiver_m(3582105.291, 532589.7313, 5232754.8054);

TEST(StageGeometry, LightTimeMatchesDirectIteration) {
  const CircularOrbit orbit;
  const double t_rx_s = 1000.0;
  for (const double guess_s : {0.075, 0.0683}) {  // first epoch, then a close guess
    const LightTime lt = solve_light_time(state_at(orbit, t_rx_s - guess_s), guess_s, kReceiver_m,
                                          Eigen::Vector3d::Zero());
    const double expected_m = direct_range_m(orbit, t_rx_s, kReceiver_m);
    EXPECT_NEAR(lt.range_m, expected_m, 1e-4) << "guess " << guess_s;
    EXPECT_NEAR(lt.flight_time_s, expected_m / kC, 1e-12);
    EXPECT_NEAR((lt.position_m - kReceiver_m).norm(), lt.range_m, 1e-6);
    EXPECT_NEAR(lt.line_of_sight.norm(), 1.0, 1e-12);
  }
}

TEST(StageGeometry, SagnacTermHasTheFirstOrderMagnitude) {
  const CircularOrbit orbit;
  const double t_rx_s = 1000.0;
  const LightTime lt = solve_light_time(state_at(orbit, t_rx_s - 0.075), 0.075, kReceiver_m, Eigen::Vector3d::Zero());
  // The same transmission instant without the Earth's rotation during the flight.
  const Eigen::Vector3d unrotated = orbit.position(t_rx_s - lt.flight_time_s);
  const double sagnac_m = lt.range_m - (unrotated - kReceiver_m).norm();
  const double expected_m = kOmega / kC * (unrotated.x() * kReceiver_m.y() - unrotated.y() * kReceiver_m.x());
  EXPECT_GT(std::abs(expected_m), 1.0);  // a geometry where the term is large (tens of metres at most)
  EXPECT_LT(std::abs(expected_m), 40.0);
  EXPECT_NEAR(sagnac_m, expected_m, 5e-3);
}

TEST(StageGeometry, RangeRateIsTheDerivativeOfTheRange) {
  const CircularOrbit orbit;
  const Eigen::Vector3d receiver_velocity_mps(12.0, -30.0, 5.0);
  const double t_s = 2000.0;
  const double h = 0.01;
  auto range_at = [&](double t) {
    return solve_light_time(state_at(orbit, t - 0.075), 0.075, kReceiver_m + receiver_velocity_mps * (t - t_s),
                            receiver_velocity_mps)
        .range_m;
  };
  const LightTime lt = solve_light_time(state_at(orbit, t_s - 0.075), 0.075, kReceiver_m, receiver_velocity_mps);
  const double numerical_mps = (range_at(t_s + h) - range_at(t_s - h)) / (2.0 * h);
  EXPECT_GT(std::abs(lt.range_rate_mps), 10.0);
  EXPECT_NEAR(lt.range_rate_mps, numerical_mps, 2e-4);
}

TEST(StageGeometry, ClockAndRelativisticTermsMoveToTransmission) {
  const CircularOrbit orbit;
  const double guess_s = 0.075;
  const orbits::SatelliteState at_guess = state_at(orbit, 500.0 - guess_s);
  const LightTime lt = solve_light_time(at_guess, guess_s, kReceiver_m, Eigen::Vector3d::Zero());
  const double step_s = guess_s - lt.flight_time_s;  // transmission minus evaluation
  EXPECT_GT(std::abs(step_s), 1e-4);
  EXPECT_DOUBLE_EQ(lt.state.clock_bias_s, at_guess.clock_bias_s + at_guess.clock_drift_s_per_s * step_s);
  EXPECT_DOUBLE_EQ(lt.state.relativistic_s, at_guess.relativistic_s + at_guess.relativistic_drift_s_per_s * step_s);
  // The velocity at transmission, rotated into the frame at reception.
  const Eigen::Vector3d expected = Eigen::AngleAxisd(-kOmega * lt.flight_time_s, Eigen::Vector3d::UnitZ()) *
                                   orbit.velocity(500.0 - lt.flight_time_s);
  EXPECT_LT((lt.velocity_mps - expected).norm(), 1e-3);
}

TEST(StageGeometry, LocalDirection) {
  EXPECT_DOUBLE_EQ(local_direction(Eigen::Vector3d(0, 0, 1)).elevation_deg, 90.0);
  EXPECT_DOUBLE_EQ(local_direction(Eigen::Vector3d(0, 1, 0)).azimuth_deg, 0.0);
  EXPECT_DOUBLE_EQ(local_direction(Eigen::Vector3d(1, 0, 0)).azimuth_deg, 90.0);
  EXPECT_DOUBLE_EQ(local_direction(Eigen::Vector3d(-1, 0, 0)).azimuth_deg, 270.0);
  EXPECT_NEAR(local_direction(Eigen::Vector3d(1, 0, 1)).elevation_deg, 45.0, 1e-12);
}

}  // namespace
}  // namespace skytrace::receiver::stages
