// The world loaders linked in: the public functions call the backend directly (backend.hpp).
#include "backend.hpp"
#include "city_model.hpp"

namespace skytrace::world {

Result<WorldModel> load_sdf_world(const std::filesystem::path& path, const SdfLoadOptions& options) {
  return backend::load_sdf_world(path, options);
}

Result<WorldModel> load_footprint_world(const std::filesystem::path& path, const FootprintLoadOptions& options) {
  return backend::load_footprint_world(path, options);
}

Result<WorldModel> load_dem_world(const std::filesystem::path& path, const DemLoadOptions& options) {
  return backend::load_dem_world(path, options);
}

Status city_model::to_wgs84(std::optional<int> epsg, bool gml_axis_order, std::vector<Eigen::Vector3d>& points,
                            const std::string& where, const std::string& crs_key) {
  return backend::to_wgs84(epsg, gml_axis_order, points, where, crs_key);
}

}  // namespace skytrace::world
