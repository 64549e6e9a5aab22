// Receiver clock: a two-state (bias, drift) oscillator driven by the power-law noise of its Allan
// parameters, steered towards system time or free running with millisecond jumps.
#pragma once

#include <cstdint>

#include "skytrace/core/random.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {

struct ClockState {
  double bias_s = 0.0;
  double drift_s_per_s = 0.0;
};

class ReceiverClock {
 public:
  // `ideal` clocks stay at zero. The random stream is keyed by the seed and the receiver index.
  ReceiverClock(const OscillatorSettings& oscillator, bool ideal, std::uint64_t stream_key);

  [[nodiscard]] const ClockState& state() const { return state_; }
  // Advances the clock by dt_s (> 0) of true time.
  void advance(double dt_s);

 private:
  OscillatorSettings oscillator_;
  bool ideal_;
  RandomStream random_;
  ClockState state_;
};

}  // namespace skytrace::receiver
