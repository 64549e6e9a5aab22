// The world loaders that need sdformat or GDAL (internal to the world layer). Their code is built
// once and goes two ways (docs/adr/0005-optional-modules.md): into the static library
// skytrace_world_linked, whose public functions (loaders.hpp) call it directly (tests, tools, the
// ROS nodes), and into the module skytrace-world.so, which the skytrace command loads on first use
// (backend_module.cpp, core/module.hpp), so that a run without such a world never loads their
// libraries.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/world/loaders.hpp"

namespace skytrace::world {

namespace backend {
[[nodiscard]] Result<WorldModel> load_sdf_world(const std::filesystem::path& path, const SdfLoadOptions& options);
[[nodiscard]] Result<WorldModel> load_footprint_world(const std::filesystem::path& path,
                                                      const FootprintLoadOptions& options);
[[nodiscard]] Result<WorldModel> load_dem_world(const std::filesystem::path& path, const DemLoadOptions& options);
}  // namespace backend

namespace city_model::backend {
// city_model.hpp's to_wgs84 (EPSG codes through PROJ).
[[nodiscard]] Status to_wgs84(std::optional<int> epsg, bool gml_axis_order, std::vector<Eigen::Vector3d>& points,
                              const std::string& where, const std::string& crs_key);
// The same for a CRS given as WKT (a raster's), easting/longitude first.
[[nodiscard]] Status wkt_to_wgs84(const std::string& wkt, std::vector<Eigen::Vector3d>& points, const std::string& where);
}  // namespace city_model::backend

// What the module hands out. A module of another build of skytrace (another revision of this
// table, or other sizes of the types its functions take) is refused instead of called.
struct WorldBackend {
  std::uint32_t revision = 0;
  std::uint64_t layout = 0;
  decltype(&backend::load_sdf_world) load_sdf_world = nullptr;
  decltype(&backend::load_footprint_world) load_footprint_world = nullptr;
  decltype(&backend::load_dem_world) load_dem_world = nullptr;
  decltype(&city_model::backend::to_wgs84) to_wgs84 = nullptr;
};
inline constexpr std::uint32_t kWorldBackendRevision = 1;
inline constexpr std::uint64_t world_backend_layout() {
  return sizeof(WorldBackend) + (sizeof(SdfLoadOptions) << 12) + (sizeof(FootprintLoadOptions) << 24) +
         (static_cast<std::uint64_t>(sizeof(DemLoadOptions)) << 36) + (static_cast<std::uint64_t>(sizeof(WorldModel)) << 48);
}
// The module's one exported function, extern "C": returns its table.
inline constexpr const char* kWorldBackendModule = "skytrace-world.so";
inline constexpr const char* kWorldBackendEntry = "skytrace_world_backend";

}  // namespace skytrace::world
