#include "skytrace/receiver/observation_generator.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <numbers>
#include <span>

#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/constants.hpp"
#include "skytrace/core/satellite_catalog.hpp"
#include "skytrace/orbits/signal_health.hpp"
#include "skytrace/receiver/ephemeris_decoding.hpp"
#include "skytrace/receiver/link_budget.hpp"
#include "skytrace/receiver/multipath.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;
// Sagnac: the Earth turns during the signal's flight (WGS84 rate for every system: it is physics,
// not a parameter of any one navigation message).
constexpr double kEarthRotation_radps = constants::kEarthRotationRateGps_radps;
// The loop that aids semi-codeless P(Y) tracking (ReceiverProfile::semicodeless_aiding_bandwidth_hz).
const Signal kAidingSignal{GnssSystem::kGps, '1', 'C'};

// The ephemeris record a receiver uses, and the satellite state it gives at some instant.
struct RecordState {
  orbits::SatelliteState state;
  const orbits::KeplerEphemeris* kepler = nullptr;
  const orbits::GlonassEphemeris* glonass = nullptr;
  const orbits::SbasEphemeris* sbas = nullptr;
};

// The record a receiver holds at its own time `t_receiver` (the epoch tag, as RTKLIB selects with
// the observation time), with a Galileo message preference falling back to the other message.
// nullopt when it holds none (the broadcast layer's select_* explain why, at a cost per call).
// Only records usable for one of the `wanted` signals qualify (orbits::record_usable).
std::optional<RecordState> select_record(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                                         const GnssTime& t_receiver, std::optional<orbits::NavMessage> message,
                                         std::span<const Signal> wanted) {
  RecordState out;
  switch (sat.system) {
    case GnssSystem::kGlonass: out.glonass = ephemerides.find_glonass(sat, t_receiver, wanted); break;
    case GnssSystem::kSbas: out.sbas = ephemerides.find_sbas(sat, t_receiver, wanted); break;
    default:
      out.kepler = ephemerides.find_kepler(sat, t_receiver, message, wanted);
      if (out.kepler == nullptr && message) out.kepler = ephemerides.find_kepler(sat, t_receiver, std::nullopt, wanted);
      break;
  }
  if (out.kepler == nullptr && out.glonass == nullptr && out.sbas == nullptr) return std::nullopt;
  return out;
}

// The record whose orbit and clock are a satellite's truth with broadcast truth: one record per
// satellite and epoch, as a real satellite has one clock, whichever messages the navigation data
// holds. It is the record of the satellite's reference message as a receiver selects it: Galileo
// I/NAV, else F/NAV; GPS and QZSS LNAV, else CNAV, else CNAV-2; BeiDou D1 (D2 on GEOs), else
// CNAV1/2/3; the other systems have one message. `default_record` is the receiver's default selection
// (Galileo I/NAV first, other systems any message), reused when it is of the first rank.
RecordState reference_record(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                             const GnssTime& t_receiver, const RecordState& default_record,
                             std::span<const Signal> wanted) {
  using M = orbits::NavMessage;
  if (default_record.kepler == nullptr) return default_record;
  static constexpr std::array<M, 2> kGalileo{M::kGalileoInav, M::kGalileoFnav};
  static constexpr std::array<M, 3> kGps{M::kGpsLnav, M::kGpsCnav, M::kGpsCnav2};
  static constexpr std::array<M, 3> kQzss{M::kQzssLnav, M::kQzssCnav, M::kQzssCnav2};
  static constexpr std::array<M, 5> kBeiDou{M::kBeiDouD1, M::kBeiDouD2, M::kBeiDouCnav1, M::kBeiDouCnav2,
                                            M::kBeiDouCnav3};
  std::span<const M> order;
  size_t first_rank = 1;  // how many messages of `order` rank first (BeiDou: D1 and D2)
  switch (sat.system) {
    case GnssSystem::kGalileo: order = kGalileo; break;
    case GnssSystem::kGps: order = kGps; break;
    case GnssSystem::kQzss: order = kQzss; break;
    case GnssSystem::kBeiDou:
      order = kBeiDou;
      first_rank = 2;
      break;
    default: return default_record;
  }
  const M message = default_record.kepler->message;
  if (std::find(order.begin(), order.begin() + static_cast<long>(first_rank), message) !=
      order.begin() + static_cast<long>(first_rank)) {
    return default_record;  // the closest record of any message is of the reference message
  }
  for (const M message_wanted : order) {
    if (const orbits::KeplerEphemeris* eph = ephemerides.find_kepler(sat, t_receiver, message_wanted, wanted)) {
      RecordState out;
      out.kepler = eph;
      return out;
    }
  }
  return default_record;
}

// The record a receiver uses for a signal: the one of the message that belongs to it (Galileo E5a:
// F/NAV; GPS L2C and L5: CNAV), when it holds one usable for its signals, else the satellite's
// default record. The signal's health is read from it.
RecordState record_for_signal(const orbits::BroadcastEphemerides& ephemerides, const SatelliteId& sat,
                              const GnssTime& t_receiver, const RecordState& default_record, const Signal& signal,
                              std::span<const Signal> receiver_signals) {
  if (default_record.kepler != nullptr) {
    const auto message = orbits::preferred_message(signal);
    if (message && *message != default_record.kepler->message) {
      if (auto r = select_record(ephemerides, sat, t_receiver, message, receiver_signals)) return *r;
    }
  }
  return default_record;
}

