#include "skytrace/receiver/stages/propagation.hpp"

#include "skytrace/receiver/stages/geometry.hpp"

namespace skytrace::receiver::stages {

void query_world(const PathQuery& world, const LocalFrame& frame, bool multipath, const PathSearchSettings& search,
                 const Eigen::Vector3d& receiver_m, const std::vector<Eigen::Vector3d>& lines_of_sight,
                 std::vector<Eigen::Vector3d>& directions, WorldOutcomes& out) {
  out.clear();
  if (lines_of_sight.empty()) return;
  const Eigen::Matrix3d to_world = frame.ecef_to_local_rotation();
  directions.clear();
  directions.reserve(lines_of_sight.size());
  for (const Eigen::Vector3d& line_of_sight : lines_of_sight) directions.push_back(to_world * line_of_sight);
  if (multipath) {
    out.path_sets = world.paths(frame.from_ecef(receiver_m), directions, search);
    out.direct.reserve(out.path_sets.size());
    for (const PathSet& set : out.path_sets) out.direct.push_back(set.direct);
  } else {
    out.direct = world.trace_line_of_sight(frame.from_ecef(receiver_m), directions);
  }
}

ReceivedPaths receive_paths(const std::vector<SignalPath>& paths, const AntennaPattern& antenna,
                            const AzimuthElevation& direct, const Eigen::Matrix3d& world_to_enu,
                            const Eigen::Vector3d& receiver_velocity_world_mps,
                            const Eigen::Vector3d& direction_rate_world_per_s) {
  ReceivedPaths out;
  out.received.reserve(paths.size());
  out.arrival_directions.reserve(paths.size());
  out.delay_rates_mps.reserve(paths.size());
  for (const SignalPath& path : paths) {
    const AzimuthElevation arrival = local_direction(world_to_enu * path.arrival_direction);
    ReceivedPath r;
    r.excess_delay_m = path.excess_delay_m;
    r.excess_delay_rate_mps = path.delay_gradient_origin.dot(receiver_velocity_world_mps) +
                              path.delay_gradient_direction.dot(direction_rate_world_per_s);
    r.amplitude = antenna_amplitude(antenna, path, arrival.elevation_deg, arrival.azimuth_deg, direct.elevation_deg,
                                    direct.azimuth_deg);
    out.arrival_directions.push_back(arrival);
    out.delay_rates_mps.push_back(r.excess_delay_rate_mps);
    out.received.push_back(r);
  }
  const bool direct_path = !paths.empty() && paths.front().type == PathType::kDirect;
  out.kind = paths.empty() ? PathKind::kNone
             : direct_path ? (paths.size() == 1 ? PathKind::kLos : PathKind::kMultipath)
                           : PathKind::kNlos;
  return out;
}

}  // namespace skytrace::receiver::stages
