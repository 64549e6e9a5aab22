// Broadcast navigation data as decoded from RINEX navigation files (2.x, 3.0x, 4.00). Field names
// follow the RINEX record layout; units are SI (s, m, rad) regardless of the file's units.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/satellite.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::orbits {

// Which navigation message a record came from (RINEX 4 names them; RINEX 2/3 imply LNAV, I/NAV or
// F/NAV from the Galileo data-source bits, D1/D2 from the BeiDou PRN).
enum class NavMessage : std::uint8_t {
  kGpsLnav, kGpsCnav, kGpsCnav2,
  kGalileoInav, kGalileoFnav,
  kBeiDouD1, kBeiDouD2, kBeiDouCnav1, kBeiDouCnav2, kBeiDouCnav3,
  kQzssLnav, kQzssCnav, kQzssCnav2,
  kNavicLnav,
  kGlonassFdma,
  kSbas,
};
[[nodiscard]] std::string_view to_string(NavMessage message);  // "LNAV", "INAV", "D1", ... (RINEX 4 names)

// Per-signal group delays as broadcast. Which applies to which signal: see group_delay_s().
struct GroupDelays {
  double tgd_s = 0.0;  // GPS/QZSS LNAV and CNAV T_GD (L1 P(Y) / L1 C/A); NavIC T_GD (L5)
  // GPS/QZSS CNAV inter-signal corrections (RINEX 4).
  double isc_l1ca_s = 0.0, isc_l2c_s = 0.0, isc_l5i5_s = 0.0, isc_l5q5_s = 0.0;
  double isc_l1cd_s = 0.0, isc_l1cp_s = 0.0;
  // Galileo broadcast group delays.
  double bgd_e1e5a_s = 0.0, bgd_e1e5b_s = 0.0;
  // BeiDou D1/D2: TGD1 (B1I - B3I) and TGD2 (B2I - B3I).
  double tgd1_s = 0.0, tgd2_s = 0.0;
  // BeiDou CNAV1/2/3 (RINEX 4).
  double tgd_b1cp_s = 0.0, tgd_b2ap_s = 0.0, tgd_b2bi_s = 0.0, isc_b1cd_s = 0.0, isc_b2ad_s = 0.0;
};

// A Keplerian ephemeris of GPS, Galileo, BeiDou, QZSS or NavIC.
struct KeplerEphemeris {
  SatelliteId satellite;
  NavMessage message = NavMessage::kGpsLnav;

  GnssTime toc;   // clock reference time (on the GPST timeline)
  GnssTime toe;   // ephemeris reference time (on the GPST timeline)
  int week = 0;   // week of toe as written in the file (GPS week for G/E/J/I in RINEX 3, BDT week for C)
  double toe_sow = 0.0;  // toe in seconds of that week (system time)

  // Clock polynomial.
  double af0_s = 0.0, af1_s_per_s = 0.0, af2_s_per_s2 = 0.0;

  // Orbit.
  double sqrt_a_sqrtm = 0.0;
  double eccentricity = 0.0;
  double i0_rad = 0.0, omega0_rad = 0.0, omega_rad = 0.0, m0_rad = 0.0;
  double delta_n_rad_per_s = 0.0, idot_rad_per_s = 0.0, omega_dot_rad_per_s = 0.0;
  double cuc_rad = 0.0, cus_rad = 0.0, crc_m = 0.0, crs_m = 0.0, cic_rad = 0.0, cis_rad = 0.0;
  // CNAV/CNAV-2 and BeiDou CNAV extras (zero for legacy messages): A is sqrt_a^2 at toe.
  double a_dot_m_per_s = 0.0, delta_n_dot_rad_per_s2 = 0.0;

  GroupDelays group_delays;

