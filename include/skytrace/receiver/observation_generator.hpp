// Observation synthesis: what one receiver records at one epoch, from the satellite orbits and
// clocks, the atmosphere and the receiver's own state. The truth of every term is kept beside the
// measurement; nothing overwrites it.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/core/random.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/receiver/clock.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {

// True antenna (reference point) position and velocity in ECEF at a true time.
struct Kinematics {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
};

// Where the receiver is at a true (GPST) time: a static point or an interpolated trajectory.
class KinematicsSource {
 public:
  virtual ~KinematicsSource() = default;
  [[nodiscard]] virtual Result<Kinematics> at(const GnssTime& t) const = 0;
};

// A receiver that stands still.
class StaticPosition final : public KinematicsSource {
 public:
  explicit StaticPosition(const Eigen::Vector3d& position_m) : position_m_(position_m) {}
  [[nodiscard]] Result<Kinematics> at(const GnssTime& /*t*/) const override {
    return Kinematics{position_m_, Eigen::Vector3d::Zero()};
  }

 private:
  Eigen::Vector3d position_m_;
};

struct GeneratorSettings {
  std::vector<Signal> signals;
  double elevation_mask_deg = 5.0;
  ReceiverProfile profile;
  // The ionosphere the signals cross (nullptr: none); Klobuchar or an IONEX map.
  std::shared_ptr<const atmosphere::IonosphereModel> ionosphere;
  atmosphere::TroposphereModel troposphere = atmosphere::TroposphereModel::kSaastamoinen;
  bool noise = false;
  bool ideal_clock = true;
  std::uint64_t seed = 1;
  int receiver_index = 0;  // keys the random streams of several receivers apart
  // Multipath (models.multipath): reflected and diffracted paths from the world (PathQuery::paths)
  // turned into code, phase, Doppler and C/N0 errors (receiver/multipath.hpp).
  bool multipath = false;
  PathSearchSettings path_search;
  // With precise truth (truth_orbits): satellites that keep the broadcast truth (the products lack
  // them, or cannot serve all of the run: sim::check_precise_coverage). For every other satellite a
  // time the products cannot serve is an error of observe(), never a silent switch of truth.
  std::set<SatelliteId> broadcast_truth;
};

enum class SatelliteStatus {
  kTracked,     // at least one signal observed
  kBelowMask,   // below the elevation mask
  kNoEphemeris, // the receiver holds no valid ephemeris (or, waiting_for_ephemeris, has not decoded one yet)
  kNoSignal,    // transmits none of the listed signals
  kBlocked,     // the world blocks the line of sight (detail: the blocking object)
  kAttenuated,  // vegetation lowers every signal below the tracking threshold
  kUnhealthy,   // the navigation message declares every listed signal it transmits unusable
};
[[nodiscard]] std::string_view to_string(SatelliteStatus status);

struct SignalMeasurement {
  Signal signal;
  double carrier_hz = 0.0;
  // Measurements, as the receiver reports them.
  double pseudorange_m = 0.0;
  double carrier_phase_cycles = 0.0;
  double doppler_hz = 0.0;
  double cn0_dbhz = 0.0;
  bool loss_of_lock = false;  // RINEX LLI bit 0: a new carrier-phase arc starts here
  bool half_cycle_unresolved = false;  // RINEX LLI bit 1: data signal whose phase polarity is not yet known
  double lock_time_s = 0.0;            // continuous carrier tracking up to this epoch
  // Truth of the terms.
  double satellite_clock_m = 0.0;   // c * the satellite's clock (one per satellite: reference record or precise)
  double group_delay_m = 0.0;       // c * code group delay of the signal relative to that clock
  double ionosphere_code_m = 0.0;   // code delay (the phase is advanced by the same amount)
  double code_noise_m = 0.0;
  double phase_noise_m = 0.0;
  double doppler_noise_mps = 0.0;
  std::int64_t ambiguity_cycles = 0;
  // Multipath errors over the direct path (models.multipath): code (DLL), carrier phase (range
  // units), range rate, and the prompt power relative to the unobstructed direct signal.
  double code_multipath_m = 0.0;
  double phase_multipath_m = 0.0;
  double range_rate_multipath_mps = 0.0;
  double multipath_power_db = 0.0;
};

// How a satellite's signals arrive (models.multipath): only the direct path, the direct path and
// others (reflections, diffraction), or no direct path at all.
enum class PathKind { kNone, kLos, kMultipath, kNlos };
[[nodiscard]] std::string_view to_string(PathKind kind);

