// Satellite state from broadcast ephemerides, with ephemeris selection as receivers do it.
#pragma once

#include <array>

#include <optional>
#include <span>
#include <cstdint>
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
// broadcast lunisolar acceleration) from t_b to t, GLONASS ICD 5.1 appendix A.3.1.2. More than a day
// from t_b gives a state of NaNs (never an unbounded integration).
[[nodiscard]] SatelliteState evaluate_glonass(const GlonassEphemeris& eph, const GnssTime& t);
// The same integration with the states at the full 60 s steps from t_b kept per record, so that a
// receiver evaluating the same record epoch after epoch integrates one partial step instead of up
// to fifteen full ones. Results are identical to evaluate_glonass (same steps in the same order).
// Not thread-safe: one per generator.
class GlonassOrbitCache {
 public:
  [[nodiscard]] SatelliteState evaluate(const GlonassEphemeris& eph, const GnssTime& t);

 private:
  struct Nodes {
    std::vector<std::array<double, 6>> forward{};   // [k]: after k steps of +60 s
    std::vector<std::array<double, 6>> backward{};  // [k]: after k steps of -60 s
  };
  std::unordered_map<const GlonassEphemeris*, Nodes> nodes_;
};
// SBAS: second-order polynomial of the broadcast state (RTCA DO-229).
[[nodiscard]] SatelliteState evaluate_sbas(const SbasEphemeris& eph, const GnssTime& t);

// True when the satellite is a BeiDou GEO (C01-C05, C59-C63).
[[nodiscard]] bool is_beidou_geo(const SatelliteId& satellite);

// Code group delay of `signal` relative to the clock reference of the ephemeris, in seconds: the
// amount the signal's code is late, so that pseudorange = ... - c (dt_sv - group_delay).
// GPS/QZSS: L1 C/A T_GD - ISC_L1CA, L1 P(Y) T_GD, L1C T_GD - ISC_L1CD/L1CP, L2 P(Y) gamma T_GD
// (gamma = (f1/f2)^2); from a CNAV record L2C T_GD - ISC_L2C and L5 T_GD - ISC_L5I5/L5Q5; from an
// LNAV record (no ISC) L2C gamma T_GD and L5 (f1/f5)^2 T_GD. Galileo I/NAV: E1 BGD(E1,E5b), E5b
// (f1/f7)^2 BGD(E1,E5b), E5a BGD(E1,E5b) + ((f1/f5)^2 - 1) BGD(E1,E5a); F/NAV: E1 BGD(E1,E5a),
// E5a (f1/f5)^2 BGD(E1,E5a), E5b BGD(E1,E5a) + ((f1/f7)^2 - 1) BGD(E1,E5b); E5 AltBOC the mean of
// E5a and E5b; E6 0. BeiDou (clock of B3I): B1I TGD1, B2I TGD2, B3I 0, B1C pilot TGD_B1Cp, data
// TGD_B1Cp + ISC_B1Cd, B2a pilot TGD_B2ap, data TGD_B2ap + ISC_B2ad, B2b TGD_B2bI (zero when the
// record does not carry them). NavIC: L5 T_GD, S (f5/fS)^2 T_GD. Signals with nothing broadcast: 0.
[[nodiscard]] double group_delay_s(const KeplerEphemeris& eph, const Signal& signal);
// The same, read as if the record were of `message` (an I/NAV record's BGDs read as F/NAV's).
[[nodiscard]] double group_delay_s(const KeplerEphemeris& eph, const Signal& signal, NavMessage message);
// GLONASS FDMA: G1 0, G2 delta_tau_n when the file gives it, else 0.
[[nodiscard]] double group_delay_s(const GlonassEphemeris& eph, const Signal& signal);

// The navigation message whose clock and group delays belong to a signal (Galileo E5a -> F/NAV,
// E1/E5b/E5 -> I/NAV; GPS/QZSS L2C and L5 -> CNAV, L1C -> CNAV-2; BeiDou B1C -> CNAV1,
// B2a -> CNAV2, B2b -> CNAV3); nullopt when any message of the system serves.
[[nodiscard]] std::optional<NavMessage> preferred_message(const Signal& signal);

// Whether a signal carries a navigation message, i.e. a receiver tracking it can decode it: GPS/QZSS
// LNAV on L1 C/A (P(Y) is encrypted), CNAV on L2C and L5, CNAV-2 on L1C; Galileo I/NAV on E1 and
// E5b, F/NAV on E5a, both on E5 AltBOC; BeiDou D1/D2 on B1I, B2I and B3I, CNAV1 on B1C, CNAV2 on
// B2a, CNAV3 on B2b; NavIC LNAV on every signal; GLONASS FDMA on L1 and L2; SBAS on every signal.
[[nodiscard]] bool signal_carries(const Signal& signal, NavMessage message);

// One usable record of a satellite as a receiver can come to hold it: its message, the span of
// receiver time over which ephemeris selection may pick it (toe -/+ the validity half window;
// Galileo from toe, as selection takes only records whose toe has passed) and when it was
// transmitted (transmission_time(), nullopt when the file does not say).
struct RecordAvailability {
  NavMessage message = NavMessage::kGpsLnav;
  GnssTime valid_from;
  GnssTime valid_until;
  std::optional<GnssTime> transmitted;
};

