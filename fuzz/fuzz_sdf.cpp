// Gazebo SDF worlds (world::load_sdf_world, which reads files through sdformat). Model URIs are
// only searched in the examples' folder, never in the environment's paths.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_support.hpp"
#include "skytrace/world/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const skytrace::fuzz::TempInputFile file(".sdf");
  if (!file.write(std::string_view(reinterpret_cast<const char*>(data), size))) return 0;
  skytrace::world::SdfLoadOptions options;
  options.use_environment_paths = false;
  options.unreadable_mesh_is_error = false;
  (void)skytrace::world::load_sdf_world(file.path(), options);
  return 0;
}
