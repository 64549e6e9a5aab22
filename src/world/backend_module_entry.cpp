// The entry of the module skytrace-world.so (backend.hpp): its table of functions.
#include "backend.hpp"

extern "C" __attribute__((visibility("default"))) const skytrace::world::WorldBackend* skytrace_world_backend() {
  using namespace skytrace::world;
  static const WorldBackend table{kWorldBackendRevision,      world_backend_layout(),
                                  &backend::load_sdf_world,   &backend::load_footprint_world,
                                  &backend::load_dem_world,   &city_model::backend::to_wgs84};
  return &table;
}
