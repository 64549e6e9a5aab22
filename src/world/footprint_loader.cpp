// City-model footprints with heights through GDAL/OGR: GeoJSON, GeoPackage and the other vector
// formats GDAL reads, as building prisms in the world frame (docs/worlds.md).
#include <GeographicLib/LocalCartesian.hpp>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

#include <fmt/format.h>

#include "backend.hpp"
#include "skytrace/world/loaders.hpp"
#include "gdal_support.hpp"

namespace skytrace::world {
namespace {

struct FeatureDeleter {
  void operator()(OGRFeature* f) const { OGRFeature::DestroyFeature(f); }
};

// One footprint: rings of (longitude, latitude) in WGS84.
struct LonLatPolygon {
  std::vector<std::vector<std::pair<double, double>>> rings;  // outer first, then holes
};

void collect_polygons(const OGRGeometry* geometry, std::vector<LonLatPolygon>& out) {
  if (geometry == nullptr) return;
  const OGRwkbGeometryType type = wkbFlatten(geometry->getGeometryType());
  if (type == wkbPolygon) {
    const auto* polygon = geometry->toPolygon();
    LonLatPolygon p;
    for (const OGRLinearRing* ring : *polygon) {
      std::vector<std::pair<double, double>> points;
      for (const OGRPoint& point : *ring) points.emplace_back(point.getX(), point.getY());
      p.rings.push_back(std::move(points));
    }
    if (!p.rings.empty()) out.push_back(std::move(p));
  } else if (type == wkbMultiPolygon || type == wkbGeometryCollection) {
    for (const OGRGeometry* part : *geometry->toGeometryCollection()) collect_polygons(part, out);
  }
}

// A number in a field within (0, max]; absent, empty, zero, negative or beyond max (PLATEAU writes
// -9999 and 9999 for unknown) is nullopt, so that the next field or the default applies.
std::optional<double> field_number(const OGRFeature& feature, const char* name, double max) {
  const int index = feature.GetFieldIndex(name);
  if (index < 0 || !feature.IsFieldSetAndNotNull(index)) return std::nullopt;
  double number = std::numeric_limits<double>::quiet_NaN();
  const OGRFieldType type = feature.GetFieldDefnRef(index)->GetType();
  if (type == OFTInteger || type == OFTInteger64 || type == OFTReal) {
    number = feature.GetFieldAsDouble(index);
  } else if (type == OFTString) {
    // "12", "12 m": the number at the start.
    const char* text = feature.GetFieldAsString(index);
    char* end = nullptr;
    const double parsed = std::strtod(text, &end);
    if (end != text) number = parsed;
  }
  if (std::isfinite(number) && number > 0.0 && number <= max) return number;
  return std::nullopt;
}

// Plausible limits: a building up to 1000 m, up to 200 storeys.
constexpr double kMaxBuildingHeight_m = 1000.0;
constexpr double kMaxStoreys = 200.0;

}  // namespace

namespace backend {

Result<WorldModel> load_footprint_world(const std::filesystem::path& path, const FootprintLoadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return make_error(ErrorCode::kIo, path.string() + ": city model file not found");
  }
  if (!(options.level_height_m > 0.0) || !(options.default_building_height_m > 0.0)) {
    return make_error(ErrorCode::kInvalidArgument, path.string() + ": footprint options: heights must be positive");
  }
  // GDAL's and GEOS's own messages ("Self-intersection at or near point ...") go to the warnings
  // below, not to stderr.
  const gdal::QuietErrors quiet;
  std::string reason;
  const gdal::Dataset dataset = gdal::open(path, GDAL_OF_VECTOR, reason);
  if (!dataset) {
    return make_error(ErrorCode::kParse, path.string() + ": GDAL cannot read it as a vector file" +
                                             (reason.empty() ? std::string() : " (" + reason + ")"));
  }

  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // longitude, latitude

