// World scenes: line of sight, vegetation path and sky mask against geometry worked out by hand,
// and EmbreeScene (float, BVH) against BruteForceScene (every triangle in double) on random rays.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <numbers>
#include <thread>

#include "skytrace/core/random.hpp"
#include "skytrace/world/scene.hpp"

namespace skytrace::world {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// An axis-aligned box in its own frame: 8 corners, 12 triangles wound counter-clockwise seen from
// outside.
TriangleMesh box_mesh(const Eigen::Vector3d& low, const Eigen::Vector3d& high) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices_m.emplace_back(static_cast<float>((i & 1) != 0 ? high.x() : low.x()),
                                 static_cast<float>((i & 2) != 0 ? high.y() : low.y()),
                                 static_cast<float>((i & 4) != 0 ? high.z() : low.z()));
  }
  // Corner index = x + 2 y + 4 z.
  const int quads[6][4] = {
      {0, 2, 3, 1},  // z = low, seen from below
      {4, 5, 7, 6},  // z = high
      {0, 1, 5, 4},  // y = low
      {2, 6, 7, 3},  // y = high
      {0, 4, 6, 2},  // x = low
      {1, 3, 7, 5},  // x = high
  };
  for (const auto& q : quads) {
    mesh.triangles.emplace_back(q[0], q[1], q[2]);
    mesh.triangles.emplace_back(q[0], q[2], q[3]);
  }
  return mesh;
}

WorldObject box(const std::string& name, const Eigen::Vector3d& low, const Eigen::Vector3d& high,
                Material material = {}) {
  WorldObject object;
  object.name = name;
  object.kind = material.is_vegetation() ? ObjectKind::kTree : ObjectKind::kBuilding;
  object.material = material;
  object.mesh = box_mesh(low, high);
  return object;
}

Material vegetation(double db_per_m) { return Material{MaterialClass::kVegetation, db_per_m}; }

// Both scenes of one world, queried the same way.
struct Scenes {
  std::unique_ptr<EmbreeScene> embree;
  std::optional<BruteForceScene> brute;

  explicit Scenes(const WorldModel& world) {
    auto e = EmbreeScene::build(world);
    EXPECT_TRUE(e.ok()) << (e.ok() ? "" : e.error().message);
    if (e.ok()) embree = std::move(*e);
    auto b = BruteForceScene::build(world);
    EXPECT_TRUE(b.ok()) << (b.ok() ? "" : b.error().message);
    if (b.ok()) brute.emplace(std::move(*b));
  }
  std::vector<const PathQuery*> both() const { return {embree.get(), &*brute}; }
};

const char* label(std::size_t index) { return index == 0 ? "embree" : "brute force"; }

TEST(WorldScene, WallBlocksRaysBelowItsTop) {
  // Wall 20 m wide, 1 m thick, 10 m high, its south face 20 m north of the antenna at 1.5 m.
  WorldModel world;
  world.objects.push_back(box("wall", {-10, 20, 0}, {10, 21, 10}, Material{MaterialClass::kBrick, 0.0}));
  const Scenes scenes(world);
  ASSERT_TRUE(scenes.embree && scenes.brute);
  const Eigen::Vector3d origin{0, 0, 1.5};
  // Top of the wall seen straight north: atan(8.5 / 20) = 23.03 deg.
  const std::vector<Eigen::Vector3d> directions = {
      enu_direction(0, 10),   enu_direction(20, 5),  enu_direction(0, 22.9), enu_direction(0, 23.2),
      enu_direction(45, 5),   enu_direction(180, 5), enu_direction(0, 90),   enu_direction(-20, -5),
  };
  for (std::size_t s = 0; s < 2; ++s) {
    SCOPED_TRACE(label(s));
    const auto out = scenes.both()[s]->trace(origin, directions);
    ASSERT_EQ(out.size(), directions.size());
    // North, 10 deg up: hits y = 20 after 20 / cos(10 deg) m.
    ASSERT_TRUE(out[0].blocked);
    EXPECT_NEAR(out[0].blocking_distance_m, 20.0 / std::cos(10 * kDegToRad), 1e-4);
    EXPECT_EQ(out[0].blocking_object, "wall");
    EXPECT_EQ(out[0].blocking_material, MaterialClass::kBrick);
    EXPECT_NEAR((out[0].blocking_point_m - Eigen::Vector3d(0, 20, 1.5 + 20 * std::tan(10 * kDegToRad))).norm(), 0,
                1e-4);
    EXPECT_NEAR((out[0].blocking_normal - Eigen::Vector3d(0, -1, 0)).norm(), 0, 1e-6);
    // Azimuth 20, 5 deg up: x = 20 tan 20 = 7.3 m, inside the wall's width.
    ASSERT_TRUE(out[1].blocked);
    EXPECT_NEAR(out[1].blocking_distance_m, 20.0 / (std::cos(20 * kDegToRad) * std::cos(5 * kDegToRad)), 1e-4);
    EXPECT_TRUE(out[2].blocked);   // just below the top
    EXPECT_FALSE(out[3].blocked);  // just above
    EXPECT_FALSE(out[4].blocked);  // azimuth 45: passes east of the wall's end (x = 20 > 10)
    EXPECT_FALSE(out[5].blocked);  // south
    EXPECT_FALSE(out[6].blocked);  // zenith
    // Below the horizon towards the wall's foot: hits the wall at y = 20 (z = -0.36 is below its
    // base, so it passes under it).
    EXPECT_FALSE(out[7].blocked);
    for (const auto& o : out) EXPECT_EQ(o.vegetation_path_m, 0.0);
  }
}

