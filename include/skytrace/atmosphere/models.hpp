// Reference atmosphere models: the exact variants common positioning engines (RTKLIB) apply, so a
// noise-free simulation can be checked to the centimetre. Better models are further choices.
#pragma once

#include <optional>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/ephemeris.hpp"

namespace skytrace::atmosphere {

// IS-GPS-200 20.3.3.5.2.5 Klobuchar model: vertical-to-slant ionospheric group delay on GPS L1 in
// metres for a receiver at `receiver` looking at `direction` at GPS time t. Other frequencies scale
// by (f_L1 / f)^2. nullopt below the horizon (never a silent 0).
[[nodiscard]] std::optional<double> klobuchar_delay_l1_m(const orbits::KlobucharCoefficients& coefficients,
                                                         const GnssTime& t, const Geodetic& receiver,
                                                         const AzimuthElevation& direction);

// Which troposphere the signals cross.
enum class TroposphereModel { kNone, kSaastamoinen, kUnb3m };

struct StandardAtmosphere {
  double sea_level_pressure_hpa = 1013.25;
  double sea_level_temperature_c = 15.0;
  double relative_humidity = 0.7;  // fraction
};

// Saastamoinen zenith hydrostatic + wet delay from a standard atmosphere at the receiver's
// ellipsoidal height, mapped by 1 / sin(elevation) (RTKLIB's tropmodel). Metres; nullopt below the
// horizon or outside -100 m .. 10 km height, where the model does not apply.
[[nodiscard]] std::optional<double> saastamoinen_delay_m(const Geodetic& receiver, double elevation_deg,
                                                         const StandardAtmosphere& atmosphere = {});

// UNB3m (Leandro, Santos & Langley 2006): surface meteorology from a latitude/season table
// (pressure, temperature, relative humidity, lapse rates), Saastamoinen zenith hydrostatic and
// Askne-Nordius wet delays at the receiver's height, Niell (1996) hydrostatic and wet mapping
// functions with the hydrostatic height correction. A different truth than the reference
// Saastamoinen above: seasons, latitude and a real mapping function.
struct TroposphereDelay {
  double zenith_hydrostatic_m = 0.0;
  double zenith_wet_m = 0.0;
  double hydrostatic_mapping = 0.0;
  double wet_mapping = 0.0;
  [[nodiscard]] double slant_m() const {
    return zenith_hydrostatic_m * hydrostatic_mapping + zenith_wet_m * wet_mapping;
  }
};
// nullopt below the horizon or outside -500 m .. 10 km height. `day_of_year` 1..366 (fractional).
[[nodiscard]] std::optional<TroposphereDelay> unb3m_delay(const Geodetic& receiver, double elevation_deg,
                                                          double day_of_year);

// Niell mapping functions alone (elevation > 0; height in metres for the hydrostatic correction).
[[nodiscard]] double niell_hydrostatic_mapping(double latitude_deg, double height_m, double elevation_deg,
                                               double day_of_year);
[[nodiscard]] double niell_wet_mapping(double latitude_deg, double elevation_deg);

}  // namespace skytrace::atmosphere
