// ROS messages of one live epoch: the fix, the velocity, the raw observations, the sky and the rays
// for RViz. Pure conversions (no node state), so that the node's loop stays short.
#pragma once

#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <sensor_msgs/NavSatFix.h>
#include <skytrace_msgs/Observations.h>
#include <skytrace_msgs/Sky.h>
#include <visualization_msgs/MarkerArray.h>

#include "live_receiver.hpp"

namespace skytrace::ros_node {

// NavSatFix from the position engine's fix: status and service bits of the constellations used,
// covariance east-north-up. No fix gives STATUS_NO_FIX with NaN coordinates.
[[nodiscard]] sensor_msgs::NavSatFix to_navsat_fix(const live::FixView& fix, const std_msgs::Header& header);
// East-north-up velocity with its covariance (angular velocity unknown: variance 1e9).
[[nodiscard]] geometry_msgs::TwistWithCovarianceStamped to_velocity(const live::FixView& fix,
                                                                    const std_msgs::Header& header);
// Every tracked signal, with the truth flags of its path.
[[nodiscard]] skytrace_msgs::Observations to_observations(const live::EpochView& epoch, const std_msgs::Header& header);
// Every satellite above the horizon with its status and whether the fix used it.
[[nodiscard]] skytrace_msgs::Sky to_sky(const live::EpochView& epoch, const std_msgs::Header& header);
// Lines from the antenna towards the satellites above the horizon in world coordinates (the
// header's frame), `length_m` long, one colour per path: direct green, through vegetation yellow,
// lost in vegetation orange, blocked red, below the mask grey.
[[nodiscard]] visualization_msgs::MarkerArray to_rays(const live::EpochView& epoch, const std_msgs::Header& header,
                                                      double length_m);

}  // namespace skytrace::ros_node
