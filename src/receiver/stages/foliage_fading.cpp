#include "skytrace/receiver/stages/foliage_fading.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "skytrace/core/constants.hpp"
#include "skytrace/receiver/stages/signal_key.hpp"

namespace skytrace::receiver::stages {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kL1_hz = 1575.42e6;
// Sampling of the field: at most 10 ms between samples (a phase lock's reaction time), and a tenth
// of the fastest wave's period.
constexpr double kMaxStep_s = 0.01;
constexpr double kMinStep_s = 1e-4;
constexpr double kCn0Averaging_s = 1.0;  // receivers report C/N0 averaged over about a second
// Excess delay of the diffuse field: leaves around the ray half-way through the canopy, scattering
// into a forward cone of 30 degrees: 0.5 (1 - cos 30 deg) of the path through the canopy.
const double kDiffuseDelayPerCanopyMetre = 0.5 * (1.0 - std::cos(30.0 * std::numbers::pi / 180.0));

}  // namespace

double foliage_k_factor(double attenuation_db, double diffuse_db) {
  const double mean_power = std::pow(10.0, -attenuation_db / 10.0);
  const double diffuse_at_extinction = std::pow(10.0, diffuse_db / 10.0);
  if (mean_power >= 1.0) return std::numeric_limits<double>::infinity();
  // mean = coherent + diffuse_at_extinction * (1 - coherent): the diffuse part grows as the
  // coherent one is taken out of the direct wave.
  const double coherent = std::max(0.0, (mean_power - diffuse_at_extinction) / (1.0 - diffuse_at_extinction));
  const double diffuse = mean_power - coherent;
  return diffuse > 0.0 ? coherent / diffuse : std::numeric_limits<double>::infinity();
}

FoliageFade FoliageComposite::for_signal(double mean_cn0_dbhz, double threshold_dbhz, double hold_s) const {
  FoliageFade fade;
  if (power.empty()) return fade;
  // Below the threshold when power < 10^((threshold - mean) / 10).
  const double power_threshold = std::pow(10.0, (threshold_dbhz - mean_cn0_dbhz) / 10.0);
  const auto hold_samples = static_cast<std::size_t>(std::max(1.0, std::ceil(hold_s / step_s - 1e-9)));
  std::size_t run = 0;
  for (std::size_t k = 0; k < power.size(); ++k) {
    if (power[k] < power_threshold) {
      ++run;
      continue;
    }
    if (run >= hold_samples) fade.slipped = true;  // lost lock in the fade, regained it after
    run = 0;
  }
  fade.faded_out = run >= hold_samples;
  const auto averaged = std::min(power.size(), static_cast<std::size_t>(std::ceil(kCn0Averaging_s / step_s - 1e-9)));
  double sum = 0.0;
  for (std::size_t k = power.size() - averaged; k < power.size(); ++k) sum += power[k];
  fade.cn0_change_db = 10.0 * std::log10(std::max(sum / static_cast<double>(averaged), 1e-12));
  return fade;
}

FoliageFading::FoliageFading(std::uint64_t seed, int receiver_index, FoliageFadingSettings settings)
    : seed_(seed), receiver_index_(receiver_index), settings_(settings) {}