// Evaluates the record's orbit and clock at instant t (on the GPST timeline).
void evaluate_record(RecordState& record, const GnssTime& t, orbits::GlonassOrbitCache& glonass_orbits) {
  if (record.kepler != nullptr) {
    record.state = orbits::evaluate_kepler(*record.kepler, t);
  } else if (record.glonass != nullptr) {
    record.state = glonass_orbits.evaluate(*record.glonass, t);
  } else {
    record.state = orbits::evaluate_sbas(*record.sbas, t);
  }
}

// The signal's health as the record declares it, and why not when unhealthy.
bool signal_healthy(const RecordState& record, const Signal& signal) {
  if (record.kepler != nullptr) return orbits::signal_healthy(*record.kepler, signal);
  if (record.glonass != nullptr) return orbits::signal_healthy(*record.glonass, signal);
  return orbits::signal_healthy(*record.sbas, signal);
}
std::string health_description(const RecordState& record) {
  if (record.kepler != nullptr) return orbits::health_description(*record.kepler);
  if (record.glonass != nullptr) return orbits::health_description(*record.glonass);
  return orbits::health_description(*record.sbas);
}

double group_delay_of(const RecordState& record, const Signal& signal) {
  if (record.kepler != nullptr) return orbits::group_delay_s(*record.kepler, signal);
  if (record.glonass != nullptr) return orbits::group_delay_s(*record.glonass, signal);
  return 0.0;  // SBAS clocks refer to L1 directly
}

// The record whose group delay parameters give a signal's code delay relative to the satellite's
// one clock (the reference record, `truth`): the reference record itself when its message
// broadcasts the signal's group delay (Galileo I/NAV carries BGD(E1,E5a) as well as BGD(E1,E5b), so
// E1, E5a and E5b all take theirs from it; GPS LNAV serves L1 C/A and P(Y), BeiDou D1/D2 B1I, B2I
// and B3I). Otherwise the record of the message that does, when the receiver holds one (GPS/QZSS
// L2C and L5: CNAV ISCs, L1C: CNAV-2; BeiDou B1C/B2a/B2b: CNAV1/2/3 TGDs): those delays refer to the
// same clock reference as the reference message's clock (GPS L1/L2 P(Y), BeiDou B3I), so no second
// clock enters. Failing both, the reference record (group_delay_s derives what it can, e.g. LNAV's
// gamma T_GD for L2C). `signal_record` is the receiver's record for the signal, which is the
// signal's own message's when the receiver holds one.
const RecordState& group_delay_record(const RecordState& truth, const RecordState& signal_record,
                                      const Signal& signal) {
  if (truth.kepler == nullptr) return truth;
  const auto wanted = orbits::preferred_message(signal);
  const orbits::NavMessage message = truth.kepler->message;
  if (!wanted || *wanted == message || message == orbits::NavMessage::kGalileoInav) return truth;
  if (signal_record.kepler != nullptr && signal_record.kepler->message == *wanted) return signal_record;
  return truth;
}

// Code group delay of a signal relative to the clock of precise products, which refer to the
// ionosphere-free combination of the IGS reference signals: GPS/QZSS L1/L2 P(Y) like the broadcast
// clock; Galileo E1/E5a like F/NAV; BeiDou B1I/B3I where the broadcast clock refers to B3I alone.
// `delays` is the record of the signal's group delay (group_delay_record), `reference` the
// satellite's reference record (BeiDou: its TGD1 converts B3I to B1I/B3I).
double precise_clock_group_delay_s(const RecordState& reference, const RecordState& delays, const Signal& signal) {
  if (delays.kepler == nullptr) return group_delay_of(delays, signal);
  const orbits::KeplerEphemeris& eph = *delays.kepler;
  switch (eph.satellite.system) {
    case GnssSystem::kGalileo: {
      orbits::KeplerEphemeris as_fnav = eph;  // I/NAV records carry BGD(E1,E5a) too
      as_fnav.message = orbits::NavMessage::kGalileoFnav;
      return orbits::group_delay_s(as_fnav, signal);
    }
    case GnssSystem::kBeiDou: {
      // The B1I/B3I ionosphere-free code is late by gamma/(gamma-1) TGD1 against B3I.
      const double gamma = std::pow(kFrequencyB1I_Hz / kFrequencyB3I_Hz, 2);
      const double tgd1_s = (reference.kepler != nullptr ? *reference.kepler : eph).group_delays.tgd1_s;
      return orbits::group_delay_s(eph, signal) - gamma / (gamma - 1.0) * tgd1_s;
    }
    default: return orbits::group_delay_s(eph, signal);
  }
}

std::uint64_t satellite_key(const SatelliteId& sat) {
  return (static_cast<std::uint64_t>(sat.system) << 8) | sat.number;
}
std::uint64_t signal_key(const Signal& signal) {
  return (static_cast<std::uint64_t>(signal.system) << 16) | (static_cast<std::uint64_t>(signal.band) << 8) |
         static_cast<std::uint64_t>(signal.attribute);
}

double quantize(double value, double step) { return step > 0.0 ? std::round(value / step) * step : value; }

AzimuthElevation local_direction(const Eigen::Vector3d& enu) {
  AzimuthElevation d;
  d.elevation_deg = std::atan2(enu.z(), std::hypot(enu.x(), enu.y())) * 180.0 / std::numbers::pi;
  const double azimuth_deg = std::atan2(enu.x(), enu.y()) * 180.0 / std::numbers::pi;
  d.azimuth_deg = azimuth_deg < 0.0 ? azimuth_deg + 360.0 : azimuth_deg;
  return d;
}