TEST(WorldScene, VegetationChordEqualsGeometry) {
  // A crown 6 m x 6 m x 6 m whose south face is 17 m north of the antenna, at 1.5 dB/m.
  WorldModel world;
  world.objects.push_back(box("crown", {-3, 17, 4}, {3, 23, 10}, vegetation(1.5)));
  const Scenes scenes(world);
  ASSERT_TRUE(scenes.embree && scenes.brute);
  const Eigen::Vector3d origin{0, 0, 7};
  const double e5 = 5 * kDegToRad;
  const double e8 = 8 * kDegToRad;
  // Horizontal: 6 m, entering through the middle of a face (on the diagonal shared by its two
  // triangles). 5 deg up: leaves through the north face (z = 7 + 23 tan 5 = 9.0 < 10), chord
  // 6 / cos 5. 8 deg up: enters at z = 9.39, leaves through the top at y = 3 / tan 8.
  const std::vector<Eigen::Vector3d> directions = {enu_direction(0, 0), enu_direction(0, 5), enu_direction(0, 8),
                                                   enu_direction(180, 0), enu_direction(0, 40)};
  const std::vector<double> expected_m = {6.0, 6.0 / std::cos(e5), (3.0 / std::tan(e8) - 17.0) / std::cos(e8), 0.0,
                                          0.0};
  for (std::size_t s = 0; s < 2; ++s) {
    SCOPED_TRACE(label(s));
    const auto out = scenes.both()[s]->trace(origin, directions);
    for (std::size_t i = 0; i < directions.size(); ++i) {
      SCOPED_TRACE(i);
      EXPECT_FALSE(out[i].blocked);  // vegetation never blocks
      EXPECT_NEAR(out[i].vegetation_path_m, expected_m[i], 1e-4);
      EXPECT_NEAR(out[i].vegetation_attenuation_db, 1.5 * expected_m[i], 1.5e-4);
    }
    // From inside the crown (its centre at 7 m): 3 m to every face straight out, 3 sqrt(2) to an edge.
    const auto inside = scenes.both()[s]->trace(
        {0, 20, 7}, {enu_direction(0, 0), enu_direction(90, 0), enu_direction(0, 90), enu_direction(45, 0)});
    EXPECT_NEAR(inside[0].vegetation_path_m, 3.0, 1e-4);
    EXPECT_NEAR(inside[1].vegetation_path_m, 3.0, 1e-4);
    EXPECT_NEAR(inside[2].vegetation_path_m, 3.0, 1e-4);
    EXPECT_NEAR(inside[3].vegetation_path_m, 3.0 * std::sqrt(2.0), 1e-4);
  }
}

