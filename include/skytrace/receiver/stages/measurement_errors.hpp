// Stage 5 of the observation model: the terms that the measurements carry beyond geometry. The
// atmosphere along the line of sight (troposphere; ionosphere on L1, scaled per carrier), the code
// group delay of each signal relative to the satellite's one clock, the multipath errors of the
// loops on the composite of a signal's paths, and the tracking-loop noise (correlated over each
// loop's time constant, one random stream per satellite and signal).
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/atmosphere/residual_field.hpp"
#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/random.hpp"
#include "skytrace/core/satellite_catalog.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/receiver/multipath.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/receiver/stages/records.hpp"
#include "skytrace/receiver/stages/signal_key.hpp"

namespace skytrace::receiver::stages {

struct AtmosphereTerms {
  double troposphere_m = 0.0;
  double ionosphere_l1_m = 0.0;  // group delay on 1575.42 MHz
};

// Slant delays for a receiver at `receiver` towards `direction` at the true time (troposphere:
// none, Saastamoinen or UNB3m, plus the wet residual field when given; ionosphere: none when
// nullptr, its residual field riding on the model). A model that gives no value (below its
// validity) counts 0; an error of the ionosphere model (outside an IONEX map) is returned.
[[nodiscard]] Result<AtmosphereTerms> atmosphere_terms(atmosphere::TroposphereModel troposphere,
                                                       const atmosphere::IonosphereModel* ionosphere,
                                                       const GnssTime& true_time, const Geodetic& receiver,
                                                       const AzimuthElevation& direction,
                                                       const atmosphere::ResidualField* troposphere_residual = nullptr);

// The ionospheric code delay on a carrier from the delay on L1: (1575.42 MHz / f)^2. The carrier
// phase is advanced by the same amount (observables.hpp).
[[nodiscard]] inline double ionosphere_code_delay_m(double ionosphere_l1_m, double carrier_hz) {
  return ionosphere_l1_m * std::pow(kFrequencyL1_Hz / carrier_hz, 2);
}

// Code group delay (s) of a signal relative to the satellite's one clock: from the group delays of
// the reference record `truth` or of the signal's own record (group_delay_record), relative to the
// precise clock when the truth is precise; plus `block_code_bias_m` (block_code_bias_m()) when the
// record used broadcasts nothing of that part (a GPS L5 signal's LNAV record, which has no ISC).
[[nodiscard]] double signal_group_delay_s(const RecordState& truth, const RecordState& signal_record,
                                          const Signal& signal, bool precise_truth, double block_code_bias_m = 0.0);

// The part of a signal's code delay that a satellite generation has and an LNAV record does not
// broadcast (m, later positive). GPS L5: LNAV has no inter-signal correction, so the model scales
// T_GD by (f1/f5)^2; real L5 code of GPS III satellites is late against that by a few metres more
// than on Block IIF, the same at every station (ESBC 2020, KMS3 2022, NYA1 2024). Relative to IIF
// (0): only differences between satellites reach a receiver's residuals, the common part joins the
// receiver's own L5 delay. Fitted on ESBC 2020-177 only (docs/validation.md, "GPS L5 code per
// block"). 0 for every other signal and block; CNAV records carry their ISC and do not use it.
[[nodiscard]] double block_code_bias_m(SatelliteBlock block, const Signal& signal);

// Multipath errors of a signal (`info`, GLONASS channel `glonass_channel`) whose loops lock on the
// composite of `paths` with an early-late spacing of `spacing_chips`; none without paths.
[[nodiscard]] MultipathErrors signal_multipath_errors(const SignalInfo& info, int glonass_channel,
                                                      double spacing_chips, const std::vector<ReceivedPath>& paths);

// Tracking-loop noise of one signal at one epoch.
struct LoopErrors {
  double code_m = 0.0;
  double phase_m = 0.0;
  double doppler_mps = 0.0;
};

// The noise of every tracked signal's code, phase and frequency loops: unit-variance first-order
// Gauss-Markov outputs (profile.hpp) scaled by the loops' jitter at the signal's C/N0. A
// semi-codeless P(Y) channel reports the Doppler of the satellite's L1 C/A loop (scaled to its
// carrier: the same range-rate error), as real receivers do (D2W - D1C scaled is within 0.008 m/s
// in ESBC's PolaRx5 file and 0.000 in NYA1's NetR9 file at any C/N0); with
// semicodeless_aiding_bandwidth_hz its phase follows that loop too, plus what its narrow loop adds.
struct AidingLoop {
  double phase_m = 0.0;
  double doppler_mps = 0.0;
};
class LoopNoise {
 public:
  LoopNoise(std::uint64_t seed, int receiver_index) : seed_(seed), receiver_index_(receiver_index) {}

  // The errors of `signal` of `sat` at `tag`; `continuing`: tracked at the previous epoch (the
  // loops run on; a new arc starts afresh). `aiding`: the L1 C/A loop's errors at this epoch, for
  // a semi-codeless channel (nullopt otherwise).
  [[nodiscard]] LoopErrors draw(const SatelliteId& sat, const Signal& signal, const ReceiverProfile& profile,
                                const SignalInfo& info, double carrier_hz, double cn0_dbhz,
                                std::optional<AidingLoop> aiding, bool continuing, const GnssTime& tag);

 private:
  struct Streams {
    RandomStream noise;
    // Unit-variance loop outputs and the receiver time they were last drawn at.
    LoopNoiseState loops;
    explicit Streams(std::uint64_t key) : noise(key) {}
  };
  std::uint64_t seed_;
  int receiver_index_;
  std::unordered_map<SignalKey, Streams, SignalKeyHash> streams_;
};

}  // namespace skytrace::receiver::stages