  struct Prism {
    std::string name;
    LonLatPolygon polygon;
    double height_m = 0.0;
  };
  std::vector<Prism> footprints;
  WorldModel world;
  world.name = path.filename().string();
  std::size_t default_heights = 0;
  for (OGRLayer* layer : dataset->GetLayers()) {
    std::unique_ptr<OGRCoordinateTransformation> to_wgs84;
    if (const OGRSpatialReference* source = layer->GetSpatialRef(); source != nullptr) {
      OGRSpatialReference from(*source);
      from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
      to_wgs84.reset(OGRCreateCoordinateTransformation(&from, &wgs84));
      if (!to_wgs84) {
        const char* crs_name = source->GetName();
        return make_error(ErrorCode::kParse, path.string() + ": layer " + layer->GetName() + ": PROJ cannot transform its CRS (" +
                                                 (crs_name != nullptr ? crs_name : "unnamed") + ") to WGS84");
      }
    }
    layer->ResetReading();
    for (std::unique_ptr<OGRFeature, FeatureDeleter> feature(layer->GetNextFeature()); feature;
         feature.reset(layer->GetNextFeature())) {
      // Two-part names ("FILE/LAYER:FID") are entities of their own in the world's summary.
      const std::string name = world.name + "/" + layer->GetName() + ":" + std::to_string(feature->GetFID());
      const OGRGeometry* geometry = feature->GetGeometryRef();
      if (geometry == nullptr) continue;
      std::unique_ptr<OGRGeometry> copy(geometry->clone());
      if (to_wgs84 && copy->transform(to_wgs84.get()) != OGRERR_NONE) {
        world.warnings.push_back(name + " skipped: its coordinates do not transform to WGS84");
        continue;
      }
      // A self-intersecting or unclosed outline is repaired (GEOS through GDAL), with a warning.
      const OGRwkbGeometryType flat_type = wkbFlatten(copy->getGeometryType());
      if ((flat_type == wkbPolygon || flat_type == wkbMultiPolygon) && !copy->IsValid()) {
        std::unique_ptr<OGRGeometry> valid(copy->MakeValid());
        if (valid) {
          world.warnings.push_back(name + ": invalid outline (self-intersecting?) repaired");
          copy = std::move(valid);
        }
      }
      std::vector<LonLatPolygon> polygons;
      collect_polygons(copy.get(), polygons);
      if (polygons.empty()) continue;  // points, lines: not buildings
      std::optional<double> height;
      if (!options.height_field.empty()) {
        height = field_number(*feature, options.height_field.c_str(), kMaxBuildingHeight_m);
      } else {
        for (const char* field : kFootprintHeightFields) {
          if ((height = field_number(*feature, field, kMaxBuildingHeight_m))) break;
        }
        if (!height) {
          for (const char* field : kFootprintLevelFields) {
            if (const auto levels = field_number(*feature, field, kMaxStoreys)) {
              height = *levels * options.level_height_m;
              break;
            }
          }
        }
      }
      if (!height) {
        height = options.default_building_height_m;
        ++default_heights;
      }
      if (!std::isfinite(*height) || !(*height > 0.0) || *height > 1000.0) {
        world.warnings.push_back(name + " skipped: height " + fmt::format("{:g}", *height) + " m is not in (0, 1000] m");
        continue;
      }
      for (size_t i = 0; i < polygons.size(); ++i) {
        footprints.push_back({polygons.size() == 1 ? name : name + "#" + std::to_string(i + 1), std::move(polygons[i]), *height});
      }
    }
  }
  if (footprints.empty()) {
    return make_error(ErrorCode::kNotFound, path.string() + ": no polygon features (building footprints) in the file");
  }
  if (default_heights > 0) {
    world.warnings.push_back(path.string() + ": " + std::to_string(default_heights) +
                             " footprint(s) without a plausible height or storey count stand " +
                             fmt::format("{:g}", options.default_building_height_m) + " m tall");
  }

  Geodetic origin;
  if (options.origin) {
    origin = *options.origin;
  } else {
    double lon0 = std::numeric_limits<double>::infinity(), lon1 = -lon0, lat0 = lon0, lat1 = -lon0;
    for (const auto& f : footprints) {
      for (const auto& [lon, lat] : f.polygon.rings.front()) {
        lon0 = std::min(lon0, lon);
        lon1 = std::max(lon1, lon);
        lat0 = std::min(lat0, lat);
        lat1 = std::max(lat1, lat);
      }
    }
    origin = Geodetic{0.5 * (lat0 + lat1), 0.5 * (lon0 + lon1), options.ground_height_m};
  }
  if (!(std::abs(origin.latitude_deg) <= 90.0) || !(std::abs(origin.longitude_deg) <= 360.0)) {
    return make_error(ErrorCode::kParse, path.string() + ": the footprints are not at longitudes and latitudes after the "
                                                         "transformation (a layer without a CRS that is not WGS84?)");
  }
  world.geo_origin = GeoOrigin{origin, 0.0};
  const GeographicLib::LocalCartesian projection(origin.latitude_deg, origin.longitude_deg, origin.height_m);
  const double ground_z_m = options.ground_height_m - origin.height_m;
  for (auto& f : footprints) {
    PolygonWithHoles projected;
    bool far = false;
    for (size_t r = 0; r < f.polygon.rings.size(); ++r) {
      Ring2 ring;
      for (const auto& [lon, lat] : f.polygon.rings[r]) {
        if (!(std::abs(lat) <= 90.0) || !std::isfinite(lon)) {
          far = true;
          break;
        }
        double x = 0.0, y = 0.0, z = 0.0;
        projection.Forward(lat, lon, options.ground_height_m, x, y, z);
        far = far || std::hypot(x, y) > 100e3;  // a city model, not a continent
        ring.emplace_back(x, y);
      }
      if (r == 0) {
        projected.outer = std::move(ring);
      } else {
        projected.holes.push_back(std::move(ring));
      }
    }
    if (far) {
      world.warnings.push_back(f.name + " skipped: more than 100 km from the world origin or not a coordinate");
      continue;
    }
    auto prism = extrude_polygon(projected, ground_z_m, ground_z_m + f.height_m);
    if (!prism.ok()) {
      world.warnings.push_back(f.name + " skipped: " + prism.error().message);
      continue;
    }
    WorldObject object;
    object.name = f.name;
    object.kind = ObjectKind::kBuilding;
    object.material = options.building_material;
    if (const MaterialRule* rule = match_material_rule(options.material_rules, {f.name}); rule != nullptr) {
      object.material = rule->material;
      if (rule->kind) object.kind = *rule->kind;
    }
    object.mesh = std::move(*prism);
    centre_mesh_horizontally(object);
    world.objects.push_back(std::move(object));
  }
  if (world.objects.empty()) {
    return make_error(ErrorCode::kParse, path.string() + ": no footprint could be built (" +
                                             (world.warnings.empty() ? std::string("?") : world.warnings.front()) + ")");
  }
  return world;
}

}  // namespace backend

}  // namespace skytrace::world
