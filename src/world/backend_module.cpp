// The world loaders from the module skytrace-world.so, loaded on the first call (backend.hpp):
// linked into the skytrace command instead of skytrace_world_linked's direct calls.
#include "backend.hpp"
#include "city_model.hpp"
#include "skytrace/core/module.hpp"

namespace skytrace::world {
namespace {

// The module's table, looked up once; `what` names the input that needed it in the error.
Result<const WorldBackend*> loaded_backend(const std::string& what) {
  static const Result<const WorldBackend*> loaded = module_table<WorldBackend>(
      kWorldBackendModule, kWorldBackendEntry, kWorldBackendRevision, world_backend_layout());
  if (!loaded) return loaded.error().with_context(what);
  return loaded;
}

}  // namespace

Result<WorldModel> load_sdf_world(const std::filesystem::path& path, const SdfLoadOptions& options) {
  auto b = loaded_backend(path.string() + ": SDF worlds");
  if (!b) return b.error();
  return (*b)->load_sdf_world(path, options);
}

Result<WorldModel> load_footprint_world(const std::filesystem::path& path, const FootprintLoadOptions& options) {
  auto b = loaded_backend(path.string() + ": footprint worlds");
  if (!b) return b.error();
  return (*b)->load_footprint_world(path, options);
}

Result<WorldModel> load_dem_world(const std::filesystem::path& path, const DemLoadOptions& options) {
  auto b = loaded_backend(path.string() + ": elevation models");
  if (!b) return b.error();
  return (*b)->load_dem_world(path, options);
}

Status city_model::to_wgs84(std::optional<int> epsg, bool gml_axis_order, std::vector<Eigen::Vector3d>& points,
                            const std::string& where, const std::string& crs_key) {
  if (!epsg) return Ok{};  // nothing to transform: no need for the module
  auto b = loaded_backend(where + ": " + crs_key);
  if (!b) return b.error();
  return (*b)->to_wgs84(epsg, gml_axis_order, points, where, crs_key);
}

}  // namespace skytrace::world
