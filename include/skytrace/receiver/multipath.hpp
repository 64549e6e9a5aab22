// What the paths of one signal (world/propagation.hpp) do to the receiver's measurements: the
// delay-lock loop's code error from the early-minus-late discriminator on the composite
// correlation function, the carrier-phase error from the composite phasor at the prompt
// correlator, the power change (C/N0), and the range-rate error from the paths' delay rates.
// Infinite front-end bandwidth (sharp correlation peaks); docs/multipath.md lists the limits.
#pragma once

#include <complex>
#include <cstddef>
#include <vector>

#include "skytrace/core/path_query.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {

// Autocorrelation of a spreading code with a piecewise-constant chip waveform (BPSK: one segment;
// sine-phased BOC(m, n): 2m/n segments of alternating sign), for a long random code: exact and
// piecewise linear between multiples of the segment length. CBOC and TMBOC are approximated by
// BOC(1,1), AltBOC(15,10) by BOC(15,10).
class CorrelationFunction {
 public:
  [[nodiscard]] static CorrelationFunction bpsk();
  [[nodiscard]] static CorrelationFunction boc(double subcarrier_factor, double chip_factor);
  [[nodiscard]] static CorrelationFunction of(const Modulation& modulation);

  // Normalised correlation (1 at zero delay) at a delay in chips.
  [[nodiscard]] double operator()(double delay_chips) const;
  [[nodiscard]] int segments() const { return static_cast<int>(values_.size()) - 1; }

 private:
  explicit CorrelationFunction(std::vector<double> values) : values_(std::move(values)) {}
  std::vector<double> values_;  // at lags j / segments chips, j = 0..segments (the last is 0)
};

// One path as the receiver's antenna delivers it.
struct ReceivedPath {
  double excess_delay_m = 0.0;
  double excess_delay_rate_mps = 0.0;
  // Complex amplitude relative to the unobstructed direct signal after the antenna, without the
  // phase of the excess path (added per wavelength).
  std::complex<double> amplitude{1.0, 0.0};
};

struct MultipathErrors {
  bool any_path = false;
  std::size_t dominant = 0;       // index of the strongest path, the one the loops lock on
  double code_m = 0.0;            // DLL code error over the direct range
  double phase_m = 0.0;           // carrier-phase error over the direct range (range units)
  double range_rate_mps = 0.0;    // error of the range rate (Doppler = -range rate / wavelength)
  double power_db = 0.0;          // prompt power relative to the unobstructed direct signal
};

// Errors of a signal of a given correlation function, chip length (m), carrier wavelength (m) and
// early-late spacing (chips) from its paths. The DLL is a non-coherent early-minus-late power
// discriminator |E|^2 - |L|^2 locked at the zero crossing nearest the strongest path's delay; the
// PLL follows the phase of the prompt correlator there.
[[nodiscard]] MultipathErrors multipath_errors(const CorrelationFunction& correlation, double chip_length_m,
                                               double wavelength_m, double spacing_chips,
                                               const std::vector<ReceivedPath>& paths);

// The amplitude a path gives through the receiver's antenna, relative to the antenna's RHCP gain
// towards the satellite's direct direction: (g_R(path) a_R + g_L(path) a_L) / g_R(direct), gains
// as amplitudes from the pattern's dBic tables (its LHCP column is the polarisation rejection).
[[nodiscard]] std::complex<double> antenna_amplitude(const AntennaPattern& antenna, const SignalPath& path,
                                                     double path_elevation_deg, double path_azimuth_deg,
                                                     double direct_elevation_deg, double direct_azimuth_deg);

}  // namespace skytrace::receiver
