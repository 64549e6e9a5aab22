// Real-time kinematic positioning: a rover's position relative to a base of known position from
// double-differenced carrier phase and code, by an extended Kalman filter over the position
// (optionally velocity) and single-differenced float ambiguities, with integer ambiguity
// resolution by LAMBDA (decorrelation + MLAMBDA search) and the ratio test. The engine takes a base
// epoch of observations and the base position, whatever their source (a receiver of the same
// scenario, a RINEX file; later an RTCM stream).
#pragma once

#include <Eigen/Core>

#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/positioning/spp.hpp"

namespace skytrace::positioning {

// ---- Integer least squares (LAMBDA) -----------------------------------------------------------

// The `candidates` best integer vectors z minimising (z - a)^T Q^-1 (z - a), best first, with
// their squared distances. Decorrelation by integer Gauss transformations and permutations
// (Teunissen 1995, de Jonge & Tiberius 1996), search by MLAMBDA's shrinking ellipsoid (Chang, Yang
// & Zhou 2005). Error when Q is not positive definite or the sizes disagree.
struct IntegerSolution {
  std::vector<Eigen::VectorXd> candidates;  // integer-valued
  std::vector<double> squared_norms;        // (z - a)^T Q^-1 (z - a), ascending
  // squared_norms[1] / squared_norms[0] (infinity when the best fits exactly; 0 with one candidate)
  [[nodiscard]] double ratio() const;
};
[[nodiscard]] Result<IntegerSolution> lambda_search(const Eigen::VectorXd& float_ambiguities,
                                                    const Eigen::MatrixXd& covariance, int candidates = 2);

// ---- Double differences -----------------------------------------------------------------------

// One single-differenced (rover minus base) observation of a satellite's signal on one band.
struct SingleDifference {
  SatelliteId satellite;
  char band = '1';             // RINEX band digit ('1' L1/E1/G1, '2' L2, '5' L5/E5a, '7' E5b ...)
  double wavelength_m = 0.0;
  double value_m = 0.0;        // observed minus modelled geometry, rover minus base
  double variance_m2 = 0.0;
  double elevation_deg = 0.0;  // at the rover
};

// Double differences of single differences within one group (one system and band): every
// satellite minus the reference, the satellite of highest elevation (`reference_by_variance`: of
// least variance). `difference` is the operator
// D (rows: double differences, columns: the group's single differences), so that the double
// differences are D y and their covariance D diag(variances) D^T.
struct DoubleDifferenceGroup {
  size_t reference = 0;          // index of the reference single difference
  std::vector<size_t> others;    // the other single differences, one double difference each
  Eigen::MatrixXd difference;    // others.size() x single differences
  Eigen::VectorXd values_m;      // D y
  Eigen::MatrixXd covariance_m2; // D diag(variance) D^T
};
[[nodiscard]] DoubleDifferenceGroup form_double_differences(const std::vector<SingleDifference>& group,
                                                            bool reference_by_variance = false);

// ---- Cycle slips -----------------------------------------------------------------------------

struct SlipSettings {
  double geometry_free_m = 0.05;  // jump of L1 - L2 (m) between epochs; 0: off
  double doppler_m = 1.0;  // phase change minus Doppler prediction, common part removed (m); 0: off
  double max_gap_s = 60.0;        // a longer gap starts a new arc
};

// Slip detection on one receiver's phases, epoch by epoch: the LLI flag, a jump of the
// geometry-free combination of two bands, a phase change the Doppler does not predict (after
// removing what all signals share: receiver clock jumps).
class SlipDetector {
 public:
  explicit SlipDetector(SlipSettings settings = {}) : settings_(settings) {}
  // Keys (satellite, band) of the epoch's phases that start a new arc (first sighting included).
  [[nodiscard]] std::vector<std::pair<SatelliteId, char>> update(const EpochMeasurements& epoch);

