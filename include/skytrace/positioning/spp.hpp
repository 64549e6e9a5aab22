// Single-point positioning on code and Doppler measurements, as a receiver's navigation engine
// does it: weighted least squares over every constellation with one clock bias per system,
// broadcast orbits and clocks, the same Klobuchar and Saastamoinen corrections a receiver applies,
// optional outlier rejection. Works on any measurements (skytrace's own, or a real RINEX file).
#pragma once

#include <Eigen/Core>

#include <array>
#include <map>
#include <optional>
#include <string>
#include <string_view>
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
  // Carrier phase for relative positioning (RTK); the single-point engine does not use it.
  std::optional<double> carrier_phase_cycles;  // RINEX sign convention (that of the pseudorange)
  bool loss_of_lock = false;           // RINEX LLI bit 0: the phase arc may have slipped here
  bool half_cycle_unresolved = false;  // RINEX LLI bit 1: phase polarity not yet known
};

struct EpochMeasurements {
  GnssTime receiver_time;  // the epoch tag (receiver clock, GPST)
  std::vector<SignalMeasurement> signals;
};

// Solution types, worst to best: single-point fixes (2D, 3D), code-differential (dgnss: relative
// positioning on code alone), RTK with float or integer-fixed ambiguities.
enum class FixType { kNone, kFix2D, kFix3D, kDgnss, kRtkFloat, kRtkFixed };
// "none", "2d", "3d", "dgnss", "rtk_float", "rtk_fixed"
[[nodiscard]] std::string_view to_string(FixType type);
// A position in three dimensions (3D, differential or RTK).
[[nodiscard]] inline bool is_3d(FixType type) { return type != FixType::kNone && type != FixType::kFix2D; }

struct SatelliteUse {
  SatelliteId satellite;
  Signal signal;  // the signal whose code was used
  AzimuthElevation direction;
  double cn0_dbhz = 0.0;
  bool used = false;           // in the final solution
  bool rejected = false;       // excluded as an outlier
  double residual_m = 0.0;     // post-fit code residual
  double sigma_m = 0.0;        // a-priori standard deviation of the corrected code
  // The satellite as the fix saw it (when has_geometry): position at transmission rotated into the
  // Earth-fixed frame at reception, c (dt_sv + dt_rel) at transmission (no group delay).
  bool has_geometry = false;
  Eigen::Vector3d satellite_position_m = Eigen::Vector3d::Zero();
  double satellite_clock_m = 0.0;
  std::string note;            // why it is not used ("below the elevation mask", "no ephemeris", ...)
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
  // Weighted sum of squared post-fit residuals, its degrees of freedom (used satellites minus
  // unknowns) and the chi-square threshold of the outlier test at the settings' probability.
  double chi_square = 0.0;
  int degrees_of_freedom = 0;
  double chi_square_threshold = 0.0;
  int iterations = 0;  // Gauss-Newton iterations of the final solution
  std::vector<SatelliteUse> satellites;  // every satellite considered, used or not
  std::string message;  // why there is no fix when type == kNone; else a warning or empty
  // Relative positioning (types dgnss, rtk_float, rtk_fixed, or an RTK engine's fallback).
  struct Relative {
    double ratio = 0.0;              // ambiguity ratio test (second best / best), 0 when not tried
    int fixed_ambiguities = 0;       // double-differenced ambiguities fixed to integers
    double age_s = 0.0;              // rover time tag minus the base epoch's
    Eigen::Vector3d baseline_enu_m = Eigen::Vector3d::Zero();  // rover minus base, at the base
    bool baseline_valid = false;
    // A moving base on the same body (two antennas): the baseline's direction from the base antenna
    // to the rover antenna, clockwise from true north, and its elevation; 1-sigma from the fixed
    // baseline's covariance. Set only for moving-base solutions with integer ambiguities.
    std::optional<double> heading_deg, pitch_deg, heading_sigma_deg, pitch_sigma_deg;
  };
  std::optional<Relative> relative;
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
  // Model errors added to the code variance, as RTKLIB adds them: this fraction of the Klobuchar
  // delay, the Saastamoinen error sigma / (sin el + 0.1), the broadcast accuracy (URA/SISA).
  double ionosphere_error_fraction = 0.5;
  double troposphere_error_m = 0.3;
  bool use_broadcast_accuracy = true;
  double sigma_doppler_mps = 0.1;      // range-rate sigma at zenith, scaled like the code
  // Which signal's code to use for a satellite: the first of this list it has (a system without
  // signals in the list: the built-in order, default_signal_priority), then any other signal.
  std::vector<Signal> signal_priority;
  // Outlier rejection: drop the worst satellite while the normalised residual test fails
  // (chi-square at this false-alarm probability) and enough satellites remain.
  bool reject_outliers = false;
  double outlier_probability = 1e-3;
  int max_iterations = 10;      // per solution; from the Earth's centre twice this
  double convergence_m = 1e-4;  // Gauss-Newton stops when the position step is smaller
  // Only these systems (empty: all in the measurements).
  std::vector<GnssSystem> systems;
};

// Signals of a system in the order a single-frequency receiver prefers their code (L1 C/A, E1,
// B1I, G1 first).
[[nodiscard]] std::vector<Signal> default_signal_priority(GnssSystem system);

// Quantile of the chi-square distribution: x with P(X <= x) = probability for `dof` degrees of
// freedom (probability in (0, 1), dof >= 1).
[[nodiscard]] double chi_square_quantile(double probability, int dof);

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
  std::array<std::vector<Signal>, kAllSystems.size()> priority_;  // per system, from the settings
  // GLONASS orbits integrated from kept 60 s nodes (bit-identical to evaluate_glonass, faster).
  orbits::GlonassOrbitCache glonass_orbits_;
  // chi_square_quantile(1 - outlier_probability, dof) per degrees of freedom: the bisection is
  // costly and the settings do not change.
  std::map<int, double> chi_square_thresholds_;
};

}  // namespace skytrace::positioning
