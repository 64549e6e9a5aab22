// CityJSON city models (CityJSON 1.0-2.0): every city object's surfaces of its highest LoD as
// triangles in the world frame (docs/worlds.md).
#include <GeographicLib/LocalCartesian.hpp>
#include <ogr_spatialref.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "skytrace/core/geoid.hpp"
#include "skytrace/core/input_limits.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::world {
namespace {

using nlohmann::json;

// The EPSG code of a CityJSON reference system: "https://www.opengis.net/def/crs/EPSG/0/7415",
// "urn:ogc:def:crs:EPSG::7415" (1.0), "EPSG:7415".
std::optional<int> epsg_code(const std::string& text) {
  static const std::regex code(R"(EPSG(?:/0/|::|:)(\d+))", std::regex::icase);
  std::smatch m;
  if (!std::regex_search(text, m, code)) return std::nullopt;
  return std::stoi(m[1].str());
}

ObjectKind kind_of(const std::string& type) {
  if (type.rfind("Building", 0) == 0 || type == "Bridge" || type.rfind("BridgePart", 0) == 0 || type == "Tunnel" ||
      type == "OtherConstruction") {
    return ObjectKind::kBuilding;
  }
  if (type == "SolitaryVegetationObject" || type == "PlantCover") return ObjectKind::kTree;
  if (type == "TINRelief" || type == "LandUse" || type == "Road" || type == "TransportSquare" || type == "WaterBody") {
    return ObjectKind::kGround;
  }
  return ObjectKind::kOther;
}

// The LoD of a geometry as a number ("2.2" -> 2.2); 0 when absent.
double lod_of(const json& geometry) {
  const auto it = geometry.find("lod");
  if (it == geometry.end()) return 0.0;
  if (it->is_number()) return it->get<double>();
  if (it->is_string()) return std::atof(it->get<std::string>().c_str());
  return 0.0;
}

// Every surface (a list of rings of vertex indices) of a geometry's boundaries, whatever its type.
void collect_surfaces(const json& boundaries, int depth, std::vector<const json*>& surfaces) {
  // A surface is an array of rings; a ring an array of integers.
  if (!boundaries.is_array() || boundaries.empty()) return;
  if (depth == 0) {
    surfaces.push_back(&boundaries);
    return;
  }
  for (const auto& part : boundaries) collect_surfaces(part, depth - 1, surfaces);
}

int surface_depth(const std::string& type) {
  if (type == "MultiSurface" || type == "CompositeSurface") return 1;
  if (type == "Solid") return 2;
  if (type == "MultiSolid" || type == "CompositeSolid") return 3;
  return -1;
}

}  // namespace

namespace {

Result<WorldModel> read_cityjson_world(const std::filesystem::path& path, const CityJsonLoadOptions& options) {
  const std::string where = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return make_error(ErrorCode::kIo, where + ": CityJSON file not found");
  json doc;
  {
    std::ifstream in(path, std::ios::binary);
    try {
      doc = json::parse(in);
    } catch (const json::exception& e) {
      return make_error(ErrorCode::kParse, where + ": not JSON (" + e.what() + ")");
    }
  }
  if (!doc.is_object() || doc.value("type", "") != "CityJSON" || !doc.contains("CityObjects") ||
      !doc["CityObjects"].is_object() || !doc.contains("vertices") || !doc["vertices"].is_array()) {
    return make_error(ErrorCode::kParse, where + ": not a CityJSON file (expected \"type\": \"CityJSON\", CityObjects, vertices)");
  }
  // Vertices: integers with transform (1.1+), or numbers (1.0).
  Eigen::Vector3d scale(1.0, 1.0, 1.0), translate(0.0, 0.0, 0.0);
  if (const auto t = doc.find("transform"); t != doc.end()) {
    try {
      for (int k = 0; k < 3; ++k) {
        scale[k] = t->at("scale").at(k).get<double>();
        translate[k] = t->at("translate").at(k).get<double>();
      }
    } catch (const json::exception&) {
      return make_error(ErrorCode::kParse, where + ": transform: expected scale and translate of three numbers");
    }
  }
  const json& raw_vertices = doc["vertices"];
  if (raw_vertices.size() > input_limits().max_grid_points) {
    return make_error(ErrorCode::kInvalidArgument, fmt::format("{}: {} vertices, more than {}", where, raw_vertices.size(),
                                                               input_limits().max_grid_points));
  }
  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(raw_vertices.size());
  for (size_t i = 0; i < raw_vertices.size(); ++i) {
    const json& v = raw_vertices[i];
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
      return make_error(ErrorCode::kParse, fmt::format("{}: vertices[{}]: expected three numbers", where, i));
    }
    const Eigen::Vector3d p(v[0].get<double>() * scale.x() + translate.x(), v[1].get<double>() * scale.y() + translate.y(),
                            v[2].get<double>() * scale.z() + translate.z());
    if (!p.allFinite()) return make_error(ErrorCode::kParse, fmt::format("{}: vertices[{}]: not finite", where, i));
    vertices.push_back(p);
  }
  if (vertices.empty()) return make_error(ErrorCode::kParse, where + ": no vertices");

