// A live session: one receiver of a scenario stepped epoch by epoch at times the caller chooses
// (wall clock, ROS or Gazebo time), with the antenna pose and the moving models of the world given
// from outside. The ROS node, the Gazebo bridge and `skytrace serve` are thin shells around it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/positioning/rtk.hpp"
#include "skytrace/positioning/spp.hpp"
#include "skytrace/receiver/observation_generator.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/setup.hpp"

namespace skytrace::sim {

struct LiveOptions {
  size_t receiver_index = 0;  // which receiver of the scenario
  bool solve_position = true;
  // Navigation engine settings; by default the receiver's elevation mask and the corrections the
  // scenario's navigation data allows (Klobuchar when it has GPS coefficients).
  std::optional<positioning::SolverSettings> solver;
  // An external pose older than this is stale: the receiver stays where it was last put, at rest.
  double pose_timeout_s = 1.0;
  // RTK against corrections given with add_base_epoch (a base's RTCM stream): the receiver
  // profile's `rtk` section, GLONASS ambiguities float (the base's make is unknown).
  bool rtk = false;
};

struct LiveEpoch {
  receiver::EpochObservations observations;
  std::optional<positioning::PositionFix> fix;  // when solve_position
  bool pose_stale = false;  // the external pose had timed out (diagnostic for the caller)
  bool restarted = false;   // the time went backwards (simulation reset): tracking started anew
};

// An antenna pose sent from outside as one line of text (`skytrace serve --pose-udp`):
//   ecef X Y Z [VX VY VZ]      metres, m/s in ECEF
//   world X Y Z [VX VY VZ]     metres in the session's world frame (Gazebo world / local ENU)
//   llh LAT_DEG LON_DEG H_M    WGS84, ellipsoidal height
struct PoseDatagram {
  enum class Frame { kEcef, kWorld } frame = Frame::kEcef;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::optional<Eigen::Vector3d> velocity;
};
// Parses a datagram (trailing blanks and line ends ignored). Values are only checked to be
// numbers: LiveSession::set_antenna_pose_* refuses non-finite or implausible poses.
[[nodiscard]] Result<PoseDatagram> parse_pose_datagram(std::string_view text);

class LiveSession {
 public:
  [[nodiscard]] static Result<std::unique_ptr<LiveSession>> create(const Scenario& scenario, const LiveOptions& options = {});
  ~LiveSession();
  LiveSession(const LiveSession&) = delete;
  LiveSession& operator=(const LiveSession&) = delete;

  // The antenna reference point from outside (from now on instead of the scenario's position or
  // trajectory), at true GPST `time`. Without a velocity, it comes from the previous pose.
  // Errors (the pose is ignored): non-finite values, a pose far below or above the Earth's surface.
  // May be called from another thread than step().
  [[nodiscard]] Status set_antenna_pose_ecef(const GnssTime& time, const Eigen::Vector3d& position_ecef_m,
                                             const std::optional<Eigen::Vector3d>& velocity_ecef_mps = std::nullopt);
  // The same in world_frame() coordinates (the Gazebo world frame).
  [[nodiscard]] Status set_antenna_pose_world(const GnssTime& time, const Eigen::Vector3d& position_world_m,
                                              const std::optional<Eigen::Vector3d>& velocity_world_mps = std::nullopt);
  // A moving base (the receiver's rtk.moving_base with rtk.base naming another receiver of the
  // scenario: two antennas on one body) is simulated beside the receiver; each epoch's fix then
  // carries the heading and pitch of the fixed baseline (fix.relative; NMEA HDT/THS). Its antenna
  // is put here; until it is, it follows the receiver's external pose at the scenario's baseline
  // (a body that translates), and before any pose it keeps its scenario position. Same checks as
  // set_antenna_pose_ecef; an error when the receiver has no moving base.
  [[nodiscard]] Status set_base_antenna_pose_ecef(const GnssTime& time, const Eigen::Vector3d& position_ecef_m,
                                                  const std::optional<Eigen::Vector3d>& velocity_ecef_mps = std::nullopt);
  [[nodiscard]] Status set_base_antenna_pose_world(const GnssTime& time, const Eigen::Vector3d& position_world_m,
                                                   const std::optional<Eigen::Vector3d>& velocity_world_mps = std::nullopt);
  [[nodiscard]] bool has_moving_base() const;
  // A base station's epoch (its observations and antenna reference point) for RTK (LiveOptions::rtk):
  // each step uses the latest one at or before its tag. Not while step() runs.
  void add_base_epoch(positioning::BaseEpoch base);

  // Moves a movable model of the world (not while step() runs).
  [[nodiscard]] Status set_object_pose(const std::string& name, const Eigen::Isometry3d& pose_world);

  // Observations (and the fix) at receiver time tag `tag`. A tag before the previous one restarts
  // the receiver (new carrier arcs, new clock): a simulation reset.
  [[nodiscard]] Result<LiveEpoch> step(const GnssTime& tag);

  [[nodiscard]] const Scenario& scenario() const;
  [[nodiscard]] const ScenarioResources& resources() const;
  [[nodiscard]] const ReceiverSettings& receiver() const;
  // The frame of world coordinates: the loaded world's, the scenario's origin keys, or else
  // east-north-up at the receiver's first position.
  [[nodiscard]] const LocalFrame& world_frame() const;
  // The receiver's first marker position (the station position of RTCM 1005/1006).
  [[nodiscard]] const Eigen::Vector3d& marker_ecef_m() const;
  // The RINEX header of this receiver's observations and a maker of its records.
  [[nodiscard]] const io::ObservationHeader& observation_header() const;
  [[nodiscard]] const RinexRecordMaker& rinex_records() const;

 private:
  struct Impl;
  explicit LiveSession(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace skytrace::sim