// Multipath: a satellite's paths as its antenna receives them. Arrival directions go from the
// world frame to the receiver's east-north-up; excess-delay rates come from the paths' delay
// gradients with the receiver's velocity and the turning of the direction to the satellite.
std::vector<ReceivedPath> receive_paths(SatelliteObservation& obs, std::vector<SignalPath> paths,
                                        const AntennaPattern& antenna, const Eigen::Matrix3d& world_to_enu,
                                        const Eigen::Vector3d& receiver_velocity_world_mps,
                                        const Eigen::Vector3d& direction_rate_world_per_s) {
  std::vector<ReceivedPath> received;
  received.reserve(paths.size());
  for (const SignalPath& path : paths) {
    const AzimuthElevation arrival = local_direction(world_to_enu * path.arrival_direction);
    ReceivedPath r;
    r.excess_delay_m = path.excess_delay_m;
    r.excess_delay_rate_mps = path.delay_gradient_origin.dot(receiver_velocity_world_mps) +
                              path.delay_gradient_direction.dot(direction_rate_world_per_s);
    r.amplitude = antenna_amplitude(antenna, path, arrival.elevation_deg, arrival.azimuth_deg,
                                    obs.direction.elevation_deg, obs.direction.azimuth_deg);
    obs.path_directions.push_back(arrival);
    obs.path_delay_rates_mps.push_back(r.excess_delay_rate_mps);
    received.push_back(r);
  }
  const bool direct = !paths.empty() && paths.front().type == PathType::kDirect;
  obs.path_kind = paths.empty() ? PathKind::kNone
                  : direct      ? (paths.size() == 1 ? PathKind::kLos : PathKind::kMultipath)
                                : PathKind::kNlos;
  obs.paths = std::move(paths);
  return received;
}

}  // namespace

std::string_view to_string(PathKind kind) {
  switch (kind) {
    case PathKind::kNone: return "";
    case PathKind::kLos: return "los";
    case PathKind::kMultipath: return "multipath";
    case PathKind::kNlos: return "nlos";
  }
  return "?";
}

std::string_view to_string(SatelliteStatus status) {
  switch (status) {
    case SatelliteStatus::kTracked: return "tracked";
    case SatelliteStatus::kBelowMask: return "below_mask";
    case SatelliteStatus::kNoEphemeris: return "no_ephemeris";
    case SatelliteStatus::kNoSignal: return "no_signal";
    case SatelliteStatus::kBlocked: return "blocked";
    case SatelliteStatus::kAttenuated: return "attenuated";
    case SatelliteStatus::kUnhealthy: return "unhealthy";
  }
  return "?";
}

ObservationGenerator::ObservationGenerator(GeneratorSettings settings, const orbits::BroadcastEphemerides& ephemerides,
                                           std::shared_ptr<const KinematicsSource> kinematics,
                                           const orbits::SatelliteStateSource* truth_orbits)
    : settings_(std::move(settings)),
      ephemerides_(ephemerides),
      truth_orbits_(truth_orbits),
      kinematics_(std::move(kinematics)),
      clock_(settings_.profile.oscillator, settings_.ideal_clock,
             stream_key(settings_.seed, {hash_name("receiver-clock"), static_cast<std::uint64_t>(settings_.receiver_index)})) {
  // The scenario's signals the receiver can track; the others are left out (run: a warning).
  std::vector<Signal> trackable;
  for (const Signal& signal : settings_.signals) {
    const SignalInfo* info = find_signal_info(signal);
    if (info == nullptr) throw std::invalid_argument("signal " + signal.to_string() + " is not in the catalogue");
    const TrackedSignal* tracked = settings_.profile.tracked(signal);
    if (tracked == nullptr) {
      untrackable_.push_back(signal);
      continue;
    }
    trackable.push_back(signal);
    signal_info_[signal] = info;
    tracked_[signal] = *tracked;
    data_modulated_[signal] = has_data_modulation(*info);
  }
  settings_.signals = std::move(trackable);
  // Aided semi-codeless loops follow the satellite's L1 C/A loop: the C/A signal comes first.
  if (settings_.profile.semicodeless_aiding_bandwidth_hz > 0.0) {
    std::stable_partition(settings_.signals.begin(), settings_.signals.end(),
                          [](const Signal& s) { return !is_semicodeless(s); });
  }
  elevation_mask_deg_ = std::max(settings_.elevation_mask_deg, settings_.profile.elevation_mask_deg);
  for (const SatelliteId& sat : ephemerides_.satellites()) {
    const bool wanted = std::any_of(settings_.signals.begin(), settings_.signals.end(),
                                    [&](const Signal& s) { return s.system == sat.system; });
    if (wanted) satellites_.push_back(sat);
  }
}

void ObservationGenerator::set_world(const PathQuery* world, const LocalFrame& frame) {
  world_ = world;
  world_frame_ = frame;
}

void ObservationGenerator::arcs_lost(const SatelliteId& sat) {
  for (const Signal& signal : settings_.signals) {
    if (const auto it = arcs_.find(SignalKey{sat, signal}); it != arcs_.end()) it->second.active = false;
  }
}

bool ObservationGenerator::transmitted(const SatelliteId& sat, const Signal& signal, const GnssTime& t) {
  const auto day = static_cast<std::int64_t>(std::floor(t.gpst_seconds_approx() / 86400.0));
  auto [it, inserted] = transmits_cache_.try_emplace(std::make_pair(sat, signal), day, false);
  if (inserted || it->second.first != day) it->second = {day, transmits(sat, signal, t)};
  return it->second.second;
}

double ObservationGenerator::satellite_power_offset_db(const SatelliteId& sat, const Signal& signal, const GnssTime& t) {
  const auto day = static_cast<std::int64_t>(std::floor(t.gpst_seconds_approx() / 86400.0));
  auto [it, inserted] = power_offset_cache_.try_emplace(std::make_pair(sat, signal), day, 0.0);
  if (inserted || it->second.first != day) {
    const auto info = satellite_info(sat, t);
    it->second = {day, info ? block_power_offset_db(info->block_id, signal) : 0.0};
  }
  return it->second.second;
}