  // The model's CRS to WGS84 longitude/latitude.
  std::unique_ptr<OGRCoordinateTransformation> to_wgs84;
  std::string crs_text;
  if (const auto md = doc.find("metadata"); md != doc.end() && md->is_object()) {
    crs_text = md->value("referenceSystem", std::string());
  }
  if (!crs_text.empty()) {
    const auto code = epsg_code(crs_text);
    if (!code) return make_error(ErrorCode::kParse, where + ": metadata.referenceSystem '" + crs_text + "': no EPSG code in it");
    OGRSpatialReference from, wgs84;
    CPLPushErrorHandler(CPLQuietErrorHandler);
    const OGRErr imported = from.importFromEPSG(*code);
    CPLPopErrorHandler();
    if (imported != OGRERR_NONE) {
      return make_error(ErrorCode::kParse, fmt::format("{}: metadata.referenceSystem: EPSG:{} is unknown to PROJ", where, *code));
    }
    // A compound CRS (horizontal + height): its horizontal part; heights are handled below.
    if (from.IsCompound()) from.StripVertical();
    wgs84.importFromEPSG(4326);
    from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to_wgs84.reset(OGRCreateCoordinateTransformation(&from, &wgs84));
    if (!to_wgs84) {
      return make_error(ErrorCode::kParse, fmt::format("{}: PROJ cannot transform EPSG:{} to WGS84", where, *code));
    }
  }
  std::vector<double> lon(vertices.size()), lat(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    lon[i] = vertices[i].x();
    lat[i] = vertices[i].y();
  }
  if (to_wgs84 && !to_wgs84->Transform(vertices.size(), lon.data(), lat.data())) {
    return make_error(ErrorCode::kParse, where + ": the vertices do not transform to WGS84");
  }
  double lon0 = std::numeric_limits<double>::infinity(), lon1 = -lon0, lat0 = lon0, lat1 = -lon0, z0 = lon0;
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (!(std::abs(lat[i]) <= 90.0) || !(std::abs(lon[i]) <= 360.0)) {
      return make_error(ErrorCode::kParse, fmt::format("{}: vertices[{}] is not at a longitude and latitude after the "
                                                       "transformation (a projected model without metadata.referenceSystem?)",
                                                       where, i));
    }
    lon0 = std::min(lon0, lon[i]);
    lon1 = std::max(lon1, lon[i]);
    lat0 = std::min(lat0, lat[i]);
    lat1 = std::max(lat1, lat[i]);
    z0 = std::min(z0, vertices[i].z());
  }
  const double centre_lat = 0.5 * (lat0 + lat1), centre_lon = 0.5 * (lon0 + lon1);
  double offset_m = 0.0;
  WorldModel world;
  world.name = path.filename().string();
  if (options.height_offset_m) {
    offset_m = *options.height_offset_m;
  } else if (const GeoidGrid* geoid = default_geoid(); geoid != nullptr) {
    offset_m = geoid->undulation_m(centre_lat, centre_lon);
    if (!std::isfinite(offset_m)) offset_m = 0.0;
  } else {
    world.warnings.push_back(where + ": no geoid grid: the model's heights are taken as ellipsoidal");
  }
  const Geodetic origin = options.origin ? *options.origin : Geodetic{centre_lat, centre_lon, z0 + offset_m};
  world.geo_origin = GeoOrigin{origin, 0.0};
  const GeographicLib::LocalCartesian projection(origin.latitude_deg, origin.longitude_deg, origin.height_m);
  std::vector<Eigen::Vector3d> local(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    double x = 0.0, y = 0.0, z = 0.0;
    projection.Forward(lat[i], lon[i], vertices[i].z() + offset_m, x, y, z);
    local[i] = Eigen::Vector3d(x, y, z);
  }

  size_t skipped_surfaces = 0;
  for (const auto& [id, object] : doc["CityObjects"].items()) {
    if (!object.is_object()) continue;
    const std::string type = object.value("type", "");
    const auto geometries = object.find("geometry");
    if (geometries == object.end() || !geometries->is_array() || geometries->empty()) continue;
    // The highest LoD the object has.
    const json* best = nullptr;
    for (const auto& g : *geometries) {
      if (!g.is_object() || surface_depth(g.value("type", "")) < 0) continue;
      if (best == nullptr || lod_of(g) > lod_of(*best)) best = &g;
    }
    if (best == nullptr) continue;
    std::vector<const json*> surfaces;  // pointers into the document
    if (const auto b = best->find("boundaries"); b != best->end()) {
      collect_surfaces(*b, surface_depth(best->value("type", "")), surfaces);
    }
    WorldObject o;
    o.name = world.name + "/" + id;
    o.kind = kind_of(type);
    if (o.kind == ObjectKind::kTree) o.material = Material{MaterialClass::kVegetation, options.vegetation_attenuation_db_per_m};
    if (o.kind == ObjectKind::kGround) o.material.material_class = MaterialClass::kGround;
    if (const MaterialRule* rule = match_material_rule(options.material_rules, {o.name, id}); rule != nullptr) {
      o.material = rule->material;
      if (rule->kind) o.kind = *rule->kind;
    }
    for (const json* surface : surfaces) {
      // Rings of indices; the plane from Newell's normal of the outer ring.
      std::vector<std::vector<int>> rings;
      bool bad = false;
      for (const auto& ring : *surface) {
        if (!ring.is_array()) {
          bad = true;
          break;
        }
        std::vector<int> indices;
        for (const auto& index : ring) {
          if (!index.is_number_integer() || index.get<long long>() < 0 ||
              index.get<long long>() >= static_cast<long long>(local.size())) {
            return make_error(ErrorCode::kParse, where + ": CityObjects." + id + ": a vertex index out of range");
          }
          indices.push_back(index.get<int>());
        }
        rings.push_back(std::move(indices));
      }
      if (bad || rings.empty() || rings.front().size() < 3) {
        ++skipped_surfaces;
        continue;
      }
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      const auto& outer = rings.front();
      for (size_t i = 0; i < outer.size(); ++i) {
        const Eigen::Vector3d& a = local[outer[i]];
        const Eigen::Vector3d& b = local[outer[(i + 1) % outer.size()]];
        normal += Eigen::Vector3d((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                                  (a.x() - b.x()) * (a.y() + b.y()));
      }
      if (normal.norm() < 1e-9) {
        ++skipped_surfaces;
        continue;
      }
      normal.normalize();
      const Eigen::Vector3d u = (std::abs(normal.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX())
                                    .cross(normal)
                                    .normalized();
      const Eigen::Vector3d v = normal.cross(u);
      PolygonWithHoles polygon;
      std::vector<int> order;  // vertex of each polygon point, outer then holes
      for (size_t r = 0; r < rings.size(); ++r) {
        Ring2 ring;
        for (int index : rings[r]) {
          ring.emplace_back(local[index].dot(u), local[index].dot(v));
          order.push_back(index);
        }
        if (r == 0) {
          polygon.outer = std::move(ring);
        } else {
          polygon.holes.push_back(std::move(ring));
        }
      }
      auto triangles = triangulate_polygon(polygon);
      if (!triangles) {
        ++skipped_surfaces;
        continue;
      }
      const int base = static_cast<int>(o.mesh.vertices_m.size());
      for (int index : order) o.mesh.vertices_m.push_back(local[index].cast<float>());
      for (const auto& t : *triangles) {
        // Counter-clockwise in (u, v) is counter-clockwise about the surface's normal: outward as modelled.
        o.mesh.triangles.emplace_back(base + t[0], base + t[1], base + t[2]);
      }
    }
    if (o.mesh.triangles.empty()) continue;
    centre_mesh_horizontally(o);
    world.objects.push_back(std::move(o));
  }
  if (skipped_surfaces > 0) {
    world.warnings.push_back(fmt::format("{}: {} surface(s) without an area or that cannot be triangulated skipped", where,
                                         skipped_surfaces));
  }
  if (world.objects.empty()) {
    return make_error(ErrorCode::kNotFound, where + ": no city object with surfaces (Solid, MultiSurface, ...) in the file");
  }
  return world;
}

}  // namespace

Result<WorldModel> load_cityjson_world(const std::filesystem::path& path, const CityJsonLoadOptions& options) {
  // A member of an unexpected JSON type ("type": 9999999999, found by the cityjson fuzz target) makes
  // nlohmann's accessors throw wherever it is read: one message for all of them.
  try {
    return read_cityjson_world(path, options);
  } catch (const json::exception& e) {
    return make_error(ErrorCode::kParse, path.string() + ": malformed CityJSON: " + e.what());
  }
}

}  // namespace skytrace::world
