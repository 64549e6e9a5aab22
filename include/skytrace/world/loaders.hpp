// Loading worlds into a WorldModel: Gazebo SDF worlds (sdformat 12), mesh files (assimp) and
// OpenStreetMap extracts (libosmium), plus the geometry and material helpers they share.
// sdformat, assimp and osmium stay inside src/world/*.cpp; nothing of them leaks through here.
//
// Everything a loader skips (a missing model, a mesh that fails to load, a building without a valid
// outline) is named in WorldModel::warnings; only input that cannot be read at all (malformed XML,
// a missing file, an OSM file without buildings) is an error. See docs/worlds.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/world/world_model.hpp"

namespace skytrace::world {

// ---------------------------------------------------------------------------------------------
// Materials and kinds (materials.cpp)

// Specific attenuation given to vegetation when nothing more specific is known (SDF tree models,
// OSM trees and woods). An order of magnitude for foliage at L band; scenarios should set their
// own.
inline constexpr double kDefaultVegetationAttenuationDbPerM = 1.0;

// "concrete", "brick", "glass", "metal", "wood", "ground", "vegetation", "unknown".
[[nodiscard]] std::string_view material_class_name(MaterialClass material_class);
// Inverse of material_class_name (case-insensitive; "stone" is concrete, "steel" metal, "foliage"
// vegetation); an error names the accepted values.
[[nodiscard]] Result<MaterialClass> parse_material_class(std::string_view name);
// "building", "tree", "ground", "other".
[[nodiscard]] std::string_view object_kind_name(ObjectKind kind);

// Case-insensitive glob: '*' matches any run of characters (also '/'), '?' one character.
[[nodiscard]] bool glob_match(std::string_view pattern, std::string_view text);

// A scenario rule: objects any of whose names match `pattern` get `material` (and `kind` if set).
// The names tried are the object name ("model/link/collision", "way/123", "file/node") and, for
// SDF, every enclosing model's name and model:// URI.
struct MaterialRule {
  std::string pattern;
  Material material;
  std::optional<ObjectKind> kind;
};

// The first rule (in order) that matches any of `names`.
[[nodiscard]] const MaterialRule* match_material_rule(const std::vector<MaterialRule>& rules,
                                                      const std::vector<std::string>& names);

// Default classification by name or URI. Names are split into words (at non-letters and at
// lower-to-upper case changes); a keyword matches a word equal to it or ending with it, plural
// s/es allowed: "PineTree_2" and "warehouse" match, "street" and "small" do not.
// Vegetation: tree, pine, oak, bush, hedge, forest, palm, shrub, foliage, birch, conifer.
[[nodiscard]] bool name_suggests_vegetation(std::string_view name);
// Buildings: house, building, office, apartment, school, station, store, shop, garage, ...
[[nodiscard]] bool name_suggests_building(std::string_view name);

// Counts of loaded entities per kind. An entity is an SDF model (the object name without its last
// two parts, link and collision), an OSM way/relation/node, or a mesh node; it takes the kind of
// its first object (all objects of a loaded entity share the kind, except ground parts).
struct WorldSummary {
  std::size_t buildings = 0;
  std::size_t trees = 0;
  std::size_t ground = 0;
  std::size_t other = 0;
  std::size_t objects = 0;
  std::size_t triangles = 0;
  std::size_t vertices = 0;
};
[[nodiscard]] WorldSummary summarize_world(const WorldModel& world);
// The entity an object belongs to (see WorldSummary).
[[nodiscard]] std::string entity_name(const std::string& object_name);

// ---------------------------------------------------------------------------------------------
// Geometry helpers (tessellation in sdf_loader.cpp, polygons in osm_loader.cpp, hull in
// mesh_loader.cpp). All meshes are closed, counter-clockwise seen from outside, metres.

// Axis-aligned box centred on the origin.
[[nodiscard]] TriangleMesh make_box(const Eigen::Vector3d& size_m);
// Cylinder along z centred on the origin; `segments` around (at least 3).
[[nodiscard]] TriangleMesh make_cylinder(double radius_m, double length_m, int segments = 32);
// Ellipsoid centred on the origin (a sphere when all radii are equal): `segments` around z,
// `rings` from pole to pole (vertices lie on the surface, so the polytope is slightly inside it).
[[nodiscard]] TriangleMesh make_ellipsoid(const Eigen::Vector3d& radii_m, int segments = 32,
                                          int rings = 16);
// Capsule along z: a cylinder of `length_m` between two hemispheres of `radius_m`.
[[nodiscard]] TriangleMesh make_capsule(double radius_m, double length_m, int segments = 32,
                                        int rings = 16);
// A finite rectangle through the origin with the given normal: size x along the frame's x axis
// projected on the plane (y's when x is the normal), size y across. Two triangles facing the
// normal.
[[nodiscard]] TriangleMesh make_plane(const Eigen::Vector3d& normal, const Eigen::Vector2d& size_m);
// Regular grid of heights (row 0 at +y, the top of a heightmap image; column 0 at -x), centred on
// the origin, spanning size_x by size_y; heights_m is rows * columns, row-major. Surface only.
[[nodiscard]] Result<TriangleMesh> make_height_grid(const std::vector<double>& heights_m, int rows,
                                                    int columns, double size_x_m, double size_y_m);

// Convex hull of points (incremental, double precision); errors for fewer than 4 points or points
// that are all in one plane. Used to turn open vegetation meshes (leaf cards) into closed volumes.
[[nodiscard]] Result<TriangleMesh> convex_hull(const std::vector<Eigen::Vector3f>& points_m);
// The convex hull of a subset of a convex mesh's vertices, built farthest vertex first until every
// vertex of the original lies within `tolerance_m` of it (so the whole original hull does). Tree crowns of a hundred faces become a few dozen,
// which the scene traces faster; the volume shrinks by at most the tolerance at any point.
// tolerance_m <= 0 returns the mesh unchanged.
[[nodiscard]] TriangleMesh simplify_convex_hull(const TriangleMesh& hull, double tolerance_m);
// Default of that tolerance for vegetation hulls: a few centimetres on crowns metres wide, well
// below what a per-metre foliage attenuation can resolve.
inline constexpr double kDefaultVegetationHullToleranceM = 0.05;

using Ring2 = std::vector<Eigen::Vector2d>;
// A polygon with holes (either orientation; rings are open, a repeated closing point is ignored).
struct PolygonWithHoles {
  Ring2 outer;
  std::vector<Ring2> holes;
};
// Shoelace area, positive counter-clockwise.
[[nodiscard]] double signed_area_m2(const Ring2& ring);
// Ear clipping of a polygon with holes (holes are bridged to the outer ring first). The triangles
// index the concatenation outer, holes[0], holes[1], ... and are counter-clockwise; their total
// area is |area(outer)| - sum |area(hole)| for a valid polygon. Errors name what is invalid (fewer
// than 3 distinct points, zero area, a ring that cannot be clipped).
[[nodiscard]] Result<std::vector<std::array<int, 3>>> triangulate_polygon(
    const PolygonWithHoles& polygon);
// Prism of a polygon with holes between two heights: walls, roof and floor (closed volume).
[[nodiscard]] Result<TriangleMesh> extrude_polygon(const PolygonWithHoles& polygon, double bottom_m,
                                                   double top_m);

// ---------------------------------------------------------------------------------------------
// Mesh files through assimp (mesh_loader.cpp)

// The up axis of a mesh file's coordinates. kAuto follows the format: COLLADA's <up_axis>, Y for
// glTF (its specification), Z for OBJ, STL, PLY and others (the robotics convention Gazebo uses).
// kY or kZ overrides what the file says.
enum class UpAxis : std::uint8_t { kAuto, kY, kZ };

// One mesh instance of a file's node tree, with the node transforms, the unit (COLLADA <unit>) and
// the up axis applied: metres, z up.
struct MeshPart {
  std::string node_name;  // the node's name
  std::string mesh_name;  // the mesh's own name (COLLADA geometry)
  TriangleMesh mesh;
};

// Reads every triangle of a mesh file (COLLADA, OBJ, STL, PLY, glTF/GLB, and whatever assimp
// reads). Points and lines are dropped; polygons are triangulated. Errors name the file and
// assimp's message.
[[nodiscard]] Result<std::vector<MeshPart>> read_mesh_file(const std::filesystem::path& path,
                                                           UpAxis up_axis = UpAxis::kAuto);

struct MeshLoadOptions {
  UpAxis up_axis = UpAxis::kAuto;
  // Extra uniform scale (after the file's unit) and the placement of the file in the world frame.
  double scale = 1.0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // Kind and material of nodes that neither a rule nor a name (tree, ground...) classifies.
  ObjectKind default_kind = ObjectKind::kBuilding;
  Material default_material{};
  std::vector<MaterialRule> material_rules;
  // Vegetation nodes become their convex hull (closed volumes, as the scene requires), simplified
  // within this distance (simplify_convex_hull; 0 keeps every hull vertex).
  double vegetation_hull_tolerance_m = kDefaultVegetationHullToleranceM;
  double vegetation_attenuation_db_per_m = kDefaultVegetationAttenuationDbPerM;
  // One object per node (names "file/node"), or the whole file as one object (name "file").
  bool split_by_node = true;
  // Replaces the file name in object names (and in WorldModel::model_poses) when not empty.
  std::string name;
};

// A world made of one mesh file placed at a geographic origin.
[[nodiscard]] Result<WorldModel> load_mesh_world(const std::filesystem::path& path,
                                                 const GeoOrigin& origin,
                                                 const MeshLoadOptions& options = {});

// ---------------------------------------------------------------------------------------------
// Gazebo SDF worlds through sdformat 12 (sdf_loader.cpp)

enum class GeometrySource : std::uint8_t {
  kCollision,            // what Gazebo's physics sees (default)
  kVisual,               // what the cameras see (finer, may include heightmaps and decorations)
  kCollisionElseVisual,  // collisions, and the visuals of links that have no collision at all
};

struct SdfLoadOptions {
  // Searched first for model:// URIs, before GAZEBO_MODEL_PATH, GZ_SIM_RESOURCE_PATH,
  // IGN_GAZEBO_RESOURCE_PATH and SDF_PATH (colon-separated lists).
  std::vector<std::filesystem::path> model_paths;
  bool use_environment_paths = true;
  GeometrySource geometry = GeometrySource::kCollision;
  // Scenario rules, tried before the SDF's own <skytrace:material> elements and the defaults.
  std::vector<MaterialRule> material_rules;
  // Replaces the world's <spherical_coordinates>.
  std::optional<GeoOrigin> geo_origin;
  // Which <world> of the file (empty: the first). A file holding only a <model> loads as a world
  // made of that model.
  std::string world_name;
  // Tessellation of round primitives.
  int round_segments = 32;
  int round_rings = 16;
  // A <plane> without an explicit <size> (Gazebo's infinite plane) becomes a square this large.
  double infinite_plane_size_m = 2000.0;
  // Vegetation meshes become their convex hull (closed, as the scene requires); false keeps them
  // as they are (only correct for meshes that are already closed volumes).
  bool vegetation_convex_hull = true;
  // The hulls simplified within this distance (simplify_convex_hull); 0 keeps every hull vertex.
  double vegetation_hull_tolerance_m = kDefaultVegetationHullToleranceM;
  double vegetation_attenuation_db_per_m = kDefaultVegetationAttenuationDbPerM;
  // A static model counts as a building when no name says what it is but its objects are at least
  // this tall and cover at least this much ground (bounding box).
  double building_min_height_m = 3.0;
  double building_min_footprint_m2 = 20.0;
  // A mesh file that exists but cannot be read (corrupt, a format assimp does not know) is an error
  // naming it: the world would otherwise lack an obstacle it was meant to have. false skips its
  // geometries with a warning. A mesh or model that is not found is always skipped with a warning,
  // as Gazebo does.
  bool unreadable_mesh_is_error = true;
};

// Loads a world (or a single model) from an SDF file. Nested models, links, collision (or visual)
// geometry of every kind (box, cylinder, sphere, capsule, ellipsoid, plane, polyline, mesh,
// heightmap), poses resolved in their frames, <include> of model:// URIs with their
// name/pose/static overrides, <spherical_coordinates>. Objects are named "model/link/collision"
// (nested models "outer/inner/link/collision"); their pose is the collision frame in the world.
// Missing models and meshes are skipped with a warning; a malformed file is an error with
// sdformat's messages.
[[nodiscard]] Result<WorldModel> load_sdf_world(const std::filesystem::path& path,
                                                const SdfLoadOptions& options = {});

// The origin as Gazebo defines it from <spherical_coordinates> (ENU world frame, heading of the
// world x axis counter-clockwise from east, elevation above the WGS84 ellipsoid): where a point of
// the world frame is on the Earth.
[[nodiscard]] Geodetic world_point_to_geodetic(const GeoOrigin& origin,
                                               const Eigen::Vector3d& world_m);
// The inverse: the world frame position of a geodetic point.
[[nodiscard]] Eigen::Vector3d geodetic_to_world_point(const GeoOrigin& origin,
                                                      const Geodetic& point);

// ---------------------------------------------------------------------------------------------
// OpenStreetMap extracts through libosmium (osm_loader.cpp)

enum class TreeCrownShape : std::uint8_t { kEllipsoid, kCylinder };

struct OsmLoadOptions {
  // The world origin; default: the centre of the file's <bounds>, else of the data used.
  std::optional<Geodetic> origin;
  // Ellipsoidal height of the ground (OSM has no heights): the origin's height when `origin` is
  // not given, and the base of every building.
  double ground_height_m = 0.0;
  // Building height: `height` tag, else building:levels * level_height_m (+ roof:height or
  // roof:levels * level_height_m when tagged), else default_building_height_m.
  double level_height_m = 3.0;
  double default_building_height_m = 10.0;
  Material building_material{};  // overridden by building:material when tagged
  std::vector<MaterialRule> material_rules;
  // Trees (natural=tree nodes): a crown of crown_diameter_m between crown_base_fraction * height
  // and the height (`height` and `diameter_crown` tags when present). The trunk is not modelled.
  bool load_trees = true;
  TreeCrownShape tree_crown_shape = TreeCrownShape::kEllipsoid;
  double tree_height_m = 8.0;
  double tree_crown_diameter_m = 5.0;
  double tree_crown_base_fraction = 0.3;
  // Woods (natural=wood, landuse=forest areas): prisms from the ground to wood_height_m.
  bool load_woods = true;
  double wood_height_m = 15.0;
  double vegetation_attenuation_db_per_m = kDefaultVegetationAttenuationDbPerM;
  // A file without any building is an error unless this is set.
  bool allow_no_buildings = false;
};

// Loads buildings (closed ways and multipolygon relations with holes, via osmium's area assembler)
// extruded to their height, trees and woods, projected on the local tangent plane of the origin
// (GeographicLib LocalCartesian). Objects are named "way/123", "relation/45", "node/67".
// .osm, .osm.pbf, .osm.bz2, .osm.gz. Objects that cannot be built are named in the warnings.
[[nodiscard]] Result<WorldModel> load_osm_world(const std::filesystem::path& path,
                                                const OsmLoadOptions& options = {});

// ---------------------------------------------------------------------------------------------
// City-model footprints with heights through GDAL/OGR (footprint_loader.cpp): GeoJSON, GeoPackage
// and any other vector format GDAL reads (LoD1 prisms, LoD2 parts as prisms).

struct FootprintLoadOptions {
  // The world origin; default: the centre of the features' extent (in WGS84).
  std::optional<Geodetic> origin;
  // Ellipsoidal height of the ground, the base of every building (the origin's height when
  // `origin` is not given).
  double ground_height_m = 0.0;
  // The height attribute: this field when given, else the first of kFootprintHeightFields a
  // feature has; else storeys (kFootprintLevelFields) * level_height_m; else
  // default_building_height_m (counted in one warning).
  std::string height_field;
  double level_height_m = 3.0;
  double default_building_height_m = 10.0;
  Material building_material{};
  std::vector<MaterialRule> material_rules;
};
inline constexpr const char* kFootprintHeightFields[] = {"height", "height_m", "measuredHeight", "building:height",
                                                         "bldg_measuredHeight", "measured_height"};
inline constexpr const char* kFootprintLevelFields[] = {"building:levels", "storeysAboveGround", "levels"};

// Loads every polygon and multipolygon feature of every layer as a building prism from the ground
// to its height, transformed from the layer's CRS to WGS84 (PROJ through GDAL; a layer without a
// CRS is taken as WGS84 longitude/latitude, as GeoJSON defines) and projected on the local tangent
// plane of the origin, east-north-up. Objects are named "FILE/LAYER:FID". Invalid outlines (self-
// intersecting, unclosed) are repaired by GEOS with a warning. Features that cannot be
// built (invalid outline, no height) are skipped and named in the warnings; a layer in a CRS PROJ
// cannot transform, or a file without any polygon, is an error naming the file.
[[nodiscard]] Result<WorldModel> load_footprint_world(const std::filesystem::path& path,
                                                      const FootprintLoadOptions& options = {});

// ---------------------------------------------------------------------------------------------
// CityJSON city models (cityjson_loader.cpp): CityJSON 1.0-2.0, every city object's geometry of
// the highest LoD it has (Solid, CompositeSolid, MultiSolid, MultiSurface, CompositeSurface), each
// surface polygon (holes included) triangulated on its own plane, roofs as modelled.

struct CityModelLoadOptions {
  // The world origin; default: the centre of the model's extent, at the height of its lowest point.
  std::optional<Geodetic> origin;
  // Ellipsoidal height of the model's z = 0. Default (nullopt): the model's heights are above mean
  // sea level and the EGM96 geoid (core/geoid) gives the ellipsoid's offset at the model's centre
  // (national height datums are within decimetres of it); without a geoid grid, 0.
  std::optional<double> height_offset_m;
  std::vector<MaterialRule> material_rules;
  double vegetation_attenuation_db_per_m = kDefaultVegetationAttenuationDbPerM;
};
using CityJsonLoadOptions = CityModelLoadOptions;

// Loads a CityJSON file. Coordinates are transformed from metadata.referenceSystem (an EPSG URL or
// "urn:ogc:def:crs:EPSG::N"; absent: WGS84 longitude/latitude) to WGS84 by PROJ through GDAL and
// projected on the tangent plane of the origin. Objects are named "FILE/ID"; Building(Part)s are
// buildings, SolitaryVegetationObject and PlantCover vegetation, TINRelief and LandUse ground.
// Errors name the file and what is wrong (not JSON, not CityJSON, a vertex index out of range, a
// CRS PROJ cannot transform).
[[nodiscard]] Result<WorldModel> load_cityjson_world(const std::filesystem::path& path,
                                                     const CityJsonLoadOptions& options = {});

// CityGML city models (citygml_loader.cpp): CityGML 1.0, 2.0 and 3.0 (GML 2 and 3 geometry), read
// as a stream. Each city object (a cityObjectMember's feature, its parts and boundary surfaces
// included) keeps the polygons (gml:Polygon, Triangle, PolygonPatch, Rectangle; holes included)
// of its highest LoD (lodNSolid, lodNMultiSurface, lodNGeometry ...; a TIN relief's triangles when
// it has no lodN geometry); implicit geometries (library objects placed by a matrix) are left out.
// Coordinates are transformed from the first srsName of the file (EPSG in any of its spellings,
// in the CRS's own axis order) to WGS84 and placed as CityJSON's are (options; heights above mean
// sea level unless height_offset_m). Objects are named "FILE/gml:id"; types as CityJSON's.
// Errors name the file and line: malformed XML, not a CityModel, coordinates that are not numbers
// or not whole points, no srsName, a CRS PROJ does not know, no surface at all.
using CityGmlLoadOptions = CityModelLoadOptions;
[[nodiscard]] Result<WorldModel> load_citygml_world(const std::filesystem::path& path,
                                                    const CityGmlLoadOptions& options = {});

// ---------------------------------------------------------------------------------------------
// Digital elevation models (dem_loader.cpp): any raster GDAL reads (GeoTIFF, ESRI ASCII grid with
// its .prj, ...), band 1 the height (its scale and offset applied, no-data cells left out).

struct DemLoadOptions {
  // The world origin; default: the centre of the model's extent, at its lowest height.
  std::optional<Geodetic> origin;
  // Ellipsoidal height of the model's height 0. Default: its heights are above mean sea level and
  // the EGM96 geoid at the model's centre gives the offset.
  std::optional<double> height_offset_m;
};

// One ground object (named FILE) through the cell centres, two triangles per square of four cells
// with heights, facing up, transformed from the raster's CRS to WGS84 (PROJ through GDAL) and
// placed on the tangent plane of the origin. Errors name the file: not a raster GDAL reads, fewer
// than 2 x 2 cells, more than the grid limit (SKYTRACE_MAX_GRID_POINTS), no georeferencing or CRS,
// a height that is no terrain's.
[[nodiscard]] Result<WorldModel> load_dem_world(const std::filesystem::path& path, const DemLoadOptions& options = {});

// An OSM length ("12", "12 m", "12.5m", "40 ft", "40'", "12'6\"") in metres.
[[nodiscard]] Result<double> parse_osm_length_m(std::string_view text);

}  // namespace skytrace::world
