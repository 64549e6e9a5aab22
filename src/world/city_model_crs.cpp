// The CRS part of the city-model loaders: coordinates to WGS84 through GDAL's OGR (PROJ).
// Built into the world backend (backend.hpp), with the other loaders that need GDAL.
#include <fmt/format.h>
#include <ogr_spatialref.h>

#include <memory>

#include "backend.hpp"
#include "city_model.hpp"

namespace skytrace::world::city_model {

namespace {

// Points from `from` (its axis mapping set) to WGS84 longitude/latitude in place; `crs` names it.
Status transform_points(OGRSpatialReference& from, std::vector<Eigen::Vector3d>& points, const std::string& where,
                        const std::string& crs) {
  // A compound CRS (horizontal + height): its horizontal part; heights are handled by place().
  if (from.IsCompound()) from.StripVertical();
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> transform(OGRCreateCoordinateTransformation(&from, &wgs84));
  if (!transform) return make_error(ErrorCode::kParse, fmt::format("{}: PROJ cannot transform {} to WGS84", where, crs));
  std::vector<double> x(points.size()), y(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    x[i] = points[i].x();
    y[i] = points[i].y();
  }
  if (!points.empty() && !transform->Transform(points.size(), x.data(), y.data())) {
    return make_error(ErrorCode::kParse, fmt::format("{}: the coordinates do not transform from {} to WGS84", where, crs));
  }
  for (size_t i = 0; i < points.size(); ++i) {
    points[i].x() = x[i];
    points[i].y() = y[i];
  }
  return Ok{};
}

}  // namespace

namespace backend {

Status to_wgs84(std::optional<int> epsg, bool gml_axis_order, std::vector<Eigen::Vector3d>& points,
                const std::string& where, const std::string& crs_key) {
  if (!epsg) return Ok{};
  OGRSpatialReference from;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  const OGRErr imported = from.importFromEPSG(*epsg);
  CPLPopErrorHandler();
  if (imported != OGRERR_NONE) {
    return make_error(ErrorCode::kParse, fmt::format("{}: {}: EPSG:{} is unknown to PROJ", where, crs_key, *epsg));
  }
  from.SetAxisMappingStrategy(gml_axis_order ? OAMS_AUTHORITY_COMPLIANT : OAMS_TRADITIONAL_GIS_ORDER);
  return transform_points(from, points, where, fmt::format("EPSG:{}", *epsg));
}

Status wkt_to_wgs84(const std::string& wkt, std::vector<Eigen::Vector3d>& points, const std::string& where) {
  OGRSpatialReference from;
  CPLPushErrorHandler(CPLQuietErrorHandler);
  const OGRErr imported = from.importFromWkt(wkt.c_str());
  CPLPopErrorHandler();
  if (imported != OGRERR_NONE) return make_error(ErrorCode::kParse, where + ": its coordinate reference system is not understood");
  from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const char* name = from.GetName();
  return transform_points(from, points, where, std::string("its CRS ") + (name != nullptr ? name : "(unnamed)"));
}

}  // namespace backend

}  // namespace skytrace::world::city_model
