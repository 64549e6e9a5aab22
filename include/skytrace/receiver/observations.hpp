// What one receiver records at one epoch: the measurements of every signal of every satellite
// and, beside them, the truth of every term (the stages of receiver/stages/ fill them in).
#pragma once

#include <Eigen/Core>

#include <complex>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/receiver/clock.hpp"

namespace skytrace::receiver {

// True antenna (reference point) position and velocity in ECEF at a true time.
struct Kinematics {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
};

enum class SatelliteStatus {
  kTracked,     // at least one signal observed
  kBelowMask,   // below the elevation mask
  kNoEphemeris, // the receiver holds no valid ephemeris (or, waiting_for_ephemeris, has not decoded one yet)
  kNoSignal,    // transmits none of the listed signals
  kBlocked,     // the world blocks the line of sight (detail: the blocking object)
  kAttenuated,  // vegetation lowers every signal below the tracking threshold
  kUnhealthy,   // the navigation message declares every listed signal it transmits unusable
};
[[nodiscard]] std::string_view to_string(SatelliteStatus status);

struct SignalMeasurement {
  Signal signal;
  double carrier_hz = 0.0;
  // Measurements, as the receiver reports them.
  double pseudorange_m = 0.0;
  double carrier_phase_cycles = 0.0;
  double doppler_hz = 0.0;
  double cn0_dbhz = 0.0;
  bool loss_of_lock = false;  // RINEX LLI bit 0: a new carrier-phase arc starts here
  bool half_cycle_unresolved = false;  // RINEX LLI bit 1: data signal whose phase polarity is not yet known
  double lock_time_s = 0.0;            // continuous carrier tracking up to this epoch
  // Truth of the terms.
  double satellite_clock_m = 0.0;   // c * the satellite's clock (one per satellite: reference record or precise)
  double group_delay_m = 0.0;       // c * code group delay of the signal relative to that clock
  double ionosphere_code_m = 0.0;   // code delay (the phase is advanced by the same amount)
  // The receiver antenna's phase centre for this signal's frequency (ANTEX): -(e . PCO) + PCV, added
  // to code and phase alike (0 without an ANTEX file).
  double antenna_phase_centre_m = 0.0;
  double code_noise_m = 0.0;
  double phase_noise_m = 0.0;
  double doppler_noise_mps = 0.0;
  std::int64_t ambiguity_cycles = 0;
  // Multipath errors over the direct path (models.multipath): code (DLL), carrier phase (range
  // units), range rate, and the prompt power relative to the unobstructed direct signal.
  double code_multipath_m = 0.0;
  double phase_multipath_m = 0.0;
  double range_rate_multipath_mps = 0.0;
  double multipath_power_db = 0.0;
  // Foliage fading (models.foliage_fading) of a direct ray through vegetation: the diffuse field's
  // code, carrier phase (range units) and range-rate errors, and the reported C/N0's change from
  // the mean.
  double foliage_code_m = 0.0;
  double foliage_phase_m = 0.0;
  double foliage_range_rate_mps = 0.0;
  double foliage_power_db = 0.0;
};

// A signal as it arrives at the antenna, whatever the receiver makes of it (recorded with
// GeneratorSettings::incoming_signals, for signal-level outputs such as IQ samples): the observables
// of its direct path without noise, multipath or ambiguity, the C/N0 it would have unobstructed at
// the antenna's output (before the receiver's implementation loss: the receiver processing the
// signal has its own), and its paths through the antenna.
struct IncomingPath {
  double excess_delay_m = 0.0;
  double excess_delay_rate_mps = 0.0;
  // Relative to the unobstructed direct signal, after the antenna, without the excess path's phase.
  std::complex<double> amplitude{1.0, 0.0};
};
struct IncomingSignal {
  Signal signal;
  double carrier_hz = 0.0;
  double pseudorange_m = 0.0;
  double carrier_phase_cycles = 0.0;
  double doppler_hz = 0.0;
  double antenna_cn0_dbhz = 0.0;
  std::vector<IncomingPath> paths;  // empty: the direct path alone (no world, or multipath off)
};

// How a satellite's signals arrive (models.multipath): only the direct path, the direct path and
// others (reflections, diffraction), or no direct path at all.
enum class PathKind { kNone, kLos, kMultipath, kNlos };
[[nodiscard]] std::string_view to_string(PathKind kind);

// A listed signal the satellite transmits but its navigation record declares unusable
// (orbits::signal_healthy): not tracked, not output.
struct UnhealthySignal {
  Signal signal;
  std::string reason;  // the health word decoded, e.g. "GPS LNAV health 23 (L1 signals dead)"
};

struct SatelliteObservation {
  SatelliteId satellite;
  SatelliteStatus status = SatelliteStatus::kTracked;
  std::string detail;  // why not tracked, for the truth file
  std::vector<UnhealthySignal> unhealthy_signals;  // left out for their health (the others may be tracked)
  // Tracked, but not output until the receiver holds an ephemeris for it (profile
  // tracking.output_requires_ephemeris; status kNoEphemeris, no signals). Unlike a satellite
  // without any valid record, its geometry and atmosphere are filled in.
  bool waiting_for_ephemeris = false;
  int glonass_channel = 0;
  AzimuthElevation direction;
  double range_m = 0.0;            // geometric, transmit to receive, Sagnac included
  double range_rate_mps = 0.0;
  double satellite_clock_m = 0.0;  // c * clock: the reference record's polynomial, or the precise clock
  double relativistic_m = 0.0;     // c * periodic relativistic clock term
  double troposphere_m = 0.0;
  double ionosphere_l1_m = 0.0;    // group delay on 1575.42 MHz
  double vegetation_path_m = 0.0;  // path length through vegetation
  double vegetation_attenuation_db = 0.0;
  Eigen::Vector3d satellite_position_m = Eigen::Vector3d::Zero();  // at transmission, frame at reception
  std::vector<SignalMeasurement> signals;
  // Multipath: the paths (world frame, amplitudes before the antenna), each path's arrival
  // direction at the antenna (local east-north-up) and its excess-delay rate.
  PathKind path_kind = PathKind::kNone;
  std::vector<SignalPath> paths;
  std::vector<AzimuthElevation> path_directions;
  std::vector<double> path_delay_rates_mps;
  // Every healthy listed signal the satellite transmits and the antenna receives, tracked or not
  // (only with GeneratorSettings::incoming_signals).
  std::vector<IncomingSignal> incoming;
};

struct EpochObservations {
  GnssTime receiver_time;  // epoch tag (receiver clock)
  GnssTime true_time;      // = receiver_time - receiver clock bias
  Kinematics receiver;
  ClockState receiver_clock;
  std::vector<SatelliteObservation> satellites;  // every satellite of the signals' systems
};

}  // namespace skytrace::receiver
