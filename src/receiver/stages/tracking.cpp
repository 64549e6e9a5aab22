#include "skytrace/receiver/stages/tracking.hpp"

#include <algorithm>
#include <cmath>

#include "skytrace/receiver/ephemeris_decoding.hpp"

namespace skytrace::receiver::stages {

double search_threshold_dbhz(const ReceiverProfile& profile, bool running) {
  return running && profile.reacquisition_threshold_dbhz ? *profile.reacquisition_threshold_dbhz
                                                         : profile.acquisition_threshold_dbhz;
}

namespace {

// Deflection of the square-law detection statistic an aided search needs:
// Q^-1(1e-4 false alarms per cell) + Q^-1(1 - 0.9 detection) = 3.72 + 1.28.
constexpr double kDetectionDeflection = 5.0;

// Signal-to-noise ratio of one coherent block of `coherent_s` at `cn0_dbhz`.
double block_snr(double cn0_dbhz, double coherent_s) { return std::pow(10.0, cn0_dbhz / 10.0) * coherent_s; }

}  // namespace

double reacquisition_dwell_s(double cn0_dbhz, double coherent_s) {
  const double rho = block_snr(cn0_dbhz, coherent_s);
  return coherent_s * kDetectionDeflection * kDetectionDeflection * (1.0 + 2.0 * rho) / (rho * rho);
}

bool TrackingState::tracked_at(const SatelliteId& sat, const Signal& signal, const std::optional<GnssTime>& last_tag) {
  const Arc& arc = arcs_[SignalKey{sat, signal}];
  return arc.active && last_tag && arc.last_tag == *last_tag;
}

void TrackingState::drop(const SatelliteId& sat, const Signal& signal) { arcs_[SignalKey{sat, signal}].active = false; }

void TrackingState::lost(const SatelliteId& sat, std::span<const Signal> signals) {
  for (const Signal& signal : signals) {
    if (const auto it = arcs_.find(SignalKey{sat, signal}); it != arcs_.end()) it->second.active = false;
  }
}

TrackingState::Lock TrackingState::lock(const ReceiverProfile& profile, const SatelliteId& sat, const Signal& signal,
                                        double cn0_dbhz, const GnssTime& tag, const std::optional<GnssTime>& last_tag,
                                        int& channels_used, SatelliteAcquisition& satellite,
                                        std::optional<double> aided_threshold_dbhz) {
  Arc& arc = arcs_[SignalKey{sat, signal}];
  const bool was_tracked = arc.active && last_tag && arc.last_tag == *last_tag;
  if (profile.channel_count > 0 && channels_used >= profile.channel_count) {
    arc.active = false;
    arc.above_since.reset();
    satellite.not_tracked_because = "no free channel";
    return Lock::kNone;
  }
  if (was_tracked) {
    if (cn0_dbhz < aided_threshold_dbhz.value_or(profile.tracking_threshold_dbhz)) {
      arc.active = false;
      arc.above_since.reset();
      satellite.not_tracked_because = "below the tracking threshold";
      return Lock::kNone;
    }
    ++channels_used;
    return Lock::kContinuing;
  }
  arc.active = false;
  if (last_tag && profile.reacquisition_threshold_dbhz && !aided_threshold_dbhz) {
    return aided_search(profile, arc, cn0_dbhz, tag, *last_tag, channels_used, satellite);
  }
  if (cn0_dbhz < aided_threshold_dbhz.value_or(satellite.acquisition_threshold_dbhz)) {
    arc.above_since.reset();
    satellite.not_tracked_because = "below the acquisition threshold";
    return Lock::kNone;
  }
  ++channels_used;  // a channel searches for it
  if (!arc.above_since || !last_tag || arc.acquiring_tag != *last_tag) {
    // Rose (or reappeared) since the last epoch: assume halfway. At the first epoch the receiver
    // has been running before the scenario starts and tracks already.
    arc.above_since = last_tag ? *last_tag + 0.5 * (tag - *last_tag) : tag - 1e9;
  }
  arc.acquiring_tag = tag;
  if (tag - *arc.above_since < profile.acquisition_time_s) {
    satellite.not_tracked_because = "acquiring";
    return Lock::kNone;
  }
  const GnssTime signal_acquired = *arc.above_since + profile.acquisition_time_s;
  if (!satellite.acquired || signal_acquired < *satellite.acquired) satellite.acquired = signal_acquired;
  return Lock::kNewArc;
}

TrackingState::Lock TrackingState::aided_search(const ReceiverProfile& profile, Arc& arc, double cn0_dbhz,
                                                const GnssTime& tag, const GnssTime& last_tag, int& channels_used,
                                                SatelliteAcquisition& satellite) {
  ++channels_used;  // a channel searches for it
  const double coherent_s = profile.integration_time_s;
  // A receiver dwells at most as long as the weakest signal it is meant to find needs (its
  // threshold's detection time), then starts the window over: a signal steadily below the
  // threshold is never found, a brief fade within a window only slows the detection.
  const double threshold_dbhz = satellite.acquisition_threshold_dbhz;
  const double longest_dwell_s = reacquisition_dwell_s(threshold_dbhz, coherent_s);
  GnssTime searched_from = last_tag;
  if (!arc.above_since || arc.acquiring_tag != last_tag) {
    // A new search, from halfway since the last epoch (where the signal was lost or appeared).
    arc.above_since = std::max(last_tag + 0.5 * (tag - last_tag), tag - longest_dwell_s);
    arc.signal_blocks = arc.noise_blocks = 0.0;
    searched_from = *arc.above_since;
  } else if (tag - *arc.above_since > longest_dwell_s) {
    arc.above_since = std::max(last_tag, tag - longest_dwell_s);  // the next window
    arc.signal_blocks = arc.noise_blocks = 0.0;
    searched_from = *arc.above_since;
  }
  arc.acquiring_tag = tag;
  // Square-law detection over the window: the signal adds rho per coherent block, the statistic's
  // variance 1 + 2 rho; detected once the deflection sum(rho) / sqrt(sum(1 + 2 rho)) reaches 5
  // (reacquisition_dwell_s for a steady signal).
  const double rho = block_snr(cn0_dbhz, coherent_s);
  const double blocks = (tag - searched_from) / coherent_s;
  const double signal_before = arc.signal_blocks, noise_before = arc.noise_blocks;
  arc.signal_blocks += blocks * rho;
  arc.noise_blocks += blocks * (1.0 + 2.0 * rho);
  if (arc.signal_blocks < kDetectionDeflection * std::sqrt(arc.noise_blocks)) {
    satellite.not_tracked_because = cn0_dbhz < threshold_dbhz ? "below the acquisition threshold" : "acquiring";
    return Lock::kNone;
  }
  // When within the interval the deflection reached 5: the larger root of
  // (S0 + k rho)^2 = d^2 (N0 + k (1 + 2 rho)) in blocks k.
  const double c = 1.0 + 2.0 * rho, d2 = kDetectionDeflection * kDetectionDeflection;
  const double b = 2.0 * signal_before * rho - d2 * c;
  const double discriminant = b * b - 4.0 * rho * rho * (signal_before * signal_before - d2 * noise_before);
  const double k = std::clamp((-b + std::sqrt(std::max(discriminant, 0.0))) / (2.0 * rho * rho), 0.0, blocks);
  const GnssTime signal_acquired = searched_from + k * coherent_s;
  if (!satellite.acquired || signal_acquired < *satellite.acquired) satellite.acquired = signal_acquired;
  return Lock::kNewArc;
}

TrackingState::CarrierArc TrackingState::carrier_arc(const ReceiverProfile& profile, const SatelliteId& sat,
                                                     const Signal& signal, bool new_arc, double cn0_dbhz, bool aided,
                                                     bool data, const GnssTime& tag,
                                                     const std::optional<GnssTime>& last_tag) {
  const SignalKey key{sat, signal};
  Arc& arc = arcs_[key];
  CarrierArc out;
  if (new_arc) {
    ++arc.index;
    RandomStream ambiguity(stream_key(seed_, {hash_name("ambiguity"), static_cast<std::uint64_t>(receiver_index_),
                                              satellite_key(sat), signal_key(signal),
                                              static_cast<std::uint64_t>(arc.index)}));
    arc.ambiguity_cycles = ambiguity.uniform_int(-1000000, 1000000);
    arc.lock_start = tag;
    out.loss_of_lock = true;
  } else if (slips_ && profile.pll_bandwidth_hz > 0.0) {
    auto stream = slip_streams_.find(key);
    if (stream == slip_streams_.end()) {
      stream = slip_streams_
                   .emplace(key, RandomStream(stream_key(seed_, {hash_name("cycle-slips"),
                                                                 static_cast<std::uint64_t>(receiver_index_),
                                                                 satellite_key(sat), signal_key(signal)})))
                   .first;
    }
    RandomStream& slips = stream->second;
    const double loop_bandwidth_hz = aided ? profile.semicodeless_aiding_bandwidth_hz : profile.pll_bandwidth_hz;
    const double probability = slip_probability(pll_jitter_rad(profile, cn0_dbhz, loop_bandwidth_hz),
                                                loop_bandwidth_hz, data, tag - *last_tag);
    if (slips.uniform() < probability) {
      // The slip is a whole number of cycles (half cycles of a Costas loop resolve again).
      const std::int64_t size = slips.uniform_int(1, 5);
      arc.ambiguity_cycles += slips.uniform() < 0.5 ? -size : size;
      ++arc.index;
      arc.lock_start = tag;
      out.loss_of_lock = true;
    }
  }
  arc.active = true;
  arc.above_since.reset();
  arc.last_tag = tag;
  out.ambiguity_cycles = arc.ambiguity_cycles;
  out.lock_time_s = tag - arc.lock_start;
  out.half_cycle_unresolved = data && out.lock_time_s < profile.half_cycle_resolution_s;
  return out;
}

bool EphemerisDecoding::holds(const orbits::BroadcastEphemerides& ephemerides, SatelliteObservation& obs,
                              const GnssTime& tag, bool first_epoch, const std::optional<GnssTime>& acquired,
                              std::span<const Candidate> candidates) {
  const SatelliteId& sat = obs.satellite;
  State& state = states_[sat];
  state.tracked_tag = tag;
  if (state.held) return true;
  if (first_epoch) {
    // The run's first epoch: the receiver ran before and holds the ephemerides of what it tracks.
    state.held = true;
    return true;
  }
  if (!state.decoding) {
    state.decoding = true;
    std::vector<Signal> signals;  // what the receiver tracks of the satellite
    signals.reserve(candidates.size());
    for (const Candidate& candidate : candidates) signals.push_back(*candidate.signal);
    state.held_from = ephemeris_held_from(ephemerides, sat, acquired.value_or(tag), signals);
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

void EphemerisDecoding::end_epoch(const GnssTime& tag) {
  for (auto it = states_.begin(); it != states_.end();) {
    if (!it->second.held && it->second.tracked_tag != tag) {
      it = states_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace skytrace::receiver::stages
