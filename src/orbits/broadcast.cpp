// Broadcast ephemeris evaluation (Keplerian systems and SBAS), group delays and ephemeris selection.
// GLONASS integration lives in glonass_orbit.cpp.
#include "skytrace/orbits/broadcast.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include "skytrace/core/constants.hpp"
#include "skytrace/orbits/signal_health.hpp"

namespace skytrace::orbits {
namespace {

namespace k = skytrace::constants;

constexpr std::int64_t kSecondsPerWeek = 604800;
constexpr double kBdtMinusGpst_s = -14.0;

struct OrbitConstants {
  double gm_m3ps2;
  double earth_rotation_radps;
  double relativistic_f_s_per_sqrtm;  // F = -2 sqrt(GM) / c^2 as each ICD states it
};

OrbitConstants orbit_constants(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGalileo:  // OS SIS ICD 5.1.1 and 5.1.4: F = -4.442807309e-10
      return {k::kGmGalileo_m3ps2, k::kEarthRotationRateGalileo_radps, -4.442807309e-10};
    case GnssSystem::kBeiDou:  // BDS-SIS-ICD: CGCS2000 GM and rotation rate, same F as Galileo
      return {k::kGmBeiDou_m3ps2, k::kEarthRotationRateBeiDou_radps, -4.442807309e-10};
    default:  // GPS (IS-GPS-200), QZSS (IS-QZSS-PNT) and NavIC (SPS ICD) all use the WGS84 values
      return {k::kGmGps_m3ps2, k::kEarthRotationRateGps_radps, k::kRelativisticF_s_per_sqrtm};
  }
}

// Seconds of week of an instant in the system's own time scale: Omega0 is referred to the start of
// the system's week, so omega_e * toe needs toe counted from there. Only BDT is offset from GPST
// (GST, QZSST and IRNWT weeks start on GPST week boundaries).
double system_seconds_of_week(const GnssTime& t, GnssSystem system) {
  std::int64_t whole_s = t.whole_seconds();
  if (system == GnssSystem::kBeiDou) whole_s += static_cast<std::int64_t>(kBdtMinusGpst_s);
  std::int64_t sow_s = whole_s % kSecondsPerWeek;
  if (sow_s < 0) sow_s += kSecondsPerWeek;
  return static_cast<double>(sow_s) + t.fraction_s();
}

bool is_kepler_system(GnssSystem system) {
  return system == GnssSystem::kGps || system == GnssSystem::kGalileo || system == GnssSystem::kBeiDou ||
         system == GnssSystem::kQzss || system == GnssSystem::kNavic;
}

double squared(double x) { return x * x; }

std::string format_time(const GnssTime& t) { return t.to_iso8601(TimeScale::kGpst, t.fraction_s() == 0.0 ? 0 : 3); }

std::string format_hours(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f h", seconds / 3600.0);
  return buf;
}

double window_s(const KeplerEphemeris& e) { return validity_half_window_s(e); }
double window_s(const GlonassEphemeris&) { return glonass_validity_half_window_s(); }
double window_s(const SbasEphemeris&) { return sbas_validity_half_window_s(); }

std::string message_label(const KeplerEphemeris& e) { return std::string(to_string(e.message)); }
std::string message_label(const GlonassEphemeris&) { return "FDMA"; }
std::string message_label(const SbasEphemeris&) { return "SBAS"; }

// The record a receiver would use: among the records passing `accept`, the one whose toe is closest
// to t and within its validity window; on equal distance the later toe, and among records with the
// same toe the last one read. `index` is sorted by toe (stable, so file order within one toe).
template <typename Record, typename Accept>
const Record* select_nearest(const std::vector<Record>& records, const std::vector<size_t>& index,
                             const GnssTime& t, double max_window_s, Accept accept) {
  const auto first_later = std::lower_bound(index.begin(), index.end(), t,
                                            [&](size_t i, const GnssTime& time) { return records[i].toe < time; });
  const Record* forward = nullptr;
  double forward_distance_s = 0.0;
  for (auto it = first_later; it != index.end(); ++it) {
    const Record& r = records[*it];
    const double distance_s = r.toe - t;
    if (forward != nullptr && r.toe != forward->toe) break;
    if (distance_s > max_window_s) break;
    if (accept(r) && distance_s <= window_s(r)) {
      forward = &r;  // keep going: a later record with the same toe wins
      forward_distance_s = distance_s;
    }
  }
  const Record* backward = nullptr;
  double backward_distance_s = 0.0;
  for (auto it = first_later; it != index.begin();) {
    --it;
    const Record& r = records[*it];
    const double distance_s = t - r.toe;
    if (distance_s > max_window_s) break;
    if (accept(r) && distance_s <= window_s(r)) {
      backward = &r;
      backward_distance_s = distance_s;
      break;
    }
  }
  if (forward != nullptr && (backward == nullptr || forward_distance_s <= backward_distance_s)) return forward;
  return backward;
}

// Why no record qualifies, for the error message (slow path only).
template <typename Record, typename Accept>
Error explain_no_record(const std::vector<Record>& records, const std::vector<size_t>& index,
                        const SatelliteId& satellite, const GnssTime& t, std::string_view wanted, Accept accept) {
  const std::string sat = satellite.to_string();
  const std::string when = format_time(t) + " GPST";
  std::vector<const Record*> matching;
  for (size_t i : index) {
    if (accept(records[i])) matching.push_back(&records[i]);
  }
  if (matching.empty()) {
    std::string others;
    for (size_t i : index) {
      const std::string label = message_label(records[i]);
      if (others.find(label) == std::string::npos) others += (others.empty() ? "" : ", ") + label;
    }
    return make_error(ErrorCode::kNotFound, "no " + std::string(wanted) + " ephemeris for " + sat + " (its " +
                                                std::to_string(index.size()) + " record(s) are " + others + ")");
  }
  const Record* nearest_healthy = nullptr;
  size_t unhealthy_in_window = 0;
  int unhealthy_value = 0;
  for (const Record* r : matching) {
    const double distance_s = std::abs(r->toe - t);
    if (!record_usable(*r)) {
      if (distance_s <= window_s(*r)) {
        ++unhealthy_in_window;
        unhealthy_value = r->health;
      }
      continue;
    }
    if (nearest_healthy == nullptr || distance_s < std::abs(nearest_healthy->toe - t)) nearest_healthy = r;
  }
  const std::string prefix = wanted.empty() ? "" : std::string(wanted) + " ";
  if (nearest_healthy == nullptr) {
    return make_error(ErrorCode::kNotFound, "no healthy " + prefix + "ephemeris for " + sat + " at " + when +
                                                ": all " + std::to_string(matching.size()) +
                                                " records are unhealthy (health " + std::to_string(matching.back()->health) + ")");
  }
  std::string message = "no " + prefix + "ephemeris for " + sat + " at " + when + " (nearest healthy record toe " +
                        format_time(nearest_healthy->toe) + ", " + format_hours(std::abs(nearest_healthy->toe - t)) +
                        " away; limit " + format_hours(window_s(*nearest_healthy)) + ")";
  if (unhealthy_in_window > 0) {
    message += "; " + std::to_string(unhealthy_in_window) + " unhealthy record(s) within the limit (health " +
               std::to_string(unhealthy_value) + ")";
  }
  return make_error(ErrorCode::kOutOfRange, std::move(message));
}

template <typename Record>
std::unordered_map<SatelliteId, std::vector<size_t>> build_index(const std::vector<Record>& records) {
  std::unordered_map<SatelliteId, std::vector<size_t>> index;
  for (size_t i = 0; i < records.size(); ++i) index[records[i].satellite].push_back(i);
  for (auto& [satellite, indices] : index) {
    std::stable_sort(indices.begin(), indices.end(),
                     [&](size_t a, size_t b) { return records[a].toe < records[b].toe; });
  }
  return index;
}

template <typename Record>
double max_window_s(const std::vector<Record>& records, const std::vector<size_t>& indices) {
  double result_s = 0.0;
  for (size_t i : indices) result_s = std::max(result_s, window_s(records[i]));
  return result_s;
}

Error no_ephemeris_at_all(const SatelliteId& satellite) {
  return make_error(ErrorCode::kNotFound, "no ephemeris at all for " + satellite.to_string());
}

// The message to look for first for a signal of a satellite: the one that carries its clock and
// group delays (preferred_message), else Galileo I/NAV (the E1 default, as RTKLIB), else for
// BeiDou B1I/B2I/B3I the D1 (MEO/IGSO) or D2 (GEO) message, whose TGD1/TGD2 those signals need.
std::optional<NavMessage> message_for(const SatelliteId& satellite, const std::optional<Signal>& signal) {
  if (signal) {
    if (auto preferred = preferred_message(*signal)) return preferred;
  }
  if (satellite.system == GnssSystem::kGalileo) return NavMessage::kGalileoInav;
  if (satellite.system == GnssSystem::kBeiDou && signal) {
    const bool legacy = signal->band == '2' || signal->band == '6' ||
                        (signal->band == '7' && (signal->attribute == 'I' || signal->attribute == 'Q' ||
                                                 signal->attribute == 'X'));
    if (legacy) return is_beidou_geo(satellite) ? NavMessage::kBeiDouD2 : NavMessage::kBeiDouD1;
  }
  return std::nullopt;
}

// Preferred message first, then any message. When both fail, the any-message error says why
// (time window, health) without the noise of "no record of the preferred message".
Result<const KeplerEphemeris*> select_with_fallback(const BroadcastEphemerides& ephemerides,
                                                    const SatelliteId& satellite, const GnssTime& t,
                                                    std::optional<NavMessage> message,
                                                    std::span<const Signal> wanted = {}) {
  auto first = ephemerides.select_kepler(satellite, t, message, wanted);
  if (first.ok() || !message) return first;
  return ephemerides.select_kepler(satellite, t, std::nullopt, wanted);
}

Status check_signal(const SatelliteId& satellite, const Signal& signal) {
  if (signal.system != satellite.system) {
    return make_error(ErrorCode::kInvalidArgument,
                      "signal " + signal.to_string() + " does not belong to satellite " + satellite.to_string());
  }
  return Ok{};
}

}  // namespace

