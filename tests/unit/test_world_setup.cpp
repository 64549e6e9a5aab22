// The scenario's world keys: OSM extracts and mesh files placed at the scenario's geographic origin
// (with a heading), material rules by name pattern, moving models, and the errors of bad keys.
// Expected positions come from the geometry written here, converted with core/frames, not from
// the loaders.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "skytrace/core/frames.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/world_setup.hpp"
#include "test_support.hpp"

namespace skytrace::sim {
namespace {

constexpr double kLatitudeDeg = 48.1;
constexpr double kLongitudeDeg = 11.5;
constexpr double kElevationM = 520.0;
constexpr double kHeadingDeg = 30.0;

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

// A point given east/north of the origin (m) in the frame of the scenario (x axis `heading` from east).
Eigen::Vector3d enu_to_world(double east_m, double north_m, double up_m) {
  const double h = kHeadingDeg * std::numbers::pi / 180.0;
  return {east_m * std::cos(h) + north_m * std::sin(h), -east_m * std::sin(h) + north_m * std::cos(h), up_m};
}

std::string osm_node(int id, double east_m, double north_m, const std::string& tags = "") {
  const LocalFrame enu{Geodetic{kLatitudeDeg, kLongitudeDeg, kElevationM}, 0.0};
  const Geodetic g = ecef_to_geodetic(enu.to_ecef(Eigen::Vector3d(east_m, north_m, 0.0)));
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer), "<node id=\"%d\" version=\"1\" lat=\"%.9f\" lon=\"%.9f\"", id, g.latitude_deg,
                g.longitude_deg);
  return std::string(buffer) + (tags.empty() ? "/>\n" : ">" + tags + "</node>\n");
}

// A 20 x 20 m building, 20 m high, 40..60 m north of the origin; a tree 30 m west.
std::string osm_text(bool with_building) {
  std::string text = "<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\">\n";
  text += osm_node(1, -10, 40) + osm_node(2, 10, 40) + osm_node(3, 10, 60) + osm_node(4, -10, 60);
  text += osm_node(10, -30, 0, R"(<tag k="natural" v="tree"/><tag k="height" v="8"/>)");
  if (with_building) {
    text += R"(<way id="100" version="1"><nd ref="1"/><nd ref="2"/><nd ref="3"/><nd ref="4"/><nd ref="1"/>)"
            R"(<tag k="building" v="yes"/><tag k="height" v="20"/></way>)";
  }
  return text + "</osm>\n";
}

// A cube 4 m wide standing on z = 0, one OBJ object named "cube".
const char* kCubeObj = R"(o cube
v -2 -2 0
v 2 -2 0
v 2 2 0
v -2 2 0
v -2 -2 4
v 2 -2 4
v 2 2 4
v -2 2 4
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
)";

class WorldSetup : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::make_temp_dir(std::string("world_setup_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    write_file(dir_ / "town.osm", osm_text(true));
    write_file(dir_ / "park.osm", osm_text(false));
    write_file(dir_ / "empty.osm", "<?xml version='1.0'?>\n<osm version=\"0.6\">\n" + osm_node(1, 0, 0) + "</osm>\n");
    write_file(dir_ / "cube.obj", kCubeObj);
    write_file(dir_ / "broken.obj", "this is not a mesh\nv 1 2\nf 7 8 9\n");
    // The kiosk drives 100 m east in 100 s, turning 90 degrees.
    write_file(dir_ / "kiosk.csv", "time_s,x_m,y_m,z_m,yaw_deg\n0,0,-30,0,0\n100,100,-30,0,90\n");
  }

  std::string scenario(const std::string& world) const {
    return "name: t\ntime:\n  start: 2020-06-25T00:00:00\n  duration_s: 60\n  interval_s: 30\n"
           "receiver:\n  position:\n    world_enu_m: [0, 0, 1.5]\n  signals: [G1C]\n"
           "ephemeris:\n  nominal: true\n"
           "world:\n" +
           world;
  }
  Result<Scenario> parse(const std::string& world) const {
    return parse_scenario(scenario(world), (dir_ / "s.yaml").string(), dir_);
  }
  static std::string origin() {
    return "  latitude_deg: 48.1\n  longitude_deg: 11.5\n  elevation_m: 520\n  heading_deg: 30\n";
  }

  std::filesystem::path dir_;
};

RayOutcome trace_towards(const LoadedWorld& world, const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  return world.scene->trace(from, {(to - from).normalized()}).front();
}

