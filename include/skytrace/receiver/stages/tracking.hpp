// Stage 4 of the observation model: the tracking state. Acquisition (a satellite is acquired on a
// signal above the acquisition threshold, held for the acquisition time, and its other signals are
// handed over down to the tracking threshold; a running receiver with an aided reacquisition
// threshold searches from it, for a detection time set by the C/N0), loss of lock below the
// tracking threshold, the channels (highest satellites first), carrier arcs with their integer
// ambiguity and cycle slips, the half-cycle flag, and the gate of ephemeris decoding (profile
// output_requires_ephemeris).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "skytrace/core/random.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/receiver/multipath.hpp"
#include "skytrace/receiver/observations.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/receiver/stages/foliage_fading.hpp"
#include "skytrace/receiver/stages/records.hpp"
#include "skytrace/receiver/stages/signal_key.hpp"

namespace skytrace::receiver::stages {

// A listed signal a satellite transmits and its record declares healthy: what tracking decides on.
struct Candidate {
  const Signal* signal = nullptr;
  double cn0_dbhz = 0.0;
  MultipathErrors multipath;
  RecordState record;  // the receiver's record for the signal (record_for_signal)
  // Foliage fading (foliage_fading.hpp) of a direct ray through vegetation: the band's composite
  // field and this signal's fades (nullptr: none).
  const FoliageComposite* foliage = nullptr;
  FoliageFade fade;
  double block_code_bias_m = 0.0;  // SatelliteSignals::Facts::code_bias_m
};

// Why a satellite's signals are not tracked at an epoch (the last reason met), and when its new
// arcs were acquired (the earliest).
struct SatelliteAcquisition {
  double acquisition_threshold_dbhz = 0.0;  // the profile's, or its tracking threshold (handover)
  std::optional<GnssTime> acquired;
  std::string not_tracked_because;
};

// The C/N0 from which a signal is acquired: the profile's aided reacquisition threshold once the
// receiver `running` (after the run's first epoch) when it has one, else its cold acquisition
// threshold.
[[nodiscard]] double search_threshold_dbhz(const ReceiverProfile& profile, bool running);

// The time an aided search takes to detect a steady signal of `cn0_dbhz` (the receiver predicts
// its code delay and Doppler, so the dwell, not the search, sets it): non-coherent sums of K
// coherent blocks of `coherent_s` until the detection statistic's deflection reaches 5 (false
// alarm 1e-4 per cell, detection 0.9): K = 25 (1 + 2 rho) / rho^2 with rho = C/N0 coherent_s,
// square-law detection (Kaplan & Hegarty 2006, 8.3). 24 dB-Hz: 0.22 s, 15 dB-Hz: 2.8 s. At the
// search threshold it is also the longest window the search integrates before starting over.
[[nodiscard]] double reacquisition_dwell_s(double cn0_dbhz, double coherent_s);

class TrackingState {
 public:
  // Carrier arcs: with `slips` (loop noise on), a continuing arc may slip.
  TrackingState(std::uint64_t seed, int receiver_index, bool slips)
      : seed_(seed), receiver_index_(receiver_index), slips_(slips) {}

  // Whether the signal was tracked at the previous epoch `last_tag` (nullopt: none).
  [[nodiscard]] bool tracked_at(const SatelliteId& sat, const Signal& signal, const std::optional<GnssTime>& last_tag);
  // The signal is not tracked (unhealthy): its arc ends.
  void drop(const SatelliteId& sat, const Signal& signal);
  // Every carrier arc of a satellite ends (its signals are blocked).
  void lost(const SatelliteId& sat, std::span<const Signal> signals);

  // The thresholds of a satellite at this epoch: while one of its signals is (or becomes) tracked
  // above the acquisition threshold, the others acquire down to the tracking threshold.
  // `running`: after the run's first epoch (search_threshold_dbhz).
  [[nodiscard]] SatelliteAcquisition begin_satellite(const ReceiverProfile& profile, bool acquirable,
                                                     bool running) const {
    SatelliteAcquisition a;
    a.acquisition_threshold_dbhz =
        acquirable ? profile.tracking_threshold_dbhz : search_threshold_dbhz(profile, running);
    return a;
  }

