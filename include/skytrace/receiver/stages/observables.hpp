// Stage 6 of the observation model: the observables from their terms (docs/conventions.md):
//     P = rho + A_s + c (dt_r - (dt_k + dt_rel - TGD_s)) + I_s + T + e_P
//     L = [rho + A_s + c (dt_r - dt_k - dt_rel) - I_s + T + e_L] / lambda_s + N
// with A_s the receiver antenna's phase centre on the signal's frequency (PCO along the line of
// sight and PCV; its rate, below 1e-4 m/s, is left out of D).
//     D = -[d rho/dt + c (d dt_r/dt - d dt_k/dt - d dt_rel/dt)] / lambda_s
// The truth of every term stays in the measurement beside them.
#pragma once

#include <cmath>

#include "skytrace/core/constants.hpp"
#include "skytrace/receiver/observations.hpp"

namespace skytrace::receiver::stages {

// The terms common to every signal of a satellite (m, m/s).
struct SatelliteTerms {
  double range_m = 0.0;                   // rho, Sagnac included
  double range_rate_mps = 0.0;            // d rho / dt
  double receiver_clock_m = 0.0;          // c dt_r
  double receiver_clock_rate_mps = 0.0;   // c d dt_r / dt
  double relativistic_m = 0.0;            // c dt_rel
  double satellite_clock_rate_mps = 0.0;  // c (d dt_k / dt + d dt_rel / dt)
  double troposphere_m = 0.0;             // T
};

// A measured C/N0 at the receiver's resolution (0: unquantised).
[[nodiscard]] inline double quantize(double value, double step) {
  return step > 0.0 ? std::round(value / step) * step : value;
}

// Pseudorange, carrier phase and Doppler of `m` from the satellite's terms and the signal's own
// (m.carrier_hz, m.satellite_clock_m, m.group_delay_m, m.ionosphere_code_m, m.antenna_phase_centre_m,
// noise, multipath, foliage fading and m.ambiguity_cycles). The ionosphere delays the code and advances the phase by the same amount.
inline void form_observables(const SatelliteTerms& t, SignalMeasurement& m) {
  const double wavelength_m = constants::kSpeedOfLight_mps / m.carrier_hz;
  const double satellite_clock_total_m = m.satellite_clock_m + t.relativistic_m;
  const double range_m = t.range_m + m.antenna_phase_centre_m;
  m.pseudorange_m = range_m + t.receiver_clock_m - (satellite_clock_total_m - m.group_delay_m) + m.ionosphere_code_m +
                    t.troposphere_m + m.code_noise_m + m.code_multipath_m + m.foliage_code_m;
  const double phase_range_m = range_m + t.receiver_clock_m - satellite_clock_total_m - m.ionosphere_code_m +
                               t.troposphere_m + m.phase_noise_m + m.phase_multipath_m + m.foliage_phase_m;
  m.carrier_phase_cycles = phase_range_m / wavelength_m + static_cast<double>(m.ambiguity_cycles);
  const double phase_range_rate_mps = t.range_rate_mps + t.receiver_clock_rate_mps - t.satellite_clock_rate_mps +
                                      m.doppler_noise_mps + m.range_rate_multipath_mps +
                                      m.foliage_range_rate_mps;
  m.doppler_hz = -phase_range_rate_mps / wavelength_m;
}

}  // namespace skytrace::receiver::stages
