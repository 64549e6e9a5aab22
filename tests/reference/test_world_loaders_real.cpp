// Real worlds from ../shared/data/worlds: citysim's simple_city.world and PX4's test_city_4.world
// with worlds/models on the model path, and the two OpenStreetMap extracts. Expected counts and
// bounds come from the files' text (regular expressions over the XML, the equivalent of grep),
// not from sdformat or osmium.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "skytrace/world/loaders.hpp"
#include "test_support.hpp"

namespace skytrace::world {
namespace {

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::size_t count_matches(const std::string& text, const std::regex& pattern) {
  return static_cast<std::size_t>(std::distance(
      std::sregex_iterator(text.begin(), text.end(), pattern), std::sregex_iterator()));
}

SdfLoadOptions options_with_models(const std::filesystem::path& models) {
  SdfLoadOptions options;
  options.use_environment_paths = false;  // the test's model path only, as GAZEBO_MODEL_PATH would
  options.model_paths.push_back(models);
  return options;
}

void report(const std::string& what, const WorldModel& world, double seconds) {
  const auto summary = summarize_world(world);
  const auto [low, high] = world_bounds(world);
  std::cout << what << ": " << seconds << " s, " << summary.objects << " objects, "
            << summary.triangles << " triangles, buildings " << summary.buildings << ", trees "
            << summary.trees << ", ground " << summary.ground << ", other " << summary.other
            << ", bounds (" << low.transpose() << ") - (" << high.transpose() << "), "
            << world.warnings.size() << " warnings\n";
  ::testing::Test::RecordProperty(what + "_load_s", std::to_string(seconds));
  ::testing::Test::RecordProperty(what + "_triangles", std::to_string(summary.triangles));
}

template <typename F>
double seconds_of(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(WorldLoadersReal, CitysimSimpleCity) {
  const auto path = SKYTRACE_SHARED_FILE("worlds/citysim/simple_city.world");
  const auto models = test::shared_data_dir() / "worlds/models";
  Result<WorldModel> loaded = WorldModel{};
  const double seconds =
      seconds_of([&] { loaded = load_sdf_world(path, options_with_models(models)); });
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const WorldModel& world = *loaded;
  report("citysim", world, seconds);

  // Independent expectation from the world's text: includes of models present in worlds/models.
  const std::string text = read_text(path);
  const std::regex include(
      R"(<include>[\s\S]*?<uri>model://([A-Za-z0-9_]+)</uri>[\s\S]*?</include>)");
  std::size_t expected_trees = 0;
  std::size_t expected_buildings = 0;
  std::size_t expected_terrain = 0;
  std::set<std::string> missing;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), include);
       it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1];
    if (!std::filesystem::exists(models / name)) {
      missing.insert(name);
    } else if (name == "pine_tree" || name == "oak_tree") {
      ++expected_trees;
    } else if (name == "city_terrain") {
      ++expected_terrain;
    } else {
      ++expected_buildings;  // every other model folder in worlds/models is a building
    }
  }
  // Inline models built from a building mesh (gas_station_137).
  expected_buildings += count_matches(text, std::regex(R"(<model name="gas_station_\d+">)"));
  EXPECT_EQ(expected_trees, 252U);  // README: 160 pine + 92 oak
  EXPECT_EQ(expected_buildings, 31U);
  EXPECT_EQ(expected_terrain, 1U);

  const auto summary = summarize_world(world);
  EXPECT_EQ(summary.trees, expected_trees);
  EXPECT_EQ(summary.buildings, expected_buildings);
  EXPECT_EQ(summary.ground, expected_terrain);
  // Every missing model is named once in the warnings.
  for (const auto& name : missing) {
    const std::string needle = "model model://" + name + " not found";
    EXPECT_TRUE(
        std::any_of(world.warnings.begin(), world.warnings.end(),
                    [&](const std::string& w) { return w.find(needle) != std::string::npos; }))
        << needle;
  }
  // Trees are closed vegetation volumes with the default attenuation.
  for (const auto& object : world.objects) {
    if (object.kind != ObjectKind::kTree) continue;
    EXPECT_TRUE(object.material.is_vegetation()) << object.name;
    EXPECT_GE(object.mesh.triangles.size(), 4U);
  }

  // Bounds: the terrain's collision plane is 500 m x 500 m (models/city_terrain/model.sdf) around
  // (0, 0) at z = 5.01 (the include's pose), and holds everything else.
  const auto [low, high] = world_bounds(world);
  EXPECT_NEAR(low.x(), -250.0, 1e-3);
  EXPECT_NEAR(high.x(), 250.0, 1e-3);
  EXPECT_NEAR(low.y(), -250.0, 1e-3);
  EXPECT_NEAR(high.y(), 250.0, 1e-3);
  // Models stand on the terrain at z = 5.01; some meshes reach a little below their origin (the
  // rubble of collapsed_industrial goes 0.38 m down).
  EXPECT_LE(low.z(), 5.01);
  EXPECT_GT(low.z(), 5.01 - 0.5);
  // The tallest building stands on the terrain: tens of metres, not inches read as metres.
  EXPECT_GT(high.z(), 5.01 + 10.0);
  EXPECT_LT(high.z(), 5.01 + 80.0);
}