TEST_F(WorldSetup, OsmAndMeshPlacedWithHeadingAndMaterialRules) {
  auto s = parse(origin() + "  osm: town.osm\n  vegetation_attenuation_db_per_m: 0.7\n"
                            "  meshes:\n    - file: cube.obj\n      name: kiosk\n      position_m: [0, -30, 0]\n"
                            "      rpy_deg: [0, 0, 45]\n      scale: 2\n"
                            "  materials:\n    - {match: \"kiosk*\", class: glass}\n    - {match: \"way/100\", class: brick}\n");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto loaded = load_world(*s);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_TRUE(loaded->has_value());
  const LoadedWorld& world = **loaded;
  EXPECT_NEAR(world.frame.origin.latitude_deg, kLatitudeDeg, 1e-12);
  EXPECT_DOUBLE_EQ(world.frame.heading_deg, kHeadingDeg);
  EXPECT_EQ(world.buildings, 2u);  // the OSM building and the kiosk
  EXPECT_EQ(world.trees, 1u);

  const Eigen::Vector3d antenna(0, 0, 1.5);
  // The building is north in ENU, i.e. at 30 degrees from the world y axis.
  const RayOutcome building = trace_towards(world, antenna, enu_to_world(0, 50, 10));
  ASSERT_TRUE(building.blocked);
  EXPECT_EQ(building.blocking_object, "way/100");
  EXPECT_EQ(building.blocking_material, MaterialClass::kBrick);
  EXPECT_NEAR(building.blocking_point_m.dot(enu_to_world(0, 1, 0)), 40.0, 0.01);  // its south face
  // Along the world y axis (30 degrees west of north) the building is out of the way (it spans
  // +-14 degrees of north at its south face).
  EXPECT_FALSE(trace_towards(world, antenna, Eigen::Vector3d(0, 50, 10)).blocked);
  // Above the 20 m roof.
  EXPECT_FALSE(trace_towards(world, antenna, enu_to_world(0, 40, 21.6)).blocked);

  // The kiosk: 8 m cube turned 45 degrees about its centre 30 m along -y: its edge is 4 sqrt(2)
  // from the centre.
  const RayOutcome kiosk = trace_towards(world, antenna, Eigen::Vector3d(0, -30, 1.5));
  ASSERT_TRUE(kiosk.blocked);
  EXPECT_EQ(kiosk.blocking_object, "kiosk/cube");
  EXPECT_EQ(kiosk.blocking_material, MaterialClass::kGlass);
  EXPECT_NEAR(kiosk.blocking_distance_m, 30.0 - 4.0 * std::sqrt(2.0), 1e-3);
  EXPECT_FALSE(trace_towards(world, antenna, Eigen::Vector3d(0, -30, 12)).blocked);  // over its 8 m top

  // The tree 30 m west: vegetation at the scenario's attenuation.
  const RayOutcome tree = trace_towards(world, antenna, enu_to_world(-30, 0, 5.2));
  EXPECT_FALSE(tree.blocked);
  EXPECT_GT(tree.vegetation_path_m, 1.0);
  EXPECT_NEAR(tree.vegetation_attenuation_db, 0.7 * tree.vegetation_path_m, 1e-9);
}

