// Receiver profiles: what a receiver (with its antenna) tracks and how well. Profiles are YAML
// files (profiles/*.yaml, format in docs/profiles.md); every value has its unit in the name.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/signal.hpp"

namespace skytrace::receiver {

struct OscillatorSettings {
  // Allan-variance coefficients of the power-law model: white frequency h0 (s), flicker frequency
  // h-1 (dimensionless), random-walk frequency h-2 (1/s).
  double h0 = 0.0;
  double h_minus1 = 0.0;
  double h_minus2 = 0.0;
  double initial_bias_s = 0.0;           // magnitude bound of the start offset
  double initial_drift_s_per_s = 0.0;    // magnitude bound of the start drift
  // Steered: the receiver keeps its clock near system time by adjusting it continuously.
  // Free running: the bias drifts and the receiver jumps it by whole milliseconds (clock.hpp).
  bool steered = true;
};

// Oscillator presets by name: "tcxo", "ocxo" (Allan coefficients only; start offsets and steering
// stay those of the profile). nullopt for an unknown name.
[[nodiscard]] std::optional<OscillatorSettings> oscillator_preset(const std::string& name);

// Antenna gain versus direction, right-hand (the direct signal) and left-hand circular (what a
// single reflection mostly becomes: the polarisation rejection is RHCP minus LHCP gain).
struct AntennaPattern {
  std::vector<double> elevation_deg;  // increasing, within [-90, 90]
  std::vector<double> azimuth_deg;    // empty: no azimuth dependence; else increasing within [0, 360)
  // Rows per azimuth (one row without azimuths), one value per elevation.
  std::vector<std::vector<double>> rhcp_gain_dbic;
  std::vector<std::vector<double>> lhcp_gain_dbic;

  // Gain towards a direction, linear interpolation in elevation (clamped at the table's ends) and
  // azimuth (wrapping around north).
  [[nodiscard]] double rhcp_dbic(double elevation_deg, double azimuth_deg) const;
  [[nodiscard]] double lhcp_dbic(double elevation_deg, double azimuth_deg) const;
};

struct TrackedSignal {
  TrackedSignal() = default;
  TrackedSignal(const Signal& tracked_signal, double extra_loss) : signal(tracked_signal), extra_loss_db(extra_loss) {}

