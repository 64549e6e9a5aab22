#include "skytrace/positioning/spp.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/constants.hpp"

namespace skytrace::positioning {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;
// Sagnac with the WGS84 rate for every system, as the observation generator applies it.
constexpr double kEarthRotation_radps = constants::kEarthRotationRateGps_radps;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
// Below this distance from the Earth's centre the estimate is not yet a place on the Earth: no
// elevation, mask or atmosphere (the first iterations from the Earth's centre).
constexpr double kMinPositionRadius_m = 6.0e6;
constexpr int kMaxSystems = static_cast<int>(kAllSystems.size());

// The broadcast records a receiver holds for one satellite and signal.
struct Records {
  const orbits::KeplerEphemeris* orbit_kepler = nullptr;  // orbit (and clock unless clock_kepler)
  const orbits::KeplerEphemeris* clock_kepler = nullptr;  // clock and group delay of the signal
  const orbits::GlonassEphemeris* glonass = nullptr;
  const orbits::SbasEphemeris* sbas = nullptr;
};

bool is_beidou_legacy(const Signal& signal) {
  return signal.system == GnssSystem::kBeiDou &&
         (signal.band == '2' || signal.band == '6' ||
          (signal.band == '7' && (signal.attribute == 'I' || signal.attribute == 'Q' || signal.attribute == 'X')));
}

// Records qualify when the signal they are used for is healthy in them (orbits::record_usable).
const orbits::KeplerEphemeris* find_with_fallback(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                                  const GnssTime& t, std::optional<orbits::NavMessage> message,
                                                  const Signal& signal) {
  const std::span<const Signal> wanted(&signal, 1);
  const orbits::KeplerEphemeris* found = ephemerides.find_kepler(sat, t, message, wanted);
  if (found == nullptr && message) found = ephemerides.find_kepler(sat, t, std::nullopt, wanted);
  return found;
}

// The records as the observation generator selects them: at the receiver's time tag, the orbit from
// the system's default message (Galileo I/NAV; BeiDou B1I/B2I/B3I D1 or D2), the clock and group
// delay from the message that belongs to the signal (Galileo E5a: F/NAV; GPS L5: CNAV), each
// falling back to any message.
std::optional<Records> select_records(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                      const Signal& signal, const GnssTime& tag) {
  Records out;
  switch (sat.system) {
    case GnssSystem::kGlonass:
      out.glonass = ephemerides.find_glonass(sat, tag, std::span<const Signal>(&signal, 1));
      if (out.glonass == nullptr) return std::nullopt;
      return out;
    case GnssSystem::kSbas:
      out.sbas = ephemerides.find_sbas(sat, tag, std::span<const Signal>(&signal, 1));
      if (out.sbas == nullptr) return std::nullopt;
      return out;
    default: break;
  }
  std::optional<orbits::NavMessage> orbit_message;
  if (sat.system == GnssSystem::kGalileo) orbit_message = orbits::NavMessage::kGalileoInav;
  if (is_beidou_legacy(signal)) {
    orbit_message = orbits::is_beidou_geo(sat) ? orbits::NavMessage::kBeiDouD2 : orbits::NavMessage::kBeiDouD1;
  }
  out.orbit_kepler = find_with_fallback(ephemerides, sat, tag, orbit_message, signal);
  if (out.orbit_kepler == nullptr) return std::nullopt;
  out.clock_kepler = out.orbit_kepler;
  const auto wanted = orbits::preferred_message(signal);
  if (wanted && *wanted != out.orbit_kepler->message) {
    if (const auto* other = find_with_fallback(ephemerides, sat, tag, wanted, signal)) out.clock_kepler = other;
  }
  return out;
}

// One satellite's measurement with everything that does not depend on the receiver position.
struct Candidate {
  size_t use_index = 0;  // into PositionFix::satellites
  int system = 0;        // GnssSystem as an index
  const SignalMeasurement* measurement = nullptr;
  double carrier_hz = 0.0;
  // Orbit evaluated once at t0 = tag - P / c, in the frame of t0, with the acceleration (gravity,
  // Coriolis, centrifugal) to move it along by the microseconds to the transmission time.
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d acceleration_mps2 = Eigen::Vector3d::Zero();
  double clock_s = 0.0;          // dt_sv + dt_rel at t0
  double clock_rate_s_per_s = 0.0;
  double group_delay_s = 0.0;
  double accuracy_m = 0.0;       // broadcast URA / SISA (0: unknown)
  // Transmission time minus t0 as the satellite clock alone gives it (before a receiver clock is
  // estimated): -(dt_sv + dt_rel - group delay).
  [[nodiscard]] double clock_step_s() const { return -(clock_s - group_delay_s); }
};

// The geometry of one candidate seen from a receiver position.
struct Geometry {
  Eigen::Vector3d satellite_m;     // at transmission, rotated into the frame at reception
  Eigen::Vector3d satellite_velocity_mps;  // likewise
  double clock_correction_m = 0.0; // c (dt_sv + dt_rel - group delay) at transmission
  double satellite_clock_m = 0.0;  // c (dt_sv + dt_rel) at transmission
  Eigen::Vector3d line_of_sight;   // unit, receiver to satellite (ECEF)
  double range_m = 0.0;
  // Seen from a place on the Earth (has_local): the satellite's local east-north-up offset and the
  // sine of its elevation; the angles themselves are worked out only where something needs them
  // (with_direction): the iterations need the sine alone.
  bool has_local = false;
  Eigen::Vector3d enu_m = Eigen::Vector3d::Zero();
  double sin_elevation = 1.0;
  bool has_direction = false;
  double elevation_deg = 90.0;
  double azimuth_deg = 0.0;
};

// The elevation and azimuth of a geometry seen from the Earth (90 and 0 deg otherwise).
void with_direction(Geometry& g) {
  if (!g.has_local || g.has_direction) return;
  g.elevation_deg = std::atan2(g.enu_m.z(), std::hypot(g.enu_m.x(), g.enu_m.y())) * kDegPerRad;
  const double azimuth_deg = std::atan2(g.enu_m.x(), g.enu_m.y()) * kDegPerRad;
  g.azimuth_deg = azimuth_deg < 0.0 ? azimuth_deg + 360.0 : azimuth_deg;
  g.has_direction = true;
}

// With the receiver's clock for the satellite's system known, the transmission time is the true
// reception time minus the flight time (light-time iteration, exactly as the signal was made);
// before that, the pseudorange corrected by the satellite clock dates it.
Geometry geometry_from(const Candidate& c, const Eigen::Vector3d& receiver_m, const Eigen::Matrix3d* to_enu,
                       std::optional<double> receiver_clock_m,
                       std::optional<double> flight_time_guess_s = std::nullopt) {
  Geometry g;
  const auto move_to = [&](double step_s) {
    g.satellite_m = c.position_m + c.velocity_mps * step_s + 0.5 * c.acceleration_mps2 * step_s * step_s;
    g.satellite_clock_m = kC * (c.clock_s + c.clock_rate_s_per_s * step_s);
    g.clock_correction_m = g.satellite_clock_m - kC * c.group_delay_s;
    return step_s;
  };
  double step_s = move_to(c.clock_step_s());
  const double pseudorange_s = c.measurement->pseudorange_m / kC;
  // From the last geometry's flight time when there is one (the receiver moved by metres since,
  // the flight time by nanoseconds: the passes below repeat sooner).
  double flight_time_s = flight_time_guess_s ? *flight_time_guess_s : (g.satellite_m - receiver_m).norm() / kC;
  // Four passes at most; once the flight time repeats exactly, further passes would repeat too.
  for (int iteration = 0; iteration < 4; ++iteration) {
    if (receiver_clock_m) step_s = move_to(pseudorange_s - *receiver_clock_m / kC - flight_time_s);
    const Eigen::Vector3d at_transmission = g.satellite_m;
    g.satellite_m = rotate_earth_frame(at_transmission, kEarthRotation_radps * flight_time_s);
    g.range_m = (g.satellite_m - receiver_m).norm();
    const double previous_flight_time_s = flight_time_s;
    flight_time_s = g.range_m / kC;
    if (flight_time_s == previous_flight_time_s) break;
    if (iteration < 3) g.satellite_m = at_transmission;
  }
  g.satellite_velocity_mps =
      rotate_earth_frame(c.velocity_mps + c.acceleration_mps2 * step_s, kEarthRotation_radps * flight_time_s);
  g.line_of_sight = (g.satellite_m - receiver_m) / g.range_m;
  if (to_enu != nullptr) {
    g.has_local = true;
    g.enu_m = *to_enu * (g.satellite_m - receiver_m);
    g.sin_elevation = g.enu_m.z() / g.enu_m.norm();
  }
  return g;
}

// Regularised lower incomplete gamma function P(a, x) (series below a + 1, continued fraction
// above; Numerical Recipes 6.2).
double regularized_gamma_p(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 1000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return sum * std::exp(log_prefactor);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

// The normal equations of the code solution: position and one clock per system, on the stack.
constexpr int kMaxUnknowns = 3 + kMaxSystems;
using NormalMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxUnknowns, kMaxUnknowns>;
using NormalVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxUnknowns, 1>;

// A weighted least-squares solution of the code equations for a given set of satellites.
struct CodeSolution {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  std::array<double, kMaxSystems> clock_m{};
  std::vector<int> systems;  // the clock columns, by system index
  int iterations = 0;
  bool converged = false;
  std::string message;
};

}  // namespace

std::string_view to_string(FixType type) {
  switch (type) {
    case FixType::kNone: return "none";
    case FixType::kFix2D: return "2d";
    case FixType::kFix3D: return "3d";
    case FixType::kDgnss: return "dgnss";
    case FixType::kRtkFloat: return "rtk_float";
    case FixType::kRtkFixed: return "rtk_fixed";
  }
  return "?";
}

std::vector<Signal> default_signal_priority(GnssSystem system) {
  auto list = [system](std::initializer_list<const char*> codes) {
    std::vector<Signal> out;
    for (const char* code : codes) out.push_back(Signal{system, code[0], code[1]});
    return out;
  };
  switch (system) {
    case GnssSystem::kGps: return list({"1C", "1W", "1P", "1X", "1L", "1S", "2W", "2P", "2X", "2L", "2S", "5Q", "5X", "5I"});
    case GnssSystem::kGlonass: return list({"1C", "1P", "2C", "2P", "4X", "4A", "4B", "6X", "6A", "6B", "3X", "3I", "3Q"});
    case GnssSystem::kGalileo: return list({"1C", "1X", "1B", "7Q", "7X", "7I", "5Q", "5X", "5I", "8Q", "8X", "8I", "6C", "6X", "6B"});
    case GnssSystem::kBeiDou: return list({"2I", "2X", "2Q", "1P", "1X", "1D", "7I", "7X", "7Q", "6I", "6X", "6Q", "5P", "5X", "5D", "7P", "7Z", "7D"});
    case GnssSystem::kQzss: return list({"1C", "1X", "1L", "1S", "2L", "2X", "2S", "5Q", "5X", "5I"});
    case GnssSystem::kNavic: return list({"5A", "5B", "5C", "5X", "9A", "9B", "9C", "9X"});
    case GnssSystem::kSbas: return list({"1C", "5I", "5Q", "5X"});
  }
  return {};
}

double chi_square_quantile(double probability, int dof) {
  if (!(probability > 0.0 && probability < 1.0) || dof < 1) return std::numeric_limits<double>::quiet_NaN();
  const double a = 0.5 * dof;
  double low = 0.0, high = dof + 10.0 * std::sqrt(2.0 * dof) + 50.0;
  while (regularized_gamma_p(a, 0.5 * high) < probability) high *= 2.0;
  for (int i = 0; i < 200 && high - low > 1e-12 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (regularized_gamma_p(a, 0.5 * mid) < probability ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

SinglePointSolver::SinglePointSolver(const orbits::BroadcastEphemerides& ephemerides, SolverSettings settings,
                                     std::optional<orbits::KlobucharCoefficients> klobuchar)
    : ephemerides_(ephemerides), settings_(std::move(settings)), klobuchar_(klobuchar) {
  for (GnssSystem system : kAllSystems) {
    auto& list = priority_[static_cast<size_t>(system)];
    for (const Signal& signal : settings_.signal_priority) {
      if (signal.system == system) list.push_back(signal);
    }
    if (list.empty()) list = default_signal_priority(system);
  }
}

Result<PositionFix> SinglePointSolver::solve(const EpochMeasurements& epoch) {
  PositionFix fix;
  fix.receiver_time = epoch.receiver_time;
  fix.time = epoch.receiver_time;
  const GnssTime& tag = epoch.receiver_time;
  const auto where = [&](const SatelliteId& sat) { return sat.to_string() + " at " + tag.to_iso8601(TimeScale::kGpst); };

  // One signal per satellite: the first of the priority list the satellite has. The measurements
  // grouped by satellite in satellite order, each satellite's in the order given.
  std::vector<const SignalMeasurement*> by_satellite;
  by_satellite.reserve(epoch.signals.size());
  for (const SignalMeasurement& m : epoch.signals) {
    if (m.signal.system != m.satellite.system) {
      return make_error(ErrorCode::kInvalidArgument,
                        "signal " + m.signal.to_string() + " given for satellite " + where(m.satellite));
    }
    if (!std::isfinite(m.pseudorange_m) || (m.doppler_hz && !std::isfinite(*m.doppler_hz))) {
      return make_error(ErrorCode::kInvalidArgument,
                        "pseudorange or Doppler of " + m.signal.to_string() + " of " + where(m.satellite) + " is not finite");
    }
    by_satellite.push_back(&m);
  }
  std::stable_sort(by_satellite.begin(), by_satellite.end(),
                   [](const SignalMeasurement* a, const SignalMeasurement* b) { return a->satellite < b->satellite; });
  const auto system_wanted = [&](GnssSystem system) {
    if (settings_.systems.empty()) return true;
    return std::find(settings_.systems.begin(), settings_.systems.end(), system) != settings_.systems.end();
  };

  std::vector<Candidate> candidates;
  candidates.reserve(by_satellite.size());
  fix.satellites.reserve(by_satellite.size());
  for (size_t first = 0; first < by_satellite.size();) {
    size_t end = first;
    while (end < by_satellite.size() && by_satellite[end]->satellite == by_satellite[first]->satellite) ++end;
    const std::span<const SignalMeasurement* const> list(by_satellite.data() + first, end - first);
    const SatelliteId sat = list.front()->satellite;
    first = end;
    const SignalMeasurement* chosen = nullptr;
    for (const Signal& wanted : priority_[static_cast<size_t>(sat.system)]) {
      const auto it = std::find_if(list.begin(), list.end(), [&](const SignalMeasurement* m) { return m->signal == wanted; });
      if (it != list.end()) {
        chosen = *it;
        break;
      }
    }
    if (chosen == nullptr) chosen = list.front();
    SatelliteUse use;
    use.satellite = sat;
    use.signal = chosen->signal;
    use.cn0_dbhz = chosen->cn0_dbhz;
    const size_t use_index = fix.satellites.size();
    auto skip = [&](std::string note) {
      use.note = std::move(note);
      fix.satellites.push_back(std::move(use));
    };
    if (!system_wanted(sat.system)) {
      skip("system not selected");
      continue;
    }
    if (settings_.min_cn0_dbhz > 0.0 && chosen->cn0_dbhz < settings_.min_cn0_dbhz) {
      skip("C/N0 below the minimum");
      continue;
    }
    if (chosen->pseudorange_m <= 0.0) {
      skip("no pseudorange");
      continue;
    }
    const std::optional<Records> records = select_records(ephemerides_, sat, chosen->signal, tag);
    if (!records) {
      skip("no valid broadcast ephemeris");
      continue;
    }
    Candidate c;
    c.use_index = use_index;
    c.system = static_cast<int>(sat.system);
    c.measurement = chosen;
    c.carrier_hz = chosen->carrier_hz;
    if (c.carrier_hz <= 0.0) {
      const SignalInfo* info = find_signal_info(chosen->signal);
      if (info == nullptr) {
        skip("signal not in the catalogue");
        continue;
      }
      c.carrier_hz = info->carrier_frequency_hz(records->glonass != nullptr ? records->glonass->frequency_channel : 0);
    }
    // Transmission time from the pseudorange, corrected by the satellite clock (evaluated at the
    // uncorrected time; the correction is below a millisecond and the orbit follows it to second
    // order, as the generator expands it).
    // A range to a navigation satellite plus a receiver clock kept within a millisecond or so; a
    // value far outside is no pseudorange (and would send the orbit to an absurd time).
    constexpr double kMaxPseudorange_m = 1e8;
    if (!(chosen->pseudorange_m > 0.0 && chosen->pseudorange_m < kMaxPseudorange_m)) {
      skip("pseudorange " + std::to_string(chosen->pseudorange_m) + " m is not a range to a navigation satellite");
      continue;
    }
    const GnssTime t0 = tag - chosen->pseudorange_m / kC;
    orbits::SatelliteState orbit, clock;
    double group_delay_s = 0.0;
    if (records->orbit_kepler != nullptr) {
      orbit = orbits::evaluate_kepler(*records->orbit_kepler, t0);
      clock = records->clock_kepler == records->orbit_kepler ? orbit : orbits::evaluate_kepler(*records->clock_kepler, t0);
      group_delay_s = orbits::group_delay_s(*records->clock_kepler, chosen->signal);
      c.accuracy_m = records->orbit_kepler->accuracy_m;
    } else if (records->glonass != nullptr) {
      orbit = clock = glonass_orbits_.evaluate(*records->glonass, t0);
      group_delay_s = orbits::group_delay_s(*records->glonass, chosen->signal);
    } else {
      orbit = clock = orbits::evaluate_sbas(*records->sbas, t0);
      c.accuracy_m = records->sbas->accuracy_m;
    }
    if (!orbit.position_m.allFinite() || !orbit.velocity_mps.allFinite() || !std::isfinite(clock.clock_bias_s)) {
      skip("no usable orbit at the transmission time");
      continue;
    }
    const Eigen::Vector3d omega(0.0, 0.0, kEarthRotation_radps);
    const Eigen::Vector3d& r0 = orbit.position_m;
    const Eigen::Vector3d& v0 = orbit.velocity_mps;
    c.position_m = r0;
    c.velocity_mps = v0;
    c.acceleration_mps2 = -constants::kGmGps_m3ps2 / std::pow(r0.norm(), 3) * r0 - 2.0 * omega.cross(v0) -
                          omega.cross(omega.cross(r0));
    c.clock_s = clock.clock_bias_s + clock.relativistic_s;
    c.clock_rate_s_per_s = clock.clock_drift_s_per_s + clock.relativistic_drift_s_per_s;
    c.group_delay_s = group_delay_s;
    fix.satellites.push_back(std::move(use));
    candidates.push_back(c);
  }

  // Per candidate, what the iterations found last.
  struct State {
    bool used = false;
    bool rejected = false;
    double residual_m = 0.0;
    double variance_m2 = 0.0;
    Geometry geometry;
    std::string note;
    // The model delays and the positions they were computed at.
    std::optional<Eigen::Vector3d> ionosphere_at_m, troposphere_at_m;
    double ionosphere_m = 0.0, troposphere_m = 0.0;
  };
  std::vector<State> states(candidates.size());

  // The ionospheric (Klobuchar, scaled to the carrier) and tropospheric (Saastamoinen) delays of a
  // candidate seen from a position on the Earth, reused near where they were last computed:
  // - the ionosphere within 10 m: the pierce point 350 km up moves by as much, where the delay
  //   changes by about 1e-6 of its value per metre of horizontal gradient (micrometres);
  // - the troposphere within 1 mm: it follows the height directly (about 3e-4 of a height change
  //   at the zenith, ten times that at 5 degrees), so only the final residuals, within the 0.1 mm
  //   convergence step of the last iteration's position, reuse it.
  constexpr double kIonosphereReuse_m = 10.0;
  constexpr double kTroposphereReuse_m = 1e-3;
  const auto atmosphere_delays = [&](State& st, const Candidate& c, const Eigen::Vector3d& position_m,
                                     const Geodetic& geodetic, const GnssTime& reception, double& ionosphere_m,
                                     double& troposphere_m) {
    const auto moved_m = [&](const std::optional<Eigen::Vector3d>& from_m) {
      return from_m ? (*from_m - position_m).norm() : std::numeric_limits<double>::infinity();
    };
    if (moved_m(st.ionosphere_at_m) > kIonosphereReuse_m) {
      st.ionosphere_m = 0.0;
      if (settings_.ionosphere_klobuchar && klobuchar_) {
        with_direction(st.geometry);
        const AzimuthElevation direction{st.geometry.azimuth_deg, st.geometry.elevation_deg};
        st.ionosphere_m = atmosphere::klobuchar_delay_l1_m(*klobuchar_, reception, geodetic, direction).value_or(0.0) *
                          std::pow(kFrequencyL1_Hz / c.carrier_hz, 2);
      }
      st.ionosphere_at_m = position_m;
    }
    if (moved_m(st.troposphere_at_m) > kTroposphereReuse_m) {
      st.troposphere_m = 0.0;
      if (settings_.troposphere_saastamoinen) {
        with_direction(st.geometry);
        st.troposphere_m = atmosphere::saastamoinen_delay_m(geodetic, st.geometry.elevation_deg).value_or(0.0);
      }
      st.troposphere_at_m = position_m;
    }
    ionosphere_m = st.ionosphere_m;
    troposphere_m = st.troposphere_m;
  };

  // The flight time of a candidate's last geometry, to start the next one from.
  const auto last_flight_time_s = [](const State& st) {
    return st.geometry.range_m > 0.0 ? std::optional<double>(st.geometry.range_m / kC) : std::nullopt;
  };
  // The mask as the sine of the elevation (what the geometry gives without an arc tangent).
  const double sin_mask = std::sin(settings_.elevation_mask_deg / kDegPerRad);
  std::vector<double> observed_m;  // per candidate: the corrected code of the iteration
  const auto solve_code = [&](Eigen::Vector3d start_m, int max_iterations) {
    CodeSolution s;
    s.position_m = start_m;
    for (int iteration = 0; iteration < max_iterations; ++iteration) {
      const bool on_earth = s.position_m.norm() > kMinPositionRadius_m;
      Geodetic geodetic;
      Eigen::Matrix3d to_enu = Eigen::Matrix3d::Identity();
      if (on_earth) {
        geodetic = ecef_to_geodetic(s.position_m);
        to_enu = ecef_to_enu_rotation(geodetic);
      }
      // The receiver clock of the previous iteration dates the reception for the ionosphere.
      const GnssTime reception = tag - (s.systems.empty() ? 0.0 : s.clock_m[s.systems.front()]) / kC;
      std::array<int, kMaxSystems> per_system{};
      observed_m.assign(candidates.size(), 0.0);
      for (size_t i = 0; i < candidates.size(); ++i) {
        const Candidate& c = candidates[i];
        State& st = states[i];
        st.used = false;
        // Reception is dated by the receiver clock (the first system's), whatever the satellite's
        // system: inter-system biases are offsets of the measurements, not of the instant.
        std::optional<double> receiver_clock_m;
        if (on_earth && !s.systems.empty()) receiver_clock_m = s.clock_m[s.systems.front()];
        st.geometry = geometry_from(c, s.position_m, on_earth ? &to_enu : nullptr, receiver_clock_m,
                                    last_flight_time_s(st));
        if (st.rejected) continue;
        if (on_earth && st.geometry.sin_elevation < sin_mask) {
          st.note = "below the elevation mask";
          continue;
        }
        double ionosphere_m = 0.0, troposphere_m = 0.0;
        if (on_earth) atmosphere_delays(st, c, s.position_m, geodetic, reception, ionosphere_m, troposphere_m);
        const double sin_el = std::max(st.geometry.sin_elevation, 0.05);
        double variance_m2 = settings_.sigma_code_zenith_m * settings_.sigma_code_zenith_m +
                             std::pow(settings_.sigma_code_elevation_m / sin_el, 2);
        if (settings_.weight_by_cn0 && c.measurement->cn0_dbhz > 0.0) {
          variance_m2 *= std::pow(10.0, (45.0 - c.measurement->cn0_dbhz) / 10.0);
        }
        variance_m2 += std::pow(settings_.ionosphere_error_fraction * ionosphere_m, 2);
        if (on_earth && settings_.troposphere_saastamoinen) {
          variance_m2 += std::pow(settings_.troposphere_error_m / (sin_el + 0.1), 2);
        }
        if (settings_.use_broadcast_accuracy && c.accuracy_m > 0.0) variance_m2 += c.accuracy_m * c.accuracy_m;
        st.variance_m2 = variance_m2;
        observed_m[i] = c.measurement->pseudorange_m + st.geometry.clock_correction_m - ionosphere_m - troposphere_m;
        st.used = true;
        st.note.clear();
        ++per_system[c.system];
      }
      // A system seen by one satellite only estimates its own clock from it: nothing left for the
      // position, so neither the satellite nor the unknown enters.
      s.systems.clear();
      for (int system = 0; system < kMaxSystems; ++system) {
        if (per_system[system] >= 2) s.systems.push_back(system);
      }
      std::array<int, kMaxSystems> column{};
      column.fill(-1);
      for (size_t k = 0; k < s.systems.size(); ++k) column[s.systems[k]] = 3 + static_cast<int>(k);
      int used = 0;
      for (size_t i = 0; i < candidates.size(); ++i) {
        if (!states[i].used) continue;
        if (column[candidates[i].system] < 0) {
          states[i].used = false;
          states[i].note = "only satellite of its system";
          continue;
        }
        ++used;
      }
      const int unknowns = 3 + static_cast<int>(s.systems.size());
      if (s.systems.empty() || used < unknowns) {
        s.message = "too few satellites: " + std::to_string(used) + " usable for " + std::to_string(unknowns) +
                    " unknowns (position and " + std::to_string(s.systems.size()) + " clock(s))";
        return s;
      }
      // The normal equations N x = b summed row by row: a row is (-line of sight, 1 in its
      // system's clock column), so each adds a 3x3 block, its clock's column and diagonal.
      NormalMatrix normal = NormalMatrix::Zero(unknowns, unknowns);
      NormalVector rhs = NormalVector::Zero(unknowns);
      for (size_t i = 0; i < candidates.size(); ++i) {
        if (!states[i].used) continue;
        const Eigen::Vector3d& e = states[i].geometry.line_of_sight;
        const int k = column[candidates[i].system];
        const double w = 1.0 / states[i].variance_m2;
        const double y = observed_m[i] - states[i].geometry.range_m;
        normal.topLeftCorner<3, 3>().noalias() += (w * e) * e.transpose();
        normal.block<3, 1>(0, k) -= w * e;
        normal(k, k) += w;
        rhs.head<3>() -= (w * y) * e;
        rhs(k) += w * y;
      }
      for (int k = 3; k < unknowns; ++k) normal.block<1, 3>(k, 0) = normal.block<3, 1>(0, k).transpose();
      const Eigen::LDLT<NormalMatrix> ldlt(normal);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || std::abs(ldlt.vectorD().minCoeff()) < 1e-12) {
        s.message = "singular geometry";
        return s;
      }
      // The unknowns: position step and the full clocks (the equations are linear in the clocks).
      const NormalVector x = ldlt.solve(rhs);
      const Eigen::Vector3d dx = x.head<3>();
      s.position_m += dx;
      for (size_t k = 0; k < s.systems.size(); ++k) s.clock_m[s.systems[k]] = x(3 + static_cast<Eigen::Index>(k));
      s.iterations = iteration + 1;
      if (!s.position_m.allFinite() || s.position_m.norm() > 1e8) {
        s.message = "the solution diverged";
        return s;
      }
      if (on_earth && dx.norm() < settings_.convergence_m) {
        s.converged = true;
        return s;
      }
    }
    s.message = "no convergence in " + std::to_string(max_iterations) + " iterations";
    return s;
  };

  // Solves from the previous fix, or from the Earth's centre (also when the previous start fails).
  const auto solve_from_best_start = [&]() {
    if (last_position_ecef_m_) {
      CodeSolution s = solve_code(*last_position_ecef_m_, settings_.max_iterations);
      if (s.converged) return s;
    }
    return solve_code(Eigen::Vector3d::Zero(), 2 * settings_.max_iterations);
  };

  CodeSolution solution;
  const int min_candidates = 4;
  if (static_cast<int>(candidates.size()) < min_candidates) {
    // Say what happened to the others, e.g. "(12 observed: 10 no valid broadcast ephemeris)".
    std::map<std::string, int> notes;
    for (const SatelliteUse& use : fix.satellites) {
      if (!use.note.empty()) ++notes[use.note];
    }
    std::string detail;
    for (const auto& [note, count] : notes) detail += (detail.empty() ? ": " : ", ") + std::to_string(count) + " " + note;
    fix.message = "too few satellites: " + std::to_string(candidates.size()) + " usable, at least 4 needed (" +
                  std::to_string(fix.satellites.size()) + " observed" + detail + ")";
    return fix;
  }
  // Residual tests: the fix is accepted, or the worst satellite excluded and the fix solved again.
  Eigen::MatrixXd h_enu, covariance;
  for (;;) {
    solution = solve_from_best_start();
    if (!solution.converged) break;
    // Final residuals and matrices at the converged position.
    const Geodetic geodetic = ecef_to_geodetic(solution.position_m);
    const Eigen::Matrix3d to_enu = ecef_to_enu_rotation(geodetic);
    const int used = static_cast<int>(std::count_if(states.begin(), states.end(), [](const State& s) { return s.used; }));
    const int unknowns = 3 + static_cast<int>(solution.systems.size());
    std::array<int, kMaxSystems> column{};
    column.fill(-1);
    for (size_t k = 0; k < solution.systems.size(); ++k) column[solution.systems[k]] = 3 + static_cast<int>(k);
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(used, unknowns);
    h_enu = Eigen::MatrixXd::Zero(used, unknowns);
    Eigen::VectorXd w(used), v(used);
    std::vector<size_t> index_of_row;
    int row = 0;
    // The last iteration's residuals are those of the position before its (tiny) step: recompute.
    const GnssTime reception = tag - solution.clock_m[solution.systems.front()] / kC;
    for (size_t i = 0; i < candidates.size(); ++i) {
      State& st = states[i];
      if (!st.used) continue;
      const Candidate& c = candidates[i];
      st.geometry = geometry_from(c, solution.position_m, &to_enu, solution.clock_m[solution.systems.front()],
                                  last_flight_time_s(st));
      double ionosphere_m = 0.0, troposphere_m = 0.0;
      atmosphere_delays(st, c, solution.position_m, geodetic, reception, ionosphere_m, troposphere_m);
      st.residual_m = c.measurement->pseudorange_m + st.geometry.clock_correction_m - ionosphere_m - troposphere_m -
                      st.geometry.range_m - solution.clock_m[c.system];
      h.block<1, 3>(row, 0) = -st.geometry.line_of_sight.transpose();
      h(row, column[c.system]) = 1.0;
      h_enu.block<1, 3>(row, 0) = -(to_enu * st.geometry.line_of_sight).transpose();
      h_enu(row, column[c.system]) = 1.0;
      w(row) = 1.0 / st.variance_m2;
      v(row) = st.residual_m;
      index_of_row.push_back(i);
      ++row;
    }
    covariance = (h.transpose() * w.asDiagonal() * h).inverse();
    fix.chi_square = v.dot(w.asDiagonal() * v);
    fix.degrees_of_freedom = used - unknowns;
    if (fix.degrees_of_freedom > 0) {
      auto [it, inserted] = chi_square_thresholds_.try_emplace(fix.degrees_of_freedom, 0.0);
      if (inserted) it->second = chi_square_quantile(1.0 - settings_.outlier_probability, fix.degrees_of_freedom);
      fix.chi_square_threshold = it->second;
    } else {
      fix.chi_square_threshold = 0.0;
    }
    const bool test_failed = fix.degrees_of_freedom > 0 && fix.chi_square > fix.chi_square_threshold;
    if (!settings_.reject_outliers || !test_failed) break;
    // Exclude the satellite with the largest standardised residual v_i / sigma(v_i), where the
    // residual covariance is Sigma - H Q H^T; then solve again while redundancy remains.
    if (fix.degrees_of_freedom < 2) {
      fix.message = "residual test failed with too little redundancy to find the outlier";
      break;
    }
    double worst = -1.0;
    size_t worst_row = 0;
    for (int r = 0; r < used; ++r) {
      const double residual_variance = 1.0 / w(r) - h.row(r) * covariance * h.row(r).transpose();
      const double standardized = std::abs(v(r)) / std::sqrt(std::max(residual_variance, 1e-6 / w(r)));
      if (standardized > worst) {
        worst = standardized;
        worst_row = static_cast<size_t>(r);
      }
    }
    State& excluded = states[index_of_row[worst_row]];
    excluded.rejected = true;
    excluded.used = false;
    excluded.note = "rejected by the residual test";
  }

  for (size_t i = 0; i < candidates.size(); ++i) {
    SatelliteUse& use = fix.satellites[candidates[i].use_index];
    State& st = states[i];
    with_direction(st.geometry);
    use.direction = {st.geometry.azimuth_deg, st.geometry.elevation_deg};
    use.used = solution.converged && st.used;
    use.rejected = st.rejected;
    use.residual_m = st.residual_m;
    use.sigma_m = std::sqrt(st.variance_m2);
    use.note = st.note;
    // Geometry at the receiver's estimate (the Earth's centre until a solution converged: none).
    use.has_geometry = solution.converged && st.geometry.range_m > 0.0;
    use.satellite_position_m = st.geometry.satellite_m;
    use.satellite_clock_m = st.geometry.satellite_clock_m;
  }
  if (!solution.converged) {
    fix.message = solution.message;
    fix.chi_square = 0.0;
    fix.degrees_of_freedom = 0;
    return fix;
  }
  fix.iterations = solution.iterations;
  fix.position_ecef_m = solution.position_m;
  fix.position = ecef_to_geodetic(solution.position_m);
  for (int system : solution.systems) fix.clock_bias_m[static_cast<GnssSystem>(system)] = solution.clock_m[system];
  fix.time = tag - solution.clock_m[solution.systems.front()] / kC;
  fix.satellites_used = static_cast<int>(std::count_if(states.begin(), states.end(), [](const State& s) { return s.used; }));
  fix.type = FixType::kFix3D;

  const Eigen::Matrix3d to_enu = ecef_to_enu_rotation(fix.position);
  fix.covariance_enu_m2 = to_enu * covariance.topLeftCorner<3, 3>() * to_enu.transpose();
  const Eigen::MatrixXd dop = (h_enu.transpose() * h_enu).inverse();
  fix.gdop = std::sqrt(dop.trace());
  fix.pdop = std::sqrt(dop(0, 0) + dop(1, 1) + dop(2, 2));
  fix.hdop = std::sqrt(dop(0, 0) + dop(1, 1));
  fix.vdop = std::sqrt(dop(2, 2));
  fix.tdop = std::sqrt(dop(3, 3));
  last_position_ecef_m_ = fix.position_ecef_m;

  // Velocity and clock drift from the Doppler of the satellites in the fix:
  //   -lambda D = rr + c dt_r' - c (dt_sv' + dt_rel'),
  // with rr the range rate as the generator defines it, the flight time changing too:
  //   rr = (e.v_sat - e.v_rx) / (1 + (e.v_sat - omega e.(y_s, -x_s, 0)) / c).
  std::vector<size_t> doppler_rows;
  for (size_t i = 0; i < candidates.size(); ++i) {
    if (states[i].used && candidates[i].measurement->doppler_hz) doppler_rows.push_back(i);
  }
  if (doppler_rows.size() >= 4) {
    const auto n = static_cast<Eigen::Index>(doppler_rows.size());
    Eigen::MatrixXd h(n, 4);
    Eigen::VectorXd y(n), w(n);
    for (Eigen::Index r = 0; r < n; ++r) {
      const size_t i = doppler_rows[static_cast<size_t>(r)];
      const Candidate& c = candidates[i];
      const Geometry& g = states[i].geometry;
      const double sat_term = g.line_of_sight.dot(g.satellite_velocity_mps);
      const double sagnac_term = kEarthRotation_radps * g.line_of_sight.dot(Eigen::Vector3d(g.satellite_m.y(), -g.satellite_m.x(), 0.0));
      const double scale = 1.0 + (sat_term - sagnac_term) / kC;
      const double wavelength_m = kC / c.carrier_hz;
      h.block<1, 3>(r, 0) = -g.line_of_sight.transpose() / scale;
      h(r, 3) = 1.0;
      y(r) = -wavelength_m * *c.measurement->doppler_hz + kC * c.clock_rate_s_per_s - sat_term / scale;
      const double sin_el = std::max(g.sin_elevation, 0.05);
      w(r) = 2.0 / (settings_.sigma_doppler_mps * settings_.sigma_doppler_mps * (1.0 + 1.0 / (sin_el * sin_el)));
    }
    const Eigen::MatrixXd normal = h.transpose() * w.asDiagonal() * h;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
      const Eigen::Vector4d x = ldlt.solve(h.transpose() * (w.asDiagonal() * y));
      fix.velocity_ecef_mps = x.head<3>();
      fix.velocity_enu_mps = to_enu * fix.velocity_ecef_mps;
      fix.clock_drift_mps = x(3);
      const Eigen::Matrix4d q = normal.inverse();
      fix.velocity_covariance_enu_m2ps2 = to_enu * q.topLeftCorner<3, 3>() * to_enu.transpose();
      fix.velocity_valid = fix.velocity_ecef_mps.allFinite();
    }
  }
  return fix;
}

}  // namespace skytrace::positioning
