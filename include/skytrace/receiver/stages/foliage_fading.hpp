// A stage of the observation model between signal power (stage 3) and tracking (stage 4): the fast
// fading of a signal whose direct ray crosses vegetation (docs/models/foliage-fading.md).
//
// Leaves and branches do not only absorb: they scatter part of the power they take out of the
// direct wave, and the scattered waves reach the antenna from around the crown. The received field
// is a Rician one (Loo's land-mobile-satellite model): a coherent part, the direct wave through the
// canopy, and a diffuse part whose mean power tends to `diffuse_db` of the unobstructed signal as
// the canopy grows thick. The mean power stays the link budget's (vegetation attenuation of the
// world); the fading moves around it. The diffuse field changes as the wind moves the leaves
// (a Gaussian Doppler spectrum, `wind_spread_hz` rms at L1) and as the antenna moves through the
// standing-wave pattern under the crown (waves from the upper hemisphere). It is a sum of
// sinusoids evaluated between epochs, so a receiver sees fades shorter than its epoch interval:
// a fade below its tracking threshold for longer than its loop holds makes the carrier slip (a new
// arc), one lasting at the epoch makes it lose the signal; the composite's phase, delay and phase
// rate over the direct wave enter the carrier phase, the code and the Doppler.
#pragma once

#include <Eigen/Core>

#include <array>
#include <complex>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "skytrace/core/random.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::receiver::stages {

struct FoliageFadingSettings {
  bool enabled = false;
  // Mean power of the canopy's diffuse field at full extinction, relative to the unobstructed
  // signal: Loo's heavy-shadowing multipath power b0 = 0.063 (-12 dB) at L band.
  double diffuse_db = -12.0;
  // RMS Doppler spread the wind gives the diffuse field at L1 (scaled with the carrier).
  double wind_spread_hz = 0.5;
};

// What a signal's fades did since the previous epoch, for one signal's mean C/N0 and thresholds.
struct FoliageFade {
  double cn0_change_db = 0.0;  // reported C/N0 (mean power over the last second) minus the mean
  bool faded_out = false;      // below the tracking threshold at the epoch for at least the hold time
  bool slipped = false;        // lost phase lock and regained it since the previous epoch
};

// The composite field of one satellite's band at an epoch, relative to the mean received power.
struct FoliageComposite {
  std::vector<double> power;  // |field|^2 at the samples since the previous epoch, the last at the epoch
  double step_s = 0.0;
  // The composite over the direct wave at the epoch: carrier phase (range units, the phase-locked
  // loop follows it continuously), code (DLL, small delays) and range rate.
  double phase_error_m = 0.0;
  double code_error_m = 0.0;
  double range_rate_error_mps = 0.0;
  // Rician K factor (coherent over diffuse power).
  double k_factor = 0.0;

  // The fades of a signal whose mean C/N0 is `mean_cn0_dbhz`, tracked down to `threshold_dbhz` by
  // a phase lock that survives fades shorter than `hold_s`.
  [[nodiscard]] FoliageFade for_signal(double mean_cn0_dbhz, double threshold_dbhz, double hold_s) const;
};

class FoliageFading {
 public:
  FoliageFading(std::uint64_t seed, int receiver_index, FoliageFadingSettings settings);

  [[nodiscard]] const FoliageFadingSettings& settings() const { return settings_; }

  // The composite field of `band` (the RINEX band digit) of `sat` at `tag`, sampled since
  // `previous_tag` (the receiver's previous epoch; nullopt: the last second): carrier
  // `carrier_hz`, mean vegetation attenuation `attenuation_db` over `vegetation_path_m` of the direct
  // ray, receiver velocity and the direction to the satellite in east-north-up. Called once per
  // satellite, band and epoch, in increasing time.
  [[nodiscard]] const FoliageComposite& composite(const SatelliteId& sat, char band, double carrier_hz,
                                                  double attenuation_db, double vegetation_path_m,
                                                  const Eigen::Vector3d& velocity_enu_mps,
                                                  const Eigen::Vector3d& satellite_enu, const GnssTime& tag,
                                                  const std::optional<GnssTime>& previous_tag);

  static constexpr int kWaves = 16;         // sinusoids of the diffuse field
  static constexpr int kMaxSamples = 2000;  // per epoch interval (longer intervals: coarser steps)

 private:
  struct Field {
    std::array<Eigen::Vector3d, kWaves> arrival_enu;  // unit vectors towards the scattering leaves
    std::array<double, kWaves> wind_hz_at_l1{};
    std::array<double, kWaves> phase_rad{};
    std::optional<GnssTime> time;  // when phase_rad holds
    double composite_phase_rad = 0.0;  // unwrapped, relative to the coherent wave
    FoliageComposite composite;
  };
  std::uint64_t seed_;
  int receiver_index_;
  FoliageFadingSettings settings_;
  std::unordered_map<std::uint64_t, Field> fields_;
  std::vector<std::complex<double>> rotation_;
  std::vector<std::complex<double>> wave_;
};

// Rician K factor of a canopy of mean attenuation `attenuation_db` whose diffuse power at full
// extinction is `diffuse_db` (the coherent power falls with the extinction, the diffuse power rises
// with it; their sum is the mean). 0: Rayleigh (no coherent part left).
[[nodiscard]] double foliage_k_factor(double attenuation_db, double diffuse_db);

}  // namespace skytrace::receiver::stages