Result<EpochObservations> ObservationGenerator::observe(const GnssTime& tag) {
  if (last_tag_) {
    if (tag <= *last_tag_) {
      return make_error(ErrorCode::kInvalidArgument, "epochs must increase: " + tag.to_iso8601(TimeScale::kGpst) +
                                                         " after " + last_tag_->to_iso8601(TimeScale::kGpst));
    }
    clock_.advance(tag - *last_tag_);
  }
  EpochObservations epoch;
  epoch.receiver_time = tag;
  epoch.receiver_clock = clock_.state();
  const double rx_clock_m = kC * epoch.receiver_clock.bias_s;
  const double rx_clock_rate_mps = kC * epoch.receiver_clock.drift_s_per_s;
  epoch.true_time = tag - epoch.receiver_clock.bias_s;
  auto kinematics = kinematics_->at(epoch.true_time);
  if (!kinematics) return kinematics.error();
  epoch.receiver = *kinematics;
  const Eigen::Vector3d& rx_m = epoch.receiver.position_m;
  const Eigen::Vector3d& rx_v_mps = epoch.receiver.velocity_mps;
  const Geodetic rx_geodetic = ecef_to_geodetic(rx_m);
  const Eigen::Matrix3d rx_to_enu = ecef_to_enu_rotation(rx_geodetic);

  // Satellites above the mask wait here for the world's verdict before their signals are measured.
  struct Pending {
    size_t index = 0;
    std::optional<RecordState> record;  // the receiver's default record (nav.rnx)
    RecordState truth;                  // the satellite's reference record, its state at transmission
    bool precise_truth = false;
    double range_m = 0.0;
    double range_rate_mps = 0.0;
    Eigen::Vector3d line_of_sight = Eigen::Vector3d::Zero();  // ECEF unit vector, receiver to satellite
    Eigen::Vector3d satellite_velocity_mps = Eigen::Vector3d::Zero();  // frame at reception
  };
  std::vector<Pending> pending;
  pending.reserve(satellites_.size());
  epoch.satellites.reserve(satellites_.size());
  for (const SatelliteId& sat : satellites_) {
    SatelliteObservation obs;
    obs.satellite = sat;
    const std::optional<orbits::NavMessage> default_message =
        sat.system == GnssSystem::kGalileo ? std::optional(orbits::NavMessage::kGalileoInav) : std::nullopt;

    std::optional<RecordState> record = select_record(ephemerides_, sat, tag, default_message, settings_.signals);
    if (!record) {
      obs.status = SatelliteStatus::kNoEphemeris;
      obs.detail = "no valid broadcast ephemeris";
      flight_time_guess_s_.erase(sat);
      epoch.satellites.push_back(std::move(obs));
      continue;
    }
    // The truth: one orbit and clock per satellite, from its reference record (or the precise
    // products below), whatever record each signal's receiver-side message has.
    RecordState truth = reference_record(ephemerides_, sat, tag, *record, settings_.signals);
    // Light-time iteration. The record is evaluated once, at a guess of the transmission time (the
    // last epoch's flight time), and the iteration moves along the second-order expansion of the
    // orbit and clock around it: the step is microseconds after the first epoch, and below 12 ms
    // even then, where the expansion is exact to 1e-10 m.
    const auto guess = flight_time_guess_s_.find(sat);
    const double guess_s = guess != flight_time_guess_s_.end() ? guess->second : 0.075;
    const GnssTime evaluation_time = epoch.true_time - guess_s;
    evaluate_record(truth, evaluation_time, glonass_orbits_);
    bool precise_truth = false;
    if (truth_orbits_ != nullptr && settings_.broadcast_truth.count(sat) == 0) {
      // Precise products as the truth: the signals come from the precise orbit and clock, while
      // the broadcast record stays the one a receiver decodes (nav.rnx, group delays). Satellites
      // the products lack or cannot serve over the run (a G/R/E product has no BeiDou) were put in
      // broadcast_truth before the run; for the others a time without products is an error (a live
      // session stepped beyond them), never a switch to the broadcast truth.
      auto precise = truth_orbits_->state(sat, evaluation_time);
      if (!precise) {
        return make_error(ErrorCode::kOutOfRange,
                          "precise truth at epoch " + tag.to_iso8601(TimeScale::kGpst, 0) + " GPST: " +
                              precise.error().message);
      }
      truth.state = *precise;
      precise_truth = true;
    }
    const orbits::SatelliteState& at_guess = truth.state;
    const Eigen::Vector3d& r0 = at_guess.position_m;
    const Eigen::Vector3d& v0 = at_guess.velocity_mps;
    // Acceleration in the Earth-fixed frame: gravity, Coriolis and centrifugal terms.
    const Eigen::Vector3d omega(0.0, 0.0, kEarthRotation_radps);
    const Eigen::Vector3d a0 = -constants::kGmGps_m3ps2 / std::pow(r0.norm(), 3) * r0 - 2.0 * omega.cross(v0) -
                               omega.cross(omega.cross(r0));
    double flight_time_s = guess_s;
    Eigen::Vector3d sat_position_m, sat_velocity_mps;
    double range_m = 0.0;
    double step_s = 0.0;  // transmission time minus evaluation time
    for (int iteration = 0; iteration < 4; ++iteration) {
      step_s = guess_s - flight_time_s;
      const Eigen::Vector3d r = r0 + v0 * step_s + 0.5 * a0 * step_s * step_s;
      sat_position_m = rotate_earth_frame(r, kEarthRotation_radps * flight_time_s);
      range_m = (sat_position_m - rx_m).norm();
      flight_time_s = range_m / kC;
    }
    step_s = guess_s - flight_time_s;
    flight_time_guess_s_[sat] = flight_time_s;
    truth.state.clock_bias_s += at_guess.clock_drift_s_per_s * step_s;
    truth.state.relativistic_s += at_guess.relativistic_drift_s_per_s * step_s;
    truth.state.velocity_mps = v0 + a0 * step_s;
    const double rotation_rad = kEarthRotation_radps * flight_time_s;
    sat_velocity_mps = rotate_earth_frame(truth.state.velocity_mps, rotation_rad);
    const Eigen::Vector3d line_of_sight = (sat_position_m - rx_m) / range_m;
    // d(range)/dt with the flight time changing too: the satellite term is scaled by (1 - d tau/dt)
    // and the Sagnac rotation angle grows with d tau/dt (d R(theta) r / d theta = (y, -x, 0)).
    const double sat_term = line_of_sight.dot(sat_velocity_mps);
    const Eigen::Vector3d rotation_derivative(sat_position_m.y(), -sat_position_m.x(), 0.0);
    const double sagnac_term = kEarthRotation_radps * line_of_sight.dot(rotation_derivative);
    const double range_rate_mps = (sat_term - line_of_sight.dot(rx_v_mps)) / (1.0 + (sat_term - sagnac_term) / kC);

    {
      const Eigen::Vector3d enu = rx_to_enu * (sat_position_m - rx_m);
      obs.direction.elevation_deg = std::atan2(enu.z(), std::hypot(enu.x(), enu.y())) * 180.0 / std::numbers::pi;
      const double azimuth_deg = std::atan2(enu.x(), enu.y()) * 180.0 / std::numbers::pi;
      obs.direction.azimuth_deg = azimuth_deg < 0.0 ? azimuth_deg + 360.0 : azimuth_deg;
    }
    obs.range_m = range_m;
    obs.range_rate_mps = range_rate_mps;
    obs.satellite_position_m = sat_position_m;
    obs.satellite_clock_m = kC * truth.state.clock_bias_s;
    obs.relativistic_m = kC * truth.state.relativistic_s;
    if (record->glonass != nullptr) obs.glonass_channel = record->glonass->frequency_channel;
    if (obs.direction.elevation_deg < elevation_mask_deg_) {
      obs.status = SatelliteStatus::kBelowMask;
      epoch.satellites.push_back(std::move(obs));
      continue;
    }
    if (settings_.troposphere == atmosphere::TroposphereModel::kSaastamoinen) {
      obs.troposphere_m = atmosphere::saastamoinen_delay_m(rx_geodetic, obs.direction.elevation_deg).value_or(0.0);
    } else if (settings_.troposphere == atmosphere::TroposphereModel::kUnb3m) {
      const double day_of_year = epoch.true_time.day_of_year(TimeScale::kGpst);
      const auto delay = atmosphere::unb3m_delay(rx_geodetic, obs.direction.elevation_deg, day_of_year);
      obs.troposphere_m = delay ? delay->slant_m() : 0.0;
    }
    if (settings_.ionosphere) {
      auto delay = settings_.ionosphere->delay_l1_m(epoch.true_time, rx_geodetic, obs.direction);
      if (!delay) return delay.error().with_context(sat.to_string());
      obs.ionosphere_l1_m = delay->value_or(0.0);
    }

    pending.push_back(Pending{epoch.satellites.size(), std::move(*record), truth, precise_truth, range_m,
                              range_rate_mps, line_of_sight, sat_velocity_mps});
    epoch.satellites.push_back(std::move(obs));
  }

  // The world: what happens to each signal on its way to the antenna, all satellites in one batch.
  std::vector<RayOutcome> outcomes;
  std::vector<PathSet> path_sets;  // multipath: every path of every satellite
  const Eigen::Matrix3d to_world = world_frame_.ecef_to_local_rotation();
  if (world_ != nullptr && !pending.empty()) {
    std::vector<Eigen::Vector3d> directions;
    directions.reserve(pending.size());
    for (const Pending& p : pending) directions.push_back(to_world * p.line_of_sight);
    if (settings_.multipath) {
      path_sets = world_->paths(world_frame_.from_ecef(rx_m), directions, settings_.path_search);
      outcomes.reserve(path_sets.size());
      for (const PathSet& set : path_sets) outcomes.push_back(set.direct);
    } else {
      outcomes = world_->trace_line_of_sight(world_frame_.from_ecef(rx_m), directions);
    }
  }

  // Channels go to the highest satellites first.
  std::vector<size_t> order(pending.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return epoch.satellites[pending[a].index].direction.elevation_deg >
           epoch.satellites[pending[b].index].direction.elevation_deg;
  });
  const ReceiverProfile& profile = settings_.profile;
  int channels_used = 0;

  for (const size_t pending_index : order) {
    Pending& p = pending[pending_index];
    SatelliteObservation& obs = epoch.satellites[p.index];
    const SatelliteId sat = obs.satellite;
    const std::optional<RecordState> record = std::move(p.record);
    const RecordState& truth = p.truth;
    const bool precise_truth = p.precise_truth;
    const double range_m = p.range_m;
    const double range_rate_mps = p.range_rate_mps;
    double attenuation_db = 0.0;
    bool direct_blocked = false;
    std::vector<ReceivedPath> received;  // multipath: the paths through the antenna
    if (!outcomes.empty()) {
      const RayOutcome& outcome = outcomes[pending_index];
      direct_blocked = outcome.blocked;
      if (outcome.blocked && (path_sets.empty() || path_sets[pending_index].paths.empty())) {
        obs.status = SatelliteStatus::kBlocked;
        obs.detail = outcome.blocking_object;
        arcs_lost(sat);
        continue;
      }
      obs.vegetation_path_m = outcome.vegetation_path_m;
      obs.vegetation_attenuation_db = outcome.vegetation_attenuation_db;
      attenuation_db = outcome.vegetation_attenuation_db;
      if (!path_sets.empty()) {
        // The paths' amplitudes carry their vegetation losses; the direct one may be absent (NLOS).
        attenuation_db = 0.0;
        const Eigen::Vector3d relative_mps = p.satellite_velocity_mps - rx_v_mps;
        const Eigen::Vector3d direction_rate =
            (relative_mps - p.line_of_sight * p.line_of_sight.dot(relative_mps)) / range_m;
        received = receive_paths(obs, std::move(path_sets[pending_index].paths), settings_.profile.antenna,
                                 rx_to_enu * to_world.transpose(), to_world * rx_v_mps, to_world * direction_rate);
        if (direct_blocked) obs.detail = "nlos, direct blocked by " + std::string(outcome.blocking_object);
      }
    }
    std::vector<MultipathErrors> multipath_of;  // per candidate signal
    // C/N0 of every signal from the link budget. A receiver acquires a satellite on a signal above
    // the acquisition threshold and hands the others over: while one signal of the satellite is
    // (or becomes) tracked, the others acquire down to the tracking threshold.
    candidates_.clear();
    std::vector<RecordState> candidate_records;  // per candidate: the receiver's record for the signal
    candidate_records.reserve(settings_.signals.size());
    bool satellite_acquirable = false;
    for (const Signal& signal : settings_.signals) {
      // A receiver records only what the satellite transmits (GPS L5 only from Block IIF on, no
      // B2I from BeiDou-3, ...); the answer is kept for the GPST day.
      if (signal.system != sat.system || !transmitted(sat, signal, tag)) continue;
      // A signal its record declares unusable is not tracked (truth.csv says why).
      RecordState signal_record = record_for_signal(ephemerides_, sat, tag, *record, signal, settings_.signals);
      if (!signal_healthy(signal_record, signal)) {
        arcs_[std::make_pair(sat, signal)].active = false;
        obs.unhealthy_signals.push_back(UnhealthySignal{signal, health_description(signal_record)});
        continue;
      }
      candidate_records.push_back(std::move(signal_record));
      // Multipath: the loops lock on the composite of the signal's paths.
      MultipathErrors multipath;
      if (!received.empty()) {
        const SignalInfo* info = signal_info_.at(signal);
        multipath = multipath_errors(CorrelationFunction::of(info->modulation), kC / info->chip_rate_hz,
                                     kC / info->carrier_frequency_hz(obs.glonass_channel),
                                     profile.correlator_spacing_chips, received);
      }
      multipath_of.push_back(multipath);
      const double cn0_dbhz = link_budget(profile, tracked_.at(signal), obs.satellite_position_m, rx_m,
                                          obs.direction.elevation_deg, obs.direction.azimuth_deg, attenuation_db,
                                          satellite_power_offset_db(sat, signal, tag))
                                  .cn0_dbhz() +
                              multipath.power_db;
      candidates_.emplace_back(&signal, cn0_dbhz);
      const Arc& arc = arcs_[std::make_pair(sat, signal)];
      if (cn0_dbhz >= profile.acquisition_threshold_dbhz || (arc.active && last_tag_ && arc.last_tag == *last_tag_)) {
        satellite_acquirable = true;
      }
    }
    const double acquisition_threshold_dbhz =
        satellite_acquirable ? profile.tracking_threshold_dbhz : profile.acquisition_threshold_dbhz;
    std::optional<GnssTime> acquired;  // when this epoch's new arcs were acquired (the earliest)
    records_used_.clear();
    std::string not_tracked_because;
    std::size_t candidate_index = 0;
    // The phase error of the satellite's L1 C/A loop at this epoch, which aided loops follow.
    std::optional<double> aiding_phase_noise_m;
    for (const auto& [signal_pointer, cn0_dbhz] : candidates_) {
      const size_t this_candidate = candidate_index++;
      const MultipathErrors& multipath = multipath_of[this_candidate];
      const Signal& signal = *signal_pointer;
      const SignalInfo* info = signal_info_.at(signal);
      const auto key = std::make_pair(sat, signal);
      Arc& arc = arcs_[key];
      const bool was_tracked = arc.active && last_tag_ && arc.last_tag == *last_tag_;
      if (profile.channel_count > 0 && channels_used >= profile.channel_count) {
        arc.active = false;
        arc.above_since.reset();
        not_tracked_because = "no free channel";
        continue;
      }
      bool new_arc = false;
      if (was_tracked) {
        if (cn0_dbhz < profile.tracking_threshold_dbhz) {
          arc.active = false;
          arc.above_since.reset();
          not_tracked_because = "below the tracking threshold";
          continue;
        }
        ++channels_used;
      } else {
        arc.active = false;
        if (cn0_dbhz < acquisition_threshold_dbhz) {
          arc.above_since.reset();
          not_tracked_because = "below the acquisition threshold";
          continue;
        }
        ++channels_used;  // a channel searches for it
        if (!arc.above_since || !last_tag_ || arc.acquiring_tag != *last_tag_) {
          // Rose (or reappeared) since the last epoch: assume halfway. At the first epoch the
          // receiver has been running before the scenario starts and tracks already.
          arc.above_since = last_tag_ ? *last_tag_ + 0.5 * (tag - *last_tag_) : tag - 1e9;
        }
        arc.acquiring_tag = tag;
        if (tag - *arc.above_since < profile.acquisition_time_s) {
          not_tracked_because = "acquiring";
          continue;
        }
        new_arc = true;
        const GnssTime signal_acquired = *arc.above_since + profile.acquisition_time_s;
        if (!acquired || signal_acquired < *acquired) acquired = signal_acquired;
      }

      // The receiver side: the record a receiver uses for this signal (the message that belongs to
      // it, Galileo E5a: F/NAV), which nav.rnx must carry.
      const RecordState* signal_record = &candidate_records[this_candidate];
      records_used_.emplace_back(signal_record->kepler, signal_record->glonass, signal_record->sbas);

      // The truth: the satellite's one clock, and the signal's code delay relative to it from the
      // group delays of the reference record (group_delay_record).
      SignalMeasurement m;
      m.signal = signal;
      m.carrier_hz = info->carrier_frequency_hz(obs.glonass_channel);
      const double wavelength_m = kC / m.carrier_hz;
      const orbits::SatelliteState& clock = truth.state;
      const RecordState& delays = group_delay_record(truth, *signal_record, signal);
      m.satellite_clock_m = kC * clock.clock_bias_s;
      m.group_delay_m = kC * (precise_truth ? precise_clock_group_delay_s(truth, delays, signal)
                                            : group_delay_of(delays, signal));
      m.ionosphere_code_m = obs.ionosphere_l1_m * std::pow(kFrequencyL1_Hz / m.carrier_hz, 2);
      m.cn0_dbhz = quantize(cn0_dbhz, profile.cn0_resolution_dbhz);

      const bool aided = profile.semicodeless_aiding_bandwidth_hz > 0.0 && aiding_phase_noise_m.has_value() &&
                         is_semicodeless(signal);
      SignalStreams* streams = nullptr;
      if (settings_.noise) {
        auto it = streams_.find(key);
        if (it == streams_.end()) {
          const auto rx = static_cast<std::uint64_t>(settings_.receiver_index);
          it = streams_
                   .emplace(key, SignalStreams(stream_key(settings_.seed, {hash_name("tracking-noise"), rx,
                                                                          satellite_key(sat), signal_key(signal)}),
                                               stream_key(settings_.seed, {hash_name("cycle-slips"), rx,
                                                                          satellite_key(sat), signal_key(signal)})))
                   .first;
        }
        streams = &it->second;
        const TrackingNoise sigma = tracking_noise(profile, *info, m.carrier_hz, cn0_dbhz);
        const double phase_bandwidth_hz = aided ? profile.semicodeless_aiding_bandwidth_hz : profile.pll_bandwidth_hz;
        // Loop outputs, correlated over each loop's time constant (profile.hpp); a new arc starts afresh.
        LoopNoiseState& loops = streams->loops;
        const double now_s = tag.gpst_seconds_approx();
        const double dt_s = loops.started && was_tracked ? now_s - loops.last_s : std::numeric_limits<double>::infinity();
        loops.code = gauss_markov_step(loops.code, dt_s, loop_time_constant_s(profile.dll_bandwidth_hz),
                                       streams->noise.gaussian());
        loops.phase = gauss_markov_step(loops.phase, dt_s, loop_time_constant_s(phase_bandwidth_hz),
                                        streams->noise.gaussian());
        loops.doppler = gauss_markov_step(loops.doppler, dt_s, loop_time_constant_s(profile.fll_bandwidth_hz),
                                          streams->noise.gaussian());
        loops.started = true;
        loops.last_s = now_s;
        m.code_noise_m = sigma.code_m * loops.code;
        m.phase_noise_m = sigma.phase_m * loops.phase;
        if (aided) {
          // The aided loop's phase is the C/A loop's (in metres) plus what its narrow loop adds.
          const double residual_m = pll_jitter_rad(profile, cn0_dbhz, phase_bandwidth_hz) * wavelength_m /
                                    (2.0 * std::numbers::pi);
          m.phase_noise_m = *aiding_phase_noise_m + residual_m * loops.phase;
        }
        if (signal == kAidingSignal) aiding_phase_noise_m = m.phase_noise_m;
        m.doppler_noise_mps = sigma.doppler_mps * loops.doppler;
      }

      // Carrier-phase arcs: a signal tracked at the previous epoch continues its arc unless the
      // loop slips (more likely the weaker the signal); an acquisition starts a new arc with a new
      // integer ambiguity. Both set the loss-of-lock flag and restart the lock time.
      const bool data = data_modulated_.at(signal);
      if (new_arc) {
        ++arc.index;
        RandomStream ambiguity(stream_key(settings_.seed, {hash_name("ambiguity"), static_cast<std::uint64_t>(settings_.receiver_index),
                                                           satellite_key(sat), signal_key(signal),
                                                           static_cast<std::uint64_t>(arc.index)}));
        arc.ambiguity_cycles = ambiguity.uniform_int(-1000000, 1000000);
        arc.lock_start = tag;
        m.loss_of_lock = true;
      } else if (streams != nullptr && profile.pll_bandwidth_hz > 0.0) {
        const double loop_bandwidth_hz = aided ? profile.semicodeless_aiding_bandwidth_hz : profile.pll_bandwidth_hz;
        const double mean_s =
            mean_time_to_slip_s(pll_jitter_rad(profile, cn0_dbhz, loop_bandwidth_hz), loop_bandwidth_hz, data);
        const double probability = -std::expm1(-(tag - *last_tag_) / mean_s);
        if (streams->slips.uniform() < probability) {
          // The slip is a whole number of cycles (half cycles of a Costas loop resolve again).
          const std::int64_t size = streams->slips.uniform_int(1, 5);
          arc.ambiguity_cycles += streams->slips.uniform() < 0.5 ? -size : size;
          ++arc.index;
          arc.lock_start = tag;
          m.loss_of_lock = true;
        }
      }
      arc.active = true;
      arc.above_since.reset();
      arc.last_tag = tag;
      m.ambiguity_cycles = arc.ambiguity_cycles;
      m.lock_time_s = tag - arc.lock_start;
      m.code_multipath_m = multipath.code_m;
      m.phase_multipath_m = multipath.phase_m;
      m.range_rate_multipath_mps = multipath.range_rate_mps;
      m.multipath_power_db = multipath.power_db;
      m.half_cycle_unresolved = data && m.lock_time_s < profile.half_cycle_resolution_s;

      const double satellite_clock_total_m = m.satellite_clock_m + obs.relativistic_m;
      m.pseudorange_m = range_m + rx_clock_m - (satellite_clock_total_m - m.group_delay_m) + m.ionosphere_code_m +
                        obs.troposphere_m + m.code_noise_m + m.code_multipath_m;
      const double phase_range_m = range_m + rx_clock_m - satellite_clock_total_m - m.ionosphere_code_m +
                                   obs.troposphere_m + m.phase_noise_m + m.phase_multipath_m;
      m.carrier_phase_cycles = phase_range_m / wavelength_m + static_cast<double>(m.ambiguity_cycles);
      const double satellite_clock_rate_mps = kC * (clock.clock_drift_s_per_s + clock.relativistic_drift_s_per_s);
      const double phase_range_rate_mps = range_rate_mps + rx_clock_rate_mps - satellite_clock_rate_mps +
                                          m.doppler_noise_mps + m.range_rate_multipath_mps;
      m.doppler_hz = -phase_range_rate_mps / wavelength_m;
      obs.signals.push_back(m);
    }
    if (obs.signals.empty() && direct_blocked) {
      obs.status = SatelliteStatus::kBlocked;  // its reflected and diffracted paths are too weak
      obs.detail = std::string(outcomes[pending_index].blocking_object) + " (indirect paths too weak)";
      obs.path_kind = PathKind::kNone;  // paths.csv still lists them
      arcs_lost(sat);
    } else if (obs.signals.empty() && candidates_.empty() && !obs.unhealthy_signals.empty()) {
      obs.status = SatelliteStatus::kUnhealthy;  // every signal it transmits of the listed ones
      obs.detail = obs.unhealthy_signals.front().reason;
    } else if (obs.signals.empty()) {
      const bool attenuated = attenuation_db > 0.0 && not_tracked_because.starts_with("below");
      obs.status = attenuated ? SatelliteStatus::kAttenuated : SatelliteStatus::kNoSignal;
      obs.detail = attenuated ? not_tracked_because + " after vegetation"
                              : (not_tracked_because.empty() ? "no listed signal tracked" : not_tracked_because);
    } else if (profile.output_requires_ephemeris && !holds_ephemeris(obs, tag, acquired)) {
      // Tracked (channel, arcs, lock time and noise streams run on) but not output.
      obs.status = SatelliteStatus::kNoEphemeris;
      obs.waiting_for_ephemeris = true;
      obs.signals.clear();
      continue;
    }
    for (const auto& [kepler, glonass, sbas] : records_used_) {
      if (kepler != nullptr) used_kepler_.insert(kepler);
      if (glonass != nullptr) used_glonass_.insert(glonass);
      if (sbas != nullptr) used_sbas_.insert(sbas);
    }
  }
  if (profile.output_requires_ephemeris) {
    // A satellite lost before its ephemeris was decoded starts decoding again at its next acquisition.
    for (auto it = ephemeris_state_.begin(); it != ephemeris_state_.end();) {
      if (!it->second.held && it->second.tracked_tag != tag) {
        it = ephemeris_state_.erase(it);
      } else {
        ++it;
      }
    }
  }
  last_tag_ = tag;
  return epoch;
}

