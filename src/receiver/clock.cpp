#include "skytrace/receiver/clock.hpp"

#include <cmath>
#include <numbers>

namespace skytrace::receiver {

ReceiverClock::ReceiverClock(const OscillatorSettings& oscillator, bool ideal, std::uint64_t stream_key)
    : oscillator_(oscillator), ideal_(ideal), random_(stream_key) {
  if (!ideal_) {
    state_.bias_s = (2.0 * random_.uniform() - 1.0) * oscillator_.initial_bias_s;
    state_.drift_s_per_s = (2.0 * random_.uniform() - 1.0) * oscillator_.initial_drift_s_per_s;
  }
}

void ReceiverClock::advance(double dt_s) {
  if (ideal_ || dt_s <= 0.0) return;
  // Discrete two-state model (Brown & Hwang): white frequency noise drives the bias, random-walk
  // frequency noise the drift; q_bias = h0/2 dt + 2 h-1 dt^2 + 2/3 pi^2 h-2 dt^3, q_drift =
  // 2 pi^2 h-2 dt (cross terms neglected). Flicker frequency noise has no finite-state model; the
  // standard approximation (Van Dierendonck et al. 1984) lumps it into the bias as 2 h-1 dt^2,
  // which gives it its Allan variance at the step dt.
  const double q_bias = oscillator_.h0 / 2.0 * dt_s + 2.0 * oscillator_.h_minus1 * dt_s * dt_s +
                        2.0 * std::numbers::pi * std::numbers::pi * oscillator_.h_minus2 * dt_s * dt_s * dt_s / 3.0;
  const double q_drift = 2.0 * std::numbers::pi * std::numbers::pi * oscillator_.h_minus2 * dt_s;
  state_.bias_s += state_.drift_s_per_s * dt_s + std::sqrt(q_bias) * random_.gaussian();
  state_.drift_s_per_s += std::sqrt(q_drift) * random_.gaussian();
  if (oscillator_.steered) {
    // The receiver steers its oscillator: the drift is pulled towards cancelling the bias with a
    // time constant of about 100 s, which keeps the bias within a few tens of nanoseconds.
    constexpr double kSteeringTimeConstant_s = 100.0;
    state_.drift_s_per_s -= state_.bias_s / kSteeringTimeConstant_s * std::min(1.0, dt_s / kSteeringTimeConstant_s);
  } else if (std::fabs(state_.bias_s) > 1e-3) {
    // Free-running receivers jump their clock by whole milliseconds to keep it within +-1 ms.
    state_.bias_s -= std::copysign(1e-3, state_.bias_s);
  }
}

}  // namespace skytrace::receiver