  enum class Lock { kNone, kContinuing, kNewArc };
  // Channel, thresholds and acquisition time of one candidate signal at `tag` (previous epoch
  // `last_tag`); `channels_used` counts the receiver's busy channels this epoch. An aided channel
  // (a semi-codeless one whose L1 C/A channel is locked) is acquired and kept down to
  // `aided_threshold_dbhz` instead of the acquisition and tracking thresholds.
  [[nodiscard]] Lock lock(const ReceiverProfile& profile, const SatelliteId& sat, const Signal& signal, double cn0_dbhz,
                          const GnssTime& tag, const std::optional<GnssTime>& last_tag, int& channels_used,
                          SatelliteAcquisition& satellite, std::optional<double> aided_threshold_dbhz = std::nullopt);

  struct CarrierArc {
    bool loss_of_lock = false;           // a new arc starts here (acquisition or slip)
    bool half_cycle_unresolved = false;  // data signal whose phase polarity is not yet known
    std::int64_t ambiguity_cycles = 0;
    double lock_time_s = 0.0;
  };
  // The carrier arc of a signal `lock` found tracked: an acquisition starts a new arc with a new
  // integer ambiguity; a continuing arc slips (more likely the weaker the signal, the loop's
  // bandwidth that of the aided loop when `aided`) by a whole number of cycles. `data`: a data
  // modulated signal (Costas loop).
  [[nodiscard]] CarrierArc carrier_arc(const ReceiverProfile& profile, const SatelliteId& sat, const Signal& signal,
                                       bool new_arc, double cn0_dbhz, bool aided, bool data, const GnssTime& tag,
                                       const std::optional<GnssTime>& last_tag);

 private:
  struct Arc {
    std::int64_t ambiguity_cycles = 0;
    int index = 0;
    GnssTime last_tag;       // last epoch it was tracked
    bool active = false;     // tracked at last_tag
    GnssTime lock_start;     // acquisition or last slip
    std::optional<GnssTime> above_since;  // acquiring: above the acquisition threshold since
    GnssTime acquiring_tag;  // last epoch it was seen acquiring
    // Aided search (profile.reacquisition_threshold_dbhz): the window's signal and noise sums in
    // coherent blocks (above_since: the window's start).
    double signal_blocks = 0.0, noise_blocks = 0.0;
  };
  // A running receiver's search for a predicted signal (profile.reacquisition_threshold_dbhz).
  Lock aided_search(const ReceiverProfile& profile, Arc& arc, double cn0_dbhz, const GnssTime& tag,
                    const GnssTime& last_tag, int& channels_used, SatelliteAcquisition& satellite);
  std::uint64_t seed_;
  int receiver_index_;
  bool slips_;
  std::unordered_map<SignalKey, Arc, SignalKeyHash> arcs_;
  std::unordered_map<SignalKey, RandomStream, SignalKeyHash> slip_streams_;
};

// output_requires_ephemeris: whether the receiver holds an ephemeris for a satellite it tracks.
// Decoding starts at a first acquisition; every satellite tracked at the run's first epoch is held
// at once (the receiver ran before), and a held satellite stays held.
class EphemerisDecoding {
 public:
  // Whether the receiver holds an ephemeris for `obs`'s satellite, tracked at `tag`, its signals
  // `candidates` (those it transmits healthy), new arcs acquired at `acquired`; `first_epoch`: the run's first. Not held: says why in
  // obs.detail; held for the first time after decoding: sets the loss-of-lock flag of every signal
  // (a new arc for the user).
  [[nodiscard]] bool holds(const orbits::BroadcastEphemerides& ephemerides, SatelliteObservation& obs,
                           const GnssTime& tag, bool first_epoch, const std::optional<GnssTime>& acquired,
                           std::span<const Candidate> candidates);
  // After an epoch: a satellite lost before its ephemeris was decoded starts again at its next
  // acquisition.
  void end_epoch(const GnssTime& tag);

 private:
  struct State {
    bool held = false;
    bool decoding = false;
    std::optional<GnssTime> held_from;  // while decoding; nullopt: no record to decode
    GnssTime tracked_tag;               // last epoch it was tracked
  };
  std::unordered_map<SatelliteId, State> states_;
};

}  // namespace skytrace::receiver::stages