bool ObservationGenerator::holds_ephemeris(SatelliteObservation& obs, const GnssTime& tag,
                                           const std::optional<GnssTime>& acquired) {
  const SatelliteId& sat = obs.satellite;
  EphemerisState& state = ephemeris_state_[sat];
  state.tracked_tag = tag;
  if (state.held) return true;
  if (!last_tag_) {
    // The run's first epoch: the receiver ran before and holds the ephemerides of what it tracks.
    state.held = true;
    return true;
  }
  if (!state.decoding) {
    state.decoding = true;
    std::vector<Signal> signals;  // what the receiver tracks of the satellite
    signals.reserve(candidates_.size());
    for (const auto& [signal, cn0_dbhz] : candidates_) signals.push_back(*signal);
    state.held_from = ephemeris_held_from(ephemerides_, sat, acquired.value_or(tag), signals);
  }
  if (state.held_from && tag >= *state.held_from) {
    // The first output: the carrier was tracked since the acquisition (the lock time says so), but
    // for the user the arcs start here; the NetR9 flags them (LLI 1), as at any acquisition.
    state.held = true;
    for (SignalMeasurement& m : obs.signals) m.loss_of_lock = true;
    return true;
  }
  obs.detail = state.held_from ? "navigation message not yet decoded (ephemeris held from " +
                                 state.held_from->to_iso8601(TimeScale::kGpst, 0) + " GPST)"
                           : "navigation message not yet decoded (no record to decode)";
  return false;
}

}  // namespace skytrace::receiver