const FoliageComposite& FoliageFading::composite(const SatelliteId& sat, char band, double carrier_hz,
                                                 double attenuation_db, double vegetation_path_m,
                                                 const Eigen::Vector3d& velocity_enu_mps,
                                                 const Eigen::Vector3d& satellite_enu, const GnssTime& tag,
                                                 const std::optional<GnssTime>& previous_tag) {
  const std::uint64_t key = satellite_key(sat) << 8 | static_cast<unsigned char>(band);
  auto [it, inserted] = fields_.try_emplace(key);
  Field& field = it->second;
  if (inserted) {
    RandomStream draw(stream_key(seed_, {hash_name("foliage-fading"), static_cast<std::uint64_t>(receiver_index_),
                                         satellite_key(sat), static_cast<std::uint64_t>(band)}));
    for (int n = 0; n < kWaves; ++n) {
      // Leaves anywhere above the antenna's horizon (uniform over the upper hemisphere).
      const double up = draw.uniform();
      const double azimuth = kTwoPi * draw.uniform();
      const double horizontal = std::sqrt(std::max(0.0, 1.0 - up * up));
      field.arrival_enu[n] = Eigen::Vector3d(horizontal * std::sin(azimuth), horizontal * std::cos(azimuth), up);
      field.wind_hz_at_l1[n] = settings_.wind_spread_hz * draw.gaussian();
      field.phase_rad[n] = kTwoPi * draw.uniform();
    }
  }
  FoliageComposite& out = field.composite;
  out.power.clear();
  const double wavelength_m = constants::kSpeedOfLight_mps / carrier_hz;
  const double k_factor = foliage_k_factor(attenuation_db, settings_.diffuse_db);
  out.k_factor = k_factor;
  const double coherent = std::isinf(k_factor) ? 1.0 : std::sqrt(k_factor / (k_factor + 1.0));
  const double diffuse = std::isinf(k_factor) ? 0.0 : std::sqrt(1.0 / (k_factor + 1.0)) / std::sqrt(double{kWaves});

  // Each wave's frequency over the direct one's: the wind's, and the antenna moving through the
  // field (waves from arrival_enu against the direct wave from the satellite).
  std::array<double, kWaves> frequency_hz{};
  double fastest_hz = 0.0;
  for (int n = 0; n < kWaves; ++n) {
    frequency_hz[n] = field.wind_hz_at_l1[n] * carrier_hz / kL1_hz +
                      velocity_enu_mps.dot(field.arrival_enu[n] - satellite_enu) / wavelength_m;
    fastest_hz = std::max(fastest_hz, std::abs(frequency_hz[n]));
  }
  const GnssTime start = previous_tag ? *previous_tag : tag - kCn0Averaging_s;
  // A field not sampled since before the interval runs on to its start (its waves keep their
  // frequencies: a stationary process).
  if (field.time && *field.time < start) {
    const double gap_s = start - *field.time;
    for (int n = 0; n < kWaves; ++n) field.phase_rad[n] = std::fmod(field.phase_rad[n] + kTwoPi * frequency_hz[n] * gap_s, kTwoPi);
  }
  const GnssTime from = field.time && *field.time > start ? *field.time : start;
  const double interval_s = std::max(tag - from, 0.0);

  double step_s = kMaxStep_s;
  if (fastest_hz > 0.0) step_s = std::clamp(0.1 / fastest_hz, kMinStep_s, kMaxStep_s);
  auto samples = static_cast<int>(std::ceil(interval_s / step_s - 1e-9));
  samples = std::clamp(samples, 1, kMaxSamples);
  step_s = interval_s > 0.0 ? interval_s / samples : step_s;
  out.step_s = step_s;

  wave_.resize(kWaves);
  rotation_.resize(kWaves);
  std::complex<double> diffuse_sum{0.0, 0.0};
  for (int n = 0; n < kWaves; ++n) {
    wave_[n] = std::polar(1.0, field.phase_rad[n]);
    rotation_[n] = std::polar(1.0, kTwoPi * frequency_hz[n] * step_s);
    diffuse_sum += wave_[n];
  }
  std::complex<double> previous = coherent + diffuse * diffuse_sum;
  if (!field.time) field.composite_phase_rad = std::arg(previous);
  double last_phase_step_rad = 0.0;
  std::complex<double> field_at_epoch = previous;
  out.power.reserve(static_cast<std::size_t>(samples));
  for (int k = 0; k < samples; ++k) {
    diffuse_sum = {0.0, 0.0};
    for (int n = 0; n < kWaves; ++n) {
      wave_[n] *= rotation_[n];
      diffuse_sum += wave_[n];
    }
    const std::complex<double> e = coherent + diffuse * diffuse_sum;
    out.power.push_back(std::norm(e));
    // The loop follows the composite's phase continuously (unwrapped from sample to sample).
    last_phase_step_rad = std::norm(previous) > 0.0 && std::norm(e) > 0.0 ? std::arg(e * std::conj(previous)) : 0.0;
    field.composite_phase_rad += last_phase_step_rad;
    previous = e;
    field_at_epoch = e;
  }
  for (int n = 0; n < kWaves; ++n) field.phase_rad[n] = std::arg(wave_[n]);
  field.time = tag;

  // A phase advance of the composite over the direct wave is a shorter carrier range.
  out.phase_error_m = -field.composite_phase_rad * wavelength_m / kTwoPi;
  out.range_rate_error_mps = -last_phase_step_rad / step_s * wavelength_m / kTwoPi;
  // The DLL on a composite of the direct wave and a diffuse one delayed by `delay`: the two-path
  // error delay * Re(d conj(e)) / |e|^2 for delays far below the correlator spacing, bounded.
  const double delay_m = kDiffuseDelayPerCanopyMetre * vegetation_path_m;
  const std::complex<double> diffuse_part = field_at_epoch - coherent;
  const double power_at_epoch = std::norm(field_at_epoch);
  const double relative = power_at_epoch > 0.0 ? std::real(diffuse_part * std::conj(field_at_epoch)) / power_at_epoch : 0.0;
  out.code_error_m = delay_m * std::clamp(relative, -2.0, 2.0);
  return out;
}

}  // namespace skytrace::receiver::stages
