#include "skytrace/atmosphere/models.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "skytrace/core/constants.hpp"

namespace skytrace::atmosphere {
namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kDegToRad = kPi / 180.0;
}  // namespace

std::optional<double> klobuchar_delay_l1_m(const orbits::KlobucharCoefficients& k, const GnssTime& t,
                                           const Geodetic& receiver, const AzimuthElevation& direction) {
  if (direction.elevation_deg <= 0.0) return std::nullopt;
  // Angles in semicircles as the ICD writes them.
  const double elevation_sc = direction.elevation_deg / 180.0;
  const double azimuth_rad = direction.azimuth_deg * kDegToRad;
  const double latitude_sc = receiver.latitude_deg / 180.0;
  const double longitude_sc = receiver.longitude_deg / 180.0;

  const double earth_angle_sc = 0.0137 / (elevation_sc + 0.11) - 0.022;
  double ipp_latitude_sc = latitude_sc + earth_angle_sc * std::cos(azimuth_rad);
  ipp_latitude_sc = std::clamp(ipp_latitude_sc, -0.416, 0.416);
  const double ipp_longitude_sc =
      longitude_sc + earth_angle_sc * std::sin(azimuth_rad) / std::cos(ipp_latitude_sc * kPi);
  const double geomagnetic_latitude_sc = ipp_latitude_sc + 0.064 * std::cos((ipp_longitude_sc - 1.617) * kPi);

  double local_time_s = 4.32e4 * ipp_longitude_sc + t.to_week_tow(TimeScale::kGpst).tow_s;
  local_time_s -= std::floor(local_time_s / 86400.0) * 86400.0;

  const double below_0_53 = 0.53 - elevation_sc;
  const double slant_factor = 1.0 + 16.0 * (below_0_53 * below_0_53 * below_0_53);
  const double phi = geomagnetic_latitude_sc;
  double amplitude_s = k.alpha[0] + phi * (k.alpha[1] + phi * (k.alpha[2] + phi * k.alpha[3]));
  double period_s = k.beta[0] + phi * (k.beta[1] + phi * (k.beta[2] + phi * k.beta[3]));
  amplitude_s = std::max(amplitude_s, 0.0);
  period_s = std::max(period_s, 72000.0);
  const double x_rad = 2.0 * kPi * (local_time_s - 50400.0) / period_s;
  const double x2 = x_rad * x_rad;
  const double delay_s = slant_factor * (std::fabs(x_rad) < 1.57
                                             ? 5e-9 + amplitude_s * (1.0 - x2 / 2.0 + x2 * x2 / 24.0)
                                             : 5e-9);
  return constants::kSpeedOfLight_mps * delay_s;
}

std::optional<double> saastamoinen_delay_m(const Geodetic& receiver, double elevation_deg,
                                           const StandardAtmosphere& atmosphere) {
  if (elevation_deg <= 0.0 || receiver.height_m < -100.0 || receiver.height_m > 1e4) return std::nullopt;
  // The terms of the receiver's place, kept while it asks for one satellite after another.
  struct PlaceTerms {
    double height_m = std::numeric_limits<double>::quiet_NaN();
    double latitude_deg = 0.0;
    StandardAtmosphere atmosphere;
    double pressure_hpa = 0.0;
    double temperature_k = 0.0;
    double water_vapour_hpa = 0.0;
    double gravity_factor = 0.0;  // 1 - 0.00266 cos(2 latitude) - 0.00028 h / km
  };
  thread_local PlaceTerms place;
  const double height_m = std::max(receiver.height_m, 0.0);
  if (height_m != place.height_m || receiver.latitude_deg != place.latitude_deg ||
      atmosphere.sea_level_pressure_hpa != place.atmosphere.sea_level_pressure_hpa ||
      atmosphere.sea_level_temperature_c != place.atmosphere.sea_level_temperature_c ||
      atmosphere.relative_humidity != place.atmosphere.relative_humidity) {
    place.height_m = height_m;
    place.latitude_deg = receiver.latitude_deg;
    place.atmosphere = atmosphere;
    place.pressure_hpa = atmosphere.sea_level_pressure_hpa * std::pow(1.0 - 2.2557e-5 * height_m, 5.2568);
    place.temperature_k = atmosphere.sea_level_temperature_c - 6.5e-3 * height_m + 273.16;
    place.water_vapour_hpa = 6.108 * atmosphere.relative_humidity *
                             std::exp((17.15 * place.temperature_k - 4684.0) / (place.temperature_k - 38.45));
    const double latitude_rad = receiver.latitude_deg * kDegToRad;
    place.gravity_factor = 1.0 - 0.00266 * std::cos(2.0 * latitude_rad) - 0.00028 * height_m / 1e3;
  }
  const double zenith_rad = kPi / 2.0 - elevation_deg * kDegToRad;
  const double hydrostatic_m = 0.0022768 * place.pressure_hpa / place.gravity_factor / std::cos(zenith_rad);
  const double wet_m =
      0.002277 * (1255.0 / place.temperature_k + 0.05) * place.water_vapour_hpa / std::cos(zenith_rad);
  return hydrostatic_m + wet_m;
}

}  // namespace skytrace::atmosphere
