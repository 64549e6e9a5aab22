// UNB3m meteorology and zenith delays (Leandro, Santos & Langley 2006, ION NTM) with the Niell
// (1996, JGR 101(B2)) mapping functions. Tables as published; latitude interpolated linearly
// between the 15-degree rows, the seasonal term peaking on day 28 (half a year later in the south).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "skytrace/atmosphere/models.hpp"

namespace skytrace::atmosphere {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDegToRad = kPi / 180.0;

// Linear interpolation in |latitude| over the rows 15, 30, 45, 60, 75 degrees (held beyond).
template <size_t N>
std::array<double, N> interpolate_rows(const std::array<std::array<double, N>, 5>& rows, double latitude_deg) {
  const double lat = std::clamp(std::abs(latitude_deg), 15.0, 75.0);
  const auto i = std::min<size_t>(static_cast<size_t>((lat - 15.0) / 15.0), 3);
  const double m = (lat - 15.0 * static_cast<double>(i + 1)) / 15.0;
  std::array<double, N> out{};
  for (size_t k = 0; k < N; ++k) out[k] = rows[i][k] + m * (rows[i + 1][k] - rows[i][k]);
  return out;
}

// cos(2 pi (doy - 28) / 365.25), shifted by half a year in the southern hemisphere.
double seasonal_cosine(double latitude_deg, double day_of_year) {
  const double doy = latitude_deg < 0.0 ? day_of_year + 182.625 : day_of_year;
  return std::cos((doy - 28.0) * 2.0 * kPi / 365.25);
}

// Marini's continued fraction normalised to 1 at zenith (Niell's form).
double marini(double sin_el, double a, double b, double c) {
  const double top = 1.0 + a / (1.0 + b / (1.0 + c));
  const double bottom = sin_el + a / (sin_el + b / (sin_el + c));
  return top / bottom;
}

// UNB3m: pressure hPa, temperature K, relative humidity %, lapse rate K/km, water vapour lambda.
constexpr std::array<std::array<double, 5>, 5> kUnb3mAverage = {{
    {1013.25, 299.65, 75.00, 6.30, 2.77},
    {1017.25, 294.15, 80.00, 6.05, 3.15},
    {1015.75, 283.15, 76.00, 5.58, 2.57},
    {1011.75, 272.15, 77.50, 5.39, 1.81},
    {1013.00, 263.65, 82.50, 4.53, 1.55},
}};
constexpr std::array<std::array<double, 5>, 5> kUnb3mAmplitude = {{
    {0.00, 0.00, 0.00, 0.00, 0.00},
    {-3.75, 7.00, 0.00, 0.25, 0.33},
    {-2.25, 11.00, -1.00, 0.32, 0.46},
    {-1.75, 15.00, -2.50, 0.81, 0.74},
    {-0.50, 14.50, 2.50, 0.62, 0.30},
}};

// Niell hydrostatic a, b, c: averages and seasonal amplitudes; wet a, b, c.
constexpr std::array<std::array<double, 3>, 5> kNiellHydrostaticAverage = {{
    {1.2769934e-3, 2.9153695e-3, 62.610505e-3},
    {1.2683230e-3, 2.9152299e-3, 62.837393e-3},
    {1.2465397e-3, 2.9288445e-3, 63.721774e-3},
    {1.2196049e-3, 2.9022565e-3, 63.824265e-3},
    {1.2045996e-3, 2.9024912e-3, 64.258455e-3},
}};
constexpr std::array<std::array<double, 3>, 5> kNiellHydrostaticAmplitude = {{
    {0.0, 0.0, 0.0},
    {1.2709626e-5, 2.1414979e-5, 9.0128400e-5},
    {2.6523662e-5, 3.0160779e-5, 4.3497037e-5},
    {3.4000452e-5, 7.2562722e-5, 84.795348e-5},
    {4.1202191e-5, 11.723375e-5, 170.37206e-5},
}};
constexpr std::array<double, 3> kNiellHeightCorrection = {2.53e-5, 5.49e-3, 1.14e-3};
constexpr std::array<std::array<double, 3>, 5> kNiellWet = {{
    {5.8021897e-4, 1.4275268e-3, 4.3472961e-2},
    {5.6794847e-4, 1.5138625e-3, 4.6729510e-2},
    {5.8118019e-4, 1.4572752e-3, 4.3908931e-2},
    {5.9727542e-4, 1.5007428e-3, 4.4626982e-2},
    {6.1641693e-4, 1.7599082e-3, 5.4736038e-2},
}};

}  // namespace

