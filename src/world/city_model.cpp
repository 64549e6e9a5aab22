#include "city_model.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <memory>
#include <regex>

#include "skytrace/core/geoid.hpp"

namespace skytrace::world::city_model {

std::optional<int> epsg_code(const std::string& text) {
  static const std::regex code(R"(EPSG(?:/0/|::|:)(\d+))", std::regex::icase);
  std::smatch m;
  if (!std::regex_search(text, m, code)) return std::nullopt;
  try {
    return std::stoi(m[1].str());
  } catch (const std::exception&) {
    return std::nullopt;  // more digits than an int holds
  }
}

ObjectKind kind_of(const std::string& type) {
  if (type.rfind("Building", 0) == 0 || type == "Bridge" || type.rfind("BridgePart", 0) == 0 || type == "Tunnel" ||
      type.rfind("TunnelPart", 0) == 0 || type == "OtherConstruction") {
    return ObjectKind::kBuilding;
  }
  if (type == "SolitaryVegetationObject" || type == "PlantCover") return ObjectKind::kTree;
  if (type == "TINRelief" || type == "ReliefFeature" || type == "LandUse" || type == "Road" || type == "TransportSquare" ||
      type == "WaterBody") {
    return ObjectKind::kGround;
  }
  return ObjectKind::kOther;
}

Result<std::vector<Eigen::Vector3d>> place(const std::vector<Eigen::Vector3d>& lon_lat_z, const std::optional<Geodetic>& origin,
                                           const std::optional<double>& height_offset_m, WorldModel& world,
                                           const std::string& where, const std::string& points_name, const std::string& hint) {
  double lon0 = std::numeric_limits<double>::infinity(), lon1 = -lon0, lat0 = lon0, lat1 = -lon0, z0 = lon0;
  for (size_t i = 0; i < lon_lat_z.size(); ++i) {
    const Eigen::Vector3d& p = lon_lat_z[i];
    if (!(std::abs(p.y()) <= 90.0) || !(std::abs(p.x()) <= 360.0) || !std::isfinite(p.z())) {
      return make_error(ErrorCode::kParse, fmt::format("{}: {}[{}] is not at a longitude and latitude after the "
                                                       "transformation ({})",
                                                       where, points_name, i, hint));
    }
    lon0 = std::min(lon0, p.x());
    lon1 = std::max(lon1, p.x());
    lat0 = std::min(lat0, p.y());
    lat1 = std::max(lat1, p.y());
    z0 = std::min(z0, p.z());
  }
  const double centre_lat = 0.5 * (lat0 + lat1), centre_lon = 0.5 * (lon0 + lon1);
  double offset_m = 0.0;
  if (height_offset_m) {
    offset_m = *height_offset_m;
  } else if (const GeoidGrid* geoid = default_geoid(); geoid != nullptr) {
    offset_m = geoid->undulation_m(centre_lat, centre_lon);
    if (!std::isfinite(offset_m)) offset_m = 0.0;
  } else {
    world.warnings.push_back(where + ": no geoid grid: the model's heights are taken as ellipsoidal");
  }
  const Geodetic at = origin ? *origin : Geodetic{centre_lat, centre_lon, z0 + offset_m};
  world.geo_origin = GeoOrigin{at, 0.0};
  const GeographicLib::LocalCartesian projection(at.latitude_deg, at.longitude_deg, at.height_m);
  std::vector<Eigen::Vector3d> local(lon_lat_z.size());
  for (size_t i = 0; i < lon_lat_z.size(); ++i) {
    double x = 0.0, y = 0.0, z = 0.0;
    projection.Forward(lon_lat_z[i].y(), lon_lat_z[i].x(), lon_lat_z[i].z() + offset_m, x, y, z);
    local[i] = Eigen::Vector3d(x, y, z);
  }
  return local;
}

WorldObject new_object(const std::string& name, const std::string& id, const std::string& type,
                       const CityModelLoadOptions& options) {
  WorldObject o;
  o.name = name;
  o.kind = kind_of(type);
  if (o.kind == ObjectKind::kTree) o.material = Material{MaterialClass::kVegetation, options.vegetation_attenuation_db_per_m};
  if (o.kind == ObjectKind::kGround) o.material.material_class = MaterialClass::kGround;
  if (const MaterialRule* rule = match_material_rule(options.material_rules, {o.name, id}); rule != nullptr) {
    o.material = rule->material;
    if (rule->kind) o.kind = *rule->kind;
  }
  return o;
}

bool add_surface(const std::vector<std::vector<Eigen::Vector3d>>& rings, WorldObject& object) {
  if (rings.empty() || rings.front().size() < 3) return false;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  const auto& outer = rings.front();
  for (size_t i = 0; i < outer.size(); ++i) {
    const Eigen::Vector3d& a = outer[i];
    const Eigen::Vector3d& b = outer[(i + 1) % outer.size()];
    normal += Eigen::Vector3d((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                              (a.x() - b.x()) * (a.y() + b.y()));
  }
  if (normal.norm() < 1e-9) return false;
  normal.normalize();
  const Eigen::Vector3d u =
      (std::abs(normal.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX()).cross(normal).normalized();
  const Eigen::Vector3d v = normal.cross(u);
  PolygonWithHoles polygon;
  std::vector<const Eigen::Vector3d*> order;  // the point of each polygon vertex, outer then holes
  for (size_t r = 0; r < rings.size(); ++r) {
    Ring2 ring;
    for (const Eigen::Vector3d& p : rings[r]) {
      ring.emplace_back(p.dot(u), p.dot(v));
      order.push_back(&p);
    }
    if (r == 0) {
      polygon.outer = std::move(ring);
    } else {
      polygon.holes.push_back(std::move(ring));
    }
  }
  auto triangles = triangulate_polygon(polygon);
  if (!triangles) return false;
  const int base = static_cast<int>(object.mesh.vertices_m.size());
  for (const Eigen::Vector3d* p : order) object.mesh.vertices_m.push_back(p->cast<float>());
  for (const auto& t : *triangles) {
    // Counter-clockwise in (u, v) is counter-clockwise about the surface's normal: outward as modelled.
    object.mesh.triangles.emplace_back(base + t[0], base + t[1], base + t[2]);
  }
  return true;
}

void keep(WorldObject&& object, WorldModel& world) {
  if (object.mesh.triangles.empty()) return;
  centre_mesh_horizontally(object);
  world.objects.push_back(std::move(object));
}

Status finish(WorldModel& world, std::size_t skipped_surfaces, const std::string& where, const std::string& surfaces) {
  if (skipped_surfaces > 0) {
    world.warnings.push_back(fmt::format("{}: {} surface(s) without an area or that cannot be triangulated skipped", where,
                                         skipped_surfaces));
  }
  if (world.objects.empty()) {
    return make_error(ErrorCode::kNotFound, where + ": no city object with surfaces (" + surfaces + ") in the file");
  }
  return Ok{};
}

}  // namespace skytrace::world::city_model
