// Real against simulated observations: per system and signal, how far a simulation is from a real
// recording at the same place and time (`skytrace compare REAL.obs SIM.obs`).
//
// Every residual is real minus simulated. The part common to all satellites of a system at an
// epoch (receiver clock, inter-system bias, a common Doppler drift) is removed by subtracting, per
// epoch and system, the median over that system's satellites of (real - sim); a system-epoch with
// a single satellite therefore carries no information and is not counted. Percentiles are of the
// absolute residuals, interpolated linearly between order statistics (numpy's default).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/satellite_state.hpp"

namespace skytrace::io {

struct CompareOptions {
  // Systems to compare; empty: every system both files observe.
  std::vector<GnssSystem> systems;
  // Signals to compare; empty: every signal both files observe (within `systems`). A listed
  // signal that one of the files lacks is an error.
  std::vector<Signal> signals;
  // Satellite positions for the elevation mask, seen from the real file's APPROX POSITION XYZ;
  // nullptr: no mask. Satellite-epochs the source has no state for are dropped and counted.
  const orbits::SatelliteStateSource* satellite_source = nullptr;
  double min_elevation_deg = 10.0;
  // A moving receiver: its ECEF position at a time (std::nullopt outside the track). When set, the
  // elevation mask looks from the position at each epoch instead of APPROX POSITION XYZ (which a
  // moving receiver's file leaves empty or sets to one point of the drive). The satellite-epochs of
  // epochs outside the track count as without position.
  std::function<std::optional<Eigen::Vector3d>(const GnssTime&)> receiver_position;
  // Epochs of the two files within this many seconds are one epoch (a receiver whose clock is not
  // steered time-tags its epochs a few ms off the full second). The real pseudorange and phase are
  // moved to the simulated epoch's time with the Doppler (the simulated one, else the real one);
  // without a Doppler on either side they are compared as they are.
  double epoch_tolerance_s = 1e-3;
};

// Statistics of residuals; the unit is the one in the name of the member holding them.
struct ResidualStatistics {
  size_t count = 0;
  // NaN when count is 0.
  double abs_p68 = std::numeric_limits<double>::quiet_NaN();
  double abs_p95 = std::numeric_limits<double>::quiet_NaN();
  double mean = std::numeric_limits<double>::quiet_NaN();
  double rms = std::numeric_limits<double>::quiet_NaN();
};

// Computes the statistics above (exposed for tests and other tools).
[[nodiscard]] ResidualStatistics residual_statistics(std::vector<double> residuals);

struct SignalComparison {
  Signal signal;
  // Pseudorange real - sim (m).
  ResidualStatistics pseudorange_m;
  // The same residuals per satellite: a constant offset of one satellite or one satellite block
  // (a code bias its navigation message does not carry) shows as its mean.
  std::map<SatelliteId, ResidualStatistics> pseudorange_by_satellite_m;
  // Doppler as range rate, -wavelength * D, real - sim (m/s): its sign matches the pseudorange's.
  ResidualStatistics doppler_mps;
  // Carrier phase change between consecutive common epochs, wavelength * (L(t) - L(t-1)), real -
  // sim (m). Only where both epochs of both files have the phase and neither file reports a loss of
  // lock (LLI bit 0) or a gap in the phase at any of its epochs in between.
  ResidualStatistics phase_difference_m;
  // C/N0 (S observations, dB-Hz): no common part removed. Files whose SIGNAL STRENGTH UNIT is
  // set to something other than DBHZ are not compared (count 0).
  size_t cn0_count = 0;
  double cn0_bias_dbhz = std::numeric_limits<double>::quiet_NaN();  // mean(real - sim)
  double cn0_mean_abs_difference_dbhz = std::numeric_limits<double>::quiet_NaN();
  // Tracked satellite-epochs (common epochs, above the mask): the signal's pseudorange is present,
  // or when a file has no pseudorange type for the signal, any of its observations.
  size_t real_tracked = 0;
  size_t sim_tracked = 0;
  size_t both_tracked = 0;
  // System-epochs where a single satellite had the pseudorange in both files (nothing to compare).
  size_t single_satellite_epochs = 0;
  // Satellite-epochs of GLONASS FDMA signals without a frequency channel in either header: no
  // Doppler or phase residual.
  size_t unknown_channel_satellite_epochs = 0;

  // |real and sim| / |real| and |real and sim| / |sim|; NaN when the denominator is 0.
  [[nodiscard]] double real_in_sim_fraction() const;
  [[nodiscard]] double sim_in_real_fraction() const;
};

struct ComparisonReport {
  std::string real_name;  // file names as given (set by compare_observation_files)
  std::string sim_name;
  // The readers' notes on both files (types read but not used, e.g. channel numbers X1).
  std::vector<std::string> warnings;
  size_t real_epochs = 0;  // observation epochs (event epochs not counted)
  size_t sim_epochs = 0;
  size_t common_epochs = 0;  // matched to within 1 ms
  GnssTime first_common_epoch;
  GnssTime last_common_epoch;
  bool elevation_mask_applied = false;
  double min_elevation_deg = 0.0;
  // The mask looked from the receiver's position at each epoch (CompareOptions::receiver_position).
  bool mask_from_receiver_track = false;
  // Distinct satellite-epochs (of either file, selected systems) dropped by the mask, and those
  // dropped because the satellite source had no state for them.
  size_t below_mask_satellite_epochs = 0;
  size_t without_position_satellite_epochs = 0;
  std::map<GnssSystem, size_t> without_position_by_system;  // the same, per system (non-zero only)
  std::vector<SignalComparison> signals;  // ordered by system (G R E C J I S) then signal
};

// Compares two files already read. Errors: no common epochs (kOutOfRange, naming both spans), no
// common signals or a requested signal missing (kNotFound), mask requested without APPROX
// POSITION XYZ in the real file (kNotFound).
[[nodiscard]] Result<ComparisonReport> compare_observations(const ObservationFile& real,
                                                            const ObservationFile& sim,
                                                            const CompareOptions& options);
// Reads both files (errors say which of REAL and SIM failed) and compares them.
[[nodiscard]] Result<ComparisonReport> compare_observation_files(
    const std::filesystem::path& real_path, const std::filesystem::path& sim_path,
    const CompareOptions& options);

// "GE" -> {GPS, Galileo}; unknown letters are kInvalidArgument.
[[nodiscard]] Result<std::vector<GnssSystem>> parse_system_letters(std::string_view text);
// "G1C,E1C" -> signals of the catalogue; unknown ones are kInvalidArgument.
[[nodiscard]] Result<std::vector<Signal>> parse_signal_list(std::string_view text);

// Aligned text table, one row per system/signal, units in the column names, preceded by '#' lines
// that describe the epochs and the mask.
[[nodiscard]] std::string format_comparison_table(const ComparisonReport& report);
// The same numbers as JSON (NaN as null).
[[nodiscard]] std::string comparison_to_json(const ComparisonReport& report);

}  // namespace skytrace::io