// world.citygml: the OSM test's building (20 x 20 m, 20 m high, 40..60 m north) as a CityGML LoD1
// solid in WGS84 (latitude first), its heights 0..20 m above a datum 520 m above the ellipsoid
// (citygml_height_offset_m), in the scenario's frame turned by its heading.
TEST_F(WorldSetup, CityGmlBuildingBlocksWhereItStands) {
  const LocalFrame enu{Geodetic{kLatitudeDeg, kLongitudeDeg, kElevationM}, 0.0};
  const auto corner = [&](double east_m, double north_m, double z_m) {
    const Geodetic g = ecef_to_geodetic(enu.to_ecef(Eigen::Vector3d(east_m, north_m, 0.0)));
    char b[96];
    std::snprintf(b, sizeof b, "%.10f %.10f %.3f ", g.latitude_deg, g.longitude_deg, z_m);
    return std::string(b);
  };
  const auto face = [&](const std::vector<std::array<double, 3>>& c) {
    std::string ring;
    for (size_t i = 0; i <= c.size(); ++i) ring += corner(c[i % c.size()][0], c[i % c.size()][1], c[i % c.size()][2]);
    return "<gml:surfaceMember><gml:Polygon><gml:exterior><gml:LinearRing><gml:posList>" + ring +
           "</gml:posList></gml:LinearRing></gml:exterior></gml:Polygon></gml:surfaceMember>";
  };
  std::string faces;
  const double w = -10, e = 10, s0 = 40, n = 60, top = 20;
  for (const auto& f : std::vector<std::vector<std::array<double, 3>>>{
           {{w, s0, 0}, {w, n, 0}, {e, n, 0}, {e, s0, 0}}, {{w, s0, top}, {e, s0, top}, {e, n, top}, {w, n, top}},
           {{w, s0, 0}, {e, s0, 0}, {e, s0, top}, {w, s0, top}}, {{e, s0, 0}, {e, n, 0}, {e, n, top}, {e, s0, top}},
           {{e, n, 0}, {w, n, 0}, {w, n, top}, {e, n, top}}, {{w, n, 0}, {w, s0, 0}, {w, s0, top}, {w, n, top}}}) {
    faces += face(f);
  }
  write_file(dir_ / "city.gml",
             "<core:CityModel xmlns:core=\"http://www.opengis.net/citygml/2.0\" xmlns:bldg=\"http://www.opengis.net/citygml/building/2.0\" "
             "xmlns:gml=\"http://www.opengis.net/gml\"><core:cityObjectMember><bldg:Building gml:id=\"b1\"><bldg:lod1Solid>"
             "<gml:Solid srsName=\"EPSG:4326\" srsDimension=\"3\"><gml:exterior><gml:CompositeSurface>" +
                 faces + "</gml:CompositeSurface></gml:exterior></gml:Solid></bldg:lod1Solid></bldg:Building></core:cityObjectMember></core:CityModel>\n");
  auto s = parse(origin() + "  citygml: city.gml\n  citygml_height_offset_m: 520\n");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto loaded = load_world(*s);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_TRUE(loaded->has_value());
  const LoadedWorld& world = **loaded;
  EXPECT_EQ(world.buildings, 1u);
  const Eigen::Vector3d antenna(0, 0, 1.5);
  const RayOutcome building = trace_towards(world, antenna, enu_to_world(0, 50, 10));
  ASSERT_TRUE(building.blocked);
  EXPECT_EQ(building.blocking_object, "city.gml/b1");
  EXPECT_NEAR(building.blocking_point_m.dot(enu_to_world(0, 1, 0)), 40.0, 0.01);  // its south face
  EXPECT_FALSE(trace_towards(world, antenna, enu_to_world(0, 40, 21.6)).blocked);  // above the 20 m roof
  EXPECT_FALSE(trace_towards(world, antenna, enu_to_world(0, -50, 10)).blocked);
  // The key needs its model.
  auto orphan = parse(origin() + "  citygml_height_offset_m: 520\n");
  ASSERT_FALSE(orphan.ok());
  EXPECT_NE(orphan.error().message.find("needs world.citygml"), std::string::npos) << orphan.error().message;
}

// world.dem: an ESRI ASCII grid (WGS84 in its .prj) whose ground rises 0.2 m per metre northward
// through the origin: a level ray north meets it 7.5 m away (1.5 m up), one south does not.
TEST_F(WorldSetup, ElevationModelIsTheGround) {
  const LocalFrame enu{Geodetic{kLatitudeDeg, kLongitudeDeg, kElevationM}, 0.0};
  const int n = 41;
  const double cell_deg = 0.0001, lower_left_lat = kLatitudeDeg - 20.5 * cell_deg, lower_left_lon = kLongitudeDeg - 20.5 * cell_deg;
  std::string grid = "ncols 41\nnrows 41\nxllcorner " + std::to_string(lower_left_lon) + "\nyllcorner " +
                     std::to_string(lower_left_lat) + "\ncellsize 0.0001\nNODATA_value -9999\n";
  for (int r = 0; r < n; ++r) {  // the first row is the northernmost
    const double lat = lower_left_lat + (n - r - 0.5) * cell_deg;
    const Eigen::Vector3d local = enu.from_ecef(geodetic_to_ecef(Geodetic{lat, kLongitudeDeg, kElevationM}));
    for (int c = 0; c < n; ++c) {
      if (c > 0) grid += ' ';
      grid += std::to_string(kElevationM + 0.2 * local.y());
    }
    grid += "\n";
  }
  write_file(dir_ / "dem.asc", grid);
  write_file(dir_ / "dem.prj",
             "GEOGCS[\"GCS_WGS_1984\",DATUM[\"D_WGS_1984\",SPHEROID[\"WGS_1984\",6378137,298.257223563]],"
             "PRIMEM[\"Greenwich\",0],UNIT[\"Degree\",0.017453292519943295]]");
  auto s = parse(origin() + "  dem: dem.asc\n  dem_height_offset_m: 0\n");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto loaded = load_world(*s);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_TRUE(loaded->has_value());
  const LoadedWorld& world = **loaded;
  const Eigen::Vector3d antenna(0, 0, 1.5);
  const RayOutcome north = trace_towards(world, antenna, antenna + enu_to_world(0, 100, 0));
  ASSERT_TRUE(north.blocked);
  EXPECT_EQ(north.blocking_object, "dem.asc");
  EXPECT_NEAR(north.blocking_distance_m, 7.5, 0.05);
  EXPECT_FALSE(trace_towards(world, antenna, antenna + enu_to_world(0, -100, 0)).blocked);
  // Without its .prj the grid's cells are nowhere; a file that is no raster is named.
  std::filesystem::remove(dir_ / "dem.prj");
  auto no_crs = load_world(*s);
  ASSERT_FALSE(no_crs.ok());
  EXPECT_NE(no_crs.error().message.find("dem.asc: no coordinate reference system"), std::string::npos) << no_crs.error().message;
  write_file(dir_ / "dem.asc", "not a raster\n");
  auto garbage = load_world(*s);
  ASSERT_FALSE(garbage.ok());
  EXPECT_NE(garbage.error().message.find("dem.asc: GDAL cannot read it as a raster"), std::string::npos) << garbage.error().message;
}

