// City-model footprints through GDAL/OGR (world/footprint_loader): heights from the attributes a
// city model uses, CRS transformed to WGS84 by PROJ, outlines repaired, bad input refused naming
// the file; and the Berlin LoD2 prisms as GeoJSON give the same buildings as the OSM extract.
#include <gtest/gtest.h>

#include <GeographicLib/UTMUPS.hpp>

#include <cmath>
#include <fstream>
#include <string>

#include "skytrace/world/loaders.hpp"
#include "test_support.hpp"

namespace skytrace::world {
namespace {

std::filesystem::path write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// Area of the downward faces (the floors) of a world's meshes: the footprints' area.
double floor_area_m2(const WorldModel& world) {
  double area = 0.0;
  for (const auto& object : world.objects) {
    for (const auto& t : object.mesh.triangles) {
      const Eigen::Vector3d a = object.pose * object.mesh.vertices_m[t[0]].cast<double>();
      const Eigen::Vector3d n = (object.pose * object.mesh.vertices_m[t[1]].cast<double>() - a)
                                    .cross(object.pose * object.mesh.vertices_m[t[2]].cast<double>() - a);
      if (n.z() < 0.0) area += 0.5 * -n.z();
    }
  }
  return area;
}

// Volume of closed meshes (divergence theorem), in the world frame.
double volume_m3(const WorldModel& world) {
  double volume = 0.0;
  for (const auto& object : world.objects) {
    for (const auto& t : object.mesh.triangles) {
      const Eigen::Vector3d a = object.pose * object.mesh.vertices_m[t[0]].cast<double>();
      const Eigen::Vector3d b = object.pose * object.mesh.vertices_m[t[1]].cast<double>();
      const Eigen::Vector3d c = object.pose * object.mesh.vertices_m[t[2]].cast<double>();
      volume += a.dot(b.cross(c)) / 6.0;
    }
  }
  return volume;
}

// A 20 x 10 m block given in WGS 84 / UTM zone 33N (EPSG:32633) around a point in Berlin: PROJ must
// bring it back to that point; heights from `height`, `measuredHeight` and storeys.
TEST(WorldFootprints, ProjectedCrsHeightFieldsAndTheOrigin) {
  const auto dir = test::make_temp_dir("world_footprints_crs");
  const double lat = 52.5086, lon = 13.3723;
  int zone = 0;
  bool north = true;
  double x = 0.0, y = 0.0;
  GeographicLib::UTMUPS::Forward(lat, lon, zone, north, x, y, 33);
  std::string features;
  auto feature = [&](double east_m, const std::string& properties) {
    char ring[512];
    std::snprintf(ring, sizeof ring, "[[%.3f,%.3f],[%.3f,%.3f],[%.3f,%.3f],[%.3f,%.3f],[%.3f,%.3f]]", x + east_m - 10, y - 5,
                  x + east_m + 10, y - 5, x + east_m + 10, y + 5, x + east_m - 10, y + 5, x + east_m - 10, y - 5);
    return std::string(R"({"type":"Feature","properties":)") + properties +
           R"(,"geometry":{"type":"Polygon","coordinates":[)" + ring + "]}}";
  };
  const auto path = write(dir / "blocks.geojson",
                          std::string(R"({"type":"FeatureCollection","crs":{"type":"name","properties":{"name":"urn:ogc:def:crs:EPSG::32633"}},"features":[)") +
                              feature(0, R"({"height":25})") + "," + feature(100, R"({"measuredHeight":"18.5"})") + "," +
                              feature(200, R"({"storeysAboveGround":4})") + "," + feature(300, R"({"measuredHeight":-9999})") +
                              "]}");
  FootprintLoadOptions options;
  options.origin = Geodetic{lat, lon, 40.0};
  options.ground_height_m = 40.0;
  auto world = load_footprint_world(path, options);
  ASSERT_TRUE(world) << world.error().message;
  ASSERT_EQ(world->objects.size(), 4U);
  auto top_of = [](const WorldObject& o) {
    double top = -1e9;
    for (const auto& v : o.mesh.vertices_m) top = std::max(top, (o.pose * v.cast<double>()).z());
    return top;
  };
  // The first block stands on the origin: its centre within a centimetre of (0, 0), 25 m tall.
  EXPECT_NEAR(world->objects[0].pose.translation().x(), 0.0, 0.01);
  EXPECT_NEAR(world->objects[0].pose.translation().y(), 0.0, 0.01);
  EXPECT_NEAR(top_of(world->objects[0]), 25.0, 1e-4);
  // 100 m further east on the UTM grid: about 100 m east (grid convergence of 1.3 degrees here).
  EXPECT_NEAR(world->objects[1].pose.translation().norm(), 100.0, 0.2);
  EXPECT_NEAR(top_of(world->objects[1]), 18.5, 1e-4);
  EXPECT_NEAR(top_of(world->objects[2]), 12.0, 1e-4);  // 4 storeys of 3 m
  EXPECT_NEAR(top_of(world->objects[3]), 10.0, 1e-4);  // -9999: unknown, the default
  ASSERT_EQ(world->warnings.size(), 1U);
  EXPECT_NE(world->warnings[0].find("1 footprint(s) without a plausible height or storey count stand 10 m tall"),
            std::string::npos)
      << world->warnings[0];
  EXPECT_EQ(world->objects[0].name, "blocks.geojson/blocks:0");
  EXPECT_EQ(world->objects[0].kind, ObjectKind::kBuilding);
  // The given height field wins.
  options.height_field = "storeysAboveGround";
  auto by_field = load_footprint_world(path, options);
  ASSERT_TRUE(by_field);
  EXPECT_NEAR(top_of(by_field->objects[2]), 4.0, 1e-4);
}

TEST(WorldFootprints, SelfIntersectingOutlinesAreRepairedAndBadFilesRefused) {
  const auto dir = test::make_temp_dir("world_footprints_bad");
  // A bow tie: GEOS makes two triangles of it.
  const auto bow_tie = write(dir / "bow.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[13.0,52.0],[13.001,52.001],[13.001,52.0],[13.0,52.001],[13.0,52.0]]]}}]})");
  auto repaired = load_footprint_world(bow_tie);
  ASSERT_TRUE(repaired) << repaired.error().message;
  EXPECT_EQ(repaired->objects.size(), 2U);
  ASSERT_FALSE(repaired->warnings.empty());
  EXPECT_NE(repaired->warnings[0].find("bow.geojson/bow:0: invalid outline (self-intersecting?) repaired"), std::string::npos)
      << repaired->warnings[0];
  auto message = [](const std::filesystem::path& p) {
    auto w = load_footprint_world(p);
    return w ? std::string() : w.error().message;
  };
  EXPECT_NE(message(dir / "absent.geojson").find("absent.geojson: city model file not found"), std::string::npos);
  const auto points = write(dir / "points.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","properties":{},"geometry":{"type":"Point","coordinates":[13.0,52.0]}}]})");
  EXPECT_NE(message(points).find("points.geojson: no polygon features"), std::string::npos) << message(points);
  const auto garbage = write(dir / "garbage.geojson", "this is not GeoJSON");
  EXPECT_NE(message(garbage).find("garbage.geojson: GDAL cannot read it as a vector file"), std::string::npos)
      << message(garbage);
  const auto far = write(dir / "degrees.geojson", R"({"type":"FeatureCollection","features":[
    {"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[500000,5800000],[500020,5800000],[500020,5800010],[500000,5800010],[500000,5800000]]]}}]})");
  EXPECT_NE(message(far).find("degrees.geojson: "), std::string::npos) << message(far);
}