bool is_beidou_geo(const SatelliteId& satellite) {
  if (satellite.system != GnssSystem::kBeiDou) return false;
  return (satellite.number >= 1 && satellite.number <= 5) || (satellite.number >= 59 && satellite.number <= 63);
}

SatelliteState evaluate_kepler(const KeplerEphemeris& eph, const GnssTime& t) {
  const GnssSystem system = eph.satellite.system;
  const OrbitConstants c = orbit_constants(system);
  const double tk_s = t - eph.toe;

  // Semi-major axis and mean motion; A_dot and delta-n-dot are zero for legacy messages
  // (IS-GPS-200 30.3.3.1.3 for CNAV, BDS-SIS-ICD B1C 7.8 for B-CNAV).
  const double a0_m = eph.sqrt_a_sqrtm * eph.sqrt_a_sqrtm;
  const double a_m = a0_m + eph.a_dot_m_per_s * tk_s;
  const double n0_radps = std::sqrt(c.gm_m3ps2 / (a0_m * a0_m * a0_m));
  const double n_radps = n0_radps + eph.delta_n_rad_per_s + 0.5 * eph.delta_n_dot_rad_per_s2 * tk_s;
  const double mean_anomaly_rad = eph.m0_rad + n_radps * tk_s;
  const double mean_anomaly_rate_radps = n0_radps + eph.delta_n_rad_per_s + eph.delta_n_dot_rad_per_s2 * tk_s;

  // Kepler's equation by Newton iteration.
  const double e = eph.eccentricity;
  double ecc_anomaly_rad = mean_anomaly_rad;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const double step_rad = (ecc_anomaly_rad - e * std::sin(ecc_anomaly_rad) - mean_anomaly_rad) /
                            (1.0 - e * std::cos(ecc_anomaly_rad));
    ecc_anomaly_rad -= step_rad;
    if (std::abs(step_rad) < 1e-13) break;
  }
  const double sin_e = std::sin(ecc_anomaly_rad);
  const double cos_e = std::cos(ecc_anomaly_rad);
  const double one_minus_e_cos = 1.0 - e * cos_e;
  const double ecc_anomaly_rate_radps = mean_anomaly_rate_radps / one_minus_e_cos;
  const double sqrt_one_minus_e2 = std::sqrt(1.0 - e * e);
  const double true_anomaly_rad = std::atan2(sqrt_one_minus_e2 * sin_e, cos_e - e);
  const double true_anomaly_rate_radps = ecc_anomaly_rate_radps * sqrt_one_minus_e2 / one_minus_e_cos;

  // Second-harmonic corrections and their rates.
  const double phi_rad = true_anomaly_rad + eph.omega_rad;
  const double sin_2phi = std::sin(2.0 * phi_rad);
  const double cos_2phi = std::cos(2.0 * phi_rad);
  const double du_rad = eph.cus_rad * sin_2phi + eph.cuc_rad * cos_2phi;
  const double dr_m = eph.crs_m * sin_2phi + eph.crc_m * cos_2phi;
  const double di_rad = eph.cis_rad * sin_2phi + eph.cic_rad * cos_2phi;
  const double du_rate = 2.0 * true_anomaly_rate_radps * (eph.cus_rad * cos_2phi - eph.cuc_rad * sin_2phi);
  const double dr_rate_mps = 2.0 * true_anomaly_rate_radps * (eph.crs_m * cos_2phi - eph.crc_m * sin_2phi);
  const double di_rate = 2.0 * true_anomaly_rate_radps * (eph.cis_rad * cos_2phi - eph.cic_rad * sin_2phi);

  const double u_rad = phi_rad + du_rad;
  const double r_m = a_m * one_minus_e_cos + dr_m;
  const double inc_rad = eph.i0_rad + eph.idot_rad_per_s * tk_s + di_rad;
  const double u_rate_radps = true_anomaly_rate_radps + du_rate;
  const double r_rate_mps = a_m * e * sin_e * ecc_anomaly_rate_radps + dr_rate_mps + eph.a_dot_m_per_s * one_minus_e_cos;
  const double inc_rate_radps = eph.idot_rad_per_s + di_rate;

  // Position and velocity in the orbital plane.
  const double sin_u = std::sin(u_rad);
  const double cos_u = std::cos(u_rad);
  const double xp_m = r_m * cos_u;
  const double yp_m = r_m * sin_u;
  const double xp_rate_mps = r_rate_mps * cos_u - yp_m * u_rate_radps;
  const double yp_rate_mps = r_rate_mps * sin_u + xp_m * u_rate_radps;

  // Longitude of the ascending node. BeiDou GEO: in the inertial-like frame of the ICD (no Earth
  // rotation over tk yet), rotated below.
  const bool geo = is_beidou_geo(eph.satellite);
  const double toe_sow_s = system_seconds_of_week(eph.toe, system);
  const double node_rate_radps =
      geo ? eph.omega_dot_rad_per_s : eph.omega_dot_rad_per_s - c.earth_rotation_radps;
  const double node_rad = eph.omega0_rad + node_rate_radps * tk_s - c.earth_rotation_radps * toe_sow_s;

  const double sin_node = std::sin(node_rad);
  const double cos_node = std::cos(node_rad);
  const double sin_i = std::sin(inc_rad);
  const double cos_i = std::cos(inc_rad);
  Eigen::Vector3d position_m(xp_m * cos_node - yp_m * cos_i * sin_node, xp_m * sin_node + yp_m * cos_i * cos_node,
                             yp_m * sin_i);
  Eigen::Vector3d velocity_mps(
      xp_rate_mps * cos_node - yp_rate_mps * cos_i * sin_node + yp_m * sin_i * sin_node * inc_rate_radps -
          position_m.y() * node_rate_radps,
      xp_rate_mps * sin_node + yp_rate_mps * cos_i * cos_node - yp_m * sin_i * cos_node * inc_rate_radps +
          position_m.x() * node_rate_radps,
      yp_rate_mps * sin_i + yp_m * cos_i * inc_rate_radps);

  if (geo) {
    // BDS-SIS-ICD 5.2.4.12: [X Y Z] = R_Z(omega_e tk) R_X(-5 deg) [X_GK Y_GK Z_GK], with
    // R_X(phi) = [1 0 0; 0 cos sin; 0 -sin cos] and R_Z(phi) = [cos sin 0; -sin cos 0; 0 0 1].
    constexpr double kTilt_rad = -5.0 * k::kPi / 180.0;
    const double sin_tilt = std::sin(kTilt_rad);
    const double cos_tilt = std::cos(kTilt_rad);
    const double spin_rad = c.earth_rotation_radps * tk_s;
    const double sin_spin = std::sin(spin_rad);
    const double cos_spin = std::cos(spin_rad);
    Eigen::Matrix3d rx;
    rx << 1.0, 0.0, 0.0, 0.0, cos_tilt, sin_tilt, 0.0, -sin_tilt, cos_tilt;
    Eigen::Matrix3d rz;
    rz << cos_spin, sin_spin, 0.0, -sin_spin, cos_spin, 0.0, 0.0, 0.0, 1.0;
    Eigen::Matrix3d rz_rate;  // d R_Z / dt
    rz_rate << -sin_spin, cos_spin, 0.0, -cos_spin, -sin_spin, 0.0, 0.0, 0.0, 0.0;
    rz_rate *= c.earth_rotation_radps;
    const Eigen::Vector3d tilted_m = rx * position_m;
    velocity_mps = rz * (rx * velocity_mps) + rz_rate * tilted_m;
    position_m = rz * tilted_m;
  }

  SatelliteState state;
  state.position_m = position_m;
  state.velocity_mps = velocity_mps;
  const double dt_clock_s = t - eph.toc;
  state.clock_bias_s = eph.af0_s + eph.af1_s_per_s * dt_clock_s + eph.af2_s_per_s2 * dt_clock_s * dt_clock_s;
  state.clock_drift_s_per_s = eph.af1_s_per_s + 2.0 * eph.af2_s_per_s2 * dt_clock_s;
  const double rel_scale_s = c.relativistic_f_s_per_sqrtm * e * eph.sqrt_a_sqrtm;
  state.relativistic_s = rel_scale_s * sin_e;
  state.relativistic_drift_s_per_s = rel_scale_s * cos_e * ecc_anomaly_rate_radps;
  return state;
}

