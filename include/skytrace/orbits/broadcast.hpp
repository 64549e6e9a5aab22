// Satellite state from broadcast ephemerides, with ephemeris selection as receivers do it.
#pragma once

#include <optional>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "skytrace/core/signal.hpp"
#include "skytrace/orbits/ephemeris.hpp"
#include "skytrace/orbits/satellite_state.hpp"

namespace skytrace::orbits {

// Keplerian evaluation per system ICD (IS-GPS-200, Galileo OS SIS ICD, BDS-SIS-ICD including the
// GEO rotation for BeiDou GEO satellites, IS-QZSS-PNT, NavIC SPS ICD). t on the GPST timeline.
[[nodiscard]] SatelliteState evaluate_kepler(const KeplerEphemeris& eph, const GnssTime& t);
// GLONASS: 4th-order Runge-Kutta integration of the PZ-90 equations of motion (J2, Earth rotation,
// broadcast lunisolar acceleration) from t_b to t, GLONASS ICD 5.1 appendix A.3.1.2.
[[nodiscard]] SatelliteState evaluate_glonass(const GlonassEphemeris& eph, const GnssTime& t);
// SBAS: second-order polynomial of the broadcast state (RTCA DO-229).
[[nodiscard]] SatelliteState evaluate_sbas(const SbasEphemeris& eph, const GnssTime& t);

// True when the satellite is a BeiDou GEO (C01-C05, C59-C63).
[[nodiscard]] bool is_beidou_geo(const SatelliteId& satellite);

// Code group delay of `signal` relative to the clock reference of the ephemeris, in seconds: the
// amount the signal's code is late, so that pseudorange = ... - c (dt_sv - group_delay).
// GPS/QZSS: L1 C/A and L1 P(Y) T_GD, L2 P(Y) gamma T_GD (gamma = (f1/f2)^2), L2C T_GD - ISC_L2C,
// L5 T_GD - ISC_L5 (CNAV ISCs, zero when not broadcast). Galileo I/NAV: E1 BGD(E1,E5b), E5b
// (f1/f7)^2 BGD(E1,E5b); F/NAV: E1 BGD(E1,E5a), E5a (f1/f5)^2 BGD(E1,E5a). BeiDou D1/D2 (clock
// of B3I): B1I TGD1, B2I TGD2, B3I 0. NavIC: L5 T_GD, S (f5/fS)^2 T_GD.
[[nodiscard]] double group_delay_s(const KeplerEphemeris& eph, const Signal& signal);
// GLONASS FDMA: G1 0, G2 delta_tau_n when the file gives it, else 0.
[[nodiscard]] double group_delay_s(const GlonassEphemeris& eph, const Signal& signal);

// The navigation message whose clock and group delays belong to a signal (Galileo E5a -> F/NAV,
// E1/E5b -> I/NAV); nullopt when any message of the system serves.
[[nodiscard]] std::optional<NavMessage> preferred_message(const Signal& signal);

// Broadcast ephemerides of all systems, indexed per satellite.
class BroadcastEphemerides final : public SatelliteStateSource {
 public:
  explicit BroadcastEphemerides(NavigationData data);

  // The record a receiver would use at t: healthy, time of ephemeris closest to t and within the
  // system's validity window, of the requested message type when given (else any). Errors name the
  // satellite and time and say why none qualifies.
  [[nodiscard]] Result<const KeplerEphemeris*> select_kepler(const SatelliteId& satellite, const GnssTime& t,
                                                             std::optional<NavMessage> message = std::nullopt) const;
  [[nodiscard]] Result<const GlonassEphemeris*> select_glonass(const SatelliteId& satellite, const GnssTime& t) const;
  [[nodiscard]] Result<const SbasEphemeris*> select_sbas(const SatelliteId& satellite, const GnssTime& t) const;

  // State from the record selected for a signal (Galileo: I/NAV or F/NAV to match it).
  [[nodiscard]] Result<SatelliteState> state_for_signal(const SatelliteId& satellite, const Signal& signal,
                                                        const GnssTime& t) const;
  // Code group delay of the signal from the record selected for it.
  [[nodiscard]] Result<double> group_delay_for_signal(const SatelliteId& satellite, const Signal& signal,
                                                      const GnssTime& t) const;
  // GLONASS frequency channel k of a satellite from its records.
  [[nodiscard]] std::optional<int> glonass_channel(const SatelliteId& satellite) const;

  // SatelliteStateSource: the default record (Galileo prefers I/NAV).
  [[nodiscard]] Result<SatelliteState> state(const SatelliteId& satellite, const GnssTime& t) const override;
  [[nodiscard]] std::vector<SatelliteId> satellites() const override;
  [[nodiscard]] std::string_view name() const override { return "broadcast"; }

  [[nodiscard]] const NavigationData& data() const { return data_; }

 private:
  NavigationData data_;
  // Indices into data_ per satellite, sorted by toe.
  std::unordered_map<SatelliteId, std::vector<size_t>> kepler_index_;
  std::unordered_map<SatelliteId, std::vector<size_t>> glonass_index_;
  std::unordered_map<SatelliteId, std::vector<size_t>> sbas_index_;
};

// Maximum |t - toe| a receiver accepts per system and message (seconds).
[[nodiscard]] double validity_half_window_s(const KeplerEphemeris& eph);
[[nodiscard]] constexpr double glonass_validity_half_window_s() { return 1800.0 + 60.0; }
[[nodiscard]] constexpr double sbas_validity_half_window_s() { return 360.0; }

}  // namespace skytrace::orbits