double niell_hydrostatic_mapping(double latitude_deg, double height_m, double elevation_deg, double day_of_year) {
  const double sin_el = std::sin(elevation_deg * kDegToRad);
  const auto average = interpolate_rows(kNiellHydrostaticAverage, latitude_deg);
  const auto amplitude = interpolate_rows(kNiellHydrostaticAmplitude, latitude_deg);
  const double season = seasonal_cosine(latitude_deg, day_of_year);
  const double a = average[0] - amplitude[0] * season;
  const double b = average[1] - amplitude[1] * season;
  const double c = average[2] - amplitude[2] * season;
  const auto& h = kNiellHeightCorrection;
  const double height_correction = (1.0 / sin_el - marini(sin_el, h[0], h[1], h[2])) * height_m / 1e3;
  return marini(sin_el, a, b, c) + height_correction;
}

double niell_wet_mapping(double latitude_deg, double elevation_deg) {
  const auto w = interpolate_rows(kNiellWet, latitude_deg);
  return marini(std::sin(elevation_deg * kDegToRad), w[0], w[1], w[2]);
}

std::optional<TroposphereDelay> unb3m_delay(const Geodetic& receiver, double elevation_deg, double day_of_year) {
  if (elevation_deg <= 0.0 || receiver.height_m < -500.0 || receiver.height_m > 1e4) return std::nullopt;
  const double latitude_deg = receiver.latitude_deg;
  const double height_m = receiver.height_m;
  const auto average = interpolate_rows(kUnb3mAverage, latitude_deg);
  const auto amplitude = interpolate_rows(kUnb3mAmplitude, latitude_deg);
  const double season = seasonal_cosine(latitude_deg, day_of_year);
  const double p0_hpa = average[0] - amplitude[0] * season;
  const double t0_k = average[1] - amplitude[1] * season;
  const double rh_percent = average[2] - amplitude[2] * season;
  const double beta_k_per_m = (average[3] - amplitude[3] * season) / 1e3;
  const double lambda = average[4] - amplitude[4] * season;

  // Water vapour pressure from relative humidity (IERS Conventions 2003, ch. 9).
  const double saturation_hpa =
      0.01 * std::exp(1.2378847e-5 * t0_k * t0_k - 1.9121316e-2 * t0_k + 33.93711047 - 6.3431645e3 / t0_k);
  const double enhancement = 1.00062 + 3.14e-6 * p0_hpa + 5.6e-7 * std::pow(t0_k - 273.15, 2);
  const double e0_hpa = rh_percent / 100.0 * saturation_hpa * enhancement;

  constexpr double kGravity_mps2 = 9.80665;
  constexpr double kDryGasConstant = 8314.34 / 28.9644;  // J / (kg K)
  constexpr double k1 = 77.604, k2 = 64.79, k3 = 3.776e5;
  constexpr double k2_prime = k2 - k1 * (18.0152 / 28.9644);
  const double exponent = kGravity_mps2 / kDryGasConstant / beta_k_per_m;
  const double t_k = t0_k - beta_k_per_m * height_m;
  const double p_hpa = p0_hpa * std::pow(t_k / t0_k, exponent);
  const double e_hpa = e0_hpa * std::pow(t_k / t0_k, exponent * (lambda + 1.0));

  // Gravity at the centre of mass of the air column (geocentric latitude, as UNB3m).
  const double geocentric_latitude_rad = std::atan((1.0 - 6.6943799901413e-3) * std::tan(latitude_deg * kDegToRad));
  const double gm_mps2 = 9.784 * (1.0 - 2.66e-3 * std::cos(2.0 * geocentric_latitude_rad) - 2.8e-7 * height_m);
  const double denominator = (lambda + 1.0) * gm_mps2;
  const double mean_vapour_temperature_k = t_k * (1.0 - beta_k_per_m * kDryGasConstant / denominator);

  TroposphereDelay d;
  d.zenith_hydrostatic_m = 1e-6 * k1 * kDryGasConstant * p_hpa / gm_mps2;
  d.zenith_wet_m = 1e-6 * (mean_vapour_temperature_k * k2_prime + k3) * kDryGasConstant /
                   (denominator - beta_k_per_m * kDryGasConstant) * e_hpa / t_k;
  d.hydrostatic_mapping = niell_hydrostatic_mapping(latitude_deg, height_m, elevation_deg, day_of_year);
  d.wet_mapping = niell_wet_mapping(latitude_deg, elevation_deg);
  return d;
}

}  // namespace skytrace::atmosphere
