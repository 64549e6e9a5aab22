#include "tf_buffer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>

namespace skytrace::ros2_node {
namespace {

// tf2 accepts frame names with a leading '/' from ROS 1 habits and strips it.
std::string bare(const std::string& frame) { return !frame.empty() && frame.front() == '/' ? frame.substr(1) : frame; }

StampedTransform compose(const StampedTransform& outer, const StampedTransform& inner) {
  StampedTransform out;
  out.transform = outer.transform * inner.transform;
  out.is_static = outer.is_static && inner.is_static;
  if (outer.is_static) {
    out.stamp_s = inner.stamp_s;
  } else if (inner.is_static) {
    out.stamp_s = outer.stamp_s;
  } else {
    out.stamp_s = std::min(outer.stamp_s, inner.stamp_s);
  }
  return out;
}

}  // namespace

Status TfBuffer::set(const std::string& parent_frame, const std::string& child_frame, const Eigen::Vector3d& translation_m,
                     const Eigen::Quaterniond& rotation, double stamp_s, bool is_static) {
  const std::string parent = bare(parent_frame), child = bare(child_frame);
  if (parent.empty() || child.empty()) {
    return Error{ErrorCode::kInvalidArgument, fmt::format("transform '{}' -> '{}' without a frame name", parent, child)};
  }
  if (parent == child) {
    return Error{ErrorCode::kInvalidArgument, fmt::format("transform from '{}' to itself ignored", child)};
  }
  if (!translation_m.allFinite() || !rotation.coeffs().allFinite() || rotation.norm() < 1e-6) {
    return Error{ErrorCode::kInvalidArgument,
                 fmt::format("transform '{}' -> '{}' with NaN, infinite or zero values ignored", parent, child)};
  }
  Edge edge;
  edge.parent = parent;
  edge.to_parent.transform = Eigen::Translation3d(translation_m) * rotation.normalized();
  edge.to_parent.stamp_s = is_static ? 0.0 : stamp_s;
  edge.to_parent.is_static = is_static;
  edges_[child] = std::move(edge);
  return Ok{};
}

bool TfBuffer::known(const std::string& frame) const {
  if (edges_.count(frame)) return true;
  return std::any_of(edges_.begin(), edges_.end(), [&](const auto& e) { return e.second.parent == frame; });
}

Result<TfBuffer::Chain> TfBuffer::chain_to_root(const std::string& frame) const {
  Chain chain{frame, StampedTransform{}};
  std::set<std::string> seen{frame};
  for (auto it = edges_.find(frame); it != edges_.end(); it = edges_.find(chain.root)) {
    chain.to_root = compose(it->second.to_parent, chain.to_root);
    chain.root = it->second.parent;
    if (!seen.insert(chain.root).second) {
      return Error{ErrorCode::kInvalidArgument, fmt::format("tf frames form a loop through '{}'", chain.root)};
    }
  }
  return chain;
}

Result<StampedTransform> TfBuffer::lookup(const std::string& target_frame, const std::string& source_frame) const {
  const std::string target = bare(target_frame), source = bare(source_frame);
  for (const auto& frame : {target, source}) {
    if (!known(frame)) {
      return Error{ErrorCode::kNotFound, fmt::format("frame '{}' does not exist (no transform on /tf or /tf_static names it)", frame)};
    }
  }
  auto from_source = chain_to_root(source);
  if (!from_source) return from_source.error();
  auto from_target = chain_to_root(target);
  if (!from_target) return from_target.error();
  if (from_source->root != from_target->root) {
    return Error{ErrorCode::kNotFound, fmt::format("frames '{}' and '{}' are not connected (trees rooted at '{}' and '{}')",
                                                   target, source, from_target->root, from_source->root)};
  }
  StampedTransform root_to_target = from_target->to_root;
  root_to_target.transform = root_to_target.transform.inverse();
  return compose(root_to_target, from_source->to_root);
}

}  // namespace skytrace::ros2_node
