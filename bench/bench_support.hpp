// Helpers shared by the benchmarks: where the real data lives, and the citysim world.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "skytrace/world/loaders.hpp"

namespace skytrace::bench {

// A file of ../shared/data (or $SKYTRACE_SHARED_DATA).
inline std::filesystem::path shared_file(const std::string& relative) {
  const char* env = std::getenv("SKYTRACE_SHARED_DATA");
  const std::filesystem::path base = env != nullptr && *env != '\0' ? env : SKYTRACE_DEFAULT_SHARED_DATA;
  return base / relative;
}

// Gazebo's citysim (simple_city.world with worlds/models on the model path); nullopt when the data
// is absent or does not load.
inline std::optional<world::WorldModel> load_citysim() {
  const auto path = shared_file("worlds/citysim/simple_city.world");
  if (!std::filesystem::exists(path)) return std::nullopt;
  world::SdfLoadOptions options;
  options.model_paths = {shared_file("worlds/models")};
  options.use_environment_paths = false;
  auto loaded = world::load_sdf_world(path, options);
  if (!loaded.ok()) return std::nullopt;
  return std::move(*loaded);
}

}  // namespace skytrace::bench
