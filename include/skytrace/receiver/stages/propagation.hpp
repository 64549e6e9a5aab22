// Stage 2 of the observation model: the propagation paths from the world. Every satellite's line
// of sight goes to the world (core::PathQuery) in one batch: blocked or not, the vegetation it
// crosses and, with multipath, its reflected and diffracted paths; then each satellite's paths as
// its antenna receives them (arrival direction, excess-delay rate, amplitude through the pattern).
#pragma once

#include <Eigen/Core>

#include <string_view>
#include <vector>

#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/receiver/multipath.hpp"
#include "skytrace/receiver/observations.hpp"
#include "skytrace/receiver/profile.hpp"

namespace skytrace::receiver::stages {

// The world's answer for every satellite of a batch, in the order of the lines of sight.
struct WorldOutcomes {
  std::vector<RayOutcome> direct;  // empty without a world
  std::vector<PathSet> path_sets;  // multipath: every path of every satellite (else empty)
  void clear() {
    direct.clear();
    path_sets.clear();
  }
};

// Asks `world` about the lines of sight (ECEF unit vectors, receiver to satellite) from a receiver
// at `receiver_m` (ECEF), `frame` being the world's frame: the direct rays only, or every path
// (`multipath`). `directions` is scratch space (world frame).
void query_world(const PathQuery& world, const LocalFrame& frame, bool multipath, const PathSearchSettings& search,
                 const Eigen::Vector3d& receiver_m, const std::vector<Eigen::Vector3d>& lines_of_sight,
                 std::vector<Eigen::Vector3d>& directions, WorldOutcomes& out);

// A satellite's paths as its antenna receives them.
struct ReceivedPaths {
  PathKind kind = PathKind::kNone;
  std::vector<AzimuthElevation> arrival_directions;  // local east-north-up
  std::vector<double> delay_rates_mps;               // excess-delay rate of each path
  std::vector<ReceivedPath> received;                // through the antenna, for the loops
};

// Arrival directions go from the world frame to the receiver's east-north-up; excess-delay rates
// come from the paths' delay gradients with the receiver's velocity and the turning of the
// direction to the satellite (`direction_rate_world_per_s`); amplitudes relative to the antenna's
// gain towards the satellite's direct direction `direct`.
[[nodiscard]] ReceivedPaths receive_paths(const std::vector<SignalPath>& paths, const AntennaPattern& antenna,
                                          const AzimuthElevation& direct, const Eigen::Matrix3d& world_to_enu,
                                          const Eigen::Vector3d& receiver_velocity_world_mps,
                                          const Eigen::Vector3d& direction_rate_world_per_s);

// The rate (1/s, ECEF) at which the unit vector to a satellite turns, from the relative velocity of
// the satellite and the receiver.
[[nodiscard]] inline Eigen::Vector3d direction_rate_per_s(const Eigen::Vector3d& line_of_sight, double range_m,
                                                          const Eigen::Vector3d& satellite_velocity_mps,
                                                          const Eigen::Vector3d& receiver_velocity_mps) {
  const Eigen::Vector3d relative_mps = satellite_velocity_mps - receiver_velocity_mps;
  return (relative_mps - line_of_sight * line_of_sight.dot(relative_mps)) / range_m;
}

}  // namespace skytrace::receiver::stages
