// CityGML city models (world::load_citygml_world, which reads a file).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_support.hpp"
#include "skytrace/world/loaders.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const skytrace::fuzz::TempInputFile file(".gml");
  if (!file.write(std::string_view(reinterpret_cast<const char*>(data), size))) return 0;
  skytrace::world::CityGmlLoadOptions options;
  options.height_offset_m = 0.0;  // no geoid grid to read for every input
  (void)skytrace::world::load_citygml_world(file.path(), options);
  return 0;
}
