#include "skytrace/receiver/link_budget.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace skytrace::receiver {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct PowerRow {
  GnssSystem system;
  char band;
  const char* attributes;  // RINEX attributes sharing the value
  double minimum_dbw;
};

// ICD minimum received powers of the tracked component (data, pilot, or both for combined
// tracking), for a 0 dBic right-hand antenna (the ICDs' "3 dBi linearly polarised" antenna is
// equivalent). A component's share of a signal's total: 10 log10(share).
constexpr PowerRow kPowers[] = {
    // IS-GPS-200N 3.3.1.6 (C/A, P(Y), L2C; IIR-M and later), IS-GPS-800J 3.3.1.6 (L1C: 3/4 pilot,
    // 1/4 data of -157.0), IS-GPS-705J 3.3.1.6 (L5 I and Q each).
    {GnssSystem::kGps, '1', "C", -158.5},
    {GnssSystem::kGps, '1', "PWYN", -161.5},
    {GnssSystem::kGps, '1', "S", -163.0},
    {GnssSystem::kGps, '1', "L", -158.25},
    {GnssSystem::kGps, '1', "X", -157.0},
    {GnssSystem::kGps, '2', "C", -160.0},
    {GnssSystem::kGps, '2', "SL", -163.0},  // CM and CL chips share L2C's -160.0 dBW time-multiplexed
    {GnssSystem::kGps, '2', "X", -160.0},
    {GnssSystem::kGps, '2', "DPWYN", -161.5},
    {GnssSystem::kGps, '5', "IQ", -157.9},
    {GnssSystem::kGps, '5', "X", -154.9},
    // GLONASS ICD edition 5.1 (2008) 3.3.1.6: L1 -161, L2 -167 dBW. CDMA signals (L1OC, L2OC,
    // L3OC ICDs 2016): -161 dBW per band split evenly between data and pilot.
    {GnssSystem::kGlonass, '1', "CP", -161.0},
    {GnssSystem::kGlonass, '2', "CP", -167.0},
    {GnssSystem::kGlonass, '4', "AB", -164.0},
    {GnssSystem::kGlonass, '4', "X", -161.0},
    {GnssSystem::kGlonass, '6', "AB", -164.0},
    {GnssSystem::kGlonass, '6', "X", -161.0},
    {GnssSystem::kGlonass, '3', "IQ", -161.0},
    {GnssSystem::kGlonass, '3', "X", -158.0},
    // Galileo OS SIS ICD 2.1 (2023) 2.3.1, at 10 degrees: E1 -157.0, E5a -155.0, E5b -155.0 dBW
    // (data + pilot, half each), E5 AltBOC the sum; E6 -155.0 dBW (HAS SIS ICD 1.0).
    {GnssSystem::kGalileo, '1', "BC", -160.0},
    {GnssSystem::kGalileo, '1', "X", -157.0},
    {GnssSystem::kGalileo, '5', "IQ", -158.0},
    {GnssSystem::kGalileo, '5', "X", -155.0},
    {GnssSystem::kGalileo, '7', "IQ", -158.0},
    {GnssSystem::kGalileo, '7', "X", -155.0},
    {GnssSystem::kGalileo, '8', "IQ", -155.0},
    {GnssSystem::kGalileo, '8', "X", -152.0},
    {GnssSystem::kGalileo, '6', "BC", -158.0},
    {GnssSystem::kGalileo, '6', "X", -155.0},
    // BeiDou ICDs: B1I 3.0 and B3I 1.0 4.4 (-163 dBW); B1C 1.0 (MEO -159 dBW, data:pilot 1:3);
    // B2a 1.0 (MEO -156 dBW, half each); B2b 1.0 (-160 dBW); B2I as B1I. IGSO/GEO 2 dB lower
    // values of B1C/B2a are not distinguished.
    {GnssSystem::kBeiDou, '2', "IQX", -163.0},
    {GnssSystem::kBeiDou, '1', "D", -165.0},
    {GnssSystem::kBeiDou, '1', "P", -160.25},
    {GnssSystem::kBeiDou, '1', "X", -159.0},
    {GnssSystem::kBeiDou, '5', "DP", -159.0},
    {GnssSystem::kBeiDou, '5', "X", -156.0},
    {GnssSystem::kBeiDou, '7', "IQX", -163.0},
    {GnssSystem::kBeiDou, '7', "DP", -163.0},
    {GnssSystem::kBeiDou, '7', "Z", -160.0},
    {GnssSystem::kBeiDou, '8', "DP", -156.0},
    {GnssSystem::kBeiDou, '8', "X", -153.0},
    {GnssSystem::kBeiDou, '6', "IQX", -163.0},
    // IS-QZSS-PNT-005 3.1.1.6, at 10 degrees: as GPS for L1C/A, L1C, L2C and L5; L1S -161.0;
    // L6 -155.7 dBW (L6D/L6E time-multiplexed halves).
    {GnssSystem::kQzss, '1', "CEB", -158.5},
    {GnssSystem::kQzss, '1', "S", -163.0},
    {GnssSystem::kQzss, '1', "L", -158.25},
    {GnssSystem::kQzss, '1', "X", -157.0},
    {GnssSystem::kQzss, '1', "Z", -161.0},
    {GnssSystem::kQzss, '2', "SL", -163.0},
    {GnssSystem::kQzss, '2', "X", -160.0},
    {GnssSystem::kQzss, '5', "IQDP", -157.9},
    {GnssSystem::kQzss, '5', "XZ", -154.9},
    {GnssSystem::kQzss, '6', "SLE", -158.7},
    {GnssSystem::kQzss, '6', "XZ", -155.7},
    // NavIC SPS ICD 1.1 (2017) 4.2: L5 SPS -159.0, S SPS -162.3 dBW; L1 SPS ICD (2023): -158.5 dBW
    // total, data:pilot 1:3.
    {GnssSystem::kNavic, '5', "A", -159.0},
    {GnssSystem::kNavic, '9', "A", -162.3},
    {GnssSystem::kNavic, '1', "D", -164.5},
    {GnssSystem::kNavic, '1', "P", -159.75},
    {GnssSystem::kNavic, '1', "X", -158.5},
    // SBAS: RTCA DO-229F 2.1.1.3 (L1 -161 dBW); DFMC SBAS L5 (ED-259) -157.9 dBW total.
    {GnssSystem::kSbas, '1', "C", -161.0},
    {GnssSystem::kSbas, '5', "IQ", -160.9},
    {GnssSystem::kSbas, '5', "X", -157.9},
};