 private:
  struct Last {
    GnssTime time;
    double phase_cycles = 0.0;
    std::optional<double> doppler_hz;
    double wavelength_m = 0.0;
  };
  SlipSettings settings_;
  std::map<std::pair<SatelliteId, char>, Last> last_;
  std::map<SatelliteId, std::pair<GnssTime, double>> last_geometry_free_m_;
};

// ---- The engine ------------------------------------------------------------------------------

enum class AmbiguityMode {
  kFloat,       // no integer resolution
  kContinuous,  // integers resolved every epoch, the float filter left as is
  kFixAndHold,  // after a fix the filter is constrained to the fixed double differences
};
enum class RtkDynamics { kStatic, kKinematic };

struct RtkSettings {
  RtkDynamics dynamics = RtkDynamics::kKinematic;
  bool estimate_velocity = false;  // kinematic: constant-velocity states (else position reset each epoch)
  AmbiguityMode ambiguity_mode = AmbiguityMode::kFixAndHold;
  double elevation_mask_deg = 15.0;
  double min_cn0_dbhz = 0.0;
  double ratio_threshold = 3.0;
  int min_fixed_ambiguities = 4;
  int max_partial_drops = 6;       // satellites left out, lowest first, when the full set fails
  // C/N0 weighting (0: off, elevation only, as RTKLIB): below this C/N0 a signal's variance grows
  // as 10^((cn0_weighting_dbhz - C/N0) / 10) (tracking jitter goes as 1 / (C/N0)), the reference
  // of each double-difference group is its signal of least variance, and the partial sets leave
  // the satellites of largest variance out first. Faded or reflected signals then weigh little.
  double cn0_weighting_dbhz = 0.0;
  // GLONASS FDMA: receivers of different make have inter-frequency biases, so its ambiguities
  // stay float unless both receivers are known to be of one design.
  bool fix_glonass = false;
  // Phase sigma a^2 + b^2 / sin^2(el) per receiver; code sigma this times code_phase_ratio.
  double sigma_phase_zenith_m = 0.003;
  double sigma_phase_elevation_m = 0.003;
  double code_phase_ratio = 100.0;
  // Process noise.
  double position_noise_mps = 30.0;           // kinematic without velocity: per sqrt(s) (reset-like)
  double acceleration_noise_mps2 = 1.0;       // kinematic with velocity: white acceleration, per sqrt(s)
  double ambiguity_noise_cycles = 1e-4;       // per sqrt(s)
  double initial_ambiguity_sigma_cycles = 30.0;
  double hold_sigma_cycles = 0.001;           // fix-and-hold pseudo-observation
  int min_hold_epochs = 5;                    // consecutive fixed epochs before holding
  SlipSettings slips;
  double max_age_s = 30.0;                    // older base epochs are not used
  // The given base position must agree with the base's own single-point fix within this: a base
  // position kilometres off would otherwise give a wrong rover position with a confident fix.
  double max_base_position_error_m = 100.0;
  int max_outage_epochs = 5;                  // an ambiguity not observed for more epochs is dropped
  double max_innovation_m = 30.0;             // larger double-difference innovations are rejected
  std::vector<GnssSystem> systems;            // empty: all but SBAS
  SolverSettings single_point;                // both receivers' single-point fixes
};

// A base station's epoch: its observations and the position of its antenna reference point.
struct BaseEpoch {
  EpochMeasurements measurements;
  Eigen::Vector3d position_ecef_m = Eigen::Vector3d::Zero();
};

class RtkEngine {
 public:
  // The ephemerides must outlive the engine.
  RtkEngine(const orbits::BroadcastEphemerides& ephemerides, RtkSettings settings,
            std::optional<orbits::KlobucharCoefficients> klobuchar = std::nullopt);

  // The rover's solution at its epoch: rtk_fixed / rtk_float / dgnss with `relative` set; the
  // rover's single-point fix (3d) with a message when the base is missing, too old, without
  // common satellites or at a position its own observations contradict; none when the rover has
  // no fix. An error only for invalid input.
  [[nodiscard]] Result<PositionFix> solve(const EpochMeasurements& rover, const BaseEpoch* base);

 private:
  using Key = std::pair<SatelliteId, char>;  // satellite, band
  struct Ambiguity {
    Eigen::Index index = 0;  // into the state
    int missed_epochs = 0;  // consecutive epochs without the ambiguity's phase
    bool fixable = true;
  };
  void reset_filter();
  void add_state(const Key& key, double value_cycles, double variance_cycles2);
  void remove_states(const std::vector<Key>& keys);

  RtkSettings settings_;
  SinglePointSolver rover_solver_;
  SinglePointSolver base_solver_;
  SlipDetector rover_slips_;
  SlipDetector base_slips_;
  // State: position (3), velocity (3, with estimate_velocity), then one single-differenced
  // ambiguity (cycles) per satellite and band.
  bool initialised_ = false;
  GnssTime last_time_;
  Eigen::VectorXd x_;
  Eigen::MatrixXd p_;
  std::map<Key, Ambiguity> ambiguities_;
  int consecutive_fixes_ = 0;
  Eigen::Vector3d last_base_position_m_ = Eigen::Vector3d::Zero();
};

// A moving-base rover (two antennas on one body): heading (clockwise from true north) and pitch of
// its fixed baseline (base antenna to rover antenna), with their 1-sigma from the baseline's
// covariance, into fix.relative. Nothing for a fix that is not RTK fixed or a baseline under 5 cm.
void add_baseline_heading(PositionFix& fix);

}  // namespace skytrace::positioning
