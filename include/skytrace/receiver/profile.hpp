// Receiver profiles: what a receiver tracks and how well. Built-in until profiles become YAML files
// (receiver-realism issue); every value has its unit in the name.
#pragma once

#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/signal.hpp"

namespace skytrace::receiver {

struct OscillatorSettings {
  // Allan-variance coefficients of the power-law model (white frequency h0, random-walk frequency h-2).
  double h0 = 0.0;
  double h_minus2 = 0.0;
  double initial_bias_s = 0.0;           // magnitude bound of the start offset
  double initial_drift_s_per_s = 0.0;    // magnitude bound of the start drift
  // Steering: the receiver keeps its clock within this bound of system time by adjusting it
  // continuously (0 = free running with millisecond jumps when the bias exceeds 1 ms... see clock.hpp).
  bool steered = true;
};

struct ReceiverProfile {
  std::string name;
  // Tracking-loop parameters for the thermal-noise formulas (Kaplan & Hegarty, ch. 8).
  double dll_bandwidth_hz = 0.0;        // 0 = no noise
  double pll_bandwidth_hz = 0.0;
  double fll_bandwidth_hz = 0.0;
  double correlator_spacing_chips = 0.1;
  double integration_time_s = 0.02;
  // C/N0 model until the link budget lands: zenith value and value at the horizon (dB-Hz).
  double cn0_zenith_dbhz = 50.0;
  double cn0_horizon_dbhz = 33.0;
  double cn0_resolution_dbhz = 0.25;
  double tracking_threshold_dbhz = 0.0;  // below: not tracked
  OscillatorSettings oscillator;
  int channel_count = 0;  // 0 = unlimited
};

// The profile of that name: `ideal` (noise-free, every signal) or a provisional real receiver.
[[nodiscard]] Result<ReceiverProfile> builtin_profile(const std::string& name);
[[nodiscard]] std::vector<std::string> builtin_profile_names();

// 1-sigma thermal noise of the code (m), carrier phase (m) and Doppler (m/s) for a signal at a
// given C/N0; zero for a profile without tracking loops (ideal).
struct TrackingNoise {
  double code_m = 0.0;
  double phase_m = 0.0;
  double doppler_mps = 0.0;
};
[[nodiscard]] TrackingNoise tracking_noise(const ReceiverProfile& profile, const SignalInfo& signal,
                                           double carrier_hz, double cn0_dbhz);

}  // namespace skytrace::receiver
