// Physical and system constants with their sources. SI units unless the name says otherwise.
#pragma once

namespace skytrace::constants {

inline constexpr double kSpeedOfLight_mps = 299792458.0;
inline constexpr double kPi = 3.1415926535898;  // the value the GPS and Galileo ICDs prescribe

// Earth rotation rate used for the Sagnac correction and the Keplerian orbit (WGS84, IS-GPS-200).
inline constexpr double kEarthRotationRateGps_radps = 7.2921151467e-5;
// Earth gravitational constants GM per system ICD (m^3/s^2).
inline constexpr double kGmGps_m3ps2 = 3.986005e14;        // IS-GPS-200, also QZSS, NavIC
inline constexpr double kGmGalileo_m3ps2 = 3.986004418e14;  // Galileo OS SIS ICD
inline constexpr double kGmBeiDou_m3ps2 = 3.986004418e14;   // BDS-SIS-ICD (CGCS2000)
inline constexpr double kGmGlonass_m3ps2 = 3.9860044e14;    // GLONASS ICD 5.1 (PZ-90)
inline constexpr double kEarthRotationRateBeiDou_radps = 7.292115e-5;   // CGCS2000
inline constexpr double kEarthRotationRateGlonass_radps = 7.292115e-5;  // PZ-90
inline constexpr double kEarthRotationRateGalileo_radps = 7.2921151467e-5;
// PZ-90 constants for the GLONASS equations of motion.
inline constexpr double kGlonassEarthSemiMajorAxis_m = 6378136.0;
inline constexpr double kGlonassJ2 = 1.0826257e-3;  // second zonal harmonic C20 = -J2

// Relativistic clock correction constant F = -2 sqrt(GM) / c^2 (s/m^0.5), IS-GPS-200 20.3.3.3.3.1.
inline constexpr double kRelativisticF_s_per_sqrtm = -4.442807633e-10;

// WGS84 ellipsoid.
inline constexpr double kWgs84SemiMajorAxis_m = 6378137.0;
inline constexpr double kWgs84Flattening = 1.0 / 298.257223563;

}  // namespace skytrace::constants