SatelliteState evaluate_sbas(const SbasEphemeris& eph, const GnssTime& t) {
  const double dt_s = t - eph.toe;
  SatelliteState state;
  state.position_m = eph.position_m + eph.velocity_mps * dt_s + 0.5 * eph.acceleration_mps2 * dt_s * dt_s;
  state.velocity_mps = eph.velocity_mps + eph.acceleration_mps2 * dt_s;
  state.clock_bias_s = eph.agf0_s + eph.agf1_s_per_s * dt_s;
  state.clock_drift_s_per_s = eph.agf1_s_per_s;
  return state;
}

double group_delay_s(const KeplerEphemeris& eph, const Signal& signal) {
  return group_delay_s(eph, signal, eph.message);
}

double group_delay_s(const KeplerEphemeris& eph, const Signal& signal, NavMessage message) {
  const GroupDelays& g = eph.group_delays;
  const char band = signal.band;
  const char attribute = signal.attribute;
  switch (eph.satellite.system) {
    case GnssSystem::kGps:
    case GnssSystem::kQzss: {
      // IS-GPS-200 20.3.3.3.3.2 and 30.3.3.3.1.1, IS-GPS-705 20.3.3.3.1.2, IS-GPS-800 3.5.3.9:
      // (dt_sv)_signal = dt_sv - T_GD + ISC_signal, i.e. the signal's code is late by T_GD - ISC.
      const bool cnav = is_cnav(message);
      if (band == '1') {
        if (attribute == 'C') return g.tgd_s - g.isc_l1ca_s;
        if (attribute == 'S') return g.tgd_s - g.isc_l1cd_s;
        if (attribute == 'L' || attribute == 'X') return g.tgd_s - g.isc_l1cp_s;
        return g.tgd_s;  // P(Y), M, codeless: T_GD is defined on L1 P(Y)
      }
      if (band == '2') {
        const bool l2c = attribute == 'S' || attribute == 'L' || attribute == 'X';
        if (l2c && cnav) return g.tgd_s - g.isc_l2c_s;
        // L2 P(Y), and L2C from an LNAV record (no ISC broadcast): gamma T_GD, which keeps the
        // L1/L2 ionosphere-free combination free of group delay as the clock definition requires.
        return squared(kFrequencyL1_Hz / kFrequencyL2_Hz) * g.tgd_s;
      }
      if (band == '5') {
        if (cnav) return g.tgd_s - (attribute == 'I' ? g.isc_l5i5_s : g.isc_l5q5_s);
        // LNAV gives nothing for L5: scale T_GD as for L2 P(Y) (zero ISC in the frequency sense).
        return squared(kFrequencyL1_Hz / kFrequencyL5_Hz) * g.tgd_s;
      }
      return 0.0;  // QZSS L6 / other: nothing broadcast
    }
    case GnssSystem::kGalileo: {
      // OS SIS ICD 5.1.5: BGD(E1,E5x) = (t_E1 - t_E5x) / (1 - gamma_1x), gamma_1x = (f_E1 / f_E5x)^2;
      // the I/NAV clock is the E1/E5b ionosphere-free clock, the F/NAV clock the E1/E5a one.
      // A signal's code is late, relative to the ionosphere-free reference of (E1, E5x), by BGD(E1,E5x)
      // on E1 and gamma_1x BGD(E1,E5x) on E5x. For the "other" E5 signal we add its delay relative to
      // E1: t_E5y - t_E1 = (gamma_1y - 1) BGD(E1,E5y). Hence, from an I/NAV record,
      //   E5a: BGD(E1,E5b) + (gamma_15 - 1) BGD(E1,E5a),
      // and from an F/NAV record,
      //   E5b: BGD(E1,E5a) + (gamma_17 - 1) BGD(E1,E5b)  (F/NAV broadcasts no BGD(E1,E5b): it is 0
      //   in the record, so this falls back to BGD(E1,E5a)).
      const double gamma15 = squared(kFrequencyL1_Hz / kFrequencyL5_Hz);
      const double gamma17 = squared(kFrequencyL1_Hz / kFrequencyE5b_Hz);
      const bool fnav = message == NavMessage::kGalileoFnav;
      const double reference_bgd_s = fnav ? g.bgd_e1e5a_s : g.bgd_e1e5b_s;
      const double e5a_s = fnav ? gamma15 * g.bgd_e1e5a_s : g.bgd_e1e5b_s + (gamma15 - 1.0) * g.bgd_e1e5a_s;
      const double e5b_s = fnav ? g.bgd_e1e5a_s + (gamma17 - 1.0) * g.bgd_e1e5b_s : gamma17 * g.bgd_e1e5b_s;
      switch (band) {
        case '1': return reference_bgd_s;
        case '5': return e5a_s;
        case '7': return e5b_s;
        case '8': return 0.5 * (e5a_s + e5b_s);  // AltBOC: no broadcast value; mean of its two sidebands
        default: return 0.0;                     // E6: nothing broadcast
      }
    }
    case GnssSystem::kBeiDou: {
      // Clock reference B3I. BDS-SIS-ICD B1I/B3I 5.2.4.10: B1I TGD1, B2I TGD2. B1C ICD 7.6 and
      // B2a ICD 7.6: (dt_sv)_B1Cd = dt_sv - (ISC_B1Cd + TGD_B1Cp), pilots TGD alone; B2b TGD_B2bI.
      switch (band) {
        case '2': return g.tgd1_s;
        case '6': return 0.0;
        case '1':
          if (attribute == 'D') return g.tgd_b1cp_s + g.isc_b1cd_s;
          if (attribute == 'P' || attribute == 'X') return g.tgd_b1cp_s;
          return 0.0;
        case '5':
          if (attribute == 'D') return g.tgd_b2ap_s + g.isc_b2ad_s;
          return g.tgd_b2ap_s;
        case '7':
          if (attribute == 'I' || attribute == 'Q' || attribute == 'X') return g.tgd2_s;
          return g.tgd_b2bi_s;
        default: return 0.0;  // B2a+b AltBOC: nothing broadcast
      }
    }
    case GnssSystem::kNavic: {
      // NavIC SPS ICD: T_GD as GPS defines it with L5 in the role of L1, gamma = (f_L5 / f_S)^2.
      if (band == '5') return g.tgd_s;
      if (band == '9') return squared(kFrequencyL5_Hz / kFrequencyNavicS_Hz) * g.tgd_s;
      return 0.0;
    }
    default: return 0.0;
  }
}