double reference_elevation_deg(GnssSystem system) {
  // Galileo and QZSS specify their minima from 10 degrees, the others from 5 degrees.
  return system == GnssSystem::kGalileo || system == GnssSystem::kQzss ? 10.0 : 5.0;
}

// Operational satellites deliver more than the ICD minimum: GPS IIR-M/IIF/III, Galileo FOC,
// GLONASS-M and BeiDou-3 measurements (high-gain antenna surveys, e.g. Steigenberger et al. 2018,
// "Transmit power and antenna gain patterns of GPS IIR-M, IIF, and III satellites") are 2-5 dB
// above; 3 dB is used for every system.
constexpr double kUsualMargin_db = 3.0;

}  // namespace

std::optional<SignalPowerSpec> signal_power_spec(const Signal& signal) {
  for (const PowerRow& row : kPowers) {
    if (row.system != signal.system || row.band != signal.band) continue;
    if (std::string_view(row.attributes).find(signal.attribute) == std::string_view::npos) continue;
    return SignalPowerSpec{row.minimum_dbw, reference_elevation_deg(signal.system), kUsualMargin_db, "ICD"};
  }
  return std::nullopt;
}

double satellite_antenna_gain_db(double off_boresight_angle_deg, double orbit_radius_m) {
  const double limb_deg = std::asin(std::min(1.0, kEarthRadiusMean_m / orbit_radius_m)) / kDeg;
  const double x = std::min(std::fabs(off_boresight_angle_deg) / limb_deg, 1.0);
  return -kSatelliteLimbBoost_db * (1.0 - x * x);
}