TEST(WorldScene, VegetationVolumesAddUpAndStopAtTheFirstWall) {
  const Eigen::Vector3d origin{0, 0, 7};
  const auto north = std::vector<Eigen::Vector3d>{enu_direction(0, 0)};
  {
    // Two crowns in a row: 6 m at 1.5 dB/m and 4 m at 2 dB/m.
    WorldModel world;
    world.objects.push_back(box("crown1", {-3, 17, 4}, {3, 23, 10}, vegetation(1.5)));
    world.objects.push_back(box("crown2", {-3, 30, 4}, {3, 34, 10}, vegetation(2.0)));
    const Scenes scenes(world);
    for (std::size_t s = 0; s < 2; ++s) {
      SCOPED_TRACE(label(s));
      const auto out = scenes.both()[s]->trace(origin, north);
      EXPECT_FALSE(out[0].blocked);
      EXPECT_NEAR(out[0].vegetation_path_m, 10.0, 1e-4);
      EXPECT_NEAR(out[0].vegetation_attenuation_db, 6 * 1.5 + 4 * 2.0, 1e-3);
    }
  }
  {
    // A wall in front of the crown hides it; a wall behind the crown leaves it whole; a wall
    // inside the crown (a trunk) cuts it where the ray stops.
    WorldModel front;
    front.objects.push_back(box("crown", {-3, 17, 4}, {3, 23, 10}, vegetation(1.5)));
    front.objects.push_back(box("wall", {-10, 10, 0}, {10, 11, 20}));
    WorldModel behind = front;
    behind.objects[1] = box("wall", {-10, 25, 0}, {10, 26, 20});
    WorldModel trunk = front;
    trunk.objects[1] = box("trunk", {-0.5, 20, 0}, {0.5, 21, 8}, Material{MaterialClass::kWood, 0.0});
    const std::vector<std::pair<const WorldModel*, std::pair<double, double>>> cases = {
        {&front, {10.0, 0.0}}, {&behind, {25.0, 6.0}}, {&trunk, {20.0, 3.0}}};
    for (const auto& [world, expected] : cases) {
      const Scenes scenes(*world);
      for (std::size_t s = 0; s < 2; ++s) {
        SCOPED_TRACE(label(s));
        const auto out = scenes.both()[s]->trace(origin, north);
        ASSERT_TRUE(out[0].blocked);
        EXPECT_NEAR(out[0].blocking_distance_m, expected.first, 1e-4);
        EXPECT_NEAR(out[0].vegetation_path_m, expected.second, 1e-4);
      }
    }
    // From inside the crown to the trunk, never leaving the crown: 1 m of foliage, blocked at 1 m.
    const Scenes scenes(trunk);
    for (std::size_t s = 0; s < 2; ++s) {
      SCOPED_TRACE(label(s));
      const auto out = scenes.both()[s]->trace({0, 19, 7}, north);
      ASSERT_TRUE(out[0].blocked);
      EXPECT_EQ(out[0].blocking_object, "trunk");
      EXPECT_NEAR(out[0].blocking_distance_m, 1.0, 1e-6);
      EXPECT_NEAR(out[0].vegetation_path_m, 1.0, 1e-6);
      EXPECT_NEAR(out[0].vegetation_attenuation_db, 1.5, 1e-6);
    }
  }
}

// Random worlds: what the two scenes must agree on, and which rays graze an edge (excluded).
struct RandomWorld {
  WorldModel world;
  std::vector<std::array<Eigen::Vector3d, 3>> all_triangles;  // world frame, for the grazing test
};

Eigen::Vector3d uniform_vector(RandomStream& random, double half_width) {
  return {half_width * (2 * random.uniform() - 1), half_width * (2 * random.uniform() - 1),
          half_width * (2 * random.uniform() - 1)};
}

Eigen::Vector3d unit_vector(RandomStream& random) {
  Eigen::Vector3d v;
  do v = uniform_vector(random, 1.0);
  while (v.norm() < 0.1 || v.norm() > 1.0);
  return v.normalized();
}

RandomWorld make_random_world(std::uint64_t seed) {
  RandomStream random(stream_key(seed, {1}));
  RandomWorld out;
  // Ten triangle soups of 150 triangles each (sizes 0.5-15 m) in a 100 m cube.
  for (int soup = 0; soup < 10; ++soup) {
    WorldObject object;
    object.name = "soup" + std::to_string(soup);
    object.material.material_class = soup % 2 == 0 ? MaterialClass::kConcrete : MaterialClass::kGlass;
    for (int t = 0; t < 150; ++t) {
      const Eigen::Vector3d centre = uniform_vector(random, 50.0);
      const double size_m = 0.5 + 14.5 * random.uniform();
      const int first = static_cast<int>(object.mesh.vertices_m.size());
      for (int k = 0; k < 3; ++k) object.mesh.vertices_m.push_back((centre + size_m * unit_vector(random)).cast<float>());
      object.mesh.triangles.emplace_back(first, first + 1, first + 2);
    }
    out.world.objects.push_back(std::move(object));
  }
  // Rotated boxes: 15 opaque, 15 vegetation (2 dB/m), a third of them movable (instanced in Embree).
  for (int b = 0; b < 30; ++b) {
    // Crowns larger than the opaque boxes, so that many rays (and some origins) meet them.
    const double base_m = b % 2 == 0 ? 1.0 : 4.0;
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(base_m) + uniform_vector(random, 1.0).cwiseAbs() * 2.0 * base_m;
    WorldObject object = box("box" + std::to_string(b), -half, half,
                             b % 2 == 0 ? Material{MaterialClass::kMetal, 0.0} : vegetation(2.0));
    object.pose = Eigen::Translation3d(uniform_vector(random, 45.0)) *
                  Eigen::AngleAxisd(2 * std::numbers::pi * random.uniform(), unit_vector(random));
    object.is_static = b % 3 != 0;
    out.world.objects.push_back(std::move(object));
  }
  for (const auto& object : out.world.objects) {
    for (const auto& tri : object.mesh.triangles) {
      out.all_triangles.push_back({object.pose * object.mesh.vertices_m[tri[0]].cast<double>(),
                                   object.pose * object.mesh.vertices_m[tri[1]].cast<double>(),
                                   object.pose * object.mesh.vertices_m[tri[2]].cast<double>()});
    }
  }
  return out;
}