double group_delay_s(const GlonassEphemeris& eph, const Signal& signal) {
  // ICD 5.1: tau_n refers to the L1 signal; delta_tau_n = t_f2 - t_f1 is how much later L2 leaves.
  if (signal.band == '2') return eph.delta_tau_n_s.value_or(0.0);
  return 0.0;
}

std::optional<NavMessage> preferred_message(const Signal& signal) {
  switch (signal.system) {
    case GnssSystem::kGalileo:
      if (signal.band == '5') return NavMessage::kGalileoFnav;
      if (signal.band == '1' || signal.band == '7' || signal.band == '8') return NavMessage::kGalileoInav;
      return std::nullopt;
    case GnssSystem::kGps:
    case GnssSystem::kQzss: {
      // The messages whose ISCs the modernised signals need; L1 C/A and P(Y) take any.
      const bool qzss = signal.system == GnssSystem::kQzss;
      const bool l1c = signal.band == '1' && (signal.attribute == 'S' || signal.attribute == 'L' || signal.attribute == 'X');
      const bool l2c = signal.band == '2' && (signal.attribute == 'S' || signal.attribute == 'L' || signal.attribute == 'X');
      if (l1c) return qzss ? NavMessage::kQzssCnav2 : NavMessage::kGpsCnav2;
      if (l2c || signal.band == '5') return qzss ? NavMessage::kQzssCnav : NavMessage::kGpsCnav;
      return std::nullopt;
    }
    case GnssSystem::kBeiDou:
      if (signal.band == '1' && (signal.attribute == 'D' || signal.attribute == 'P' || signal.attribute == 'X'))
        return NavMessage::kBeiDouCnav1;
      if (signal.band == '5') return NavMessage::kBeiDouCnav2;
      if (signal.band == '7' && (signal.attribute == 'D' || signal.attribute == 'P' || signal.attribute == 'Z'))
        return NavMessage::kBeiDouCnav3;
      return std::nullopt;
    default: return std::nullopt;
  }
}