// The Berlin LoD2 prisms as GeoJSON and as OpenStreetMap: the same buildings.
TEST(WorldFootprints, BerlinGeoJsonAndOsmGiveTheSameBuildings) {
  const auto geojson = SKYTRACE_SHARED_FILE("worlds/berlin_potsdamer_platz/potsdamer_platz_lod2_prisms_wgs84.geojson");
  const auto osm = test::shared_data_dir() / "worlds/berlin_potsdamer_platz/potsdamer_platz.osm";
  const Geodetic origin{52.5093, 13.3744, 73.4};
  FootprintLoadOptions footprint_options;
  footprint_options.origin = origin;
  footprint_options.ground_height_m = origin.height_m;
  OsmLoadOptions osm_options;
  osm_options.origin = origin;
  osm_options.ground_height_m = origin.height_m;
  auto from_geojson = load_footprint_world(geojson, footprint_options);
  auto from_osm = load_osm_world(osm, osm_options);
  ASSERT_TRUE(from_geojson) << from_geojson.error().message;
  ASSERT_TRUE(from_osm) << from_osm.error().message;
  // 464 footprints; the three self-intersecting ones are two polygons each once repaired.
  EXPECT_EQ(from_osm->objects.size(), 464U);
  EXPECT_EQ(from_geojson->objects.size(), 467U);
  // The same footprints (to 0.1 % of their area) ...
  const double a_geojson = floor_area_m2(*from_geojson), a_osm = floor_area_m2(*from_osm);
  EXPECT_GT(a_osm, 5e4);
  EXPECT_NEAR(a_geojson / a_osm, 1.0, 0.001) << a_geojson << " m2 against " << a_osm << " m2";
  const auto [low_g, high_g] = world_bounds(*from_geojson);
  const auto [low_o, high_o] = world_bounds(*from_osm);
  EXPECT_LT((low_g.head<2>() - low_o.head<2>()).norm(), 0.1);
  EXPECT_LT((high_g.head<2>() - high_o.head<2>()).norm(), 0.1);
  // ... and heights from grounds 1.4 m apart: the OSM extract's `height` counts from 33.8 m
  // (DHHN2016), the GeoJSON's height_m from ground_dhhn2016_m_approx, 35.2 m (e.g. v3hgepFA: roof at
  // 75.0 m, 41.2 against 39.8 m). So 1.4 m and a few per cent of volume apart, by the data.
  EXPECT_NEAR(high_o.z() - high_g.z(), 1.4, 0.15);
  const double v_geojson = volume_m3(*from_geojson), v_osm = volume_m3(*from_osm);
  EXPECT_NEAR(v_geojson / v_osm, 0.97, 0.01) << v_geojson << " m3 against " << v_osm << " m3";
}

