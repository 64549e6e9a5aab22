// Single-point positioning on code and Doppler measurements, as a receiver's navigation engine
// does it: weighted least squares over every constellation with one clock bias per system,
// broadcast orbits and clocks, the same Klobuchar and Saastamoinen corrections a receiver applies,
// optional outlier rejection. Works on any measurements (skytrace's own, or a real RINEX file).
#pragma once

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::positioning {

// One signal of one satellite as the receiver measured it at the epoch.
struct SignalMeasurement {
  SatelliteId satellite;
  Signal signal;
  double pseudorange_m = 0.0;
  std::optional<double> doppler_hz;  // receiver convention: positive when approaching
  double carrier_hz = 0.0;           // for Doppler to range rate (GLONASS: the channel's frequency)
  double cn0_dbhz = 0.0;
};

struct EpochMeasurements {
  GnssTime receiver_time;  // the epoch tag (receiver clock, GPST)
  std::vector<SignalMeasurement> signals;
};

enum class FixType { kNone, kFix2D, kFix3D };

struct SatelliteUse {
  SatelliteId satellite;
  Signal signal;  // the signal whose code was used
  AzimuthElevation direction;
  double cn0_dbhz = 0.0;
  bool used = false;           // in the final solution
  bool rejected = false;       // excluded as an outlier
  double residual_m = 0.0;     // post-fit code residual
};

struct PositionFix {
  GnssTime receiver_time;
  GnssTime time;  // receiver_time corrected by the estimated clock bias (GPST)
  FixType type = FixType::kNone;
  Eigen::Vector3d position_ecef_m = Eigen::Vector3d::Zero();
  Geodetic position;
  Eigen::Vector3d velocity_ecef_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_mps = Eigen::Vector3d::Zero();
  bool velocity_valid = false;
  // Receiver clock bias (m) per system, relative to that system's time as the broadcast clocks give
  // it; the GPS one (or the first system used) is the receiver clock.
  std::map<GnssSystem, double> clock_bias_m;
  double clock_drift_mps = 0.0;
  Eigen::Matrix3d covariance_enu_m2 = Eigen::Matrix3d::Zero();  // position, east-north-up
  Eigen::Matrix3d velocity_covariance_enu_m2ps2 = Eigen::Matrix3d::Zero();
  double gdop = 0.0, pdop = 0.0, hdop = 0.0, vdop = 0.0, tdop = 0.0;
  int satellites_used = 0;
  std::vector<SatelliteUse> satellites;  // every satellite considered, used or not
  std::string message;  // why there is no fix, when type == kNone
};

struct SolverSettings {
  double elevation_mask_deg = 10.0;
  double min_cn0_dbhz = 0.0;
  bool ionosphere_klobuchar = true;    // needs GPS Klobuchar coefficients in the navigation data
  bool troposphere_saastamoinen = true;
  // Code variance: a^2 + b^2 / sin^2(el) (RTKLIB's model), m.
  double sigma_code_zenith_m = 0.3;
  double sigma_code_elevation_m = 0.3;
  bool weight_by_cn0 = false;          // scale the variance by 10^((45 - C/N0) / 10) as well
  // Outlier rejection: drop the worst satellite while the normalised residual test fails
  // (chi-square at this false-alarm probability) and enough satellites remain.
  bool reject_outliers = false;
  double outlier_probability = 1e-3;
  int max_iterations = 10;
  // Only these systems (empty: all in the measurements).
  std::vector<GnssSystem> systems;
};

// The navigation engine. Keeps the last solution as the starting point of the next epoch.
class SinglePointSolver {
 public:
  // The ephemerides must outlive the solver.
  SinglePointSolver(const orbits::BroadcastEphemerides& ephemerides, SolverSettings settings,
                    std::optional<orbits::KlobucharCoefficients> klobuchar = std::nullopt);

  // The fix of one epoch; type kNone (with a message) when it cannot be computed, an error only for
  // invalid input.
  [[nodiscard]] Result<PositionFix> solve(const EpochMeasurements& epoch);

 private:
  const orbits::BroadcastEphemerides& ephemerides_;
  SolverSettings settings_;
  std::optional<orbits::KlobucharCoefficients> klobuchar_;
  std::optional<Eigen::Vector3d> last_position_ecef_m_;
};

}  // namespace skytrace::positioning