bool signal_carries(const Signal& signal, NavMessage message) {
  using S = GnssSystem;
  const char band = signal.band;
  const char attribute = signal.attribute;
  const auto attribute_in = [&](std::string_view set) { return set.find(attribute) != std::string_view::npos; };
  const bool gps_like = signal.system == S::kGps || signal.system == S::kQzss;
  const bool is_qzss = signal.system == S::kQzss;
  switch (message) {
    case NavMessage::kGpsLnav:
    case NavMessage::kQzssLnav:
      return gps_like && is_qzss == (message == NavMessage::kQzssLnav) && band == '1' && attribute == 'C';
    case NavMessage::kGpsCnav:
    case NavMessage::kQzssCnav:
      return gps_like && is_qzss == (message == NavMessage::kQzssCnav) &&
             ((band == '2' && attribute_in("SLX")) || (band == '5' && attribute_in("IQX")));
    case NavMessage::kGpsCnav2:
    case NavMessage::kQzssCnav2:
      return gps_like && is_qzss == (message == NavMessage::kQzssCnav2) && band == '1' && attribute_in("SLX");
    case NavMessage::kGalileoInav: return signal.system == S::kGalileo && (band == '1' || band == '7' || band == '8');
    case NavMessage::kGalileoFnav: return signal.system == S::kGalileo && (band == '5' || band == '8');
    case NavMessage::kBeiDouD1:
    case NavMessage::kBeiDouD2:
      return signal.system == S::kBeiDou && (band == '2' || band == '6' || band == '7') && attribute_in("IQX");
    case NavMessage::kBeiDouCnav1: return signal.system == S::kBeiDou && band == '1' && attribute_in("DPX");
    case NavMessage::kBeiDouCnav2: return signal.system == S::kBeiDou && band == '5';
    case NavMessage::kBeiDouCnav3: return signal.system == S::kBeiDou && band == '7' && attribute_in("DPZ");
    case NavMessage::kNavicLnav: return signal.system == S::kNavic;
    case NavMessage::kGlonassFdma: return signal.system == S::kGlonass && (band == '1' || band == '2');
    case NavMessage::kSbas: return signal.system == S::kSbas;
  }
  return false;
}