TEST_F(WorldSetup, OsmOriginIsTheExtractCentreWithoutOriginKeys) {
  auto s = parse("  osm: town.osm\n");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto loaded = load_world(*s);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  // No <bounds>: the centre of the data (nodes between 30 m west and 10 m east, 0 and 60 m north).
  const LocalFrame enu{Geodetic{kLatitudeDeg, kLongitudeDeg, kElevationM}, 0.0};
  const Eigen::Vector3d centre = enu.from_ecef(geodetic_to_ecef((*loaded)->frame.origin));
  EXPECT_NEAR(centre.x(), -10.0, 0.01);
  EXPECT_NEAR(centre.y(), 30.0, 0.01);
  EXPECT_DOUBLE_EQ((*loaded)->frame.heading_deg, 0.0);
}

TEST_F(WorldSetup, OsmWithoutBuildingsWarnsWithVegetationAndFailsWhenEmpty) {
  auto park = load_world(parse(origin() + "  osm: park.osm\n").value());
  ASSERT_TRUE(park.ok()) << park.error().message;
  ASSERT_FALSE((*park)->warnings.empty());
  EXPECT_NE((*park)->warnings.back().find("no buildings in the OSM data, only vegetation"), std::string::npos);

  auto empty = load_world(parse(origin() + "  osm: empty.osm\n").value());
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("empty.osm: no buildings, trees or woods"), std::string::npos)
      << empty.error().message;
}

TEST_F(WorldSetup, MovingModelFollowsItsTrajectoryAsOneBody) {
  auto s = parse(origin() + "  meshes:\n    - {file: cube.obj, name: kiosk, position_m: [500, 500, 0]}\n"
                            "  moving:\n    - {model: kiosk, trajectory: kiosk.csv}\n");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto loaded = load_world(*s);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  LoadedWorld& world = **loaded;
  ASSERT_EQ(world.moving.size(), 1u);
  const Eigen::Vector3d antenna(0, 0, 1.5);
  // Loaded at the first pose of its trajectory (not at its placement).
  RayOutcome hit = trace_towards(world, antenna, Eigen::Vector3d(0, -30, 1.5));
  ASSERT_TRUE(hit.blocked);
  EXPECT_NEAR(hit.blocking_distance_m, 28.0, 1e-4);
  // Half way: 50 m east, turned 45 degrees; its corner points back at y = -30 + 2 sqrt(2).
  ASSERT_TRUE(move_models_to(world, s->time.start + 50.0).ok());
  EXPECT_FALSE(trace_towards(world, antenna, Eigen::Vector3d(0, -30, 1.5)).blocked);
  const Eigen::Vector3d beside(50, 0, 1.5);
  hit = trace_towards(world, beside, Eigen::Vector3d(50, -30, 1.5));
  ASSERT_TRUE(hit.blocked);
  EXPECT_NEAR(hit.blocking_distance_m, 30.0 - 2.0 * std::sqrt(2.0), 1e-3);
  // After the last sample it stays at the last pose.
  ASSERT_TRUE(move_models_to(world, s->time.start + 1000.0).ok());
  hit = trace_towards(world, Eigen::Vector3d(100, 0, 1.5), Eigen::Vector3d(100, -30, 1.5));
  ASSERT_TRUE(hit.blocked);
  EXPECT_NEAR(hit.blocking_distance_m, 28.0, 1e-4);
  // Moved from outside by its model name.
  ASSERT_TRUE(set_object_pose(world, "kiosk", Eigen::Isometry3d(Eigen::Translation3d(0, 10, 0))).ok());
  hit = trace_towards(world, antenna, Eigen::Vector3d(0, 10, 1.5));
  ASSERT_TRUE(hit.blocked);
  EXPECT_NEAR(hit.blocking_distance_m, 8.0, 1e-4);
  const auto unknown = set_object_pose(world, "bus", Eigen::Isometry3d::Identity());
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().message.find("bus"), std::string::npos);
}

