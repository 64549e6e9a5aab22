// Helpers of the world loaders' tests: a text file written, an object found by its name's end, an
// object's bounds.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "skytrace/world/world_model.hpp"

namespace skytrace::test {

inline std::filesystem::path write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

inline const world::WorldObject* find_object(const world::WorldModel& world, const std::string& suffix) {
  for (const auto& o : world.objects) {
    if (o.name.size() >= suffix.size() && o.name.compare(o.name.size() - suffix.size(), suffix.size(), suffix) == 0) return &o;
  }
  return nullptr;
}

inline std::pair<Eigen::Vector3d, Eigen::Vector3d> object_bounds(const world::WorldObject& o) {
  world::WorldModel one;
  one.objects.push_back(o);
  return world::world_bounds(one);
}

}  // namespace skytrace::test