std::optional<ServedSpan> served_span(const NavigationData& nav) {
  std::optional<ServedSpan> span;
  const auto extend = [&](const GnssTime& toe, double half_window_s) {
    const GnssTime a = toe - half_window_s, b = toe + half_window_s;
    if (!span) span = ServedSpan{a, b};
    if (a < span->first) span->first = a;
    if (span->last < b) span->last = b;
  };
  for (const auto& e : nav.kepler) extend(e.toe, validity_half_window_s(e));
  for (const auto& e : nav.glonass) extend(e.toe, glonass_validity_half_window_s());
  for (const auto& e : nav.sbas) extend(e.toe, sbas_validity_half_window_s());
  return span;
}

double validity_half_window_s(const KeplerEphemeris& eph) {
  // RTKLIB 2.4.3 MAXDTOE*: GPS 7200, QZSS 7200, Galileo 14400, BeiDou 21600, NavIC 7200 s; a
  // narrower window here only makes a satellite absent where RTKLIB would still accept it.
  switch (eph.satellite.system) {
    case GnssSystem::kGps:
    case GnssSystem::kQzss:
      // IS-GPS-200 20.3.4.4: the record fits over its fit interval centred on toe (4 h nominal).
      return std::max(7200.0, eph.fit_interval_h * 3600.0 / 2.0);
    case GnssSystem::kGalileo: return 14400.0;  // nominal validity of a Galileo data set: 4 h
    // BeiDou uploads a new data set every hour and the ICD states no fit interval; a tracking
    // receiver never holds one older than that. Farther out the BDS-2 orbits degrade to tens of
    // metres (50-120 m at 5 h on 2016-06-06 against GFZ's orbits), so records are not stretched to
    // RTKLIB's 6 h.
    case GnssSystem::kBeiDou: return 3600.0;
    case GnssSystem::kNavic: return 7200.0;
    default: return 7200.0;
  }
}

BroadcastEphemerides::BroadcastEphemerides(NavigationData data) : data_(std::move(data)) {
  glonass_index_ = build_index(data_.glonass);
  sbas_index_ = build_index(data_.sbas);
  kepler_slot_.assign(kAllSystems.size() * 256, -1);
  for (auto& [satellite, indices] : build_index(data_.kepler)) {
    kepler_slot_[static_cast<size_t>(satellite.system) * 256 + satellite.number] =
        static_cast<std::int32_t>(kepler_satellites_.size());
    const double max_window = max_window_s(data_.kepler, indices);
    std::uint32_t messages = 0;
    for (size_t i : indices) messages |= 1U << static_cast<unsigned>(data_.kepler[i].message);
    kepler_satellites_.push_back(KeplerSatellite{satellite, std::move(indices), max_window, messages});
  }
}

