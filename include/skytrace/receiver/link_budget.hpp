// C/N0 from a link budget: the power a satellite delivers (the ICD minimum received power plus
// the usual margin, scaled by the satellite antenna's off-boresight gain and the true range),
// the receiver antenna's gain, the implementation loss and the noise density k T_sys; minus the
// attenuation on the way (vegetation). Numbers and sources in docs/profiles.md.
#pragma once

#include <Eigen/Core>

#include <array>
#include <optional>
#include <string_view>

#include "skytrace/core/satellite_catalog.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {

// 10 log10(k), k = 1.380649e-23 J/K (Boltzmann).
inline constexpr double kBoltzmann_dbw_per_k_hz = -228.5991631;
// Mean Earth radius for the reference geometry of the ICD minima (receivers near the ground).
inline constexpr double kEarthRadiusMean_m = 6371000.0;

struct SignalPowerSpec {
  double minimum_dbw = 0.0;               // ICD minimum received power of the tracked component
  double reference_elevation_deg = 5.0;   // lowest elevation at which the ICD guarantees it
  double margin_db = 0.0;                 // usual excess of operational satellites over the minimum
  std::string_view source;                // document and paragraph
};

// The power specification of a signal; nullopt for signals without a public one (military, PRS).
[[nodiscard]] std::optional<SignalPowerSpec> signal_power_spec(const Signal& signal);

// The shaped beams of navigation satellites rise from nadir to the Earth's limb, compensating
// the longer path: GPS IIR-M/IIF L1 patterns (Marquis & Reigh 2015; Steigenberger et al. 2018)
// by about 2 dB; the published Galileo, GLONASS and BeiDou patterns are alike.
inline constexpr double kSatelliteLimbBoost_db = 2.0;

// Gain of the satellite's antenna at an angle off boresight (nadir), relative to its gain towards
// the limb: quadratic in the angle, -kSatelliteLimbBoost_db at nadir, flat beyond the limb.
[[nodiscard]] double satellite_antenna_gain_db(double off_boresight_deg, double orbit_radius_m);

// Range (m) from a receiver on a sphere of radius kEarthRadiusMean_m to a satellite at radius
// `orbit_radius_m` seen at `elevation_deg`, and the satellite's off-boresight angle (deg) there.
[[nodiscard]] double slant_range_m(double orbit_radius_m, double elevation_deg);
[[nodiscard]] double off_boresight_deg(double orbit_radius_m, double elevation_deg);

// Received power (dBW, into a 0 dBic antenna) at the true range and off-boresight angle: the
// minimum plus margin at the reference geometry, scaled by the free-space loss ratio and the
// satellite antenna's gain change.
[[nodiscard]] double received_power_dbw(const SignalPowerSpec& spec, double range_m, double orbit_radius_m,
                                        double off_boresight_angle_deg);

// Noise density (dBW/Hz) of a system noise temperature.
[[nodiscard]] double noise_density_dbw_per_hz(double system_noise_temperature_k);

// Semi-codeless tracking of the encrypted P(Y) code (GPS L1/L2, RINEX attributes W and D): the
// unknown W-code bits, 20 P-code chips (about 2 us) each, are estimated over one bit and wiped
// off, which squares the noise. The post-correlation C/N0 loses the squaring loss
// 10 log10(1 + 1 / (2 C/N0 T_w)) (Woo 2000, Navigation 47(2); Kaplan & Hegarty 2017, ch. 8): a few
// dB for strong signals, growing dB for dB below about 50 dB-Hz.
inline constexpr double kWBitDuration_s = 20.0 / 10.23e6;
[[nodiscard]] bool is_semicodeless(const Signal& signal);
// Squaring loss (dB, >= 0) at a pre-squaring C/N0 for a predetection time (s).
[[nodiscard]] double squaring_loss_db(double cn0_dbhz, double predetection_time_s);

// The terms of one signal's budget (dB).
struct LinkBudget {
  double received_power_dbw = 0.0;
  double antenna_gain_dbic = 0.0;
  double implementation_loss_db = 0.0;  // profile's loss plus the signal's extra loss less the antenna's band response
  double noise_density_dbw_per_hz = 0.0;
  double attenuation_db = 0.0;          // vegetation, ...
  double squaring_loss_db = 0.0;        // semi-codeless tracking only
  [[nodiscard]] double cn0_dbhz() const {
    return received_power_dbw + antenna_gain_dbic - implementation_loss_db - attenuation_db - squaring_loss_db -
           noise_density_dbw_per_hz;
  }
};

// The power a satellite generation delivers relative to its signal's row of the ICD table (dB,
// added to the received power). GPS L2C: the ICD minimum of GPS III (IS-GPS-200 Table 3-Vb,
// -158.5 dBW against -160.0 for IIR-M/IIF) and the measured surplus of IIF and III over IIR-M
// (docs/validation.md, "GPS L2C power per block"); GPS L2 P(Y): per block, IIR and III near the
// minimum, IIR-M and IIF above it (flex power; docs/validation.md, "GPS L2 P(Y) power per
// block"). 0 elsewhere.
[[nodiscard]] double block_power_offset_db(SatelliteBlock block, const Signal& signal);

// What the budgets of one satellite's signals share at an instant: the range, the orbit radius and
// the satellite antenna's gain towards the receiver, and the reference terms of the last reference
// elevation asked for (5 deg, 10 for Galileo and QZSS). The free received_power_dbw is this with
// the geometry given as numbers.
class SatelliteLink {
 public:
  SatelliteLink(const Eigen::Vector3d& satellite_m, const Eigen::Vector3d& receiver_m);
  SatelliteLink(double range_m, double orbit_radius_m, double off_boresight_angle_deg);
  [[nodiscard]] double received_power_dbw(const SignalPowerSpec& spec);

 private:
  explicit SatelliteLink(const std::array<double, 3>& geometry);  // range, orbit radius, angle
  double range_m_ = 0.0;
  double orbit_radius_m_ = 0.0;
  double off_boresight_gain_db_ = 0.0;
  double reference_elevation_deg_ = -1.0;  // none yet
  double reference_loss_ratio_db_ = 0.0;   // 20 log10(reference range / range)
  double reference_gain_db_ = 0.0;
};

// The budget of a signal from a satellite at `satellite_m` (ECEF) to a receiver at `receiver_m`
// seen at (elevation, azimuth), through `attenuation_db` of obstacles, from a satellite delivering
// `satellite_power_offset_db` more than its signal's row (block_power_offset_db). A signal
// without a power specification is treated like its system's L1 civil signal.
[[nodiscard]] LinkBudget link_budget(const ReceiverProfile& profile, const TrackedSignal& signal,
                                     const Eigen::Vector3d& satellite_m, const Eigen::Vector3d& receiver_m,
                                     double elevation_deg, double azimuth_deg, double attenuation_db,
                                     double satellite_power_offset_db = 0.0);
// The same with the satellite's shared terms (the same value to the bit).
[[nodiscard]] LinkBudget link_budget(const ReceiverProfile& profile, const TrackedSignal& signal, SatelliteLink& link,
                                     double elevation_deg, double azimuth_deg, double attenuation_db,
                                     double satellite_power_offset_db = 0.0);

}  // namespace skytrace::receiver