  Signal signal;
  // Beyond the implementation loss (semi-codeless tracking, the receiver's reporting, satellites
  // stronger than their ICD row); negative when a fit on real data finds the signal stronger than
  // the link budget says. The antenna's band response is the antenna's (below).
  double extra_loss_db = 0.0;
  // The antenna's table for the signal's band and the band's response (antenna.hpp); no table: the
  // profile's `antenna`.
  std::shared_ptr<const AntennaPattern> antenna;
  double antenna_band_response_db = 0.0;
};

// How the receiver's navigation engine computes RTK (scenario key receivers[].rtk): the profile's
// optional `rtk:` section, every value defaulted (docs/profiles.md).
struct RtkProfile {
  double elevation_mask_deg = 15.0;
  double min_cn0_dbhz = 0.0;            // 0: no C/N0 mask
  double ratio_threshold = 3.0;
  std::string ambiguity_mode = "fix-and-hold";  // fix-and-hold, continuous, float
  std::string dynamics = "kinematic";           // kinematic, static
  bool estimate_velocity = false;       // kinematic: constant-velocity states
  double sigma_phase_m = 0.003;         // a and b of a^2 + b^2 / sin^2(el), per receiver
  double code_phase_ratio = 100.0;
  double acceleration_noise_mps2 = 1.0; // with estimate_velocity
  double ambiguity_noise_cycles = 1e-4; // per sqrt(s)
  double cn0_weighting_dbhz = 0.0;      // 0: elevation weighting only (positioning::RtkSettings)
};

struct ReceiverProfile {
  std::string name;
  std::string source;  // the file it was read from
  // Signals the receiver can track; `all_signals` = every signal of the catalogue (ideal).
  bool all_signals = false;
  std::vector<TrackedSignal> signals;
  int channel_count = 0;  // signal channels; 0 = unlimited
  double elevation_mask_deg = 0.0;
  // The antenna profile used when the scenario names none (profiles/antennas; antenna.hpp).
  std::string default_antenna;
  // The older form: an antenna table inside the receiver profile (`antenna:`), then the pattern of
  // every band; also the table of signals without an antenna of their own.
  bool inline_antenna = false;
  AntennaPattern antenna;
  // The antenna in use once attached (attach_antenna): its profile name and RINEX ANT # / TYPE.
  std::string antenna_name;
  std::string antenna_rinex_type;
  // Referred to the antenna element's port, with the default antenna's chain (LNA, cable) when the
  // profile names one: attach_antenna swaps that chain for the one in use.
  double system_noise_temperature_k = 290.0;
  double implementation_loss_db = 0.0;
  // Tracking-loop parameters for the thermal-noise formulas (Kaplan & Hegarty, ch. 8).
  double dll_bandwidth_hz = 0.0;  // 0 = no code noise
  double pll_bandwidth_hz = 0.0;  // 0 = no phase noise and no cycle slips
  double fll_bandwidth_hz = 0.0;  // 0 = no Doppler noise
  // Semi-codeless P(Y) carrier loops (GPS L1W/L2W) aided by the satellite's L1 C/A loop: the
  // aided loop follows the C/A loop (the same phase error in metres) and tracks only the
  // difference, the ionosphere's divergence, with this narrow bandwidth. 0 = unaided (a loop of
  // pll_bandwidth_hz of its own). Applies while L1 C/A is simulated and tracked.
  double semicodeless_aiding_bandwidth_hz = 0.0;
  double correlator_spacing_chips = 0.1;
  double integration_time_s = 0.02;
  // Tracking state: a signal is acquired after `acquisition_time_s` above the acquisition
  // threshold and tracked down to the tracking threshold; a data signal's half-cycle ambiguity is
  // resolved `half_cycle_resolution_s` after acquisition.
  double acquisition_threshold_dbhz = 0.0;
  double tracking_threshold_dbhz = 0.0;
  // Semi-codeless P(Y) channels (GPS L1W/L2W) take their code and carrier from the satellite's
  // L1 C/A channel and need no search: while L1 C/A is locked they are acquired and kept down to
  // this C/N0 (as reported). Unset (nullopt): the acquisition and tracking thresholds above.
  std::optional<double> semicodeless_threshold_dbhz;
  double acquisition_time_s = 0.0;
  // Aided reacquisition (the datasheets' reacquisition and hot-start sensitivities): once the
  // receiver runs (after the run's first epoch) it predicts every satellite's code delay and
  // Doppler from its fix and almanac, searches a few cells and integrates longer, so a signal is
  // acquired from this C/N0 after the detection time of that narrow search (stages::
  // reacquisition_dwell_s: shorter the stronger the signal) instead of the cold acquisition
  // threshold and time. Unset (nullopt): cold acquisition throughout.
  std::optional<double> reacquisition_threshold_dbhz;
  double half_cycle_resolution_s = 0.0;
  double cn0_resolution_dbhz = 0.25;
  // Outputs a satellite's measurements only once it holds a broadcast ephemeris for it (as the
  // Trimble NetR9 does; u-blox and Septentrio output raw measurements without). The satellite is
  // tracked meanwhile (channel, lock time, arcs); receiver/ephemeris_decoding.hpp says when.
  bool output_requires_ephemeris = false;
  OscillatorSettings oscillator;
  RtkProfile rtk;  // the optional rtk section