const BroadcastEphemerides::KeplerSatellite* BroadcastEphemerides::kepler_satellite(const SatelliteId& satellite) const {
  const std::int32_t slot = kepler_slot_[static_cast<size_t>(satellite.system) * 256 + satellite.number];
  return slot < 0 ? nullptr : &kepler_satellites_[static_cast<size_t>(slot)];
}

const KeplerEphemeris* BroadcastEphemerides::find_kepler(const SatelliteId& satellite, const GnssTime& t,
                                                          std::optional<NavMessage> message,
                                                          std::span<const Signal> wanted) const {
  const KeplerSatellite* records = kepler_satellite(satellite);
  if (records == nullptr) return nullptr;
  static_assert(static_cast<unsigned>(NavMessage::kSbas) < 32, "KeplerSatellite::messages has 32 bits");
  if (message && (records->messages & (1U << static_cast<unsigned>(*message))) == 0) return nullptr;
  // A Galileo data set is first broadcast after its toe (the age of data is never negative), so a
  // receiver at t can only hold records with toe < t; RTKLIB applies the same rule.
  const bool toe_must_be_past = satellite.system == GnssSystem::kGalileo;
  const auto accept = [&](const KeplerEphemeris& e) {
    return record_usable(e, wanted) && (!message || e.message == *message) && (!toe_must_be_past || e.toe < t);
  };
  return select_nearest(data_.kepler, records->records, t, records->max_window_s, accept);
}

std::vector<RecordAvailability> BroadcastEphemerides::record_availability(const SatelliteId& satellite,
                                                                           std::span<const Signal> wanted) const {
  std::vector<RecordAvailability> out;
  if (const KeplerSatellite* kepler = kepler_satellite(satellite)) {
    const bool toe_must_be_past = satellite.system == GnssSystem::kGalileo;  // as find_kepler
    for (size_t i : kepler->records) {
      const KeplerEphemeris& e = data_.kepler[i];
      if (!record_usable(e, wanted)) continue;
      const double w = window_s(e);
      out.push_back({e.message, toe_must_be_past ? e.toe : e.toe - w, e.toe + w, transmission_time(e)});
    }
  }
  if (const auto it = glonass_index_.find(satellite); it != glonass_index_.end()) {
    for (size_t i : it->second) {
      const GlonassEphemeris& g = data_.glonass[i];
      if (!record_usable(g, wanted)) continue;
      const double w = window_s(g);
      out.push_back({NavMessage::kGlonassFdma, g.toe - w, g.toe + w, transmission_time(g)});
    }
  }
  if (const auto it = sbas_index_.find(satellite); it != sbas_index_.end()) {
    for (size_t i : it->second) {
      const SbasEphemeris& r = data_.sbas[i];
      if (!record_usable(r, wanted)) continue;
      const double w = window_s(r);
      out.push_back({NavMessage::kSbas, r.toe - w, r.toe + w, transmission_time(r)});
    }
  }
  return out;
}

const GlonassEphemeris* BroadcastEphemerides::find_glonass(const SatelliteId& satellite, const GnssTime& t,
                                                            std::span<const Signal> wanted) const {
  const auto it = glonass_index_.find(satellite);
  if (it == glonass_index_.end()) return nullptr;
  const auto accept = [&](const GlonassEphemeris& e) { return record_usable(e, wanted); };
  return select_nearest(data_.glonass, it->second, t, glonass_validity_half_window_s(), accept);
}

const SbasEphemeris* BroadcastEphemerides::find_sbas(const SatelliteId& satellite, const GnssTime& t,
                                                      std::span<const Signal> wanted) const {
  const auto it = sbas_index_.find(satellite);
  if (it == sbas_index_.end()) return nullptr;
  const auto accept = [&](const SbasEphemeris& e) { return record_usable(e, wanted); };
  return select_nearest(data_.sbas, it->second, t, sbas_validity_half_window_s(), accept);
}

Result<const KeplerEphemeris*> BroadcastEphemerides::select_kepler(const SatelliteId& satellite, const GnssTime& t,
                                                                   std::optional<NavMessage> message,
                                                                   std::span<const Signal> wanted) const {
  if (const KeplerEphemeris* found = find_kepler(satellite, t, message, wanted)) return found;
  const KeplerSatellite* kepler = kepler_satellite(satellite);
  if (kepler == nullptr) return no_ephemeris_at_all(satellite);
  const std::string_view wanted_message = message ? to_string(*message) : "";
  const auto matches = [&](const KeplerEphemeris& e) { return !message || e.message == *message; };
  if (satellite.system == GnssSystem::kGalileo) {
    const auto matches_past = [&](const KeplerEphemeris& e) { return matches(e) && e.toe < t; };
    const auto& indices = kepler->records;
    const bool any_match = std::any_of(indices.begin(), indices.end(), [&](size_t i) { return matches(data_.kepler[i]); });
    const bool any_past = std::any_of(indices.begin(), indices.end(), [&](size_t i) { return matches_past(data_.kepler[i]); });
    if (any_match && !any_past) {
      return make_error(ErrorCode::kOutOfRange, "no " + std::string(wanted_message) + (wanted_message.empty() ? "" : " ") +
                                                    "ephemeris for " + satellite.to_string() + " at " + format_time(t) +
                                                    " GPST: every record has its toe at or after that time (Galileo data "
                                                    "sets are transmitted after their toe)");
    }
    return explain_no_record(data_.kepler, indices, satellite, t, wanted_message, matches_past);
  }
  return explain_no_record(data_.kepler, kepler->records, satellite, t, wanted_message, matches);
}

