// What a scenario needs before its first epoch, built once and shared by `skytrace run` and by live
// sessions (ROS node, Gazebo bridge, virtual receiver): world, ephemerides, precise truth,
// ionosphere, and the receivers' kinematics and observation generators.
#pragma once

#include <Eigen/Core>

#include <memory>
#include <optional>

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

struct ScenarioResources {
  std::optional<LoadedWorld> world;
  std::unique_ptr<orbits::BroadcastEphemerides> ephemerides;
  std::unique_ptr<orbits::PreciseEphemerides> precise;             // signal truth when given
  std::shared_ptr<const atmosphere::IonosphereModel> ionosphere;  // nullptr: none
};

// Loads everything the scenario names and checks the ephemerides cover [start, end] (the scenario's
// span by default). Errors name the file or key.
[[nodiscard]] Result<ScenarioResources> prepare_resources(const Scenario& scenario);
[[nodiscard]] Status check_coverage(const Scenario& scenario, const orbits::BroadcastEphemerides& ephemerides,
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

// The generator of receiver `index`, moving as `kinematics` says, in the scenario's world.
[[nodiscard]] Result<std::unique_ptr<receiver::ObservationGenerator>> make_generator(
    const Scenario& scenario, const ScenarioResources& resources, size_t index,
    std::shared_ptr<const receiver::KinematicsSource> kinematics);

// The RINEX header of a receiver's observation file.
[[nodiscard]] io::ObservationHeader make_observation_header(const Scenario& scenario, const ReceiverSettings& receiver,
                                                            const Eigen::Vector3d& marker_m,
                                                            const orbits::BroadcastEphemerides& ephemerides);

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

 private:
  const io::ObservationHeader& header_;
  std::map<Signal, size_t> code_column_;  // column of a signal's code; phase, Doppler, C/N0 follow it
};

// The tracked signals of an epoch as the navigation engine's input.
[[nodiscard]] positioning::EpochMeasurements to_measurements(const receiver::EpochObservations& epoch);

}  // namespace skytrace::sim
