#include "skytrace/receiver/observation_generator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "skytrace/core/constants.hpp"
#include "skytrace/receiver/link_budget.hpp"
#include "skytrace/receiver/stages/observables.hpp"

namespace skytrace::receiver {
namespace {

constexpr double kC = constants::kSpeedOfLight_mps;
// The loop that aids semi-codeless P(Y) tracking (ReceiverProfile::semicodeless_aiding_bandwidth_hz).
const Signal kAidingSignal{GnssSystem::kGps, '1', 'C'};

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
             stream_key(settings_.seed, {hash_name("receiver-clock"), static_cast<std::uint64_t>(settings_.receiver_index)})),
      tracking_(settings_.seed, settings_.receiver_index, settings_.noise),
      loop_noise_(settings_.seed, settings_.receiver_index),
      foliage_fading_(settings_.seed, settings_.receiver_index, settings_.foliage) {
  if (truth_orbits_ != nullptr) {
    truth_view_ = truth_orbits_->sequential_view();
    if (truth_view_ != nullptr) truth_orbits_ = truth_view_.get();
  }
  // The scenario's signals the receiver can track; the others are left out (run: a warning).
  std::vector<std::pair<Signal, ListedSignal>> trackable;
  for (const Signal& signal : settings_.signals) {
    const SignalInfo* info = find_signal_info(signal);
    if (info == nullptr) throw std::invalid_argument("signal " + signal.to_string() + " is not in the catalogue");
    const TrackedSignal* tracked = settings_.profile.tracked(signal);
    if (tracked == nullptr) {
      untrackable_.push_back(signal);
      continue;
    }
    trackable.emplace_back(signal, ListedSignal{info, *tracked, has_data_modulation(*info)});
  }
  // Aided semi-codeless channels follow the satellite's L1 C/A channel: the C/A signal comes first.
  if (settings_.profile.semicodeless_aiding_bandwidth_hz > 0.0 || settings_.profile.semicodeless_threshold_dbhz) {
    std::stable_partition(trackable.begin(), trackable.end(),
                          [](const auto& entry) { return !is_semicodeless(entry.first); });
  }
  settings_.signals.clear();
  for (auto& [signal, listed] : trackable) {
    settings_.signals.push_back(signal);
    listed_.push_back(std::move(listed));
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

namespace {

// The satellite's slot `used` of the epoch, as a default-constructed observation that keeps the
// storage of the slot's vectors and strings from an earlier epoch: copy-assigning an empty vector
// or string keeps the target's capacity.
SatelliteObservation& reused_slot(std::vector<SatelliteObservation>& satellites, size_t used) {
  if (used == satellites.size()) return satellites.emplace_back();
  static const SatelliteObservation kBlank;
  SatelliteObservation& obs = satellites[used];
  obs = kBlank;
  return obs;
}

}  // namespace

Result<EpochObservations> ObservationGenerator::observe(const GnssTime& tag) {
  EpochObservations epoch;
  if (auto st = observe(tag, epoch); !st) return st.error();
  return epoch;
}

Status ObservationGenerator::observe(const GnssTime& tag, EpochObservations& epoch) {
  if (last_tag_) {
    if (tag <= *last_tag_) {
      return make_error(ErrorCode::kInvalidArgument, "epochs must increase: " + tag.to_iso8601(TimeScale::kGpst) +
                                                         " after " + last_tag_->to_iso8601(TimeScale::kGpst));
    }
    clock_.advance(tag - *last_tag_);
  }
  size_t used = 0;  // satellites written into epoch.satellites so far
  epoch.receiver_time = tag;
  epoch.receiver_clock = clock_.state();
  epoch.true_time = tag - epoch.receiver_clock.bias_s;
  auto kinematics = kinematics_->at(epoch.true_time);
  if (!kinematics) return kinematics.error();
  epoch.receiver = *kinematics;
  const Eigen::Vector3d& rx_m = epoch.receiver.position_m;
  const Geodetic rx_geodetic = ecef_to_geodetic(rx_m);
  const Eigen::Matrix3d rx_to_enu = ecef_to_enu_rotation(rx_geodetic);

  // Stage 1, geometry and light time, and the atmosphere along the line of sight (stage 5) of every
  // satellite; those above the mask wait for the world's verdict before their signals are measured.
  pending_.clear();
  lines_of_sight_.clear();
  epoch.satellites.reserve(satellites_.size());
  flight_time_guess_s_.resize(satellites_.size());
  for (size_t satellite_index = 0; satellite_index < satellites_.size(); ++satellite_index) {
    const SatelliteId& sat = satellites_[satellite_index];
    std::optional<double>& flight_time_guess_s = flight_time_guess_s_[satellite_index];
    SatelliteObservation& obs = reused_slot(epoch.satellites, used++);
    obs.satellite = sat;
    std::optional<stages::RecordState> record = stages::select_default_record(ephemerides_, sat, tag, settings_.signals);
    if (!record) {
      obs.status = SatelliteStatus::kNoEphemeris;
      obs.detail = "no valid broadcast ephemeris";
      flight_time_guess_s.reset();
      continue;
    }
    // The truth: one orbit and clock per satellite, from its reference record (or the precise
    // products below), whatever record each signal's receiver-side message has. It is evaluated
    // once, at a guess of the transmission time (the last epoch's flight time).
    stages::RecordState truth = stages::reference_record(ephemerides_, sat, tag, *record, settings_.signals);
    const double guess_s = flight_time_guess_s.value_or(stages::kFirstFlightTimeGuess_s);
    const GnssTime evaluation_time = epoch.true_time - guess_s;
    const bool from_precise_products = truth_orbits_ != nullptr && settings_.broadcast_truth.count(sat) == 0;
    if (!from_precise_products) stages::evaluate_record(truth, evaluation_time, glonass_orbits_);
    bool precise_truth = false;
    if (from_precise_products) {
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
    const stages::LightTime light_time =
        stages::solve_light_time(truth.state, guess_s, rx_m, epoch.receiver.velocity_mps);
    flight_time_guess_s = light_time.flight_time_s;
    truth.state = light_time.state;
    obs.direction = stages::local_direction(rx_to_enu * (light_time.position_m - rx_m));
    obs.range_m = light_time.range_m;
    obs.range_rate_mps = light_time.range_rate_mps;
    obs.satellite_position_m = light_time.position_m;
    obs.satellite_clock_m = kC * truth.state.clock_bias_s;
    obs.relativistic_m = kC * truth.state.relativistic_s;
    if (record->glonass != nullptr) obs.glonass_channel = record->glonass->frequency_channel;
    if (obs.direction.elevation_deg < elevation_mask_deg_) {
      obs.status = SatelliteStatus::kBelowMask;
      continue;
    }
    auto atmosphere = stages::atmosphere_terms(settings_.troposphere, settings_.ionosphere.get(), epoch.true_time,
                                               rx_geodetic, obs.direction, settings_.troposphere_residual.get());
    if (!atmosphere) return atmosphere.error().with_context(sat.to_string());
    obs.troposphere_m = atmosphere->troposphere_m;
    obs.ionosphere_l1_m = atmosphere->ionosphere_l1_m;

    pending_.push_back(Pending{used - 1, *record, truth, precise_truth, light_time});
    lines_of_sight_.push_back(light_time.line_of_sight);
  }
  epoch.satellites.resize(used);

  // Stage 2: what the world does to each signal on its way to the antenna, all satellites in one batch.
  world_outcomes_.clear();
  if (world_ != nullptr) {
    stages::query_world(*world_, world_frame_, settings_.multipath, settings_.path_search, rx_m, lines_of_sight_,
                        world_directions_, world_outcomes_);
  }

  // Stages 2 to 6 per satellite; channels go to the highest satellites first.
  order_.resize(pending_.size());
  for (size_t i = 0; i < order_.size(); ++i) order_[i] = i;
  std::stable_sort(order_.begin(), order_.end(), [&](size_t a, size_t b) {
    return epoch.satellites[pending_[a].index].direction.elevation_deg >
           epoch.satellites[pending_[b].index].direction.elevation_deg;
  });
  int channels_used = 0;
  for (const size_t pending_index : order_) observe_satellite(epoch, pending_index, rx_to_enu, channels_used);
  if (settings_.profile.output_requires_ephemeris) ephemeris_decoding_.end_epoch(tag);
  last_tag_ = tag;
  return Ok{};
}

namespace {

Eigen::Vector3d enu_unit_vector(const AzimuthElevation& direction) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double horizontal = std::cos(direction.elevation_deg * kDeg);
  return {horizontal * std::sin(direction.azimuth_deg * kDeg), horizontal * std::cos(direction.azimuth_deg * kDeg),
          std::sin(direction.elevation_deg * kDeg)};
}

// A phase lock survives a fade below its threshold shorter than two coherent integrations or the
// loop's time constant (1 / noise bandwidth), whichever is longer.
double fade_hold_s(const ReceiverProfile& profile) {
  const double loop_s = profile.pll_bandwidth_hz > 0.0 ? 1.0 / profile.pll_bandwidth_hz : 0.0;
  return std::max(2.0 * profile.integration_time_s, loop_s);
}

}  // namespace

const stages::FoliageComposite& ObservationGenerator::band_field(const SatelliteId& sat, const Signal& signal,
                                                                 const SignalInfo& info, const SatelliteObservation& obs,
                                                                 const Eigen::Vector3d& velocity_enu_mps,
                                                                 const Eigen::Vector3d& satellite_enu,
                                                                 const GnssTime& tag) {
  for (const auto& [band, field] : band_fields_) {
    if (band == signal.band) return *field;
  }
  const double carrier_hz = info.carrier_frequency_hz(obs.glonass_channel);
  const stages::FoliageComposite& field =
      foliage_fading_.composite(sat, signal.band, carrier_hz, obs.vegetation_attenuation_db, obs.vegetation_path_m,
                                velocity_enu_mps, satellite_enu, tag, last_tag_);
  band_fields_.emplace_back(signal.band, &field);
  return field;
}

const AntennaPattern* ObservationGenerator::signal_antenna(const TrackedSignal* tracked) const {
  return tracked != nullptr && tracked->antenna ? tracked->antenna.get() : &settings_.profile.antenna;
}

const std::vector<ReceivedPath>& ObservationGenerator::received_through(const AntennaPattern* antenna,
                                                                        const std::vector<ReceivedPath>& received,
                                                                        const SatelliteObservation& obs) {
  for (const auto& [pattern, paths] : band_received_) {
    if (pattern == antenna) return paths;
  }
  std::vector<ReceivedPath> paths = received;
  for (size_t i = 0; i < paths.size(); ++i) {
    const AzimuthElevation& arrival = obs.path_directions[i];
    paths[i].amplitude = antenna_amplitude(*antenna, obs.paths[i], arrival.elevation_deg, arrival.azimuth_deg,
                                           obs.direction.elevation_deg, obs.direction.azimuth_deg);
  }
  band_received_.emplace_back(antenna, std::move(paths));
  return band_received_.back().second;
}

void ObservationGenerator::observe_satellite(EpochObservations& epoch, size_t pending_index,
                                             const Eigen::Matrix3d& rx_to_enu, int& channels_used) {
  const Pending& p = pending_[pending_index];
  SatelliteObservation& obs = epoch.satellites[p.index];
  const SatelliteId sat = obs.satellite;
  const GnssTime& tag = epoch.receiver_time;
  const Eigen::Vector3d& rx_m = epoch.receiver.position_m;
  const ReceiverProfile& profile = settings_.profile;

  // Stage 2: the direct ray (blocked, vegetation) and, with multipath, the paths through the antenna.
  double attenuation_db = 0.0;
  bool direct_blocked = false;
  std::vector<ReceivedPath> received;  // multipath: the paths through the antenna
  const AntennaPattern* received_antenna = nullptr;  // the band table `received` went through
  band_received_.clear();
  if (!world_outcomes_.direct.empty()) {
    const RayOutcome& outcome = world_outcomes_.direct[pending_index];
    std::vector<PathSet>& path_sets = world_outcomes_.path_sets;
    direct_blocked = outcome.blocked;
    if (outcome.blocked && (path_sets.empty() || path_sets[pending_index].paths.empty())) {
      obs.status = SatelliteStatus::kBlocked;
      obs.detail = outcome.blocking_object;
      tracking_.lost(sat, settings_.signals);
      return;
    }
    obs.vegetation_path_m = outcome.vegetation_path_m;
    obs.vegetation_attenuation_db = outcome.vegetation_attenuation_db;
    attenuation_db = outcome.vegetation_attenuation_db;
    if (!path_sets.empty()) {
      // The paths' amplitudes carry their vegetation losses; the direct one may be absent (NLOS).
      attenuation_db = 0.0;
      const Eigen::Matrix3d to_world = world_frame_.ecef_to_local_rotation();
      const Eigen::Vector3d direction_rate =
          stages::direction_rate_per_s(p.light_time.line_of_sight, p.light_time.range_m, p.light_time.velocity_mps,
                                       epoch.receiver.velocity_mps);
      received_antenna = signal_antenna(listed_.empty() ? nullptr : &listed_.front().tracked);
      stages::ReceivedPaths arriving =
          stages::receive_paths(path_sets[pending_index].paths, *received_antenna, obs.direction,
                                rx_to_enu * to_world.transpose(), to_world * epoch.receiver.velocity_mps,
                                to_world * direction_rate);
      obs.path_kind = arriving.kind;
      obs.path_directions = std::move(arriving.arrival_directions);
      obs.path_delay_rates_mps = std::move(arriving.delay_rates_mps);
      obs.paths = std::move(path_sets[pending_index].paths);
      received = std::move(arriving.received);
      if (direct_blocked) obs.detail = "nlos, direct blocked by " + std::string(outcome.blocking_object);
    }
  }

  // Stage 3 (with the multipath errors of stage 5, whose prompt power enters C/N0): the signals the
  // satellite transmits healthy, and their C/N0 from the link budget.
  candidates_.clear();
  bool acquirable = false;
  // Foliage fading: the direct ray crosses vegetation (and is not blocked); one field per band.
  const bool fading = settings_.foliage.enabled && settings_.noise && obs.vegetation_attenuation_db > 0.0 &&
                      !direct_blocked;
  band_fields_.clear();
  Eigen::Vector3d velocity_enu_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d satellite_enu = Eigen::Vector3d::Zero();
  if (fading) {
    velocity_enu_mps = rx_to_enu * epoch.receiver.velocity_mps;
    satellite_enu = enu_unit_vector(obs.direction);
  }
  const stages::SatelliteTerms terms{p.light_time.range_m,
                                     p.light_time.range_rate_mps,
                                     kC * epoch.receiver_clock.bias_s,
                                     kC * epoch.receiver_clock.drift_s_per_s,
                                     obs.relativistic_m,
                                     kC * (p.truth.state.clock_drift_s_per_s + p.truth.state.relativistic_drift_s_per_s),
                                     obs.troposphere_m};
  SatelliteLink link(obs.satellite_position_m, rx_m);  // the budget terms the signals share
  for (size_t signal_index = 0; signal_index < settings_.signals.size(); ++signal_index) {
    const Signal& signal = settings_.signals[signal_index];
    const ListedSignal& listed = listed_[signal_index];
    // A receiver records only what the satellite transmits; the answer is kept for the GPST day.
    if (signal.system != sat.system) continue;
    const stages::SatelliteSignals::Facts& facts = satellite_signals_.facts(sat, signal, tag);
    if (!facts.transmitted) continue;
    // A signal its record declares unusable is not tracked (truth.csv says why).
    stages::RecordState signal_record =
        stages::record_for_signal(ephemerides_, sat, tag, p.record, signal, settings_.signals);
    if (!stages::signal_healthy(signal_record, signal)) {
      tracking_.drop(sat, signal);
      obs.unhealthy_signals.push_back(UnhealthySignal{signal, stages::health_description(signal_record)});
      continue;
    }
    // Multipath: the loops lock on the composite of the signal's paths.
    // A band whose antenna table differs from the first signal's gets its own path amplitudes.
    const AntennaPattern* antenna = signal_antenna(&listed.tracked);
    const std::vector<ReceivedPath>& through_antenna =
        received.empty() || antenna == received_antenna ? received : received_through(antenna, received, obs);
    const MultipathErrors multipath = stages::signal_multipath_errors(*listed.info, obs.glonass_channel,
                                                                      profile.correlator_spacing_chips, through_antenna);
    const double cn0_dbhz = stages::signal_cn0_dbhz(profile, listed.tracked, link, obs.direction, attenuation_db,
                                                    facts.power_offset_db,
                                                    multipath.power_db);
    if (settings_.incoming_signals) {
      IncomingSignal in;
      in.signal = signal;
      SignalMeasurement clean;
      clean.signal = signal;
      clean.carrier_hz = listed.info->carrier_frequency_hz(obs.glonass_channel);
      clean.satellite_clock_m = kC * p.truth.state.clock_bias_s;
      clean.group_delay_m =
          kC * stages::signal_group_delay_s(p.truth, signal_record, signal, p.precise_truth, facts.code_bias_m);
      clean.ionosphere_code_m = stages::ionosphere_code_delay_m(obs.ionosphere_l1_m, clean.carrier_hz);
      clean.antenna_phase_centre_m =
          stages::antenna_phase_centre_m(settings_.antenna_phase_centre.get(), signal, obs.direction);
      stages::form_observables(terms, clean);
      in.carrier_hz = clean.carrier_hz;
      in.pseudorange_m = clean.pseudorange_m;
      in.carrier_phase_cycles = clean.carrier_phase_cycles;
      in.doppler_hz = clean.doppler_hz;
      in.antenna_cn0_dbhz = cn0_dbhz - multipath.power_db + profile.implementation_loss_db;
      in.paths.reserve(through_antenna.size());
      for (const ReceivedPath& r : through_antenna) {
        in.paths.push_back(IncomingPath{r.excess_delay_m, r.excess_delay_rate_mps, r.amplitude});
      }
      obs.incoming.push_back(std::move(in));
    }
    stages::Candidate candidate{&signal, cn0_dbhz, multipath, std::move(signal_record), nullptr, {}, facts.code_bias_m};
    if (fading) {
      candidate.foliage = &band_field(sat, signal, *listed.info, obs, velocity_enu_mps, satellite_enu, tag);
      candidate.fade = candidate.foliage->for_signal(cn0_dbhz, profile.tracking_threshold_dbhz, fade_hold_s(profile));
      candidate.cn0_dbhz += candidate.fade.cn0_change_db;
    }
    if ((candidate.cn0_dbhz >= stages::search_threshold_dbhz(profile, last_tag_.has_value()) &&
         !candidate.fade.faded_out) ||
        tracking_.tracked_at(sat, signal, last_tag_)) {
      acquirable = true;
    }
    candidates_.push_back(std::move(candidate));
  }

  stages::SatelliteAcquisition acquisition = tracking_.begin_satellite(profile, acquirable, last_tag_.has_value());
  obs.signals.reserve(candidates_.size());
  records_used_.clear();
  // The errors of the satellite's L1 C/A loop at this epoch, which aided loops follow.
  std::optional<stages::AidingLoop> aiding_loop;
  bool aiding_locked = false;  // the satellite's L1 C/A channel this epoch (candidates list it first)
  for (const stages::Candidate& candidate : candidates_) {
    const Signal& signal = *candidate.signal;
    const double cn0_dbhz = candidate.cn0_dbhz;
    // Stage 4: channel, acquisition, lock; a foliage fade lasting at the epoch loses the signal.
    if (candidate.fade.faded_out) {
      tracking_.drop(sat, signal);
      acquisition.not_tracked_because = "below the tracking threshold in a foliage fade";
      continue;
    }
    const std::optional<double> aided_threshold_dbhz =
        aiding_locked && is_semicodeless(signal) ? profile.semicodeless_threshold_dbhz : std::nullopt;
    const auto lock =
        tracking_.lock(profile, sat, signal, cn0_dbhz, tag, last_tag_, channels_used, acquisition, aided_threshold_dbhz);
    if (lock == stages::TrackingState::Lock::kNone) continue;
    if (signal == kAidingSignal) aiding_locked = true;
    // The receiver side: the record a receiver uses for this signal (the message that belongs to
    // it, Galileo E5a: F/NAV), which nav.rnx must carry.
    records_used_.emplace_back(candidate.record.kepler, candidate.record.glonass, candidate.record.sbas);

    // Stage 5: the satellite's one clock, the signal's code delay relative to it, the ionosphere,
    // the loop noise and the multipath errors.
    const ListedSignal& listed = listed_[static_cast<size_t>(candidate.signal - settings_.signals.data())];
    const SignalInfo& info = *listed.info;
    SignalMeasurement m;
    m.signal = signal;
    m.carrier_hz = info.carrier_frequency_hz(obs.glonass_channel);
    m.satellite_clock_m = kC * p.truth.state.clock_bias_s;
    m.group_delay_m = kC * stages::signal_group_delay_s(p.truth, candidate.record, signal, p.precise_truth,
                                                       candidate.block_code_bias_m);
    m.ionosphere_code_m = stages::ionosphere_code_delay_m(obs.ionosphere_l1_m, m.carrier_hz);
    m.antenna_phase_centre_m = stages::antenna_phase_centre_m(settings_.antenna_phase_centre.get(), signal, obs.direction);
    m.cn0_dbhz = stages::quantize(cn0_dbhz, profile.cn0_resolution_dbhz);
    // Semi-codeless channels report the C/A loop's Doppler; their phase follows it when the
    // profile aids their carrier loop.
    const bool follows_ca = aiding_loop.has_value() && is_semicodeless(signal);
    const bool aided = profile.semicodeless_aiding_bandwidth_hz > 0.0 && follows_ca;
    if (settings_.noise) {
      const stages::LoopErrors noise =
          loop_noise_.draw(sat, signal, profile, info, m.carrier_hz, cn0_dbhz,
                           follows_ca ? aiding_loop : std::nullopt, lock == stages::TrackingState::Lock::kContinuing, tag);
      m.code_noise_m = noise.code_m;
      m.phase_noise_m = noise.phase_m;
      m.doppler_noise_mps = noise.doppler_mps;
      if (signal == kAidingSignal) aiding_loop = stages::AidingLoop{m.phase_noise_m, m.doppler_noise_mps};
    }
    m.code_multipath_m = candidate.multipath.code_m;
    m.phase_multipath_m = candidate.multipath.phase_m;
    m.range_rate_multipath_mps = candidate.multipath.range_rate_mps;
    m.multipath_power_db = candidate.multipath.power_db;
    if (candidate.foliage != nullptr) {
      m.foliage_code_m = candidate.foliage->code_error_m;
      m.foliage_phase_m = candidate.foliage->phase_error_m;
      m.foliage_range_rate_mps = candidate.foliage->range_rate_error_mps;
      m.foliage_power_db = candidate.fade.cn0_change_db;
    }

    // Stage 4: the carrier arc (acquisition or slip set the loss-of-lock flag and restart the lock
    // time; a foliage fade that broke the phase lock since the last epoch starts a new arc).
    const bool new_arc = lock == stages::TrackingState::Lock::kNewArc || candidate.fade.slipped;
    const auto arc = tracking_.carrier_arc(profile, sat, signal, new_arc,
                                           cn0_dbhz, aided, listed.data_modulated, tag, last_tag_);
    m.loss_of_lock = arc.loss_of_lock;
    m.ambiguity_cycles = arc.ambiguity_cycles;
    m.lock_time_s = arc.lock_time_s;
    m.half_cycle_unresolved = arc.half_cycle_unresolved;

    // Stage 6: the observables.
    stages::form_observables(terms, m);
    obs.signals.push_back(m);
  }
  if (obs.signals.empty() && direct_blocked) {
    obs.status = SatelliteStatus::kBlocked;  // its reflected and diffracted paths are too weak
    // Say how weak: the strongest signal through its indirect paths and why it was not tracked.
    double strongest_dbhz = -std::numeric_limits<double>::infinity();
    for (const stages::Candidate& candidate : candidates_) strongest_dbhz = std::max(strongest_dbhz, candidate.cn0_dbhz);
    obs.detail = std::string(world_outcomes_.direct[pending_index].blocking_object);
    obs.detail += " (indirect paths too weak";
    if (std::isfinite(strongest_dbhz)) {
      char level[32];
      std::snprintf(level, sizeof level, ": %.1f dB-Hz", strongest_dbhz);
      obs.detail += level;
      if (!acquisition.not_tracked_because.empty()) obs.detail += ", " + acquisition.not_tracked_because;
    }
    obs.detail += ")";
    obs.path_kind = PathKind::kNone;  // paths.csv still lists them
    tracking_.lost(sat, settings_.signals);
  } else if (obs.signals.empty() && candidates_.empty() && !obs.unhealthy_signals.empty()) {
    obs.status = SatelliteStatus::kUnhealthy;  // every signal it transmits of the listed ones
    obs.detail = obs.unhealthy_signals.front().reason;
  } else if (obs.signals.empty()) {
    const std::string& because = acquisition.not_tracked_because;
    const bool attenuated = attenuation_db > 0.0 && because.starts_with("below");
    obs.status = attenuated ? SatelliteStatus::kAttenuated : SatelliteStatus::kNoSignal;
    obs.detail = attenuated ? because + " after vegetation" : (because.empty() ? "no listed signal tracked" : because);
  } else if (profile.output_requires_ephemeris &&
             !ephemeris_decoding_.holds(ephemerides_, obs, tag, !last_tag_, acquisition.acquired, candidates_)) {
    // Tracked (channel, arcs, lock time and noise streams run on) but not output.
    obs.status = SatelliteStatus::kNoEphemeris;
    obs.waiting_for_ephemeris = true;
    obs.signals.clear();
    return;
  }
  // A satellite's signals mostly share one record: each record once into the sets.
  const orbits::KeplerEphemeris* last_kepler = nullptr;
  const orbits::GlonassEphemeris* last_glonass = nullptr;
  const orbits::SbasEphemeris* last_sbas = nullptr;
  for (const auto& [kepler, glonass, sbas] : records_used_) {
    if (kepler != nullptr && kepler != last_kepler) used_kepler_.insert(last_kepler = kepler);
    if (glonass != nullptr && glonass != last_glonass) used_glonass_.insert(last_glonass = glonass);
    if (sbas != nullptr && sbas != last_sbas) used_sbas_.insert(last_sbas = sbas);
  }
}

}  // namespace skytrace::receiver