Result<const GlonassEphemeris*> BroadcastEphemerides::select_glonass(const SatelliteId& satellite,
                                                                     const GnssTime& t,
                                                                     std::span<const Signal> wanted) const {
  if (const GlonassEphemeris* found = find_glonass(satellite, t, wanted)) return found;
  const auto it = glonass_index_.find(satellite);
  if (it == glonass_index_.end()) return no_ephemeris_at_all(satellite);
  return explain_no_record(data_.glonass, it->second, satellite, t, "", [](const GlonassEphemeris&) { return true; });
}

Result<const SbasEphemeris*> BroadcastEphemerides::select_sbas(const SatelliteId& satellite, const GnssTime& t,
                                                               std::span<const Signal> wanted) const {
  if (const SbasEphemeris* found = find_sbas(satellite, t, wanted)) return found;
  const auto it = sbas_index_.find(satellite);
  if (it == sbas_index_.end()) return no_ephemeris_at_all(satellite);
  return explain_no_record(data_.sbas, it->second, satellite, t, "", [](const SbasEphemeris&) { return true; });
}

Result<SatelliteState> BroadcastEphemerides::state_for_signal(const SatelliteId& satellite, const Signal& signal,
                                                              const GnssTime& t) const {
  if (auto valid = check_signal(satellite, signal); !valid.ok()) return valid.error();
  const std::span<const Signal> wanted(&signal, 1);
  if (satellite.system == GnssSystem::kGlonass) {
    auto record = select_glonass(satellite, t, wanted);
    if (!record.ok()) return record.error();
    return evaluate_glonass(**record, t);
  }
  if (satellite.system == GnssSystem::kSbas) {
    auto record = select_sbas(satellite, t, wanted);
    if (!record.ok()) return record.error();
    return evaluate_sbas(**record, t);
  }
  auto record = select_with_fallback(*this, satellite, t, message_for(satellite, signal), wanted);
  if (!record.ok()) return record.error();
  return evaluate_kepler(**record, t);
}

Result<double> BroadcastEphemerides::group_delay_for_signal(const SatelliteId& satellite, const Signal& signal,
                                                            const GnssTime& t) const {
  if (auto valid = check_signal(satellite, signal); !valid.ok()) return valid.error();
  const std::span<const Signal> wanted(&signal, 1);
  if (satellite.system == GnssSystem::kGlonass) {
    auto record = select_glonass(satellite, t, wanted);
    if (!record.ok()) return record.error();
    return group_delay_s(**record, signal);
  }
  if (satellite.system == GnssSystem::kSbas) {
    auto record = select_sbas(satellite, t, wanted);
    if (!record.ok()) return record.error();
    return 0.0;  // SBAS broadcasts no group delay: a_Gf0 refers to its L1 signal
  }
  auto record = select_with_fallback(*this, satellite, t, message_for(satellite, signal), wanted);
  if (!record.ok()) return record.error();
  return group_delay_s(**record, signal);
}

bool BroadcastEphemerides::has_usable_record(const SatelliteId& satellite, const GnssTime& t,
                                             std::span<const Signal> wanted) const {
  switch (satellite.system) {
    case GnssSystem::kGlonass: return find_glonass(satellite, t, wanted) != nullptr;
    case GnssSystem::kSbas: return find_sbas(satellite, t, wanted) != nullptr;
    default: return find_kepler(satellite, t, std::nullopt, wanted) != nullptr;
  }
}

std::optional<int> BroadcastEphemerides::glonass_channel(const SatelliteId& satellite) const {
  const auto it = glonass_index_.find(satellite);
  if (it == glonass_index_.end() || it->second.empty()) return std::nullopt;
  return data_.glonass[it->second.back()].frequency_channel;
}

Result<SatelliteState> BroadcastEphemerides::state(const SatelliteId& satellite, const GnssTime& t) const {
  switch (satellite.system) {
    case GnssSystem::kGlonass: {
      auto record = select_glonass(satellite, t);
      if (!record.ok()) return record.error();
      return evaluate_glonass(**record, t);
    }
    case GnssSystem::kSbas: {
      auto record = select_sbas(satellite, t);
      if (!record.ok()) return record.error();
      return evaluate_sbas(**record, t);
    }
    default: {
      if (!is_kepler_system(satellite.system)) return no_ephemeris_at_all(satellite);
      auto record = select_with_fallback(*this, satellite, t, message_for(satellite, std::nullopt));
      if (!record.ok()) return record.error();
      return evaluate_kepler(**record, t);
    }
  }
}

std::vector<SatelliteId> BroadcastEphemerides::satellites() const {
  std::vector<SatelliteId> result;
  result.reserve(kepler_satellites_.size() + glonass_index_.size() + sbas_index_.size());
  for (const KeplerSatellite& kepler : kepler_satellites_) result.push_back(kepler.satellite);
  for (const auto& [satellite, indices] : glonass_index_) result.push_back(satellite);
  for (const auto& [satellite, indices] : sbas_index_) result.push_back(satellite);
  std::sort(result.begin(), result.end());
  result.erase(std::unique(result.begin(), result.end()), result.end());
  return result;
}

}  // namespace skytrace::orbits