// A listed signal the satellite transmits but its navigation record declares unusable
// (orbits::signal_healthy): not tracked, not output.
struct UnhealthySignal {
  Signal signal;
  std::string reason;  // the health word decoded, e.g. "GPS LNAV health 23 (L1 signals dead)"
};

struct SatelliteObservation {
  SatelliteId satellite;
  SatelliteStatus status = SatelliteStatus::kTracked;
  std::string detail;  // why not tracked, for the truth file
  std::vector<UnhealthySignal> unhealthy_signals;  // left out for their health (the others may be tracked)
  // Tracked, but not output until the receiver holds an ephemeris for it (profile
  // tracking.output_requires_ephemeris; status kNoEphemeris, no signals). Unlike a satellite
  // without any valid record, its geometry and atmosphere are filled in.
  bool waiting_for_ephemeris = false;
  int glonass_channel = 0;
  AzimuthElevation direction;
  double range_m = 0.0;            // geometric, transmit to receive, Sagnac included
  double range_rate_mps = 0.0;
  double satellite_clock_m = 0.0;  // c * clock: the reference record's polynomial, or the precise clock
  double relativistic_m = 0.0;     // c * periodic relativistic clock term
  double troposphere_m = 0.0;
  double ionosphere_l1_m = 0.0;    // group delay on 1575.42 MHz
  double vegetation_path_m = 0.0;  // path length through vegetation
  double vegetation_attenuation_db = 0.0;
  Eigen::Vector3d satellite_position_m = Eigen::Vector3d::Zero();  // at transmission, frame at reception
  std::vector<SignalMeasurement> signals;
  // Multipath: the paths (world frame, amplitudes before the antenna), each path's arrival
  // direction at the antenna (local east-north-up) and its excess-delay rate.
  PathKind path_kind = PathKind::kNone;
  std::vector<SignalPath> paths;
  std::vector<AzimuthElevation> path_directions;
  std::vector<double> path_delay_rates_mps;
};

struct EpochObservations {
  GnssTime receiver_time;  // epoch tag (receiver clock)
  GnssTime true_time;      // = receiver_time - receiver clock bias
  Kinematics receiver;
  ClockState receiver_clock;
  std::vector<SatelliteObservation> satellites;  // every satellite of the signals' systems
};

// Generates one receiver's observations epoch by epoch (in increasing time), keeping the carrier
// arcs, the receiver clock and the noise streams from one epoch to the next.
class ObservationGenerator {
 public:
  // `truth_orbits`, when given (precise products), supplies the orbits and clocks the signals come
  // from, except for the satellites of settings.broadcast_truth; the broadcast ephemerides remain
  // what the receiver decodes. Both must outlive the generator.
  ObservationGenerator(GeneratorSettings settings, const orbits::BroadcastEphemerides& ephemerides,
                       std::shared_ptr<const KinematicsSource> kinematics,
                       const orbits::SatelliteStateSource* truth_orbits = nullptr);

  // The world the receiver is in (nullptr: open sky) and the frame of its coordinates. The query
  // must outlive the generator.
  void set_world(const PathQuery* world, const LocalFrame& frame);

  // Observations at the receiver time tag `tag`.
  [[nodiscard]] Result<EpochObservations> observe(const GnssTime& tag);

  // Every ephemeris record used so far (for the navigation file that goes with the observations).
  [[nodiscard]] const std::set<const orbits::KeplerEphemeris*>& used_kepler() const { return used_kepler_; }
  [[nodiscard]] const std::set<const orbits::GlonassEphemeris*>& used_glonass() const { return used_glonass_; }
  [[nodiscard]] const std::set<const orbits::SbasEphemeris*>& used_sbas() const { return used_sbas_; }
  [[nodiscard]] const GeneratorSettings& settings() const { return settings_; }
  // Satellites the generator considers (those of the systems of the listed signals).
  [[nodiscard]] const std::vector<SatelliteId>& satellites() const { return satellites_; }
  // Listed signals the profile cannot track (left out of the observations).
  [[nodiscard]] const std::vector<Signal>& untrackable_signals() const { return untrackable_; }

 private:
  // Tracking state and carrier arc of one signal of one satellite.
  struct Arc {
    std::int64_t ambiguity_cycles = 0;
    int index = 0;
    GnssTime last_tag;       // last epoch it was tracked
    bool active = false;     // tracked at last_tag
    GnssTime lock_start;     // acquisition or last slip
    std::optional<GnssTime> above_since;  // acquiring: above the acquisition threshold since
    GnssTime acquiring_tag;  // last epoch it was seen acquiring
  };
  struct SignalStreams {
    RandomStream noise;
    RandomStream slips;
    // Unit-variance loop outputs of the code, phase and Doppler noise (first-order Gauss-Markov,
    // profile.hpp), and the receiver time they were last drawn at.
    LoopNoiseState loops;
    SignalStreams(std::uint64_t noise_key, std::uint64_t slip_key) : noise(noise_key), slips(slip_key) {}
  };

