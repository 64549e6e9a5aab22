#include "skytrace/receiver/multipath.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace skytrace::receiver {

namespace {

// Polarisation rejection assumed when a profile's antenna has no LHCP table (geodetic antennas
// reject 10-20 dB at high elevations).
constexpr double kDefaultCrossPolarRejection_db = 12.0;

std::complex<double> composite(const CorrelationFunction& r, const std::vector<std::complex<double>>& a,
                               const std::vector<double>& delay_chips, double at_chips) {
  std::complex<double> sum = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) sum += a[k] * r(at_chips - delay_chips[k]);
  return sum;
}

double wrap_pi(double x) { return std::remainder(x, 2.0 * std::numbers::pi); }

}  // namespace

CorrelationFunction CorrelationFunction::bpsk() { return CorrelationFunction({1.0, 0.0}); }

CorrelationFunction CorrelationFunction::boc(double subcarrier_factor, double chip_factor) {
  const int n = std::max(1, static_cast<int>(std::lround(2.0 * subcarrier_factor / chip_factor)));
  std::vector<int> sign(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) sign[static_cast<std::size_t>(i)] = i % 2 == 0 ? 1 : -1;
  // Lags of whole segments: the overlap within one chip (the next chip is independent, mean 0).
  std::vector<double> values(static_cast<std::size_t>(n) + 1, 0.0);
  for (int j = 0; j <= n; ++j) {
    int sum = 0;
    for (int i = 0; i + j < n; ++i) sum += sign[static_cast<std::size_t>(i)] * sign[static_cast<std::size_t>(i + j)];
    values[static_cast<std::size_t>(j)] = static_cast<double>(sum) / n;
  }
  return CorrelationFunction(std::move(values));
}

CorrelationFunction CorrelationFunction::of(const Modulation& modulation) {
  switch (modulation.kind) {
    case Modulation::Kind::kBpsk: return bpsk();
    case Modulation::Kind::kCboc:
    case Modulation::Kind::kTmboc: return boc(1.0, 1.0);
    case Modulation::Kind::kBoc:
    case Modulation::Kind::kAltBoc: return boc(modulation.subcarrier_factor, modulation.chip_factor);
  }
  return bpsk();
}

double CorrelationFunction::operator()(double delay_chips) const {
  const int n = segments();
  const double x = std::abs(delay_chips) * n;
  if (x >= n) return 0.0;
  const auto j = static_cast<std::size_t>(x);
  const double w = x - static_cast<double>(j);
  return (1.0 - w) * values_[j] + w * values_[j + 1];
}

MultipathErrors multipath_errors(const CorrelationFunction& correlation, double chip_length_m, double wavelength_m,
                                 double spacing_chips, const std::vector<ReceivedPath>& paths) {
  MultipathErrors out;
  if (paths.empty()) return out;
  out.any_path = true;
  double strongest = -1.0;
  for (std::size_t k = 0; k < paths.size(); ++k) {
    if (std::norm(paths[k].amplitude) > strongest) {
      strongest = std::norm(paths[k].amplitude);
      out.dominant = k;
    }
  }
  const double k_wave = 2.0 * std::numbers::pi / wavelength_m;
  std::vector<std::complex<double>> a(paths.size());
  std::vector<double> delay_chips(paths.size());
  for (std::size_t k = 0; k < paths.size(); ++k) {
    a[k] = paths[k].amplitude * std::polar(1.0, -k_wave * paths[k].excess_delay_m);
    delay_chips[k] = paths[k].excess_delay_m / chip_length_m;
  }
  const double half = 0.5 * spacing_chips;
  auto discriminator = [&](double eps) {
    return std::norm(composite(correlation, a, delay_chips, eps - half)) -
           std::norm(composite(correlation, a, delay_chips, eps + half));
  };
  // The stable lock point: where the discriminator rises through zero, nearest the strongest
  // path's peak (where the loop acquired).
  const double start = delay_chips[out.dominant];
  double lo = start, hi = start;
  const double d0 = discriminator(start);
  bool bracketed = d0 == 0.0;
  const double step = std::max(spacing_chips / 8.0, 1e-3);
  if (d0 < 0.0) {
    for (double x = start + step; x <= start + 1.5; x += step) {
      if (discriminator(x) >= 0.0) {
        lo = x - step;
        hi = x;
        bracketed = true;
        break;
      }
    }
  } else if (d0 > 0.0) {
    for (double x = start - step; x >= start - 1.5; x -= step) {
      if (discriminator(x) <= 0.0) {
        lo = x;
        hi = x + step;
        bracketed = true;
        break;
      }
    }
  }
  double eps = start;
  if (bracketed && hi > lo) {
    for (int i = 0; i < 60 && hi - lo > 1e-12; ++i) {
      const double mid = 0.5 * (lo + hi);
      (discriminator(mid) < 0.0 ? lo : hi) = mid;
    }
    eps = 0.5 * (lo + hi);
  }
  out.code_m = eps * chip_length_m;

  // Carrier phase relative to the dominant path's own phase, so that a lone reflected path gives
  // its full excess length and not that modulo a wavelength.
  const double dominant_delay_m = paths[out.dominant].excess_delay_m;
  auto phase_error_m = [&](double dt_s) {
    std::complex<double> prompt = 0.0;
    const double dominant_now_m = dominant_delay_m + paths[out.dominant].excess_delay_rate_mps * dt_s;
    for (std::size_t k = 0; k < paths.size(); ++k) {
      const double delay_m = paths[k].excess_delay_m + paths[k].excess_delay_rate_mps * dt_s;
      prompt += paths[k].amplitude * std::polar(1.0, -k_wave * (delay_m - dominant_now_m)) *
                correlation(eps - delay_chips[k]);
    }
    return std::pair(dominant_now_m - std::arg(prompt) / k_wave, prompt);
  };
  const auto [phase_m, prompt] = phase_error_m(0.0);
  out.phase_m = phase_m;
  out.power_db = 10.0 * std::log10(std::max(std::norm(prompt), 1e-30));
  // Rate from the phase a short time later (code lock held): the relative phases rotate with the
  // excess-delay rates, 1 ms keeps every rotation well below half a cycle.
  constexpr double kDt_s = 1e-3;
  const std::complex<double> later_prompt = phase_error_m(kDt_s).second;
  const double rotation_m = wrap_pi(std::arg(later_prompt) - std::arg(prompt)) / k_wave;
  out.range_rate_mps = paths[out.dominant].excess_delay_rate_mps - rotation_m / kDt_s;
  return out;
}

std::complex<double> antenna_amplitude(const AntennaPattern& antenna, const SignalPath& path, double path_elevation_deg,
                                       double path_azimuth_deg, double direct_elevation_deg, double direct_azimuth_deg) {
  const double direct_db = antenna.rhcp_dbic(direct_elevation_deg, direct_azimuth_deg);
  const double rhcp_db = antenna.rhcp_dbic(path_elevation_deg, path_azimuth_deg);
  const double lhcp_db = antenna.lhcp_gain_dbic.empty() ? rhcp_db - kDefaultCrossPolarRejection_db
                                                        : antenna.lhcp_dbic(path_elevation_deg, path_azimuth_deg);
  const double g_rhcp = std::pow(10.0, (rhcp_db - direct_db) / 20.0);
  const double g_lhcp = std::pow(10.0, (lhcp_db - direct_db) / 20.0);
  return g_rhcp * path.rhcp_amplitude + g_lhcp * path.lhcp_amplitude;
}

}  // namespace skytrace::receiver