double slant_range_m(double orbit_radius_m, double elevation_deg) {
  const double r = kEarthRadiusMean_m;
  const double s = std::sin(elevation_deg * kDeg), c = std::cos(elevation_deg * kDeg);
  return std::sqrt(orbit_radius_m * orbit_radius_m - r * r * c * c) - r * s;
}

double off_boresight_deg(double orbit_radius_m, double elevation_deg) {
  return std::asin(kEarthRadiusMean_m * std::cos(elevation_deg * kDeg) / orbit_radius_m) / kDeg;
}

double received_power_dbw(const SignalPowerSpec& spec, double range_m, double orbit_radius_m,
                          double off_boresight_angle_deg) {
  return SatelliteLink(range_m, orbit_radius_m, off_boresight_angle_deg).received_power_dbw(spec);
}

bool is_semicodeless(const Signal& signal) {
  return signal.system == GnssSystem::kGps && (signal.band == '1' || signal.band == '2') &&
         (signal.attribute == 'W' || signal.attribute == 'D');
}

double squaring_loss_db(double cn0_dbhz, double predetection_time_s) {
  const double snr = 2.0 * std::pow(10.0, cn0_dbhz / 10.0) * predetection_time_s;
  return 10.0 * std::log10(1.0 + 1.0 / snr);
}

double noise_density_dbw_per_hz(double system_noise_temperature_k) {
  // Every signal of a receiver asks with the same temperature: the last answer is kept.
  thread_local double last_temperature_k = std::numeric_limits<double>::quiet_NaN();
  thread_local double last_density = 0.0;
  if (system_noise_temperature_k != last_temperature_k) {
    last_temperature_k = system_noise_temperature_k;
    last_density = kBoltzmann_dbw_per_k_hz + 10.0 * std::log10(system_noise_temperature_k);
  }
  return last_density;
}

double block_power_offset_db(SatelliteBlock block, const Signal& signal) {
  // GPS L2C (the CM/CL rows and their sum): the ICD's -158.5 dBW for GPS III against the row's
  // -160.0, then what IIF and III deliver beyond the usual margin relative to IIR-M, fitted on
  // ESBC 2020-177 (PolaRx5) and tested on NYA1 2024-124 (NetR9): docs/validation.md.
  const bool gps_l2 = signal.system == GnssSystem::kGps && signal.band == '2';
  if (gps_l2 && std::string_view("SLX").find(signal.attribute) != std::string_view::npos) {
    switch (block) {
      case SatelliteBlock::kGpsIIF: return 2.9;
      case SatelliteBlock::kGpsIIIA: return 1.5 + 2.0;
      default: return 0.0;
    }
  }
  // GPS L2 P(Y): what each block delivers against the row's -161.5 dBW plus the usual margin. IIR-M
  // and IIF can raise their P(Y) power ("flex power", Steigenberger et al. 2019, GPS Solutions 23:8,
  // regional and switched by the operator), IIR and III transmit it near the minimum. Fitted on
  // ESBC 2020-177 (PolaRx5, G2W C/N0 per block after the squaring loss) and tested unchanged on
  // NYA1 2024-124 and SLAC 2021-118 (NetR9): docs/validation.md.
  if (gps_l2 && std::string_view("DPWY").find(signal.attribute) != std::string_view::npos) {
    switch (block) {
      case SatelliteBlock::kGpsIIRA:
      case SatelliteBlock::kGpsIIRB: return -4.1;
      case SatelliteBlock::kGpsIIRM: return 1.4;
      case SatelliteBlock::kGpsIIF: return 3.4;
      case SatelliteBlock::kGpsIIIA: return -2.8;
      default: return 0.0;
    }
  }
  return 0.0;
}

SatelliteLink::SatelliteLink(double range_m, double orbit_radius_m, double off_boresight_angle_deg)
    : range_m_(range_m),
      orbit_radius_m_(orbit_radius_m),
      off_boresight_gain_db_(satellite_antenna_gain_db(off_boresight_angle_deg, orbit_radius_m)) {}

