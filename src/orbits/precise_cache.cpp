#include "skytrace/orbits/precise_cache.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace skytrace::orbits {

void PreciseOrbitCache::refit(Fit& fit, const SatelliteId& satellite, size_t first) const {
  const auto& epochs = precise_.orbits().epochs;
  fit.start = epochs[first];
  fit.end = epochs[first + 1];
  fit.half_span_s = 0.5 * (fit.end - fit.start);
  fit.usable = false;
  // Chebyshev nodes of the first kind, u_j = cos(pi (j + 1/2) / N), and the discrete cosine
  // transform of the values there: c_k = 2/N sum_j f(u_j) cos(pi k (j + 1/2) / N).
  constexpr int n = kNodes;
  std::array<PreciseEphemerides::Orbit, n> values;
  for (int j = 0; j < n; ++j) {
    const double u = std::cos(std::numbers::pi * (j + 0.5) / n);
    auto value = precise_.orbit(satellite, fit.start + fit.half_span_s * (1.0 + u));
    if (!value) return;
    values[j] = *value;
  }
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d position = Eigen::Vector3d::Zero(), velocity = Eigen::Vector3d::Zero();
    for (int j = 0; j < n; ++j) {
      const double weight = std::cos(std::numbers::pi * k * (j + 0.5) / n);
      position += weight * values[j].position_m;
      velocity += weight * values[j].velocity_mps;
    }
    fit.position_coefficients[k] = (2.0 / n) * position;
    fit.velocity_coefficients[k] = (2.0 / n) * velocity;
  }
  fit.usable = true;
}

namespace {

// Clenshaw's recurrence for sum' c_k T_k(u) (the first term halved).
Eigen::Vector3d chebyshev_sum(const std::array<Eigen::Vector3d, PreciseOrbitCache::kNodes>& c, double u) {
  Eigen::Vector3d b1 = Eigen::Vector3d::Zero(), b2 = Eigen::Vector3d::Zero();
  for (int k = PreciseOrbitCache::kNodes - 1; k >= 1; --k) {
    const Eigen::Vector3d b0 = 2.0 * u * b1 - b2 + c[k];
    b2 = b1;
    b1 = b0;
  }
  return u * b1 - b2 + 0.5 * c[0];
}

}  // namespace

Result<PreciseEphemerides::Orbit> PreciseOrbitCache::orbit(const SatelliteId& satellite, const GnssTime& t) const {
  const auto& epochs = precise_.orbits().epochs;
  if (epochs.size() < 2 || t < epochs.front() || t > epochs.back()) return precise_.orbit(satellite, t);
  Fit& fit = fits_[satellite];
  if (fit.half_span_s == 0.0 || t < fit.start || t > fit.end) {
    const auto upper = static_cast<size_t>(std::upper_bound(epochs.begin(), epochs.end(), t) - epochs.begin());
    refit(fit, satellite, std::min(upper, epochs.size() - 1) - 1);
  }
  if (!fit.usable) return precise_.orbit(satellite, t);
  const double u = std::clamp((t - fit.start) / fit.half_span_s - 1.0, -1.0, 1.0);
  PreciseEphemerides::Orbit out;
  out.position_m = chebyshev_sum(fit.position_coefficients, u);
  out.velocity_mps = chebyshev_sum(fit.velocity_coefficients, u);
  return out;
}

Result<SatelliteState> PreciseOrbitCache::state(const SatelliteId& satellite, const GnssTime& t) const {
  auto orbit_here = orbit(satellite, t);
  if (!orbit_here) return orbit_here.error();
  auto clock_here = precise_.clock(satellite, t);
  if (!clock_here) return clock_here.error();
  return PreciseEphemerides::state_from(*orbit_here, *clock_here);
}

}  // namespace skytrace::orbits
