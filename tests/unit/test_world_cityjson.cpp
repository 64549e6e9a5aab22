// CityJSON city models (world/cityjson_loader): a LoD2 house with a gable roof in UTM 33N with a
// transform, ground and vegetation objects, the highest LoD chosen, heights offset to the
// ellipsoid; errors naming the file.
#include <gtest/gtest.h>

#include <GeographicLib/UTMUPS.hpp>

#include <cmath>
#include <fstream>

#include "skytrace/world/loaders.hpp"
#include "test_support.hpp"
#include "world_objects.hpp"

namespace skytrace::world {
namespace {

using test::find_object;
using test::object_bounds;
using test::write_text;

// A house 10 m (east) x 8 m (north), walls 6 m, ridge at 9 m along x, standing on z = 34 m (above
// mean sea level) at a point in Berlin, in EPSG:32633 with integer vertices in millimetres.
std::string house_cityjson(double east_m, double north_m, const std::string& crs) {
  const double e = east_m, n = north_m;
  auto v = [&](double x, double y, double z) {
    char s[96];
    std::snprintf(s, sizeof s, "[%lld,%lld,%lld]", std::llround((x + e - 390000.0) * 1000.0),
                  std::llround((y + n - 5800000.0) * 1000.0), std::llround(z * 1000.0));
    return std::string(s);
  };
  // 0-3 floor corners, 4-7 eaves, 8-9 ridge ends; 10-12 a ground triangle; 13-15 a hedge panel.
  const std::string vertices = v(0, 0, 34) + "," + v(10, 0, 34) + "," + v(10, 8, 34) + "," + v(0, 8, 34) + "," +
                               v(0, 0, 40) + "," + v(10, 0, 40) + "," + v(10, 8, 40) + "," + v(0, 8, 40) + "," +
                               v(0, 4, 43) + "," + v(10, 4, 43) + "," + v(-20, -20, 34) + "," + v(30, -20, 34) + "," +
                               v(5, 30, 34) + "," + v(15, 0, 34) + "," + v(15, 8, 34) + "," + v(15, 8, 36);
  return R"({"type":"CityJSON","version":"2.0","transform":{"scale":[0.001,0.001,0.001],"translate":[390000,5800000,0]},)"
         R"("metadata":{"referenceSystem":")" + crs + R"("},"CityObjects":{)"
         R"("house":{"type":"Building","geometry":[)"
         // LoD1: a 6 m box (must lose against LoD2).
         R"({"type":"Solid","lod":"1","boundaries":[[[[0,3,2,1]],[[4,5,6,7]],[[0,1,5,4]],[[1,2,6,5]],[[2,3,7,6]],[[3,0,4,7]]]]},)"
         // LoD2: floor, walls with gables, two roof planes.
         R"({"type":"Solid","lod":"2.2","boundaries":[[[[0,3,2,1]],[[0,1,5,4]],[[1,2,6,9,5]],[[2,3,7,6]],[[3,0,4,8,7]],[[4,5,9,8]],[[7,8,9,6]]]]}]},)"
         R"("ground":{"type":"TINRelief","geometry":[{"type":"CompositeSurface","lod":1,"boundaries":[[[10,11,12]]]}]},)"
         R"("hedge":{"type":"SolitaryVegetationObject","geometry":[{"type":"MultiSurface","lod":1,"boundaries":[[[13,14,15]]]}]}},)"
         R"("vertices":[)" + vertices + "]}";
}

TEST(WorldCityJson, Lod2HouseGroundAndVegetationInUtm) {
  const auto dir = test::make_temp_dir("world_cityjson");
  const double lat = 52.5086, lon = 13.3723;
  int zone = 0;
  bool north = true;
  double x = 0.0, y = 0.0;
  GeographicLib::UTMUPS::Forward(lat, lon, zone, north, x, y, 33);
  const auto path = write_text(dir / "city.json", house_cityjson(x, y, "https://www.opengis.net/def/crs/EPSG/0/32633"));
  CityJsonLoadOptions options;
  options.height_offset_m = 39.6;  // the geoid above the ellipsoid there
  options.origin = Geodetic{lat, lon, 73.6};
  auto world = load_cityjson_world(path, options);
  ASSERT_TRUE(world) << world.error().message;
  ASSERT_EQ(world->objects.size(), 3U);
  const WorldObject* house = find_object(*world, "/house");
  ASSERT_NE(house, nullptr);
  EXPECT_EQ(house->name, "city.json/house");
  EXPECT_EQ(house->kind, ObjectKind::kBuilding);
  const auto [low, high] = object_bounds(*house);
  // The house's south-west corner is the origin: z from 0 (34 m + 39.6 m = 73.6 m) to the ridge.
  EXPECT_NEAR(low.z(), 0.0, 0.01);
  EXPECT_NEAR(high.z(), 9.0, 0.01);  // LoD2's ridge, not LoD1's flat 6 m
  // UTM's grid north is 1.3 degrees off true north here and its scale 0.9997: the floor is 80 m2
  // on the grid, 80.05 m2 on the ground, turned by the grid convergence (corners within 0.2 m).
  double floor_m2 = 0.0;
  for (const auto& t : house->mesh.triangles) {
    const Eigen::Vector3d a = house->mesh.vertices_m[t[0]].cast<double>();
    const Eigen::Vector3d n = (house->mesh.vertices_m[t[1]].cast<double>() - a).cross(house->mesh.vertices_m[t[2]].cast<double>() - a);
    if (n.z() < -1e-6) floor_m2 += 0.5 * -n.z();
  }
  EXPECT_NEAR(floor_m2, 80.05, 0.03);
  EXPECT_NEAR(low.x(), 0.0, 0.2);
  EXPECT_NEAR(low.y(), 0.0, 0.2);
  // 7 surfaces: floor, 2 walls of 4 corners, 2 gable walls of 5, 2 roof planes: 2 + 2*2 + 2*3 + 2*2 triangles.
  EXPECT_EQ(house->mesh.triangles.size(), 16U);
  const WorldObject* ground = find_object(*world, "/ground");
  ASSERT_NE(ground, nullptr);
  EXPECT_EQ(ground->kind, ObjectKind::kGround);
  const WorldObject* hedge = find_object(*world, "/hedge");
  ASSERT_NE(hedge, nullptr);
  EXPECT_EQ(hedge->kind, ObjectKind::kTree);
  EXPECT_TRUE(hedge->material.is_vegetation());
}

TEST(WorldCityJson, BadFilesNameTheFileAndWhat) {
  const auto dir = test::make_temp_dir("world_cityjson_bad");
  auto message = [](const std::filesystem::path& p) {
    auto w = load_cityjson_world(p);
    return w ? std::string() : w.error().message;
  };
  EXPECT_NE(message(dir / "absent.json").find("absent.json: CityJSON file not found"), std::string::npos);
  EXPECT_NE(message(write_text(dir / "text.json", "{not json")).find("text.json: not JSON"), std::string::npos);
  EXPECT_NE(message(write_text(dir / "geo.json", R"({"type":"FeatureCollection","features":[]})")).find("geo.json: not a CityJSON file"),
            std::string::npos);
  std::string house = house_cityjson(390000, 5800000, "EPSG:32633");
  const auto bad_index = write_text(dir / "index.json", std::string(house).replace(house.find("[[[10,11,12]]]"), 14, "[[[10,11,99]]]"));
  EXPECT_NE(message(bad_index).find("index.json: CityObjects.ground: a vertex index out of range"), std::string::npos)
      << message(bad_index);
  const auto unknown_crs = write_text(dir / "crs.json", house_cityjson(390000, 5800000, "urn:ogc:def:crs:EPSG::999999"));
  EXPECT_NE(message(unknown_crs).find("crs.json: metadata.referenceSystem: EPSG:999999 is unknown to PROJ"), std::string::npos)
      << message(unknown_crs);
  // Projected metres without their CRS: not longitudes and latitudes.
  std::string no_crs = house_cityjson(390000, 5800000, "");
  no_crs.replace(no_crs.find(R"("metadata":{"referenceSystem":""},)"), std::string(R"("metadata":{"referenceSystem":""},)").size(), "");
  EXPECT_NE(message(write_text(dir / "nocrs.json", no_crs)).find("is not at a longitude and latitude"), std::string::npos)
      << message(dir / "nocrs.json");
}

}  // namespace
}  // namespace skytrace::world