  // Issue of data: GPS/QZSS IODE and IODC, Galileo IODnav (both), BeiDou AODE and AODC, NavIC IODEC.
  int iode = 0;
  int iodc = 0;
  int health = 0;            // 0 = healthy (SV health word; Galileo: the RINEX health bits)
  double accuracy_m = 0.0;   // URA (GPS/QZSS/NavIC), SISA (Galileo), URA (BeiDou), metres
  double fit_interval_h = 0.0;  // GPS/QZSS fit interval in hours (0 = not given)
  std::uint32_t data_source = 0;  // Galileo data source bits (bit 0 I/NAV E1-B, 1 F/NAV, 2 I/NAV E5b, 8 af for E5a, 9 af for E5b)
  int codes_on_l2 = 0;       // GPS: codes on L2 channel
  int l2p_data_flag = 0;     // GPS: L2 P data flag
  double transmission_time_sow = 0.0;  // transmission time of message (seconds of week, system time)

  // Where the record came from, for messages (file name and 1-based line of the record's first line).
  std::string source;
};

// A GLONASS FDMA broadcast state vector (PZ-90.11), as in the RINEX record.
struct GlonassEphemeris {
  SatelliteId satellite;
  GnssTime toe;               // t_b on the GPST timeline (RINEX gives it in UTC)
  double minus_tau_n_s = 0.0;  // RINEX "SV clock bias (-TauN)"
  double gamma_n = 0.0;        // RINEX "SV relative frequency bias (+GammaN)"
  double message_frame_time_s = 0.0;  // t_k, seconds of the UTC day (RINEX)
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration_mps2 = Eigen::Vector3d::Zero();  // lunisolar, as broadcast
  int health = 0;              // B_n MSB (0 = healthy)
  int frequency_channel = 0;   // k, -7..+6
  double age_days = 0.0;       // E_n
  // RINEX 3.05 fourth line (absent in older files).
  std::optional<double> delta_tau_n_s;  // L1/L2 group delay difference (tau_L2 - tau_L1)
  int status_flags = 0;
  int urai = 0;
  int health_flags = 0;
  std::string source;
};

// An SBAS (GEO) broadcast state.
struct SbasEphemeris {
  SatelliteId satellite;
  GnssTime toe;                 // t_0 on the GPST timeline
  double agf0_s = 0.0, agf1_s_per_s = 0.0;
  double transmission_time_sow = 0.0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration_mps2 = Eigen::Vector3d::Zero();
  int health = 0;
  double accuracy_m = 0.0;  // URA
  int iodn = 0;
  std::string source;
};

struct KlobucharCoefficients {
  std::array<double, 4> alpha{};  // s, s/semicircle, s/semicircle^2, s/semicircle^3
  std::array<double, 4> beta{};   // s, s/semicircle, ...
};

struct NequickGCoefficients {
  double ai0_sfu = 0.0, ai1_sfu_per_deg = 0.0, ai2_sfu_per_deg2 = 0.0;
};

struct IonosphereCoefficients {
  std::optional<KlobucharCoefficients> gps;     // GPSA/GPSB (also RINEX 2 ION ALPHA/BETA)
  std::optional<KlobucharCoefficients> qzss;    // QZSA/QZSB
  std::optional<KlobucharCoefficients> beidou;  // BDSA/BDSB
  std::optional<KlobucharCoefficients> navic;   // IRNA/IRNB
  std::optional<NequickGCoefficients> galileo;  // GAL
};

// A time-system correction (RINEX "TIME SYSTEM CORR" or a RINEX 4 STO record), e.g. GPUT, GAGP.
struct TimeSystemCorrection {
  std::string type;  // "GPUT", "GAUT", "GAGP", "BDUT", "GLUT", "GLGP", "QZGP", "IRUT", ...
  double a0_s = 0.0;
  double a1_s_per_s = 0.0;
  GnssTime reference_time;
  std::string source;
};

// All navigation data read from one or several files.
struct NavigationData {
  std::vector<KeplerEphemeris> kepler;
  std::vector<GlonassEphemeris> glonass;
  std::vector<SbasEphemeris> sbas;
  IonosphereCoefficients ionosphere;
  std::vector<TimeSystemCorrection> time_corrections;
  std::optional<int> leap_seconds;  // GPS - UTC from the header, when given
  std::vector<std::string> source_files;

  // Appends another file's content; records identical to ones already present are dropped, and
  // header values already known are kept.
  void merge(NavigationData other);
  [[nodiscard]] size_t record_count() const { return kepler.size() + glonass.size() + sbas.size(); }
};

}  // namespace skytrace::orbits