// True when the ray passes within `margin` (barycentric) of an edge of a triangle in front of the
// origin, or starts within 1e-4 m of a triangle: float and double may then disagree legitimately.
bool grazes_an_edge(const RandomWorld& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                    double margin) {
  for (const auto& [a, b, c] : world.all_triangles) {
    const Eigen::Vector3d e1 = b - a;
    const Eigen::Vector3d e2 = c - a;
    const Eigen::Vector3d p = direction.cross(e2);
    const double det = e1.dot(p);
    if (det == 0.0) continue;
    const Eigen::Vector3d s = origin - a;
    const double u = s.dot(p) / det;
    const double v = direction.dot(s.cross(e1)) / det;
    const double t = e2.dot(s.cross(e1)) / det;
    const double w = 1.0 - u - v;
    if (t < -1e-4) continue;
    if (std::min({u, v, w}) > -margin && std::min({std::abs(u), std::abs(v), std::abs(w)}) < margin) return true;
    if (std::abs(t) < 1e-4 && std::min({u, v, w}) > -margin) return true;
  }
  return false;
}

TEST(WorldScene, EmbreeAgreesWithBruteForceOnRandomRays) {
  const RandomWorld random_world = make_random_world(20240611);
  const Scenes scenes(random_world.world);
  ASSERT_TRUE(scenes.embree && scenes.brute);
  EXPECT_EQ(scenes.embree->stats().triangles, 1500U + 30U * 12U);
  EXPECT_EQ(scenes.embree->stats().convex_vegetation_objects, 15U);  // the boxes are convex volumes
  // The same world with its vegetation boxes traced as triangles (the general method).
  EmbreeSceneOptions as_triangles;
  as_triangles.convex_vegetation_volumes = false;
  auto triangles = EmbreeScene::build(random_world.world, as_triangles);
  ASSERT_TRUE(triangles.ok());
  EXPECT_EQ((*triangles)->stats().convex_vegetation_objects, 0U);
  // Each opaque object alone, to check that a line-of-sight blocker really is on the ray.
  std::map<std::string, BruteForceScene> alone;
  for (const auto& object : random_world.world.objects) {
    if (object.material.is_vegetation()) continue;
    WorldModel single;
    single.objects.push_back(object);
    auto scene = BruteForceScene::build(single);
    ASSERT_TRUE(scene.ok());
    alone.emplace(object.name, std::move(*scene));
  }
  int other_blocker = 0;
  RandomStream random(stream_key(20240611, {2}));
  int rays = 0, excluded = 0, blocked = 0, with_vegetation = 0;
  double worst_distance_m = 0.0, worst_vegetation_m = 0.0;
  for (int batch = 0; batch < 250; ++batch) {
    const Eigen::Vector3d origin = uniform_vector(random, 60.0);
    std::vector<Eigen::Vector3d> directions;
    for (int i = 0; i < 48; ++i) directions.push_back(unit_vector(random));
    const auto fast = scenes.embree->trace(origin, directions);
    const auto reference = scenes.brute->trace(origin, directions);
    const auto general = (*triangles)->trace(origin, directions);
    const auto line_of_sight = scenes.embree->trace_line_of_sight(origin, directions);
    for (std::size_t i = 0; i < directions.size(); ++i) {
      ++rays;
      if (grazes_an_edge(random_world, origin, directions[i], 1e-6)) {
        ++excluded;
        continue;
      }
      SCOPED_TRACE(::testing::Message() << "origin " << origin.transpose() << " direction "
                                        << directions[i].transpose());
      ASSERT_EQ(fast[i].blocked, reference[i].blocked);
      ASSERT_EQ(general[i].blocked, reference[i].blocked);
      ASSERT_EQ(line_of_sight[i].blocked, reference[i].blocked);
      EXPECT_NEAR(general[i].vegetation_path_m, reference[i].vegetation_path_m, 1e-4);
      EXPECT_EQ(general[i].blocking_object, reference[i].blocking_object);
      if (line_of_sight[i].blocked) {
        // Any opaque object on the ray; no vegetation reported behind it.
        const auto it = alone.find(std::string(line_of_sight[i].blocking_object));
        ASSERT_NE(it, alone.end()) << line_of_sight[i].blocking_object;
        EXPECT_TRUE(it->second.trace(origin, {directions[i]}).front().blocked) << line_of_sight[i].blocking_object;
        EXPECT_EQ(line_of_sight[i].vegetation_path_m, 0.0);
        other_blocker += line_of_sight[i].blocking_object != reference[i].blocking_object ? 1 : 0;
      } else {
        EXPECT_NEAR(line_of_sight[i].vegetation_path_m, reference[i].vegetation_path_m, 1e-4);
        EXPECT_NEAR(line_of_sight[i].vegetation_attenuation_db, 2.0 * reference[i].vegetation_path_m, 2e-4);
      }
      if (fast[i].blocked) {
        ++blocked;
        EXPECT_EQ(fast[i].blocking_object, reference[i].blocking_object);
        EXPECT_EQ(fast[i].blocking_material, reference[i].blocking_material);
        EXPECT_NEAR(fast[i].blocking_distance_m, reference[i].blocking_distance_m, 1e-4);
        EXPECT_GT(fast[i].blocking_normal.dot(reference[i].blocking_normal), 1 - 1e-9);
        EXPECT_LE(fast[i].blocking_normal.dot(directions[i]), 0.0);  // turned towards the origin
        worst_distance_m =
            std::max(worst_distance_m, std::abs(fast[i].blocking_distance_m - reference[i].blocking_distance_m));
      }
      if (reference[i].vegetation_path_m > 0) ++with_vegetation;
      EXPECT_NEAR(fast[i].vegetation_path_m, reference[i].vegetation_path_m, 1e-4);
      EXPECT_NEAR(fast[i].vegetation_attenuation_db, 2.0 * reference[i].vegetation_path_m, 2e-4);
      worst_vegetation_m =
          std::max(worst_vegetation_m, std::abs(fast[i].vegetation_path_m - reference[i].vegetation_path_m));
    }
  }
  EXPECT_GE(rays - excluded, 10000);
  EXPECT_LT(excluded, rays / 100);
  // The worlds must exercise both answers and vegetation.
  EXPECT_GT(blocked, rays / 5);
  EXPECT_LT(blocked, rays * 4 / 5);
  EXPECT_GT(with_vegetation, rays / 20);
  EXPECT_GT(other_blocker, 0);  // the test sees rays whose first-found blocker is not the nearest
  RecordProperty("rays", rays);
  RecordProperty("excluded_grazing", excluded);
  std::cout << "random rays: " << rays << " compared, " << excluded << " grazing excluded, " << blocked
            << " blocked, " << with_vegetation << " through vegetation; worst distance difference "
            << worst_distance_m << " m, worst vegetation path difference " << worst_vegetation_m << " m\n";
}

