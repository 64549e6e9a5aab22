// Digital elevation models (any raster GDAL reads: GeoTIFF, ESRI ASCII grid, ...) as the world's
// ground: one triangle mesh through the cell centres (docs/worlds.md).
#include <gdal.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "backend.hpp"
#include "city_model.hpp"
#include "gdal_support.hpp"
#include "skytrace/core/input_limits.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::world {
namespace backend {

Result<WorldModel> load_dem_world(const std::filesystem::path& path, const DemLoadOptions& options) {
  const std::string where = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return make_error(ErrorCode::kIo, where + ": elevation model not found");
  const gdal::QuietErrors quiet;
  std::string reason;
  const gdal::Dataset dataset = gdal::open(path, GDAL_OF_RASTER, reason);
  if (!dataset) {
    return make_error(ErrorCode::kParse, where + ": GDAL cannot read it as a raster" + (reason.empty() ? "" : " (" + reason + ")"));
  }
  if (dataset->GetRasterCount() < 1) return make_error(ErrorCode::kParse, where + ": a raster without bands");
  const int columns = dataset->GetRasterXSize(), rows = dataset->GetRasterYSize();
  if (columns < 2 || rows < 2) {
    return make_error(ErrorCode::kParse, fmt::format("{}: {} x {} cells: at least 2 x 2 needed for a surface", where, columns, rows));
  }
  const auto cells = static_cast<std::uint64_t>(columns) * static_cast<std::uint64_t>(rows);
  if (cells > input_limits().max_grid_points) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: {} x {} cells, more than {} (crop the model to the area "
                                                               "of the run, or raise SKYTRACE_MAX_GRID_POINTS)",
                                                               where, columns, rows, input_limits().max_grid_points));
  }
  double gt[6] = {0, 1, 0, 0, 0, 1};
  if (dataset->GetGeoTransform(gt) != CE_None) {
    return make_error(ErrorCode::kParse, where + ": no georeferencing (geotransform): where the cells are is unknown");
  }
  const OGRSpatialReference* crs = dataset->GetSpatialRef();
  if (crs == nullptr) {
    return make_error(ErrorCode::kParse, where + ": no coordinate reference system (a GeoTIFF key or a .prj file beside it)");
  }
  char* wkt_text = nullptr;
  crs->exportToWkt(&wkt_text);
  const std::string wkt = wkt_text != nullptr ? wkt_text : "";
  CPLFree(wkt_text);

  GDALRasterBand* band = dataset->GetRasterBand(1);
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  int has_scale = 0, has_offset = 0;
  const double scale = band->GetScale(&has_scale), offset = band->GetOffset(&has_offset);
  std::vector<double> heights(static_cast<std::size_t>(cells));
  if (band->RasterIO(GF_Read, 0, 0, columns, rows, heights.data(), columns, rows, GDT_Float64, 0, 0) != CE_None) {
    return make_error(ErrorCode::kParse, where + ": cannot read its heights (" + std::string(CPLGetLastErrorMsg()) + ")");
  }
  // Cell centres in the raster's CRS; cells without a height (no-data, not finite) stay out.
  std::vector<Eigen::Vector3d> points;
  std::vector<std::int64_t> point_of(static_cast<std::size_t>(cells), -1);
  points.reserve(static_cast<std::size_t>(cells));
  std::size_t missing = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const std::size_t k = static_cast<std::size_t>(r) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(c);
      double h = heights[k];
      if ((has_nodata != 0 && h == nodata) || !std::isfinite(h)) {
        ++missing;
        continue;
      }
      h = h * (has_scale != 0 ? scale : 1.0) + (has_offset != 0 ? offset : 0.0);
      if (std::abs(h) > 1e5) {
        return make_error(ErrorCode::kParse, fmt::format("{}: cell ({}, {}) is {} m high: not a terrain height", where, c, r, h));
      }
      const double x = gt[0] + (c + 0.5) * gt[1] + (r + 0.5) * gt[2];
      const double y = gt[3] + (c + 0.5) * gt[4] + (r + 0.5) * gt[5];
      point_of[k] = static_cast<std::int64_t>(points.size());
      points.emplace_back(x, y, h);
    }
  }
  if (points.size() < 3) return make_error(ErrorCode::kParse, where + ": fewer than three cells with a height");
  if (auto st = city_model::backend::wkt_to_wgs84(wkt, points, where); !st) return st.error();
  WorldModel world;
  world.name = path.filename().string();
  auto placed = city_model::place(points, options.origin, options.height_offset_m, world, where, "cell",
                                  "the raster's georeferencing");
  if (!placed) return placed.error();

  WorldObject ground;
  ground.name = world.name;
  ground.kind = ObjectKind::kGround;
  ground.material.material_class = MaterialClass::kGround;
  ground.mesh.vertices_m.reserve(placed->size());
  for (const Eigen::Vector3d& p : *placed) ground.mesh.vertices_m.push_back(p.cast<float>());
  // Two triangles per square of four cell centres that all have a height, facing up.
  const auto add = [&](std::int64_t a, std::int64_t b, std::int64_t c) {
    if (a < 0 || b < 0 || c < 0) return;
    const Eigen::Vector3d pa = (*placed)[static_cast<std::size_t>(a)];
    const Eigen::Vector3d n = ((*placed)[static_cast<std::size_t>(b)] - pa).cross((*placed)[static_cast<std::size_t>(c)] - pa);
    if (n.z() >= 0.0) {
      ground.mesh.triangles.emplace_back(static_cast<int>(a), static_cast<int>(b), static_cast<int>(c));
    } else {
      ground.mesh.triangles.emplace_back(static_cast<int>(a), static_cast<int>(c), static_cast<int>(b));
    }
  };
  for (int r = 0; r + 1 < rows; ++r) {
    for (int c = 0; c + 1 < columns; ++c) {
      const auto at = [&](int rr, int cc) {
        return point_of[static_cast<std::size_t>(rr) * static_cast<std::size_t>(columns) + static_cast<std::size_t>(cc)];
      };
      add(at(r, c), at(r, c + 1), at(r + 1, c + 1));
      add(at(r, c), at(r + 1, c + 1), at(r + 1, c));
    }
  }
  if (ground.mesh.triangles.empty()) return make_error(ErrorCode::kParse, where + ": no four neighbouring cells with heights");
  if (missing > 0) world.warnings.push_back(fmt::format("{}: {} cell(s) without a height left out", where, missing));
  world.objects.push_back(std::move(ground));
  return world;
}

}  // namespace backend

}  // namespace skytrace::world
