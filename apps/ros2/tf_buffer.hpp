// The latest transforms of /tf and /tf_static, enough for what the node asks of tf: where a frame
// is in the world frame now (tf2's lookupTransform(world, frame, TimePoint(0))), through any chain
// of parents. No interpolation: the node steps at the latest pose, as ROS 1's node does.
#pragma once

#include <Eigen/Geometry>

#include <map>
#include <optional>
#include <string>

#include "skytrace/core/error.hpp"

namespace skytrace::ros2_node {

struct StampedTransform {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();  // parent <- child
  double stamp_s = 0.0;  // ROS time; a chain's oldest dynamic stamp; 0 for static transforms only
  bool is_static = true;
};

class TfBuffer {
 public:
  // A transform parent <- child (the child's pose in the parent frame). Errors: a non-finite or
  // non-normalisable rotation, a frame that is its own parent, empty names.
  [[nodiscard]] Status set(const std::string& parent, const std::string& child, const Eigen::Vector3d& translation_m,
                           const Eigen::Quaterniond& rotation, double stamp_s, bool is_static);
  // `target` <- `source`: an error naming the frames when either is unknown or they are not connected.
  [[nodiscard]] Result<StampedTransform> lookup(const std::string& target, const std::string& source) const;
  void clear() { edges_.clear(); }  // after the clock went back, as tf2 clears its buffer

 private:
  struct Edge {
    std::string parent;
    StampedTransform to_parent;
  };
  // root <- frame, the chain's root name and its oldest dynamic stamp.
  struct Chain {
    std::string root;
    StampedTransform to_root;
  };
  [[nodiscard]] Result<Chain> chain_to_root(const std::string& frame) const;
  [[nodiscard]] bool known(const std::string& frame) const;
  std::map<std::string, Edge> edges_;  // by child frame: a frame has one parent
};

}  // namespace skytrace::ros2_node
