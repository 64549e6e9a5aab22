#include "skytrace/atmosphere/residual_field.hpp"

#include <cmath>
#include <numbers>
#include <random>

namespace skytrace::atmosphere {
namespace {
constexpr double kEarthRadius_m = 6371e3;
constexpr double kShellHeight_m = 350e3;
constexpr double kDegToRad = std::numbers::pi / 180.0;
}  // namespace

ResidualField::ResidualField(const Settings& settings) {
  if (!(settings.sigma_m > 0.0) || settings.modes <= 0) return;
  amplitude_m_ = settings.sigma_m * std::sqrt(2.0 / settings.modes);
  std::mt19937_64 random(settings.seed);
  std::normal_distribution<double> wave(0.0, 1.0 / settings.correlation_length_m);
  std::normal_distribution<double> frequency(0.0, 1.0 / settings.correlation_time_s);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  for (int k = 0; k < settings.modes; ++k) {
    // Drawn in a fixed order, so a seed always gives the same field.
    const double kx = wave(random), ky = wave(random), omega = frequency(random), phi = phase(random);
    modes_.push_back(Mode{kx, ky, omega, phi});
  }
}

ResidualField::Settings ResidualField::for_gradient_ppm(double ppm, double correlation_length_m,
                                                        double correlation_time_s, std::uint64_t seed) {
  Settings s;
  s.sigma_m = ppm * 1e-6 * correlation_length_m;
  s.correlation_length_m = correlation_length_m;
  s.correlation_time_s = correlation_time_s;
  s.seed = seed;
  return s;
}

double ResidualField::value_m(double latitude_deg, double longitude_deg, const GnssTime& t) const {
  if (modes_.empty()) return 0.0;
  // Metres on a sphere around the place: distances between nearby points (baselines, pierce
  // points of one satellite) are what matter.
  const double y_m = kEarthRadius_m * latitude_deg * kDegToRad;
  const double x_m = kEarthRadius_m * std::cos(latitude_deg * kDegToRad) * longitude_deg * kDegToRad;
  // Seconds since the GPS epoch: continuous (no wrap at midnight); at 1e9 s a double still resolves
  // the mode phases to 1e-10 rad.
  const double t_s = t.gpst_seconds_approx();
  double sum = 0.0;
  for (const Mode& m : modes_) sum += std::cos(m.kx_per_m * x_m + m.ky_per_m * y_m + m.omega_per_s * t_s + m.phase_rad);
  return amplitude_m_ * sum;
}

double IonosphereWithResidual::residual_l1_m(const GnssTime& t, const Geodetic& receiver,
                                            const AzimuthElevation& direction) const {
  const auto p = thin_shell_pierce_point(receiver, direction, kEarthRadius_m, kShellHeight_m);
  if (!p) return 0.0;  // below the horizon
  return p->mapping_factor * field_.value_m(p->latitude_deg, p->longitude_deg, t);
}

Result<std::optional<double>> IonosphereWithResidual::delay_l1_m(const GnssTime& t, const Geodetic& receiver,
                                                                 const AzimuthElevation& direction) const {
  std::optional<double> delay = 0.0;
  if (model_) {
    auto modelled = model_->delay_l1_m(t, receiver, direction);
    if (!modelled) return modelled.error();
    delay = *modelled;
  } else if (direction.elevation_deg < 0.0) {
    delay.reset();
  }
  if (!delay) return delay;
  // A residual never makes the delay negative (no electron content below zero).
  return std::optional<double>(std::max(0.0, *delay + residual_l1_m(t, receiver, direction)));
}

double troposphere_residual_m(const ResidualField& field, const GnssTime& t, const Geodetic& receiver,
                              const AzimuthElevation& direction) {
  const double el = std::max(direction.elevation_deg, 1.0) * kDegToRad;
  const double mapping = 1.0 / (std::sin(el) + 0.00035 / (std::tan(el) + 0.017));  // Chao (1974), wet
  return mapping * field.value_m(receiver.latitude_deg, receiver.longitude_deg, t);
}

}  // namespace skytrace::atmosphere