TEST(WorldLoadersReal, CitysimVisualHeightmap) {
  const auto path = SKYTRACE_SHARED_FILE("worlds/citysim/simple_city.world");
  auto options = options_with_models(test::shared_data_dir() / "worlds/models");
  options.geometry = GeometrySource::kVisual;
  const auto world = load_sdf_world(path, options).value();
  // The visual terrain is the 257 x 257 JPEG heightmap: 256 * 256 * 2 triangles, 500 m x 500 m x
  // 75 m at pos (40, -20, 0) in the model placed at z = 5.01.
  const WorldObject* terrain = nullptr;
  for (const auto& object : world.objects) {
    if (object.name == "city_terrain_1/link/visual") terrain = &object;
  }
  ASSERT_NE(terrain, nullptr);
  EXPECT_EQ(terrain->kind, ObjectKind::kGround);
  EXPECT_EQ(terrain->mesh.triangles.size(), 256U * 256U * 2U);
  WorldModel single;
  single.objects.push_back(*terrain);
  const auto [low, high] = world_bounds(single);
  EXPECT_NEAR(low.x(), 40.0 - 250.0, 1e-3);
  EXPECT_NEAR(high.y(), -20.0 + 250.0, 1e-3);
  EXPECT_GE(low.z(), 5.01 - 1e-4);
  EXPECT_LE(high.z(), 5.01 + 75.0 + 1e-4);
  EXPECT_GT(high.z() - low.z(), 10.0);  // the image is not flat
}

TEST(WorldLoadersReal, Px4TestCity4) {
  const auto path = SKYTRACE_SHARED_FILE("worlds/px4_avoidance/test_city_4.world");
  Result<WorldModel> loaded = WorldModel{};
  const double seconds = seconds_of([&] {
    loaded = load_sdf_world(path, options_with_models(test::shared_data_dir() / "worlds/models"));
  });
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const WorldModel& world = *loaded;
  report("test_city_4", world, seconds);

  // From the text: models named House N / Office Building N are buildings, asphalt tiles are flat.
  const std::string text = read_text(path);
  const std::size_t houses =
      count_matches(text, std::regex(R"(<model name='(House|Office Building) \d'>)"));
  const std::size_t tiles = count_matches(text, std::regex(R"(<model name='asphalt_plane'>)"));
  EXPECT_EQ(houses, 69U);
  EXPECT_EQ(tiles, 144U);
  const auto summary = summarize_world(world);
  EXPECT_EQ(summary.buildings, houses);
  EXPECT_EQ(summary.other, tiles);
  EXPECT_EQ(summary.trees, 0U);
  EXPECT_EQ(summary.objects, houses + tiles);
  EXPECT_TRUE(std::any_of(world.warnings.begin(), world.warnings.end(), [](const std::string& w) {
    return w.find("model://ground_plane not found") != std::string::npos;
  }));

  // Model origins from the text (the model-level <pose>, 6 spaces in, after the link): the bounds
  // hold every origin and reach at most 10 m beyond them (half a 20 m tile; houses and offices
  // are smaller: 5.8 m and 8.9 m from their origin).
  double min_x = 1e9;
  double max_x = -1e9;
  double min_y = 1e9;
  double max_y = -1e9;
  std::size_t poses = 0;
  const std::regex block(R"(<model name='[^']+'>([\s\S]*?)\n    </model>)");
  const std::regex pose(R"(\n      <pose>\s*(\S+)\s+(\S+)\s+(\S+)\s)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), block);
       it != std::sregex_iterator(); ++it) {
    const std::string body = (*it)[1];
    std::smatch m;
    ASSERT_TRUE(std::regex_search(body, m, pose));
    min_x = std::min(min_x, std::stod(m[1]));
    max_x = std::max(max_x, std::stod(m[1]));
    min_y = std::min(min_y, std::stod(m[2]));
    max_y = std::max(max_y, std::stod(m[2]));
    ++poses;
  }
  EXPECT_EQ(poses, houses + tiles);
  const auto [low, high] = world_bounds(world);
  EXPECT_LE(low.x(), min_x);
  EXPECT_GE(low.x(), min_x - 10.0);
  EXPECT_LE(low.y(), min_y);
  EXPECT_GE(low.y(), min_y - 10.0);
  EXPECT_GE(high.x(), max_x);
  EXPECT_LE(high.x(), max_x + 10.0);
  EXPECT_GE(high.y(), max_y);
  EXPECT_LE(high.y(), max_y + 10.0);
  std::cout << "test_city_4 model origins x " << min_x << ".." << max_x << ", y " << min_y << ".."
            << max_y << "\n";
  EXPECT_NEAR(low.z(), -0.05, 1e-4);  // tile bottoms (0.1 m thick at z = 0)
  // The office buildings are the tallest: about 18.7 m (inches in the COLLADA file).
  EXPECT_GT(high.z(), 15.0);
  EXPECT_LT(high.z(), 25.0);
}