// Broadcast ephemerides of all systems, indexed per satellite.
class BroadcastEphemerides final : public SatelliteStateSource {
 public:
  explicit BroadcastEphemerides(NavigationData data);

  // The record a receiver would use at t: usable for the signals it wants (record_usable: one of
  // `wanted` healthy; any signal of the system when `wanted` names none of it), time of ephemeris
  // closest to t and within the system's validity window, of the requested message type when given
  // (else any). Errors name the satellite and time and say why none qualifies.
  [[nodiscard]] Result<const KeplerEphemeris*> select_kepler(const SatelliteId& satellite, const GnssTime& t,
                                                             std::optional<NavMessage> message = std::nullopt,
                                                             std::span<const Signal> wanted = {}) const;
  [[nodiscard]] Result<const GlonassEphemeris*> select_glonass(const SatelliteId& satellite, const GnssTime& t,
                                                               std::span<const Signal> wanted = {}) const;
  [[nodiscard]] Result<const SbasEphemeris*> select_sbas(const SatelliteId& satellite, const GnssTime& t,
                                                         std::span<const Signal> wanted = {}) const;
  // The same selections without building an explanation: nullptr when no record qualifies (for
  // per-epoch loops, where most misses are satellites simply not broadcasting to this station).
  [[nodiscard]] const KeplerEphemeris* find_kepler(const SatelliteId& satellite, const GnssTime& t,
                                                   std::optional<NavMessage> message = std::nullopt,
                                                   std::span<const Signal> wanted = {}) const;
  [[nodiscard]] const GlonassEphemeris* find_glonass(const SatelliteId& satellite, const GnssTime& t,
                                                     std::span<const Signal> wanted = {}) const;
  [[nodiscard]] const SbasEphemeris* find_sbas(const SatelliteId& satellite, const GnssTime& t,
                                               std::span<const Signal> wanted = {}) const;
  // Whether the receiver holds a record of the satellite usable for `wanted` at t (any message).
  [[nodiscard]] bool has_usable_record(const SatelliteId& satellite, const GnssTime& t,
                                       std::span<const Signal> wanted = {}) const;

  // State from the record selected for a signal: the preferred message (Galileo: I/NAV or F/NAV to
  // match it; BeiDou B1I/B2I/B3I: D1, or D2 for GEO), falling back to any message when none of the
  // preferred one qualifies.
  [[nodiscard]] Result<SatelliteState> state_for_signal(const SatelliteId& satellite, const Signal& signal,
                                                        const GnssTime& t) const;
  // Code group delay of the signal from the record selected for it.
  [[nodiscard]] Result<double> group_delay_for_signal(const SatelliteId& satellite, const Signal& signal,
                                                      const GnssTime& t) const;
  // The satellite's records usable for `wanted` of every message, in order of toe (Keplerian,
  // GLONASS, SBAS).
  [[nodiscard]] std::vector<RecordAvailability> record_availability(const SatelliteId& satellite,
                                                                    std::span<const Signal> wanted = {}) const;
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
  std::unordered_map<SatelliteId, std::vector<size_t>> glonass_index_;
  std::unordered_map<SatelliteId, std::vector<size_t>> sbas_index_;
  // The Keplerian records per satellite (indices into data_.kepler sorted by toe) and the largest
  // validity window among them (which bounds the search around t). find_kepler is asked at every
  // epoch for every signal: a satellite is found by its system and number, not by a hash.
  struct KeplerSatellite {
    SatelliteId satellite;
    std::vector<size_t> records;
    double max_window_s = 0.0;
    std::uint32_t messages = 0;  // bit m: a record of NavMessage m (a request for another finds none at once)
  };
  std::vector<KeplerSatellite> kepler_satellites_;
  std::vector<std::int32_t> kepler_slot_;  // system * 256 + number: index into kepler_satellites_, -1: none
  [[nodiscard]] const KeplerSatellite* kepler_satellite(const SatelliteId& satellite) const;
};

// Maximum |t - toe| a receiver accepts per system and message (seconds): GPS/QZSS half the fit
// interval and at least 2 h, Galileo 4 h, BeiDou 6 h, NavIC 2 h (never more than RTKLIB 2.4.3's
// MAXDTOE for GPS fit intervals up to 4 h, so it accepts the same record), GLONASS 30 min + 60 s,
// SBAS 360 s.
[[nodiscard]] double validity_half_window_s(const KeplerEphemeris& eph);
[[nodiscard]] constexpr double glonass_validity_half_window_s() { return 1800.0 + 60.0; }
[[nodiscard]] constexpr double sbas_validity_half_window_s() { return 360.0; }

// The span the records can serve: from the earliest reference time less its validity window to the
// latest plus its window; none without records. For plain messages when a run or an observation
// file lies outside it.
struct ServedSpan {
  GnssTime first, last;
};
[[nodiscard]] std::optional<ServedSpan> served_span(const NavigationData& nav);

}  // namespace skytrace::orbits
