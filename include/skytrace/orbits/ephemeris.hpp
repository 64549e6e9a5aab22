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
// GPS or QZSS CNAV / CNAV-2: the messages that broadcast inter-signal corrections (ISC).
[[nodiscard]] bool is_cnav(NavMessage message);

// Time a receiver needs, from the moment it tracks a satellite, to collect a complete ephemeris and
// clock of the message: the period at which the message repeats them (the receiver starts
// anywhere in the cycle and needs every part once).
//   GPS/QZSS LNAV 30 s: subframes 1-3 of every 30-s frame (IS-GPS-200).
//   Galileo I/NAV 30 s: word types 1-4 in every 30-s nominal subframe (a receiver combining E1-B and
//   E5b could halve it; not modelled). F/NAV 50 s: page types 1-4 of the 50-s subframe (OS SIS ICD).
//   BeiDou D1 30 s: subframes 1-3 of the 30-s frame. D2 (GEO) 30 s too: D2 runs at 500 bit/s
//   with 3-s frames, but the ephemeris fills the 10 pages of subframe 1 and each frame carries one
//   page (B1I ICD 3.0, 5.3.2), so the cycle is 10 frames.
//   GLONASS 30 s: strings 1-4 of every 30-s frame (ICD 5.1).
//   NavIC 48 s: subframes 1 and 2 of the 48-s master frame (SPS ICD 1.1).
//   SBAS 12 s: a lower bound (frame synchronisation on the preamble spread over three 1-s messages,
//   then the GEO navigation message, type 9, which RTCA DO-229 lets be up to 120 s apart).
//   GPS/QZSS CNAV 48 s: message types 10, 11 and a clock message at least every 48 s (IS-GPS-200,
//   CNAV broadcast intervals). CNAV-2 and BeiDou CNAV1 18 s: ephemeris and clock in subframe 2 of
//   every 18-s frame. BeiDou CNAV2 (B2a) and CNAV3 (B2b) 48 s as GPS CNAV: their ICDs leave the
//   order of the message types to the operator.
[[nodiscard]] double ephemeris_decode_time_s(NavMessage message);

// RINEX writes 0.9999E9 for an unknown value (RINEX 3.05 GLONASS: .999999999999E+09); the readers
// store it for a blank transmission time too.
inline constexpr double kUnknownTransmissionTime_s = 0.9999e9;

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
  // Transmission time of message (RINEX: seconds of the week of `week`, system time; may be
  // negative or beyond a week to refer to that week; kUnknownTransmissionTime_s when unknown).
  // transmission_time() places it on the timeline.
  double transmission_time_sow = 0.0;

  // Where the record came from, for messages (file name and 1-based line of the record's first line).
  std::string source;
};

// A GLONASS FDMA broadcast state vector (PZ-90.11), as in the RINEX record.
struct GlonassEphemeris {
  SatelliteId satellite;
  GnssTime toe;               // t_b on the GPST timeline (RINEX gives it in UTC)
  double minus_tau_n_s = 0.0;  // RINEX "SV clock bias (-TauN)"
  double gamma_n = 0.0;        // RINEX "SV relative frequency bias (+GammaN)"
  double message_frame_time_s = 0.0;  // t_k, seconds of the UTC day (RINEX); kUnknownTransmissionTime_s when unknown
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
  double transmission_time_sow = 0.0;  // GPS seconds of week (start of the message), as Keplerian records
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration_mps2 = Eigen::Vector3d::Zero();
  int health = 0;
  double accuracy_m = 0.0;  // URA
  int iodn = 0;
  std::string source;
};

// When a record was transmitted, on the GPST timeline, from its transmission time of message
// (GLONASS: the message frame time t_k, seconds of the UTC day, placed on the UTC day within 12 h
// of t_b; the others: seconds of the record's week in the system's time, BeiDou in BDT, taken
// within half a week of toe as RINEX allows a value adjusted by a week either way). nullopt when the
// file does not say: blank, 0.9999E9, or anything beyond two weeks; for Keplerian and SBAS records
// also 0, what writers without the value leave there (a true 0 is the first instant of a week).
// GLONASS t_k = 0 is a frame at 00:00:00 UTC and is kept.
[[nodiscard]] std::optional<GnssTime> transmission_time(const KeplerEphemeris& eph);
[[nodiscard]] std::optional<GnssTime> transmission_time(const GlonassEphemeris& eph);
[[nodiscard]] std::optional<GnssTime> transmission_time(const SbasEphemeris& eph);

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
  // What the readers skipped as defined but not used (RINEX 4 EOP records, GLONASS CDMA and other
  // messages, BDGIM ionosphere, ...): one note per file, naming the file.
  std::vector<std::string> warnings;

  // Appends another file's content; records identical to ones already present are dropped, and
  // header values already known are kept.
  void merge(NavigationData other);
  [[nodiscard]] size_t record_count() const { return kepler.size() + glonass.size() + sbas.size(); }
};

}  // namespace skytrace::orbits