TEST(WorldScene, LineOfSightIsAnOcclusionTest) {
  // Without vegetation the line-of-sight query blocks the same rays as the reference, names the
  // blocker and its material, and fills no geometry.
  RandomWorld random_world = make_random_world(99);
  std::erase_if(random_world.world.objects, [](const WorldObject& o) { return o.material.is_vegetation(); });
  auto quick = EmbreeScene::build(random_world.world);
  auto brute = BruteForceScene::build(random_world.world);
  ASSERT_TRUE(quick.ok() && brute.ok());
  RandomStream random(stream_key(99, {2}));
  int blocked = 0;
  for (int batch = 0; batch < 40; ++batch) {
    const Eigen::Vector3d origin = uniform_vector(random, 60.0);
    std::vector<Eigen::Vector3d> directions;
    for (int i = 0; i < 50; ++i) directions.push_back(unit_vector(random));
    const auto fast = (*quick)->trace_line_of_sight(origin, directions);
    const auto reference = brute->trace(origin, directions);
    for (std::size_t i = 0; i < directions.size(); ++i) {
      if (grazes_an_edge(random_world, origin, directions[i], 1e-6)) continue;
      EXPECT_EQ(fast[i].blocked, reference[i].blocked);
      if (fast[i].blocked) {
        const auto object = std::find_if(random_world.world.objects.begin(), random_world.world.objects.end(),
                                         [&](const WorldObject& o) { return o.name == fast[i].blocking_object; });
        ASSERT_NE(object, random_world.world.objects.end()) << fast[i].blocking_object;
        EXPECT_EQ(fast[i].blocking_material, object->material.material_class);
        EXPECT_EQ(fast[i].blocking_distance_m, 0.0);
      }
      blocked += fast[i].blocked ? 1 : 0;
    }
  }
  EXPECT_GT(blocked, 200);
}

