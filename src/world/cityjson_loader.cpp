// CityJSON city models (CityJSON 1.0-2.0): every city object's surfaces of its highest LoD as
// triangles in the world frame (docs/worlds.md).
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "skytrace/core/input_limits.hpp"
#include "skytrace/world/loaders.hpp"
#include "city_model.hpp"

namespace skytrace::world {
namespace {

using nlohmann::json;

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

  // The model's CRS to WGS84 longitude/latitude, then the world frame.
  std::optional<int> epsg;
  std::string crs_text;
  if (const auto md = doc.find("metadata"); md != doc.end() && md->is_object()) {
    crs_text = md->value("referenceSystem", std::string());
  }
  if (!crs_text.empty()) {
    epsg = city_model::epsg_code(crs_text);
    if (!epsg) return make_error(ErrorCode::kParse, where + ": metadata.referenceSystem '" + crs_text + "': no EPSG code in it");
  }
  if (auto st = city_model::to_wgs84(epsg, false, vertices, where, "metadata.referenceSystem"); !st) return st.error();
  WorldModel world;
  world.name = path.filename().string();
  auto placed = city_model::place(vertices, options.origin, options.height_offset_m, world, where, "vertices",
                                  "a projected model without metadata.referenceSystem?");
  if (!placed) return placed.error();
  const std::vector<Eigen::Vector3d>& local = *placed;

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
    WorldObject o = city_model::new_object(world.name + "/" + id, id, type, options);
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
      std::vector<std::vector<Eigen::Vector3d>> points;
      points.reserve(rings.size());
      for (const auto& ring : rings) {
        std::vector<Eigen::Vector3d>& ring_points = points.emplace_back();
        for (int index : ring) ring_points.push_back(local[index]);
      }
      if (!city_model::add_surface(points, o)) ++skipped_surfaces;
    }
    city_model::keep(std::move(o), world);
  }
  if (auto st = city_model::finish(world, skipped_surfaces, where, "Solid, MultiSurface, ..."); !st) return st.error();
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