namespace {
// Range, orbit radius and off-boresight angle (deg) of a satellite seen from a receiver.
std::array<double, 3> link_geometry(const Eigen::Vector3d& satellite_m, const Eigen::Vector3d& receiver_m) {
  const Eigen::Vector3d to_receiver = receiver_m - satellite_m;
  const double range_m = to_receiver.norm();
  const double orbit_radius_m = satellite_m.norm();
  const double cos_angle = std::clamp(-satellite_m.dot(to_receiver) / (orbit_radius_m * range_m), -1.0, 1.0);
  return {range_m, orbit_radius_m, std::acos(cos_angle) / kDeg};
}
}  // namespace

SatelliteLink::SatelliteLink(const Eigen::Vector3d& satellite_m, const Eigen::Vector3d& receiver_m)
    : SatelliteLink(link_geometry(satellite_m, receiver_m)) {}

SatelliteLink::SatelliteLink(const std::array<double, 3>& geometry)
    : SatelliteLink(geometry[0], geometry[1], geometry[2]) {}

double SatelliteLink::received_power_dbw(const SignalPowerSpec& spec) {
  if (spec.reference_elevation_deg != reference_elevation_deg_) {
    reference_elevation_deg_ = spec.reference_elevation_deg;
    reference_loss_ratio_db_ =
        20.0 * std::log10(slant_range_m(orbit_radius_m_, spec.reference_elevation_deg) / range_m_);
    reference_gain_db_ =
        satellite_antenna_gain_db(off_boresight_deg(orbit_radius_m_, spec.reference_elevation_deg), orbit_radius_m_);
  }
  return spec.minimum_dbw + spec.margin_db + reference_loss_ratio_db_ + off_boresight_gain_db_ - reference_gain_db_;
}

LinkBudget link_budget(const ReceiverProfile& profile, const TrackedSignal& signal, const Eigen::Vector3d& satellite_m,
                       const Eigen::Vector3d& receiver_m, double elevation_deg, double azimuth_deg,
                       double attenuation_db, double satellite_power_offset_db) {
  SatelliteLink link(satellite_m, receiver_m);
  return link_budget(profile, signal, link, elevation_deg, azimuth_deg, attenuation_db, satellite_power_offset_db);
}

LinkBudget link_budget(const ReceiverProfile& profile, const TrackedSignal& signal, SatelliteLink& link,
                       double elevation_deg, double azimuth_deg, double attenuation_db,
                       double satellite_power_offset_db) {
  std::optional<SignalPowerSpec> spec = signal_power_spec(signal.signal);
  if (!spec) spec = signal_power_spec(Signal{signal.signal.system, '1', 'C'});
  if (!spec) spec = SignalPowerSpec{-158.5, 5.0, kUsualMargin_db, "GPS L1 C/A"};
  LinkBudget b;
  b.received_power_dbw = link.received_power_dbw(*spec) + satellite_power_offset_db;
  const AntennaPattern& antenna = signal.antenna ? *signal.antenna : profile.antenna;
  b.antenna_gain_dbic = antenna.rhcp_dbic(elevation_deg, azimuth_deg);
  // The band response joins the signal's extra loss (both quarter-dB steps: the sum is exact, so a
  // response moved from a profile's extra loss into its antenna keeps the C/N0 to the bit).
  b.implementation_loss_db = profile.implementation_loss_db + (signal.extra_loss_db - signal.antenna_band_response_db);
  b.noise_density_dbw_per_hz = noise_density_dbw_per_hz(profile.system_noise_temperature_k);
  b.attenuation_db = attenuation_db;
  if (is_semicodeless(signal.signal)) {
    // The loss acts on the P(Y) signal as it reaches the correlators; the signal's extra loss is
    // then what the receiver's reporting adds or removes.
    const double before_squaring_dbhz = b.received_power_dbw + b.antenna_gain_dbic - profile.implementation_loss_db +
                                        signal.antenna_band_response_db - b.attenuation_db - b.noise_density_dbw_per_hz;
    b.squaring_loss_db = squaring_loss_db(before_squaring_dbhz, kWBitDuration_s);
  }
  return b;
}

}  // namespace skytrace::receiver