// One direction from many origins (the lit tests of scattering patches): each outcome is what
// trace_line_of_sight gives from that origin alone, vegetation and blocker included, in Embree's
// batch (vegetation as convex volumes and as triangles) and in the interface's default (the
// brute-force scene); invalid input as in a single query.
TEST(WorldScene, LineOfSightFromManyOriginsIsEachOriginAlone) {
  const RandomWorld random_world = make_random_world(4242);
  const Scenes scenes(random_world.world);
  ASSERT_TRUE(scenes.embree && scenes.brute);
  EmbreeSceneOptions as_triangles;  // vegetation traced as triangles: origins inside it counted too
  as_triangles.convex_vegetation_volumes = false;
  auto triangles = EmbreeScene::build(random_world.world, as_triangles);
  ASSERT_TRUE(triangles.ok());
  RandomStream random(stream_key(4242, {3}));
  int compared = 0, blocked = 0, with_vegetation = 0;
  for (int batch = 0; batch < 60; ++batch) {
    const Eigen::Vector3d direction = unit_vector(random);
    std::vector<Eigen::Vector3d> origins;
    for (int i = 0; i < 40; ++i) origins.push_back(uniform_vector(random, 60.0));
    if (batch == 0) origins.push_back(Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
    for (const PathQuery* scene : {static_cast<const PathQuery*>(scenes.embree.get()), static_cast<const PathQuery*>(triangles->get()),
                                   static_cast<const PathQuery*>(&*scenes.brute)}) {
      const auto batched = scene->trace_line_of_sight_from(origins, direction);
      ASSERT_EQ(batched.size(), origins.size());
      for (std::size_t i = 0; i < origins.size(); ++i) {
        const RayOutcome alone = scene->trace_line_of_sight(origins[i], {direction}).front();
        EXPECT_EQ(batched[i].blocked, alone.blocked);
        EXPECT_EQ(batched[i].blocking_object, alone.blocking_object);
        EXPECT_EQ(batched[i].blocking_material, alone.blocking_material);
        EXPECT_EQ(batched[i].vegetation_path_m, alone.vegetation_path_m);
        EXPECT_EQ(batched[i].vegetation_attenuation_db, alone.vegetation_attenuation_db);
        ++compared;
        blocked += alone.blocked ? 1 : 0;
        with_vegetation += alone.vegetation_path_m > 0.0 ? 1 : 0;
      }
    }
  }
  // Both answers and vegetation are met; an invalid direction blocks every ray.
  EXPECT_GT(blocked, compared / 10);
  EXPECT_LT(blocked, compared * 9 / 10);
  EXPECT_GT(with_vegetation, compared / 50);
  const auto invalid = scenes.embree->trace_line_of_sight_from({Eigen::Vector3d::Zero()}, Eigen::Vector3d::Zero());
  ASSERT_EQ(invalid.size(), 1U);
  EXPECT_TRUE(invalid[0].blocked);
  const RayOutcome invalid_alone = scenes.embree->trace_line_of_sight(Eigen::Vector3d::Zero(), {Eigen::Vector3d::Zero()}).front();
  EXPECT_EQ(invalid[0].blocking_object, invalid_alone.blocking_object);
}

TEST(WorldScene, MovingAnObjectUnblocksAndBlocksAgain) {
  WorldModel world;
  world.objects.push_back(box("truck", {-2, 8, 0}, {2, 12, 4}, Material{MaterialClass::kMetal, 0.0}));
  world.objects.back().is_static = false;
  world.objects.push_back(box("hedge", {-2, -12, 0}, {2, -8, 4}, vegetation(1.0)));
  world.objects.back().is_static = false;
  world.objects.push_back(box("house", {50, 50, 0}, {60, 60, 10}));
  auto embree = EmbreeScene::build(world);
  auto brute = BruteForceScene::build(world);
  ASSERT_TRUE(embree.ok() && brute.ok());
  const Eigen::Vector3d origin{0, 0, 1};
  const std::vector<Eigen::Vector3d> directions = {enu_direction(0, 0), enu_direction(180, 0)};
  auto check = [&](bool truck_blocks, double hedge_m) {
    for (const PathQuery* query : {static_cast<const PathQuery*>(embree->get()), static_cast<const PathQuery*>(&*brute)}) {
      const auto out = query->trace(origin, directions);
      EXPECT_EQ(out[0].blocked, truck_blocks);
      if (truck_blocks) {
        EXPECT_NEAR(out[0].blocking_distance_m, 8.0, 1e-4);
        EXPECT_EQ(out[0].blocking_object, "truck");
      }
      EXPECT_NEAR(out[1].vegetation_path_m, hedge_m, 1e-4);
    }
  };
  auto move = [&](const std::string& name, const Eigen::Isometry3d& pose) {
    ASSERT_TRUE((*embree)->set_object_pose(name, pose).ok());
    ASSERT_TRUE(brute->set_object_pose(name, pose).ok());
  };
  check(true, 4.0);
  move("truck", Eigen::Isometry3d(Eigen::Translation3d(30, 0, 0)));
  move("hedge", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 20)));
  check(false, 0.0);
  move("truck", Eigen::Isometry3d::Identity());
  // Turned by 90 deg about its own centre line: still 4 m thick along the ray.
  move("hedge", Eigen::Isometry3d(Eigen::Translation3d(0, -10, 0) * Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()) *
                                  Eigen::Translation3d(0, 10, 0)));
  check(true, 4.0);
  // Moved the truck back by 3 m north: the front face is now 11 m away.
  move("truck", Eigen::Isometry3d(Eigen::Translation3d(0, 3, 0)));
  EXPECT_NEAR((*embree)->trace(origin, directions)[0].blocking_distance_m, 11.0, 1e-4);

  const auto unknown = (*embree)->set_object_pose("bus", Eigen::Isometry3d::Identity());
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::kNotFound);
  EXPECT_NE(unknown.error().message.find("bus"), std::string::npos);
  const auto fixed = (*embree)->set_object_pose("house", Eigen::Isometry3d::Identity());
  ASSERT_FALSE(fixed.ok());
  EXPECT_NE(fixed.error().message.find("static"), std::string::npos);
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE((*embree)->set_object_pose("truck", bad).ok());
}

