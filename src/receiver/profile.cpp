#include "skytrace/receiver/profile.hpp"

#include <cmath>
#include <numbers>

#include "skytrace/core/constants.hpp"

namespace skytrace::receiver {

std::vector<std::string> builtin_profile_names() { return {"ideal", "septentrio-polarx5"}; }

Result<ReceiverProfile> builtin_profile(const std::string& name) {
  ReceiverProfile p;
  p.name = name;
  if (name == "ideal") {
    // No noise, ideal clock, every signal above the mask in open sky (C/N0 33 dB-Hz at the
    // horizon); signals attenuated by vegetation below 25 dB-Hz are lost.
    p.tracking_threshold_dbhz = 25.0;
    return p;
  }
  if (name == "septentrio-polarx5") {
    // Provisional geodetic receiver: narrow correlator, carrier-aided DLL, OCXO-class steered clock.
    p.dll_bandwidth_hz = 0.25;
    p.pll_bandwidth_hz = 10.0;
    p.fll_bandwidth_hz = 2.0;
    p.correlator_spacing_chips = 0.1;
    p.integration_time_s = 0.01;
    p.cn0_zenith_dbhz = 51.0;
    p.cn0_horizon_dbhz = 35.0;
    p.cn0_resolution_dbhz = 0.25;
    p.tracking_threshold_dbhz = 28.0;
    p.oscillator.h0 = 2e-21;
    p.oscillator.h_minus2 = 1e-24;
    p.oscillator.initial_bias_s = 5e-7;
    p.oscillator.initial_drift_s_per_s = 1e-9;
    p.oscillator.steered = true;
    p.channel_count = 544;
    return p;
  }
  std::string names;
  for (const auto& n : builtin_profile_names()) names += (names.empty() ? "" : ", ") + n;
  return make_error(ErrorCode::kNotFound, "unknown receiver profile '" + name + "' (known: " + names + ")");
}

TrackingNoise tracking_noise(const ReceiverProfile& profile, const SignalInfo& signal, double carrier_hz,
                             double cn0_dbhz) {
  TrackingNoise noise;
  const double cn0_hz = std::pow(10.0, cn0_dbhz / 10.0);
  const double t_s = profile.integration_time_s;
  if (profile.dll_bandwidth_hz > 0.0) {
    // Coherent early-minus-late DLL with BPSK-like correlation peak of chip width 1/chip_rate.
    const double d = profile.correlator_spacing_chips;
    const double var_chips2 = profile.dll_bandwidth_hz * d / (2.0 * cn0_hz) * (1.0 + 2.0 / (t_s * cn0_hz * (2.0 - d)));
    const double chip_m = constants::kSpeedOfLight_mps / signal.chip_rate_hz;
    // A BOC signal's sharper peak divides the error by about sqrt(subcarrier factor) relative to BPSK.
    double shape = 1.0;
    if (signal.modulation.subcarrier_factor > 0.0) shape = 1.0 / std::sqrt(2.0 * signal.modulation.subcarrier_factor / signal.modulation.chip_factor);
    noise.code_m = std::sqrt(var_chips2) * chip_m * shape;
  }
  const double wavelength_m = constants::kSpeedOfLight_mps / carrier_hz;
  if (profile.pll_bandwidth_hz > 0.0) {
    const double var_rad2 = profile.pll_bandwidth_hz / cn0_hz * (1.0 + 1.0 / (2.0 * t_s * cn0_hz));
    noise.phase_m = std::sqrt(var_rad2) * wavelength_m / (2.0 * std::numbers::pi);
  }
  if (profile.fll_bandwidth_hz > 0.0) {
    // FLL thermal noise (Hz) scaled to range rate.
    const double var_hz2 = 4.0 * profile.fll_bandwidth_hz / (std::pow(2.0 * std::numbers::pi * t_s, 2) * cn0_hz) *
                           (1.0 + 1.0 / (t_s * cn0_hz));
    noise.doppler_mps = std::sqrt(var_hz2) * wavelength_m;
  }
  return noise;
}

}  // namespace skytrace::receiver
