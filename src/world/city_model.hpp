// What the CityJSON and CityGML loaders share (internal to the world layer): city object types,
// the model's CRS to WGS84 (PROJ through GDAL), placing the model on the tangent plane of its
// origin, and planar surface polygons as triangles.
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::world::city_model {

// The EPSG code of a reference system: "https://www.opengis.net/def/crs/EPSG/0/7415",
// "urn:ogc:def:crs:EPSG::7415", "EPSG:7415"; of a compound "urn:ogc:def:crs,crs:EPSG::6697,
// crs:EPSG::6695" the first (horizontal) one.
[[nodiscard]] std::optional<int> epsg_code(const std::string& text);

// Building(Part)s, bridges, tunnels are buildings; SolitaryVegetationObject and PlantCover
// vegetation; TINRelief, ReliefFeature, LandUse, roads, squares and water ground.
[[nodiscard]] ObjectKind kind_of(const std::string& type);

// Points of the model (x, y in the CRS of `epsg`, z its height) as longitude, latitude (degrees)
// and z. `gml_axis_order`: coordinates in the CRS's own axis order (GML: latitude first for
// EPSG:4326), else easting/longitude first (CityJSON). nullopt `epsg`: already longitude/latitude.
// Errors name `where`, the CRS's key `crs_key` and the code.
[[nodiscard]] Status to_wgs84(std::optional<int> epsg, bool gml_axis_order, std::vector<Eigen::Vector3d>& points,
                              const std::string& where, const std::string& crs_key);


// Longitude/latitude/z points in the world frame: the origin (given, or the centre of the
// extent at the lowest point), heights moved by `height_offset_m` (nullopt: the EGM96 geoid at the
// centre, the model's heights being above mean sea level). Sets world.geo_origin; a warning when no
// geoid grid is at hand. Errors: a point that is not at a longitude and latitude, named as
// `points_name`[i] with `hint` (what may be wrong).
[[nodiscard]] Result<std::vector<Eigen::Vector3d>> place(const std::vector<Eigen::Vector3d>& lon_lat_z,
                                                         const std::optional<Geodetic>& origin,
                                                         const std::optional<double>& height_offset_m, WorldModel& world,
                                                         const std::string& where, const std::string& points_name,
                                                         const std::string& hint);

// An empty city object named `name` (rules also match its `id`) of CityGML/CityJSON type `type`:
// its kind, and vegetation or ground material, before the material rules of `options`.
[[nodiscard]] WorldObject new_object(const std::string& name, const std::string& id, const std::string& type,
                                     const CityModelLoadOptions& options);

// A planar surface (outer ring, then holes; world-frame points) triangulated on its own plane
// (Newell's normal of the outer ring), counter-clockwise about that normal, into `object`'s mesh.
// False for a surface without an area or that cannot be triangulated.
[[nodiscard]] bool add_surface(const std::vector<std::vector<Eigen::Vector3d>>& rings, WorldObject& object);

// An object with triangles centred (centre_mesh_horizontally) and added to `world`; nothing for
// one without.
void keep(WorldObject&& object, WorldModel& world);

// The end of a load: one warning counting `skipped_surfaces`, and an error naming `where` when no
// object has surfaces (`surfaces` says what was looked for).
[[nodiscard]] Status finish(WorldModel& world, std::size_t skipped_surfaces, const std::string& where,
                            const std::string& surfaces);

}  // namespace skytrace::world::city_model