// gz-sim's geo-referencing example: its header comment holds "--" (not XML, accepted by
// sdformat's parser) and its origin is Rio de Janeiro.
TEST(WorldLoadersReal, GzSimSphericalCoordinatesExample) {
  const auto path = SKYTRACE_SHARED_FILE("worlds/gz_sim/spherical_coordinates.sdf");
  const auto world = load_sdf_world(path, options_with_models({})).value();
  ASSERT_TRUE(world.geo_origin.has_value());
  const std::string text = read_text(path);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(text, m, std::regex(R"(<latitude_deg>([^<]+)</latitude_deg>)")));
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.latitude_deg, std::stod(m[1]));
  ASSERT_TRUE(std::regex_search(text, m, std::regex(R"(<longitude_deg>([^<]+)</longitude_deg>)")));
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.longitude_deg, std::stod(m[1]));
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.latitude_deg, -22.986687);
  EXPECT_DOUBLE_EQ(world.geo_origin->heading_deg, 0.0);
}

struct OsmExpectation {
  std::string file;
  std::size_t readme_buildings;
  std::map<double, std::size_t> heights_m;  // height -> number of buildings
  std::vector<std::string> skipped;         // buildings named in the warnings
};

void check_osm(const OsmExpectation& expected) {
  const auto path = test::shared_data_dir() / "worlds/osm" / expected.file;
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data file absent: " << path;
  Result<WorldModel> loaded = WorldModel{};
  const double seconds = seconds_of([&] { loaded = load_osm_world(path); });
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const WorldModel& world = *loaded;
  report(expected.file, world, seconds);

  // The README's count is of building tags; some cannot be built and are named as skipped.
  const std::string text = read_text(path);
  EXPECT_EQ(count_matches(text, std::regex(R"re(k="building")re")), expected.readme_buildings);
  const auto summary = summarize_world(world);
  EXPECT_EQ(summary.buildings + expected.skipped.size(), expected.readme_buildings);
  for (const auto& name : expected.skipped) {
    EXPECT_TRUE(std::any_of(world.warnings.begin(), world.warnings.end(),
                            [&](const std::string& w) { return w.rfind(name + " ", 0) == 0; }))
        << name;
  }
  std::map<double, std::size_t> heights;
  for (const auto& object : world.objects) {
    if (object.kind != ObjectKind::kBuilding) continue;
    WorldModel single;
    single.objects.push_back(object);
    const auto [low, high] = world_bounds(single);
    EXPECT_NEAR(low.z(), 0.0, 1e-5);
    heights[std::round((high.z() - low.z()) * 1000.0) / 1000.0]++;
    // Footprints of metres to a few hundred metres (West Oakland's way 52538639 is 243 m long):
    // projected, not in degrees.
    const double longest_m = std::max(high.x() - low.x(), high.y() - low.y());
    EXPECT_GT(longest_m, 2.0) << object.name;
    EXPECT_LT(longest_m, 400.0) << object.name;
  }
  EXPECT_EQ(heights, expected.heights_m);
  // Everything within the extract's few hundred metres around the origin.
  const auto [low, high] = world_bounds(world);
  EXPECT_GT(low.x(), -1000.0);
  EXPECT_LT(high.x(), 1000.0);
}

TEST(WorldLoadersReal, OsmBavaria) {
  // 33 building ways and one relation. Skipped: way 275490779 has a single node, way 275490781's
  // closing edge crosses its outline, relation 318560 (a Berlin building) has no member in the
  // file. Loaded: 8 with building:levels=2 (6 m), 23 at the 10 m default.
  check_osm({"planet_10.068,48.135_10.071,48.137.osm",
             34,
             {{6.0, 8}, {10.0, 23}},
             {"way/275490779", "way/275490781", "relation/318560"}});
}

TEST(WorldLoadersReal, OsmWestOakland) {
  // 23 building ways: levels 5 (15 m) and 4 (12 m), 21 at the 10 m default.
  check_osm({"West-Oakland.osm", 23, {{10.0, 21}, {12.0, 1}, {15.0, 1}}, {}});
}

}  // namespace
}  // namespace skytrace::world