TEST(WorldScene, SkyMaskOfAWallIsItsElevationAngle) {
  // A long wall 10 m high whose face is 20 m north of the antenna (at ground level): at azimuth
  // az the face is 20 / cos(az) away, so the mask is atan(10 cos(az) / 20).
  WorldModel world;
  world.objects.push_back(box("wall", {-500, 20, 0}, {500, 21, 10}));
  const Scenes scenes(world);
  for (std::size_t s = 0; s < 2; ++s) {
    SCOPED_TRACE(label(s));
    const auto mask = sky_mask_elevation_deg(*scenes.both()[s], {0, 0, 0}, 5.0);
    ASSERT_TRUE(mask.ok()) << mask.error().message;
    ASSERT_EQ(mask->size(), 72U);
    for (std::size_t i = 0; i < mask->size(); ++i) {
      const double azimuth_deg = 5.0 * static_cast<double>(i);
      const double cos_az = std::cos(azimuth_deg * kDegToRad);
      const double expected_deg = cos_az > 0.0 ? std::atan(10.0 * cos_az / 20.0) / kDegToRad : 0.0;
      EXPECT_NEAR((*mask)[i], expected_deg, 0.1) << "azimuth " << azimuth_deg;
    }
    EXPECT_NEAR((*mask)[0], std::atan(0.5) / kDegToRad, 0.01);
  }
  // Under a roof: blocked up to the zenith. Bad input: errors.
  WorldModel roofed;
  roofed.objects.push_back(box("roof", {-5, -5, 3}, {5, 5, 3.2}));
  auto roof = EmbreeScene::build(roofed);
  ASSERT_TRUE(roof.ok());
  const auto covered = sky_mask_elevation_deg(**roof, {0, 0, 0}, 90.0);
  ASSERT_TRUE(covered.ok());
  EXPECT_EQ(*covered, std::vector<double>(4, 90.0));
  EXPECT_FALSE(sky_mask_elevation_deg(**roof, {0, 0, 0}, 0.0).ok());
  EXPECT_FALSE(sky_mask_elevation_deg(**roof, {std::nan(""), 0, 0}, 10.0).ok());
}