TEST_F(WorldSetup, BadWorldInputNamesKeyFileAndLine) {
  // Unknown model to move: the known models are listed.
  auto s = parse(origin() + "  meshes:\n    - {file: cube.obj, name: kiosk}\n  moving:\n    - {model: bus, trajectory: kiosk.csv}\n");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto loaded = load_world(*s);
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().message.find("world.moving: no model named 'bus' in the world (models: kiosk)"), std::string::npos)
      << loaded.error().message;

  // A trajectory row that is not a number.
  write_file(dir_ / "bad.csv", "t,x,y,z,yaw\n0,0,0,0,0\n10,1,north,0,0\n");
  loaded = load_world(parse(origin() + "  meshes:\n    - {file: cube.obj, name: kiosk}\n"
                                       "  moving:\n    - {model: kiosk, trajectory: bad.csv}\n")
                          .value());
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().message.find("bad.csv:3"), std::string::npos) << loaded.error().message;
  EXPECT_NE(loaded.error().message.find("y_m"), std::string::npos) << loaded.error().message;

  // A mesh file that cannot be read stops with its name.
  loaded = load_world(parse(origin() + "  meshes:\n    - {file: broken.obj}\n").value());
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().message.find("broken.obj"), std::string::npos) << loaded.error().message;

  struct Case {
    std::string world, expected;
  };
  const Case cases[] = {
      {"  meshes:\n    - {file: cube.obj}\n", "s.yaml:14: world.meshes: meshes are placed in the world frame"},
      {origin() + "  meshes:\n    - {file: cube.obj, scale: 0}\n", "s.yaml:18: world.meshes[0].scale: expected a scale above 0"},
      {origin() + "  meshes:\n    - {file: cube.obj, up_axis: x}\n", "world.meshes[0].up_axis: unknown value 'x'"},
      {origin() + "  meshes:\n    - {file: missing.obj}\n", "world.meshes[0].file: file not found"},
      {origin() + "  meshes:\n    - {file: cube.obj}\n    - {file: cube.obj}\n", "s.yaml:19: world.meshes[1]: two meshes named 'cube.obj'"},
      {origin() + "  meshes:\n    - {file: cube.obj, colour: red}\n", "world.meshes[0].colour: unknown key"},
      {origin() + "  osm: town.osm\n  materials:\n    - {match: \"glass*\", class: plastic}\n",
       "s.yaml:19: world.materials[0].class: unknown material class 'plastic'"},
      {origin() + "  osm: town.osm\n  materials:\n    - {match: \"*\", class: glass, attenuation_db_per_m: 2}\n",
       "world.materials[0].attenuation_db_per_m: only vegetation has an attenuation"},
      {origin() + "  osm: town.osm\n  materials:\n    - {class: glass}\n", "world.materials[0]: missing required key 'match'"},
      {origin() + "  osm: town.osm\n  moving:\n    - {model: a, trajectory: nowhere.csv}\n", "world.moving[0].trajectory: file not found"},
      {origin() + "  osm: town.osm\n  moving:\n    - {model: a, trajectory: kiosk.csv}\n    - {model: a, trajectory: kiosk.csv}\n",
       "s.yaml:20: world.moving[1].model: model 'a' is listed twice"},
      {origin() + "  moving:\n    - {model: a, trajectory: kiosk.csv}\n", "world.moving: moving models need a world"},
      {"  osm: town.osm\n  latitude_deg: 48\n", "s.yaml:13: world: give both world.latitude_deg and world.longitude_deg"},
  };
  for (const Case& c : cases) {
    const auto r = parse(c.world);
    ASSERT_FALSE(r.ok()) << c.world;
    EXPECT_NE(r.error().message.find(c.expected), std::string::npos) << r.error().message;
  }
}

}  // namespace
}  // namespace skytrace::sim