  // The profile's entry for a signal, or nullptr when the receiver cannot track it.
  [[nodiscard]] const TrackedSignal* tracked(const Signal& signal) const;
};

// Parses a profile from YAML text; `source` names the file in messages ("file:line: key: ...").
[[nodiscard]] Result<ReceiverProfile> parse_profile(const std::string& yaml_text, const std::string& source);

// Folders searched for a profile by name, in order: `scenario_dir`/profiles, the entries of
// SKYTRACE_PROFILE_PATH (separated by ':'), the project's profiles folder.
[[nodiscard]] std::vector<std::filesystem::path> profile_search_path(const std::filesystem::path& scenario_dir);

// A profile by name (searched as above) or by path (contains '/' or ends in .yaml; relative to
// `scenario_dir`).
[[nodiscard]] Result<ReceiverProfile> load_profile(const std::string& name_or_path,
                                                   const std::filesystem::path& scenario_dir = {});

// Names of the profiles found on the search path (sorted, without duplicates).
[[nodiscard]] std::vector<std::string> available_profile_names(const std::filesystem::path& scenario_dir = {});

// Former built-in lookup, now by name from the project's folder (kept for existing callers), with
// its default antenna attached for every signal it tracks (antenna.hpp).
[[nodiscard]] Result<ReceiverProfile> builtin_profile(const std::string& name);

// 1-sigma thermal noise of the code (m), carrier phase (m) and Doppler (m/s) for a signal at a
// given C/N0; zero for a profile without tracking loops (ideal).
struct TrackingNoise {
  double code_m = 0.0;
  double phase_m = 0.0;
  double doppler_mps = 0.0;
};
[[nodiscard]] TrackingNoise tracking_noise(const ReceiverProfile& profile, const SignalInfo& signal,
                                           double carrier_hz, double cn0_dbhz);

// Tracking-loop outputs are not white: a loop of noise bandwidth B_L smooths its discriminator
// noise over its time constant, for a first-order loop 1 / (4 B_L) (B_L = K / 4, K the loop gain;
// Kaplan & Hegarty 2017, ch. 8). The noise is drawn as a first-order Gauss-Markov process with that
// correlation time and the thermal-noise 1-sigma: epochs far apart (30 s) stay independent, 10 Hz
// outputs of a 0.25 Hz DLL are correlated as a real receiver's are.
[[nodiscard]] double loop_time_constant_s(double bandwidth_hz);  // infinity for 0 Hz (no loop)
// One unit-variance step: a x + sqrt(1 - a^2) w with a = exp(-dt / tau); w alone when dt is not
// finite (a new arc) or tau is 0. `white` is a standard normal draw.
[[nodiscard]] double gauss_markov_step(double previous, double dt_s, double tau_s, double white);
struct LoopNoiseState {
  double code = 0.0;
  double phase = 0.0;
  double doppler = 0.0;
  bool started = false;
  double last_s = 0.0;  // receiver time of the last draw (GPST seconds)
};

// PLL thermal phase jitter (rad, 1 sigma) of the profile at a C/N0.
[[nodiscard]] double pll_jitter_rad(const ReceiverProfile& profile, double cn0_dbhz);
// The same for a loop of another bandwidth (an aided loop's).
[[nodiscard]] double pll_jitter_rad(const ReceiverProfile& profile, double cn0_dbhz, double bandwidth_hz);

// Mean time to a cycle slip (s) of a first-order loop with thermal jitter `jitter_rad` and noise
// bandwidth `bandwidth_hz` (Viterbi 1966: T = pi^2 rho I0(rho)^2 / (2 B_L), rho the loop SNR).
// A Costas loop (data signals) slips by half cycles: its SNR is 1 / (4 sigma^2) instead of 1 / sigma^2.
[[nodiscard]] double mean_time_to_slip_s(double jitter_rad, double bandwidth_hz, bool costas);

// The probability of a slip within `interval_s`, 1 - exp(-interval_s / T), for a draw against a
// uniform number on the grid k 2^-53 (RandomStream::uniform). Where a lower bound of T shows the
// probability below 2^-60, the bound's probability (as far below the grid, and as non-zero) is
// returned instead: every draw decides the same, without evaluating the Bessel function.
[[nodiscard]] double slip_probability(double jitter_rad, double bandwidth_hz, bool costas, double interval_s);

// Whether the signal carries navigation data on the tracked component (a Costas loop with a
// half-cycle ambiguity) rather than a pilot.
[[nodiscard]] bool has_data_modulation(const SignalInfo& signal);

}  // namespace skytrace::receiver