TEST(WorldScene, DegenerateInput) {
  const std::vector<Eigen::Vector3d> directions = {enu_direction(0, 10), enu_direction(90, 45)};
  // An empty world answers free.
  const Scenes empty{WorldModel{}};
  for (const PathQuery* query : empty.both()) {
    for (const auto& o : query->trace({0, 0, 0}, directions)) {
      EXPECT_FALSE(o.blocked);
      EXPECT_EQ(o.vegetation_path_m, 0.0);
    }
  }
  // Zero-area triangles (repeated and collinear vertices) are skipped; the valid one still blocks.
  WorldModel world;
  WorldObject sheet;
  sheet.name = "sheet";
  sheet.mesh.vertices_m = {{-5, 10, -5}, {5, 10, -5}, {0, 10, 5}, {1, 10, 1}, {2, 10, 2}, {3, 10, 3}};
  sheet.mesh.triangles = {{0, 1, 2}, {3, 3, 4}, {3, 4, 5}};
  world.objects.push_back(sheet);
  const Scenes scenes(world);
  ASSERT_TRUE(scenes.embree && scenes.brute);
  EXPECT_EQ(scenes.embree->stats().degenerate_triangles, 2U);
  EXPECT_EQ(scenes.brute->stats().degenerate_triangles, 2U);
  EXPECT_EQ(scenes.embree->stats().triangles, 1U);
  for (const PathQuery* query : scenes.both()) {
    const auto out = query->trace({0, 0, 0}, {Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 2, 0.2)});
    EXPECT_TRUE(out[0].blocked);
    EXPECT_NEAR(out[0].blocking_distance_m, 10.0, 1e-6);
    // Directions need not be unit: distances stay in metres.
    EXPECT_NEAR(out[1].blocking_distance_m, std::hypot(10.0, 1.0), 1e-6);
  }
  // Invalid rays: answered as blocked by "(invalid ray)" (never open sky), or an error through
  // trace_checked that names the ray; never a crash.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const PathQuery* query : scenes.both()) {
    const auto out = query->trace({0, 0, 0}, {Eigen::Vector3d(nan, 1, 0), Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 1, 0)});
    ASSERT_EQ(out.size(), 3U);
    EXPECT_TRUE(out[0].blocked);
    EXPECT_EQ(out[0].blocking_object, kInvalidRayObject);
    EXPECT_EQ(out[1].blocking_object, kInvalidRayObject);
    EXPECT_EQ(out[2].blocking_object, "sheet");
    const auto bad_origin = query->trace({nan, 0, 0}, {Eigen::Vector3d(0, 1, 0)});
    EXPECT_EQ(bad_origin[0].blocking_object, kInvalidRayObject);
  }
  const auto checked = trace_checked(*scenes.embree, {0, 0, 0}, {Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(nan, 0, 0)});
  ASSERT_FALSE(checked.ok());
  EXPECT_NE(checked.error().message.find("direction 1"), std::string::npos) << checked.error().message;
  EXPECT_FALSE(trace_checked(*scenes.embree, {0, nan, 0}, {Eigen::Vector3d(0, 1, 0)}).ok());
  EXPECT_TRUE(trace_checked(*scenes.embree, {0, 0, 0}, {Eigen::Vector3d(0, 1, 0)}).ok());
  // Broken worlds: the error names the object and the element.
  WorldModel broken;
  broken.objects.push_back(sheet);
  broken.objects[0].mesh.triangles.emplace_back(0, 1, 9);
  const auto bad_index = EmbreeScene::build(broken);
  ASSERT_FALSE(bad_index.ok());
  EXPECT_NE(bad_index.error().message.find("'sheet': triangle 3 vertex index 9"), std::string::npos)
      << bad_index.error().message;
  broken.objects[0].mesh.triangles.pop_back();
  broken.objects[0].mesh.vertices_m[2].x() = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(BruteForceScene::build(broken).ok());
  WorldModel twins;
  twins.objects = {box("car", {0, 0, 0}, {1, 1, 1}), box("car", {5, 0, 0}, {6, 1, 1})};
  twins.objects[0].is_static = twins.objects[1].is_static = false;
  EXPECT_FALSE(EmbreeScene::build(twins).ok());
}

TEST(WorldScene, TwoThreadsTraceTheSameScene) {
  const RandomWorld random_world = make_random_world(7);
  auto scene = EmbreeScene::build(random_world.world);
  ASSERT_TRUE(scene.ok());
  RandomStream random(stream_key(7, {3}));
  std::vector<Eigen::Vector3d> directions;
  for (int i = 0; i < 400; ++i) directions.push_back(unit_vector(random));
  const Eigen::Vector3d origin{1, 2, 3};
  const auto expected = (*scene)->trace(origin, directions);
  std::vector<RayOutcome> first, second;
  std::thread a([&] { for (int k = 0; k < 20; ++k) first = (*scene)->trace(origin, directions); });
  std::thread b([&] { for (int k = 0; k < 20; ++k) second = (*scene)->trace(origin, directions); });
  a.join();
  b.join();
  for (std::size_t i = 0; i < directions.size(); ++i) {
    for (const auto* out : {&first, &second}) {
      EXPECT_EQ((*out)[i].blocked, expected[i].blocked);
      EXPECT_EQ((*out)[i].blocking_distance_m, expected[i].blocking_distance_m);
      EXPECT_EQ((*out)[i].vegetation_path_m, expected[i].vegetation_path_m);
    }
  }
}

}  // namespace
}  // namespace skytrace::world