// PLATEAU LoD1 buildings of Shibuya as a GeoPackage in JGD2011 (EPSG:6668): measuredHeight, with
// -9999 / 9999 for unknown heights and storeys.
TEST(WorldFootprints, PlateauShibuyaGeoPackage) {
  const auto gpkg = SKYTRACE_SHARED_FILE("worlds/plateau_shibuya/shibuya_plateau_lod1_buildings.gpkg");
  FootprintLoadOptions options;
  options.ground_height_m = 70.0;
  auto world = load_footprint_world(gpkg, options);
  ASSERT_TRUE(world) << world.error().message;
  EXPECT_EQ(world->objects.size(), 802U);
  ASSERT_TRUE(world->geo_origin);
  EXPECT_NEAR(world->geo_origin->origin.latitude_deg, 35.659, 0.005);   // Shibuya
  EXPECT_NEAR(world->geo_origin->origin.longitude_deg, 139.700, 0.005);
  ASSERT_EQ(world->warnings.size(), 1U);
  EXPECT_NE(world->warnings[0].find("7 footprint(s) without a plausible height or storey count stand 10 m tall"),
            std::string::npos)
      << world->warnings[0];
  const auto [low, high] = world_bounds(*world);
  EXPECT_NEAR(low.z(), 0.0, 1e-3);
  EXPECT_GT(high.z(), 50.0);   // Shibuya's towers
  EXPECT_LT(high.z(), 300.0);
  EXPECT_LT((high - low).head<2>().norm(), 2000.0);  // a district, not a misplaced continent
}

}  // namespace
}  // namespace skytrace::world