  // Whether the receiver holds an ephemeris for a satellite it tracks at `tag`, when the profile
  // outputs only such satellites (output_requires_ephemeris); `acquired` is when this epoch's new
  // arcs of it were acquired. Starts decoding at a first acquisition, holds at once at the run's
  // first epoch. Not held: says why in obs.detail; held for the first time after decoding: sets
  // the loss-of-lock flag of every signal (a new arc for the user).
  bool holds_ephemeris(SatelliteObservation& obs, const GnssTime& tag, const std::optional<GnssTime>& acquired);
  // Ends every carrier arc of a satellite (its signals are blocked).
  void arcs_lost(const SatelliteId& sat);
  // Whether the satellite transmits the signal, cached per GPST day.
  bool transmitted(const SatelliteId& sat, const Signal& signal, const GnssTime& t);
  // What the satellite's block delivers beyond the signal's ICD row (link_budget.hpp), cached per day.
  double satellite_power_offset_db(const SatelliteId& sat, const Signal& signal, const GnssTime& t);

  GeneratorSettings settings_;
  std::map<Signal, const SignalInfo*> signal_info_;
  std::map<Signal, TrackedSignal> tracked_;
  std::map<Signal, bool> data_modulated_;
  std::vector<Signal> untrackable_;
  double elevation_mask_deg_ = 0.0;  // the scenario's and the profile's, whichever is higher
  std::vector<std::pair<const Signal*, double>> candidates_;  // a satellite's signals and C/N0 (scratch)
  // Per (satellite, signal) state, looked up several times per signal and epoch: hashed.
  using SignalKey = std::pair<SatelliteId, Signal>;
  struct SignalKeyHash {
    std::size_t operator()(const SignalKey& k) const noexcept {
      return std::hash<std::uint32_t>{}(static_cast<std::uint32_t>(k.first.system) << 24 |
                                        static_cast<std::uint32_t>(k.first.number) << 16 |
                                        static_cast<std::uint32_t>(static_cast<unsigned char>(k.second.band)) << 8 |
                                        static_cast<std::uint32_t>(static_cast<unsigned char>(k.second.attribute)));
    }
  };
  std::unordered_map<SignalKey, std::pair<std::int64_t, bool>, SignalKeyHash> transmits_cache_;
  // block_power_offset_db of (satellite, signal) for a GPST day, like transmits_cache_.
  std::unordered_map<SignalKey, std::pair<std::int64_t, double>, SignalKeyHash> power_offset_cache_;
  std::map<SatelliteId, double> flight_time_guess_s_;
  const orbits::BroadcastEphemerides& ephemerides_;
  const orbits::SatelliteStateSource* truth_orbits_ = nullptr;
  const PathQuery* world_ = nullptr;
  LocalFrame world_frame_;
  std::shared_ptr<const KinematicsSource> kinematics_;
  ReceiverClock clock_;
  std::optional<GnssTime> last_tag_;
  std::vector<SatelliteId> satellites_;
  std::unordered_map<SignalKey, Arc, SignalKeyHash> arcs_;
  std::unordered_map<SignalKey, SignalStreams, SignalKeyHash> streams_;
  // output_requires_ephemeris: per tracked satellite, whether the receiver holds an ephemeris, or
  // when it will (decoding since its acquisition). Dropped when lost before it is held.
  struct EphemerisState {
    bool held = false;
    bool decoding = false;
    std::optional<GnssTime> held_from;  // while decoding; nullopt: no record to decode
    GnssTime tracked_tag;               // last epoch it was tracked
  };
  std::unordered_map<SatelliteId, EphemerisState> ephemeris_state_;
  // The records a satellite's signals used this epoch, entered into used_* once it is output.
  std::vector<std::tuple<const orbits::KeplerEphemeris*, const orbits::GlonassEphemeris*, const orbits::SbasEphemeris*>>
      records_used_;
  orbits::GlonassOrbitCache glonass_orbits_;  // integration nodes per GLONASS record
  std::set<const orbits::KeplerEphemeris*> used_kepler_;
  std::set<const orbits::GlonassEphemeris*> used_glonass_;
  std::set<const orbits::SbasEphemeris*> used_sbas_;
};

}  // namespace skytrace::receiver
