// Observation synthesis: what one receiver records at one epoch, from the satellite orbits and
// clocks, the atmosphere and the receiver's own state. The truth of every term is kept beside the
// measurement; nothing overwrites it. The generator composes the stages of receiver/stages/:
// geometry and light time, propagation paths, signal power, tracking state, measurement errors
// and observables; a model belongs to one stage.
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
#include "skytrace/atmosphere/residual_field.hpp"
#include "skytrace/atmosphere/models.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/core/random.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/receiver/antex.hpp"
#include "skytrace/receiver/clock.hpp"
#include "skytrace/receiver/observations.hpp"
#include "skytrace/receiver/stages/geometry.hpp"
#include "skytrace/receiver/stages/measurement_errors.hpp"
#include "skytrace/receiver/stages/propagation.hpp"
#include "skytrace/receiver/stages/records.hpp"
#include "skytrace/receiver/stages/signal_power.hpp"
#include "skytrace/receiver/stages/tracking.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver {

// Where the receiver is at a true (GPST) time: a static point or an interpolated trajectory.
class KinematicsSource {
 public:
  virtual ~KinematicsSource() = default;
  [[nodiscard]] virtual Result<Kinematics> at(const GnssTime& t) const = 0;
  // Whether the receiver stays at one point whatever the time (its paths can be kept).
  [[nodiscard]] virtual bool fixed() const { return false; }
};

// A receiver that stands still.
class StaticPosition final : public KinematicsSource {
 public:
  explicit StaticPosition(const Eigen::Vector3d& position_m) : position_m_(position_m) {}
  [[nodiscard]] Result<Kinematics> at(const GnssTime& /*t*/) const override {
    return Kinematics{position_m_, Eigen::Vector3d::Zero()};
  }
  [[nodiscard]] bool fixed() const override { return true; }

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
  // The residual field of the zenith wet delay shared by the scenario's receivers (nullptr: none).
  std::shared_ptr<const atmosphere::ResidualField> troposphere_residual;
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
  // The receiver antenna's phase centre offsets and variations per frequency (receiver.antex;
  // nullptr: the phase centre is the antenna reference point).
  std::shared_ptr<const AntennaPhaseCentre> antenna_phase_centre;
  // Fast fading of direct rays through vegetation (models.foliage_fading; applies with noise).
  stages::FoliageFadingSettings foliage;
  // Record every arriving signal in SatelliteObservation::incoming (for IQ samples).
  bool incoming_signals = false;
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
  // The same into `epoch`, whose storage (satellites, signals, strings) is reused: a run that hands
  // epochs back saves an allocation per satellite and epoch. Every field is overwritten.
  [[nodiscard]] Status observe(const GnssTime& tag, EpochObservations& epoch);

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
  // A satellite above the mask, waiting for the world's verdict before its signals are measured.
  struct Pending {
    size_t index = 0;              // in the epoch's satellites
    stages::RecordState record;    // the receiver's default record (nav.rnx)
    stages::RecordState truth;     // the satellite's reference record, its state at transmission
    bool precise_truth = false;
    stages::LightTime light_time;
  };

  // Stages 2 to 6 for one satellite above the mask (`pending_index` in this epoch's batch).
  void observe_satellite(EpochObservations& epoch, size_t pending_index, const Eigen::Matrix3d& rx_to_enu,
                         int& channels_used);

  GeneratorSettings settings_;
  // Per signal of settings_.signals (same order): its catalogue entry and how the profile tracks
  // it, found by position in the per-signal loops.
  struct ListedSignal {
    const SignalInfo* info = nullptr;
    TrackedSignal tracked;
    bool data_modulated = false;
  };
  std::vector<ListedSignal> listed_;
  std::vector<Signal> untrackable_;
  double elevation_mask_deg_ = 0.0;  // the scenario's and the profile's, whichever is higher
  // Per satellite of satellites_: the last epoch's flight time (nullopt: none yet, or lost).
  std::vector<std::optional<double>> flight_time_guess_s_;
  const orbits::BroadcastEphemerides& ephemerides_;
  const orbits::SatelliteStateSource* truth_orbits_ = nullptr;
  // The truth source's view for this generator's forward-moving queries (precise orbits: fits per
  // SP3 interval), when it has one; truth_orbits_ then points to it.
  std::unique_ptr<orbits::SatelliteStateSource> truth_view_;
  const PathQuery* world_ = nullptr;
  LocalFrame world_frame_;
  std::shared_ptr<const KinematicsSource> kinematics_;
  ReceiverClock clock_;
  std::optional<GnssTime> last_tag_;
  std::vector<SatelliteId> satellites_;
  // The stages' state from one epoch to the next.
  stages::SatelliteSignals satellite_signals_;
  stages::TrackingState tracking_;
  stages::LoopNoise loop_noise_;
  stages::FoliageFading foliage_fading_;
  stages::EphemerisDecoding ephemeris_decoding_;
  orbits::GlonassOrbitCache glonass_orbits_;  // integration nodes per GLONASS record
  // Scratch of one epoch and one satellite, kept to avoid allocations per epoch.
  std::vector<Pending> pending_;
  std::vector<Eigen::Vector3d> lines_of_sight_;
  std::vector<Eigen::Vector3d> world_directions_;
  stages::WorldOutcomes world_outcomes_;
  std::vector<size_t> order_;
  std::vector<stages::Candidate> candidates_;
  // Multipath: a satellite's paths through the antenna tables of bands other than the first
  // signal's (bands sharing a table share one entry).
  std::vector<std::pair<const AntennaPattern*, std::vector<ReceivedPath>>> band_received_;
  [[nodiscard]] const AntennaPattern* signal_antenna(const TrackedSignal* tracked) const;
  [[nodiscard]] const std::vector<ReceivedPath>& received_through(const AntennaPattern* antenna,
                                                                  const std::vector<ReceivedPath>& received,
                                                                  const SatelliteObservation& obs);
  // Foliage fading: a satellite's composite field per band this epoch (advanced once per band).
  std::vector<std::pair<char, const stages::FoliageComposite*>> band_fields_;
  [[nodiscard]] const stages::FoliageComposite& band_field(const SatelliteId& sat, const Signal& signal,
                                                           const SignalInfo& info, const SatelliteObservation& obs,
                                                           const Eigen::Vector3d& velocity_enu_mps,
                                                           const Eigen::Vector3d& satellite_enu, const GnssTime& tag);
  // The records a satellite's signals used this epoch, entered into used_* once it is output.
  std::vector<std::tuple<const orbits::KeplerEphemeris*, const orbits::GlonassEphemeris*, const orbits::SbasEphemeris*>>
      records_used_;
  std::set<const orbits::KeplerEphemeris*> used_kepler_;
  std::set<const orbits::GlonassEphemeris*> used_glonass_;
  std::set<const orbits::SbasEphemeris*> used_sbas_;
};

}  // namespace skytrace::receiver
