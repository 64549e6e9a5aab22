// What a scenario needs before its first epoch, built once and shared by `skytrace run` and by live
// sessions (ROS node, Gazebo bridge, virtual receiver): world, ephemerides, precise truth,
// ionosphere, and the receivers' kinematics and observation generators.
#pragma once

#include <Eigen/Core>

#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/positioning/spp.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/world_setup.hpp"

namespace skytrace::sim {

// What the precise products (ephemeris.precise_orbits / precise_clocks) give over a run, per
// satellite of the receivers' systems in the navigation data.
struct PreciseTruthCoverage {
  GnssTime from;  // span of transmission times checked: the run's start minus kTransmissionLead_s
  GnssTime to;    // the run's end
  // Satellites the products lack altogether (no orbit or no clock samples at all), and satellites
  // they hold but cannot serve over all of [from, to] (missing epochs, gaps); both keep the broadcast
  // truth for the whole run, so that no signal switches between two truths.
  std::map<SatelliteId, orbits::PreciseEphemerides::Coverage> lacking;
  std::map<SatelliteId, orbits::PreciseEphemerides::Coverage> gaps;
  [[nodiscard]] std::set<SatelliteId> broadcast_truth() const;
  // One warning line each for the lacking satellites and for those with gaps (none when empty).
  [[nodiscard]] std::vector<std::string> warnings() const;
  // summary.json's "precise_truth" object.
  [[nodiscard]] std::string to_json() const;
};

// The signals of an epoch left the satellites up to this long before it: 0.14 s of flight time
// (BeiDou GEO/IGSO), plus the receiver clock offset (within a millisecond). The products must serve
// the run's span extended by this at its start.
inline constexpr double kTransmissionLead_s = 0.2;

struct ScenarioResources {
  std::optional<LoadedWorld> world;
  std::unique_ptr<orbits::BroadcastEphemerides> ephemerides;
  std::unique_ptr<orbits::PreciseEphemerides> precise;             // signal truth when given
  std::optional<PreciseTruthCoverage> precise_coverage;            // with precise: over the scenario's span
  std::shared_ptr<const atmosphere::IonosphereModel> ionosphere;  // nullptr: none (with its residual field)
  std::shared_ptr<const atmosphere::ResidualField> troposphere_residual;  // nullptr: none
  std::vector<std::string> warnings;                               // for the user (run: stderr, summary)
  // Systems of the receivers' signals without any usable ephemeris at the start (check_coverage),
  // with the warning: left out of the generators and the observation headers.
  std::map<GnssSystem, std::string> left_out_systems;
};

// What the broadcast records can serve of the receivers' systems over a run.
struct SystemCoverage {
  // Systems none of whose satellites has a record usable for the receivers' signals of the system
  // at the start, with the warning saying so.
  std::map<GnssSystem, std::string> left_out;
  // Systems served at the start but not at the end (their satellites lose their ephemerides).
  std::vector<std::string> warnings;
};

// Loads everything the scenario names and checks the ephemerides cover [start, end] (the scenario's
// span by default): the broadcast records (check_coverage) and, when given, the precise products
// (check_precise_coverage). Errors name the file or key.
[[nodiscard]] Result<ScenarioResources> prepare_resources(const Scenario& scenario);
// Broadcast coverage of the receivers' systems: a system without a usable record at `start` is left
// out (as a receiver does), one without at `end` warned about; an error (kOutOfRange, exit 4) naming
// the systems and the files' span when no system can be served, or a receiver keeps none of its own.
[[nodiscard]] Result<SystemCoverage> check_coverage(const Scenario& scenario,
                                                    const orbits::BroadcastEphemerides& ephemerides,
                                                    const GnssTime& start, const GnssTime& end);
// A receiver's signals without those of left-out systems.
[[nodiscard]] std::vector<Signal> served_signals(const ReceiverSettings& receiver,
                                                 const std::map<GnssSystem, std::string>& left_out_systems);
// The precise products against the run [start, end]: an error (kOutOfRange, exit 4) naming the key,
// the files, their span and the run's when the SP3 epochs or the clock file's samples do not reach
// from start to end (the fraction of a second of flight time before start is extrapolated, as the
// interpolation allows up to one sample interval beyond the data); kNotFound when neither the SP3
// files nor a clock file hold any clock. Otherwise per satellite what it lacks or where it has gaps.
[[nodiscard]] Result<PreciseTruthCoverage> check_precise_coverage(const Scenario& scenario,
                                                                  const orbits::BroadcastEphemerides& ephemerides,
                                                                  const orbits::PreciseEphemerides& precise,
                                                                  const GnssTime& start, const GnssTime& end);

// Loads the navigation data a scenario names (files, or the nominal constellation for its span).
[[nodiscard]] Result<orbits::NavigationData> load_navigation(const Scenario& scenario);

// The frame of world_enu_m coordinates: the loaded world's, else the scenario's origin keys.
[[nodiscard]] std::optional<LocalFrame> world_origin(const Scenario& scenario, const std::optional<LoadedWorld>& world);

// Antenna reference point: marker + antenna height up + offsets east/north.
[[nodiscard]] Eigen::Vector3d antenna_point(const Eigen::Vector3d& marker_m, const ReceiverSettings& receiver);

// Where a receiver is over time (its static position or its trajectory file); `marker_m` gets the
// first marker position.
[[nodiscard]] Result<std::shared_ptr<const receiver::KinematicsSource>> make_kinematics(
    const Scenario& scenario, const ReceiverSettings& receiver, const std::optional<LocalFrame>& world_frame,
    Eigen::Vector3d& marker_m);

// The IGS name (type and radome) under which a receiver's antenna is looked up in its ANTEX file:
// receiver.antenna_type, else the IGS name of the antenna profile in use (receiver.antenna or the
// receiver profile's default, `antenna_rinex_type`); empty when neither has one.
[[nodiscard]] std::string antex_antenna_name(const ReceiverSettings& receiver, const std::string& antenna_rinex_type = {});

// The phase centre model of a receiver for `signals` from its ANTEX file (receiver.antex; nullptr
// without one): the type-mean calibration of antex_antenna_name valid at the scenario's start.
[[nodiscard]] Result<std::shared_ptr<const receiver::AntennaPhaseCentre>> load_antenna_phase_centre(
    const Scenario& scenario, const ReceiverSettings& receiver, std::span<const Signal> signals,
    const std::string& antenna_rinex_type = {});

// The generator of receiver `index`, moving as `kinematics` says, in the scenario's world.
[[nodiscard]] Result<std::unique_ptr<receiver::ObservationGenerator>> make_generator(
    const Scenario& scenario, const ScenarioResources& resources, size_t index,
    std::shared_ptr<const receiver::KinematicsSource> kinematics);

// The RINEX header of a receiver's observation file.
// Signals of `left_out_systems` (ScenarioResources) are not listed. ANT # / TYPE: the scenario's
// antenna_type, else `antenna_in_use` (the generator profile's antenna_rinex_type).
[[nodiscard]] io::ObservationHeader make_observation_header(
    const Scenario& scenario, const ReceiverSettings& receiver, const Eigen::Vector3d& marker_m,
    const orbits::BroadcastEphemerides& ephemerides, const std::map<GnssSystem, std::string>& left_out_systems = {},
    const std::string& antenna_in_use = {});

// The creation date written into RINEX headers ("YYYYMMDD HHMMSS UTC"): SOURCE_DATE_EPOCH (seconds
// since 1970, the reproducible-builds convention) when set, else the scenario's start time, so
// that the same scenario and seed give byte-identical files.
[[nodiscard]] std::string rinex_creation_date(const Scenario& scenario);

// RINEX signal strength indicator (1-9) of a C/N0 (RINEX 3.04 5.7).
[[nodiscard]] int signal_strength_indicator(double cn0_dbhz);

// Turns generated epochs into RINEX records of a given header.
class RinexRecordMaker {
 public:
  explicit RinexRecordMaker(const io::ObservationHeader& header);
  [[nodiscard]] io::ObservationEpoch record(const receiver::EpochObservations& epoch) const;
  // The same into `out`, whose lists keep their storage from epoch to epoch.
  void record_into(const receiver::EpochObservations& epoch, io::ObservationEpoch& out) const;

 private:
  const io::ObservationHeader& header_;
  std::map<Signal, size_t> code_column_;  // column of a signal's code; phase, Doppler, C/N0 follow it
};

// The tracked signals of an epoch as the navigation engine's input.
[[nodiscard]] positioning::EpochMeasurements to_measurements(const receiver::EpochObservations& epoch);
// The same into `out`, reusing its storage.
void to_measurements(const receiver::EpochObservations& epoch, positioning::EpochMeasurements& out);

}  // namespace skytrace::sim
