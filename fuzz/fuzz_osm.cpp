// OpenStreetMap XML extracts (world::load_osm_world, which reads files through libosmium).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_support.hpp"
#include "skytrace/world/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const skytrace::fuzz::TempInputFile file(".osm");
  if (!file.write(std::string_view(reinterpret_cast<const char*>(data), size))) return 0;
  skytrace::world::OsmLoadOptions options;
  options.allow_no_buildings = true;  // reach the trees and woods of extracts without buildings
  (void)skytrace::world::load_osm_world(file.path(), options);
  return 0;
}
