// World loaders: tessellation, polygon triangulation with holes, convex hull, SDF worlds written to
// temporary files (poses, frames, nesting, includes, materials, errors, spherical coordinates),
// mesh files (units and up axis) and small OpenStreetMap extracts. Expected numbers are computed
// by hand or with independent formulas (exact volumes, shoelace areas, core's ENU frames).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "skytrace/core/frames.hpp"
#include "skytrace/world/loaders.hpp"
#include "test_support.hpp"

namespace skytrace::world {
namespace {

constexpr double kPi = std::numbers::pi;

std::filesystem::path write_file(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

// Signed volume (divergence theorem): positive for a closed mesh wound counter-clockwise outward.
double signed_volume_m3(const TriangleMesh& mesh) {
  double six_volume = 0.0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices_m[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d b = mesh.vertices_m[static_cast<std::size_t>(t[1])].cast<double>();
    const Eigen::Vector3d c = mesh.vertices_m[static_cast<std::size_t>(t[2])].cast<double>();
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

// Closed and consistently oriented: every directed edge appears once and its reverse once.
// Vertices are compared by position (extrusions keep coincident bridge points apart).
bool is_closed_consistent(const TriangleMesh& mesh) {
  std::map<std::array<float, 3>, int> ids;
  const auto id = [&](int v) {
    const auto& p = mesh.vertices_m[static_cast<std::size_t>(v)];
    return ids.emplace(std::array<float, 3>{p.x(), p.y(), p.z()}, static_cast<int>(ids.size()))
        .first->second;
  };
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++edges[{id(t[k]), id(t[(k + 1) % 3])}];
  }
  for (const auto& [edge, count] : edges) {
    const auto reverse = edges.find({edge.second, edge.first});
    if (reverse == edges.end() || reverse->second != count) return false;
  }
  return !edges.empty();
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> object_bounds(const WorldObject& object) {
  WorldModel single;
  single.objects.push_back(object);
  return world_bounds(single);
}

const WorldObject* find_object(const WorldModel& world, const std::string& name) {
  for (const auto& object : world.objects) {
    if (object.name == name) return &object;
  }
  return nullptr;
}

bool has_warning(const WorldModel& world, const std::string& needle) {
  for (const auto& w : world.warnings) {
    if (w.find(needle) != std::string::npos) return true;
  }
  return false;
}

std::string all_warnings(const WorldModel& world) {
  std::string out;
  for (const auto& w : world.warnings) out += w + "\n";
  return out;
}

void expect_vector_near(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected,
                        double tolerance_m) {
  EXPECT_NEAR(actual.x(), expected.x(), tolerance_m);
  EXPECT_NEAR(actual.y(), expected.y(), tolerance_m);
  EXPECT_NEAR(actual.z(), expected.z(), tolerance_m);
}

// ---------------------------------------------------------------------------------------------
// Tessellation

TEST(WorldPrimitives, BoxIsClosedWithExactVolume) {
  const TriangleMesh box = make_box({2.0, 3.0, 4.0});
  EXPECT_EQ(box.triangles.size(), 12U);
  EXPECT_TRUE(is_closed_consistent(box));
  EXPECT_NEAR(signed_volume_m3(box), 24.0, 1e-9);
}

TEST(WorldPrimitives, CylinderVolumeIsThePrismOfItsPolygon) {
  const int n = 32;
  const TriangleMesh cylinder = make_cylinder(1.5, 4.0, n);
  EXPECT_TRUE(is_closed_consistent(cylinder));
  // Regular 32-gon inscribed in the circle: n/2 r^2 sin(2 pi / n), times the length.
  const double expected = 0.5 * n * 1.5 * 1.5 * std::sin(2.0 * kPi / n) * 4.0;
  EXPECT_NEAR(signed_volume_m3(cylinder), expected, 1e-5 * expected);
  const auto [low, high] = object_bounds(WorldObject{"c", ObjectKind::kOther, {}, cylinder});
  EXPECT_NEAR(low.z(), -2.0, 1e-6);
  EXPECT_NEAR(high.z(), 2.0, 1e-6);
  EXPECT_NEAR(high.x(), 1.5, 1e-6);
}

TEST(WorldPrimitives, EllipsoidAndCapsuleAreClosedAndCloseToTheirVolume) {
  const TriangleMesh ellipsoid = make_ellipsoid({1.0, 2.0, 3.0}, 32, 16);
  EXPECT_TRUE(is_closed_consistent(ellipsoid));
  const double exact = 4.0 / 3.0 * kPi * 6.0;
  // Inscribed polytope: slightly smaller (about 2 % at 32 x 16).
  EXPECT_LT(signed_volume_m3(ellipsoid), exact);
  EXPECT_GT(signed_volume_m3(ellipsoid), 0.97 * exact);
  const auto [low, high] = object_bounds(WorldObject{"e", ObjectKind::kOther, {}, ellipsoid});
  expect_vector_near(high, {1.0, 2.0, 3.0}, 1e-5);
  expect_vector_near(low, {-1.0, -2.0, -3.0}, 1e-5);

  const TriangleMesh capsule = make_capsule(0.5, 2.0, 32, 16);
  EXPECT_TRUE(is_closed_consistent(capsule));
  const double capsule_exact = kPi * 0.25 * 2.0 + 4.0 / 3.0 * kPi * 0.125;
  EXPECT_LT(signed_volume_m3(capsule), capsule_exact);
  EXPECT_GT(signed_volume_m3(capsule), 0.97 * capsule_exact);
  const auto [capsule_low, capsule_high] =
      object_bounds(WorldObject{"k", ObjectKind::kOther, {}, capsule});
  EXPECT_NEAR(capsule_high.z(), 1.5, 1e-6);
  EXPECT_NEAR(capsule_low.z(), -1.5, 1e-6);
}

TEST(WorldPrimitives, PlaneFacesItsNormal) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.0, 1.0, 1.0).normalized();
  const TriangleMesh plane = make_plane(normal, {4.0, 2.0});
  ASSERT_EQ(plane.triangles.size(), 2U);
  double area = 0.0;
  for (const auto& t : plane.triangles) {
    const Eigen::Vector3d a = plane.vertices_m[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d b = plane.vertices_m[static_cast<std::size_t>(t[1])].cast<double>();
    const Eigen::Vector3d c = plane.vertices_m[static_cast<std::size_t>(t[2])].cast<double>();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    EXPECT_NEAR(n.normalized().dot(normal), 1.0, 1e-6);
    area += 0.5 * n.norm();
  }
  EXPECT_NEAR(area, 8.0, 1e-5);
  // Size x along the world x axis (which lies in this plane).
  EXPECT_NEAR(std::abs(plane.vertices_m[0].x()), 2.0, 1e-6);
}

TEST(WorldPrimitives, HeightGridRowZeroIsNorthAndFacesUp) {
  const auto grid = make_height_grid({0.0, 1.0, 2.0, 3.0, 4.0, 5.0}, 2, 3, 10.0, 4.0).value();
  ASSERT_EQ(grid.vertices_m.size(), 6U);
  expect_vector_near(grid.vertices_m[0].cast<double>(), {-5.0, 2.0, 0.0},
                     1e-6);  // row 0, column 0: north-west
  expect_vector_near(grid.vertices_m[5].cast<double>(), {5.0, -2.0, 5.0}, 1e-6);
  ASSERT_EQ(grid.triangles.size(), 4U);
  for (const auto& t : grid.triangles) {
    const Eigen::Vector3f n = (grid.vertices_m[static_cast<std::size_t>(t[1])] -
                               grid.vertices_m[static_cast<std::size_t>(t[0])])
                                  .cross(grid.vertices_m[static_cast<std::size_t>(t[2])] -
                                         grid.vertices_m[static_cast<std::size_t>(t[0])]);
    EXPECT_GT(n.z(), 0.0F);
  }
  EXPECT_FALSE(make_height_grid({1.0, 2.0}, 1, 2, 1.0, 1.0).ok());
}

// ---------------------------------------------------------------------------------------------
// Polygons

double triangles_area(const PolygonWithHoles& polygon,
                      const std::vector<std::array<int, 3>>& triangles, bool& all_ccw) {
  std::vector<Eigen::Vector2d> points = polygon.outer;
  for (const auto& hole : polygon.holes) points.insert(points.end(), hole.begin(), hole.end());
  double area = 0.0;
  all_ccw = true;
  for (const auto& t : triangles) {
    const double a = signed_area_m2({points[static_cast<std::size_t>(t[0])],
                                     points[static_cast<std::size_t>(t[1])],
                                     points[static_cast<std::size_t>(t[2])]});
    if (a <= 0.0) all_ccw = false;
    area += a;
  }
  return area;
}

bool inside_ring(const Ring2& ring, const Eigen::Vector2d& p) {
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    if ((ring[i].y() > p.y()) != (ring[j].y() > p.y()) &&
        p.x() < (ring[j].x() - ring[i].x()) * (p.y() - ring[i].y()) / (ring[j].y() - ring[i].y()) +
                    ring[i].x()) {
      in = !in;
    }
  }
  return in;
}

// Area of the triangles = area of the outer ring - area of the holes, every triangle
// counter-clockwise, and every triangle's centroid inside the polygon (not in a hole).
void expect_valid_triangulation(const PolygonWithHoles& polygon) {
  const auto triangles = triangulate_polygon(polygon);
  ASSERT_TRUE(triangles.ok()) << triangles.error().message;
  double expected = std::abs(signed_area_m2(polygon.outer));
  for (const auto& hole : polygon.holes) expected -= std::abs(signed_area_m2(hole));
  bool all_ccw = false;
  EXPECT_NEAR(triangles_area(polygon, *triangles, all_ccw), expected,
              1e-9 * std::max(1.0, expected));
  EXPECT_TRUE(all_ccw);
  std::vector<Eigen::Vector2d> points = polygon.outer;
  for (const auto& hole : polygon.holes) points.insert(points.end(), hole.begin(), hole.end());
  for (const auto& t : *triangles) {
    const Eigen::Vector2d centroid =
        (points[static_cast<std::size_t>(t[0])] + points[static_cast<std::size_t>(t[1])] +
         points[static_cast<std::size_t>(t[2])]) /
        3.0;
    EXPECT_TRUE(inside_ring(polygon.outer, centroid));
    for (const auto& hole : polygon.holes) EXPECT_FALSE(inside_ring(hole, centroid));
  }
}

TEST(WorldPolygons, SquareWithHoleAreaIsOuterMinusHole) {
  PolygonWithHoles polygon;
  polygon.outer = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  polygon.holes = {
      {{2, 2}, {6, 2}, {6, 6}, {2, 6}}};  // counter-clockwise too: orientation is fixed inside
  const auto triangles = triangulate_polygon(polygon).value();
  bool all_ccw = false;
  EXPECT_NEAR(triangles_area(polygon, triangles, all_ccw), 100.0 - 16.0, 1e-9);
  EXPECT_TRUE(all_ccw);
  // n + h + 2 vertices after bridging: (4 + 4 + 2) - 2 triangles.
  EXPECT_EQ(triangles.size(), 8U);
  expect_valid_triangulation(polygon);
}

TEST(WorldPolygons, ConcaveClockwiseRingsWithTwoHolesAndClosingPoints) {
  PolygonWithHoles polygon;
  // An L shape, clockwise, with its closing point repeated.
  polygon.outer = {{0, 0}, {0, 20}, {8, 20}, {8, 8}, {20, 8}, {20, 0}, {0, 0}};
  polygon.holes = {{{2, 2}, {2, 5}, {5, 5}, {5, 2}, {2, 2}},  // square, clockwise
                   {{12, 2}, {17, 2}, {17, 6}, {12, 6}},      // rectangle, counter-clockwise
                   {{3, 10}, {6, 10}, {4.5, 17}}};            // triangle in the vertical arm
  expect_valid_triangulation(polygon);
}

TEST(WorldPolygons, HolesSharingTheBridgeLineAndCollinearPoints) {
  PolygonWithHoles polygon;
  // Two holes on the same horizontal line as an outer vertex, collinear points on the outer ring.
  polygon.outer = {{0, 0}, {5, 0}, {10, 0}, {10, 5}, {10, 10}, {0, 10}};
  polygon.holes = {{{1, 4}, {3, 4}, {3, 5}, {1, 5}}, {{5, 4}, {7, 4}, {7, 5}, {5, 5}}};
  expect_valid_triangulation(polygon);
}

TEST(WorldPolygons, RandomStarPolygonsWithHoles) {
  std::mt19937 random(42);
  std::uniform_real_distribution<double> radius(4.0, 10.0);
  for (int trial = 0; trial < 200; ++trial) {
    PolygonWithHoles polygon;
    const int n = 5 + trial % 40;
    for (int i = 0; i < n; ++i) {
      const double angle = 2.0 * kPi * i / n;
      const double r = radius(random);
      polygon.outer.emplace_back(r * std::cos(angle), r * std::sin(angle));
    }
    // Holes well inside the inner radius 4: a small square and a small triangle.
    const double offset = 0.5 * (trial % 3);
    polygon.holes.push_back(
        {{-2.0 + offset, -1.0}, {-1.0 + offset, -1.0}, {-1.0 + offset, 0.0}, {-2.0 + offset, 0.0}});
    if (trial % 2 == 0) polygon.holes.push_back({{1.0, 1.0}, {2.5, 1.2}, {1.5, 2.5}});
    SCOPED_TRACE("trial " + std::to_string(trial));
    expect_valid_triangulation(polygon);
  }
}

// Many holes on a grid and an outer ring on a half-metre grid: bridges meet at shared x and y
// values, the ties that break naive hole bridging. The outer ring (radius >= 10 m, at least 8
// vertices, angles increasing) stays simple and contains every hole (within 8.5 m of the centre).
TEST(WorldPolygons, GridAlignedHolesWithTies) {
  std::mt19937 random(1);
  std::uniform_real_distribution<double> radius(10.0, 14.0);
  std::bernoulli_distribution take(0.3);
  for (int trial = 0; trial < 400; ++trial) {
    PolygonWithHoles polygon;
    const int n = 8 + trial % 50;
    for (int i = 0; i < n; ++i) {
      const double angle = 2.0 * kPi * i / n;
      const double r = radius(random);
      polygon.outer.emplace_back(std::round(2.0 * r * std::cos(angle)) / 2.0,
                                 std::round(2.0 * r * std::sin(angle)) / 2.0);
    }
    for (int gx = -3; gx <= 2; ++gx) {
      for (int gy = -3; gy <= 2; ++gy) {
        if (!take(random)) continue;
        const double x = 2.0 * gx;
        const double y = 2.0 * gy;
        if (trial % 2 == 1) {
          polygon.holes.push_back({{x, y}, {x + 1, y}, {x + 1, y + 1}, {x, y + 1}});
        } else {
          polygon.holes.push_back({{x, y}, {x + 1, y + 0.5}, {x, y + 1}});
        }
      }
    }
    SCOPED_TRACE("trial " + std::to_string(trial) + ", " + std::to_string(polygon.holes.size()) +
                 " holes");
    expect_valid_triangulation(polygon);
  }
}

TEST(WorldPolygons, InvalidPolygonsAreErrors) {
  EXPECT_FALSE(triangulate_polygon(PolygonWithHoles{{{0, 0}, {1, 1}}, {}}).ok());
  EXPECT_FALSE(
      triangulate_polygon(PolygonWithHoles{{{0, 0}, {1, 1}, {2, 2}}, {}}).ok());  // no area
  PolygonWithHoles outside;
  outside.outer = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  outside.holes = {{{5, 5}, {6, 5}, {6, 6}}};
  const auto result = triangulate_polygon(outside);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("hole"), std::string::npos);
}

TEST(WorldPolygons, ExtrusionIsAClosedPrism) {
  PolygonWithHoles polygon;
  polygon.outer = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  polygon.holes = {{{2, 2}, {6, 2}, {6, 6}, {2, 6}}};
  const auto prism = extrude_polygon(polygon, 1.0, 4.0).value();
  EXPECT_TRUE(is_closed_consistent(prism));
  EXPECT_NEAR(signed_volume_m3(prism), 84.0 * 3.0, 1e-6);
  EXPECT_FALSE(extrude_polygon(polygon, 4.0, 4.0).ok());
}

// ---------------------------------------------------------------------------------------------
// Convex hull

TEST(WorldHull, CubeWithInteriorPointsGivesTheCube) {
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 8; ++i)
    points.emplace_back((i & 1) != 0 ? 2.0F : 0.0F, (i & 2) != 0 ? 3.0F : 0.0F,
                        (i & 4) != 0 ? 4.0F : 0.0F);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> u(0.1F, 1.9F);
  for (int i = 0; i < 200; ++i) points.emplace_back(u(random), 1.5F * u(random), 2.0F * u(random));
  const auto hull = convex_hull(points).value();
  EXPECT_TRUE(is_closed_consistent(hull));
  EXPECT_NEAR(signed_volume_m3(hull), 24.0, 1e-5);
  EXPECT_EQ(hull.vertices_m.size(), 8U);
}

TEST(WorldHull, EveryPointIsInsideTheHullOfASphereCloud) {
  std::mt19937 random(3);
  std::normal_distribution<float> g(0.0F, 1.0F);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 500; ++i) {
    Eigen::Vector3f p(g(random), g(random), g(random));
    points.push_back(p.normalized() * (i % 3 == 0 ? 0.5F : 2.0F));
  }
  const auto hull = convex_hull(points).value();
  EXPECT_TRUE(is_closed_consistent(hull));
  for (const auto& t : hull.triangles) {
    const Eigen::Vector3d a = hull.vertices_m[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d n =
        (hull.vertices_m[static_cast<std::size_t>(t[1])].cast<double>() - a)
            .cross(hull.vertices_m[static_cast<std::size_t>(t[2])].cast<double>() - a)
            .normalized();
    for (const auto& p : points) EXPECT_LE(n.dot(p.cast<double>() - a), 1e-5);
  }
  // Close to the 2 m sphere's volume, below it.
  const double sphere = 4.0 / 3.0 * kPi * 8.0;
  EXPECT_LT(signed_volume_m3(hull), sphere);
  EXPECT_GT(signed_volume_m3(hull), 0.9 * sphere);
}

TEST(WorldHull, SimplifiedHullStaysWithinTheTolerance) {
  // A 2 m sphere of 300 points: its hull has hundreds of faces; within 5 cm far fewer are needed.
  std::mt19937 random(11);
  std::normal_distribution<float> g(0.0F, 1.0F);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 300; ++i) points.push_back(Eigen::Vector3f(g(random), g(random), g(random)).normalized() * 2.0F);
  const auto hull = convex_hull(points).value();
  constexpr double kToleranceM = 0.05;
  const TriangleMesh simple = simplify_convex_hull(hull, kToleranceM);
  EXPECT_TRUE(is_closed_consistent(simple));
  EXPECT_LT(simple.triangles.size(), hull.triangles.size() / 2);
  // Every vertex of the original within the tolerance outside the simplified hull, and the
  // simplified one inside the original (its vertices are a subset).
  double worst_outside_m = 0.0;
  for (const auto& t : simple.triangles) {
    const Eigen::Vector3d a = simple.vertices_m[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d n = (simple.vertices_m[static_cast<std::size_t>(t[1])].cast<double>() - a)
                                  .cross(simple.vertices_m[static_cast<std::size_t>(t[2])].cast<double>() - a)
                                  .normalized();
    for (const auto& p : hull.vertices_m) worst_outside_m = std::max(worst_outside_m, n.dot(p.cast<double>() - a));
  }
  EXPECT_LE(worst_outside_m, kToleranceM + 1e-6);
  EXPECT_GT(worst_outside_m, 0.5 * kToleranceM);  // it did use the tolerance
  EXPECT_LT(signed_volume_m3(simple), signed_volume_m3(hull));
  EXPECT_GT(signed_volume_m3(simple), 0.95 * signed_volume_m3(hull));
  // No tolerance, or a box (every corner matters): unchanged.
  EXPECT_EQ(simplify_convex_hull(hull, 0.0).triangles.size(), hull.triangles.size());
  std::vector<Eigen::Vector3f> corners;
  for (int i = 0; i < 8; ++i) corners.emplace_back((i & 1) != 0 ? 2.0F : 0.0F, (i & 2) != 0 ? 3.0F : 0.0F, (i & 4) != 0 ? 4.0F : 0.0F);
  EXPECT_EQ(simplify_convex_hull(convex_hull(corners).value(), kToleranceM).vertices_m.size(), 8U);
}

TEST(WorldHull, FlatPointsAreAnError) {
  EXPECT_FALSE(convex_hull({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5F, 0.5F, 0}}).ok());
  EXPECT_FALSE(convex_hull({{0, 0, 0}, {1, 0, 0}}).ok());
}

// ---------------------------------------------------------------------------------------------
// Materials and names

TEST(WorldMaterials, GlobAndDefaults) {
  EXPECT_TRUE(glob_match("*tree*", "model://Pine_Tree"));
  EXPECT_TRUE(glob_match("house_?", "HOUSE_3"));
  EXPECT_FALSE(glob_match("house_?", "house_12"));
  EXPECT_TRUE(glob_match("*", ""));
  EXPECT_TRUE(glob_match("a*b*c", "a/xx/b/yy/c"));
  EXPECT_FALSE(glob_match("a*b*c", "a/xx/b/yy/d"));

  EXPECT_TRUE(name_suggests_vegetation("pine_tree_12"));
  EXPECT_TRUE(name_suggests_vegetation("model://oak_tree"));
  EXPECT_TRUE(name_suggests_vegetation("BigOakTree"));
  EXPECT_TRUE(name_suggests_vegetation("hedges"));
  EXPECT_FALSE(name_suggests_vegetation("street_lamp"));
  EXPECT_FALSE(name_suggests_vegetation("house_1"));
  EXPECT_TRUE(name_suggests_building("House 1"));
  EXPECT_TRUE(name_suggests_building("model://fire_station"));
  EXPECT_TRUE(name_suggests_building("warehouse_3"));
  EXPECT_FALSE(name_suggests_building("small_box"));
  EXPECT_FALSE(name_suggests_building("asphalt_plane"));

  EXPECT_EQ(parse_material_class("Glass").value(), MaterialClass::kGlass);
  EXPECT_EQ(parse_material_class("stone").value(), MaterialClass::kConcrete);
  EXPECT_FALSE(parse_material_class("cheese").ok());
  for (const auto c : {MaterialClass::kConcrete, MaterialClass::kBrick, MaterialClass::kGlass,
                       MaterialClass::kMetal, MaterialClass::kWood, MaterialClass::kGround,
                       MaterialClass::kVegetation}) {
    EXPECT_EQ(parse_material_class(material_class_name(c)).value(), c);
  }
  const std::vector<MaterialRule> rules = {
      {"*glass*", {MaterialClass::kGlass, 0.0}, std::nullopt},
      {"*tree*", {MaterialClass::kVegetation, 1.0}, ObjectKind::kTree}};
  EXPECT_EQ(match_material_rule(rules, {"a/b/c", "model://pine_tree"}), &rules[1]);
  EXPECT_EQ(match_material_rule(rules, {"a/b/c"}), nullptr);

  EXPECT_EQ(entity_name("city/house_1/link/collision"), "city/house_1");
  EXPECT_EQ(entity_name("house_1/link/collision"), "house_1");
  EXPECT_EQ(entity_name("way/12"), "way/12");
}

TEST(WorldMaterials, OsmLengths) {
  EXPECT_DOUBLE_EQ(parse_osm_length_m("12").value(), 12.0);
  EXPECT_DOUBLE_EQ(parse_osm_length_m("12 m").value(), 12.0);
  EXPECT_DOUBLE_EQ(parse_osm_length_m(" 12.5m").value(), 12.5);
  EXPECT_DOUBLE_EQ(parse_osm_length_m("7,5").value(), 7.5);
  EXPECT_NEAR(parse_osm_length_m("40 ft").value(), 12.192, 1e-12);
  EXPECT_NEAR(parse_osm_length_m("12'6\"").value(), 12 * 0.3048 + 6 * 0.0254, 1e-12);
  EXPECT_FALSE(parse_osm_length_m("tall").ok());
  EXPECT_FALSE(parse_osm_length_m("-3").ok());
  EXPECT_FALSE(parse_osm_length_m("12 km").ok());
}

// ---------------------------------------------------------------------------------------------
// SDF

SdfLoadOptions isolated_options(const std::filesystem::path& models = {}) {
  SdfLoadOptions options;
  options.use_environment_paths = false;
  if (!models.empty()) options.model_paths.push_back(models);
  return options;
}

std::string world_sdf(const std::string& body, const std::string& version = "1.9") {
  return "<?xml version=\"1.0\"?>\n<sdf version=\"" + version +
         "\" xmlns:skytrace=\"https://skytrace.dev/sdf\">\n<world name=\"test_world\">\n" + body +
         "\n</world>\n</sdf>\n";
}

std::string static_model(const std::string& name, const std::string& pose,
                         const std::string& geometry, const std::string& extra = "") {
  return "<model name=\"" + name + "\"><static>true</static><pose>" + pose + "</pose>" + extra +
         "<link name=\"link\"><collision name=\"collision\"><geometry>" + geometry +
         "</geometry></collision></link></model>\n";
}

TEST(WorldSdf, PrimitivesArePlacedByTheirPoses) {
  const auto dir = test::make_temp_dir("world_sdf_primitives");
  const std::string half_pi = std::to_string(kPi / 2.0);
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf(
          static_model("box", "1 2 3 0 0 " + half_pi, "<box><size>2 4 6</size></box>") +
          static_model("cyl", "0 0 0 " + half_pi + " 0 0",
                       "<cylinder><radius>1</radius><length>4</length></cylinder>") +
          static_model("ball", "5 5 5 0 0 0", "<sphere><radius>0.5</radius></sphere>") +
          static_model("ground", "0 0 -1 0 0 0",
                       "<plane><normal>0 0 1</normal><size>10 20</size></plane>") +
          static_model("endless", "0 0 -2 0 0 0", "<plane><normal>0 0 1</normal></plane>") +
          // A collision pose inside the link, with a capsule and an ellipsoid.
          "<model name=\"posed\"><static>true</static><pose>10 0 0 0 0 0</pose><link name=\"l\">"
          "<pose>0 10 0 0 0 0</pose><collision name=\"c\"><pose>0 0 10 0 0 0</pose><geometry>"
          "<capsule><radius>1</radius><length>2</length></capsule></geometry></collision>"
          "<collision name=\"e\"><geometry><ellipsoid><radii>1 2 "
          "3</radii></ellipsoid></geometry></collision>"
          "</link></model>"));
  const auto world = load_sdf_world(path, isolated_options()).value();
  EXPECT_EQ(world.name, "test_world");
  ASSERT_EQ(world.objects.size(), 7U) << all_warnings(world);

  const WorldObject* box = find_object(world, "box/link/collision");
  ASSERT_NE(box, nullptr);
  // Yaw 90 degrees: the 2 m x side lies along y, the 4 m y side along x.
  auto [low, high] = object_bounds(*box);
  expect_vector_near(low, {1.0 - 2.0, 2.0 - 1.0, 0.0}, 1e-5);
  expect_vector_near(high, {1.0 + 2.0, 2.0 + 1.0, 6.0}, 1e-5);

  // Roll 90 degrees: the cylinder's axis (z) turns to -y.
  std::tie(low, high) = object_bounds(*find_object(world, "cyl/link/collision"));
  EXPECT_NEAR(low.y(), -2.0, 1e-5);
  EXPECT_NEAR(high.y(), 2.0, 1e-5);
  EXPECT_NEAR(high.z(), 1.0, 1e-5);

  std::tie(low, high) = object_bounds(*find_object(world, "ball/link/collision"));
  expect_vector_near(low, {4.5, 4.5, 4.5}, 1e-5);
  expect_vector_near(high, {5.5, 5.5, 5.5}, 1e-5);

  const WorldObject* ground = find_object(world, "ground/link/collision");
  ASSERT_NE(ground, nullptr);
  EXPECT_EQ(ground->kind, ObjectKind::kGround);
  EXPECT_EQ(ground->material.material_class, MaterialClass::kGround);
  std::tie(low, high) = object_bounds(*ground);
  expect_vector_near(low, {-5.0, -10.0, -1.0}, 1e-5);
  expect_vector_near(high, {5.0, 10.0, -1.0}, 1e-5);
  std::tie(low, high) = object_bounds(*find_object(world, "endless/link/collision"));
  EXPECT_NEAR(high.x(), 1000.0, 1e-3);  // no <size>: Gazebo's infinite plane, 2 km square

  // Model (10, 0, 0) + link (0, 10, 0) + collision (0, 0, 10); capsule half height 1 + 1.
  std::tie(low, high) = object_bounds(*find_object(world, "posed/l/c"));
  expect_vector_near(0.5 * (low + high), {10.0, 10.0, 10.0}, 1e-5);
  EXPECT_NEAR(high.z() - low.z(), 4.0, 1e-5);
  std::tie(low, high) = object_bounds(*find_object(world, "posed/l/e"));
  expect_vector_near(high, {11.0, 12.0, 3.0}, 1e-5);

  // The scene's object frame is the collision frame.
  const WorldObject* posed = find_object(world, "posed/l/c");
  expect_vector_near(posed->pose.translation(), {10.0, 10.0, 10.0}, 1e-9);
  EXPECT_TRUE(posed->is_static);
}

TEST(WorldSdf, NestedModelsAndFramesResolve) {
  const auto dir = test::make_temp_dir("world_sdf_nested");
  const std::string half_pi = "1.5707963267948966";
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf(
          "<frame name=\"plaza\"><pose>100 0 0 0 0 " + half_pi +
          "</pose></frame>\n"
          "<model name=\"outer\"><static>true</static><pose>10 0 0 0 0 " +
          half_pi +
          "</pose>"
          "<frame name=\"corner\"><pose>0 5 0 0 0 0</pose></frame>"
          "<link name=\"l\"><pose>1 0 0 0 0 0</pose><collision name=\"c\"><geometry><box><size>1 1 "
          "1</size></box>"
          "</geometry></collision></link>"
          "<model name=\"inner\"><pose relative_to=\"corner\">2 0 0 0 0 0</pose><link name=\"li\">"
          "<collision name=\"ci\"><geometry><box><size>1 1 "
          "1</size></box></geometry></collision></link></model>"
          "</model>\n"
          "<model name=\"at_plaza\"><static>true</static><pose relative_to=\"plaza\">3 0 0 0 0 "
          "0</pose>"
          "<link name=\"l\"><collision name=\"c\"><geometry><box><size>1 1 "
          "1</size></box></geometry></collision>"
          "</link></model>"));
  const auto world = load_sdf_world(path, isolated_options()).value();
  // outer at (10, 0) turned 90 degrees: its x is the world y.
  expect_vector_near(find_object(world, "outer/l/c")->pose.translation(), {10.0, 1.0, 0.0}, 1e-9);
  // inner: corner (0, 5) then 2 along x, in outer's frame: (2, 5) -> world (10 - 5, 2).
  const WorldObject* inner = find_object(world, "outer/inner/li/ci");
  ASSERT_NE(inner, nullptr) << all_warnings(world);
  expect_vector_near(inner->pose.translation(), {5.0, 2.0, 0.0}, 1e-9);
  EXPECT_TRUE(inner->is_static);  // inherits the static parent
  expect_vector_near(find_object(world, "at_plaza/l/c")->pose.translation(), {100.0, 3.0, 0.0},
                     1e-9);
  const auto summary = summarize_world(world);
  EXPECT_EQ(summary.objects, 3U);
  EXPECT_EQ(summary.other, 3U);  // outer, outer/inner, at_plaza: small boxes
}

TEST(WorldSdf, IncludesOverridesAndMissingModels) {
  const auto dir = test::make_temp_dir("world_sdf_includes");
  const auto models = dir / "models";
  write_file(models / "tower_block" / "model.config",
             "<?xml version=\"1.0\"?><model><name>tower_block</name><sdf "
             "version=\"1.6\">model.sdf</sdf></model>");
  write_file(
      models / "tower_block" / "model.sdf",
      "<?xml version=\"1.0\"?><sdf version=\"1.6\"><model name=\"tower_block\"><pose>50 50 0 0 0 "
      "0</pose>"
      "<link name=\"link\"><collision name=\"collision\"><pose>0 0 10 0 0 0</pose><geometry><box>"
      "<size>10 10 20</size></box></geometry></collision></link></model></sdf>");
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf("<frame name=\"plaza\"><pose>100 0 0 0 0 1.5707963267948966</pose></frame>\n"
                "<include><uri>model://tower_block</uri><name>a</name>"
                "<pose>5 0 0 0 0 0</pose><static>true</static></include>\n"
                "<include><uri>model://tower_block</uri><name>b</name></include>\n"
                "<include><uri>model://nowhere_to_be_found</uri></include>\n"
                "<include><uri>model://nowhere_to_be_found</uri><name>x2</name></include>\n"
                // A pose in another frame: this include is left to sdformat.
                "<include><uri>model://tower_block</uri><name>c</name>"
                "<pose relative_to=\"plaza\">1 0 0 0 0 0</pose></include>\n"
                // Gazebo classic restores poses saved in <state>.
                "<include><uri>model://tower_block</uri><name>d</name></include>\n"
                "<state world_name=\"test_world\"><model name=\"d\"><pose>-7 -7 0 0 0 0</pose>"
                "</model></state>"));
  const auto world = load_sdf_world(path, isolated_options(models)).value();
  ASSERT_EQ(world.objects.size(), 4U) << all_warnings(world);
  const WorldObject* a = find_object(world, "a/link/collision");
  ASSERT_NE(a, nullptr);
  // The include's pose replaces the model's own <pose>.
  expect_vector_near(a->pose.translation(), {5.0, 0.0, 10.0}, 1e-9);
  EXPECT_TRUE(a->is_static);
  EXPECT_EQ(a->kind, ObjectKind::kBuilding);  // "tower" in the URI
  const WorldObject* b = find_object(world, "b/link/collision");
  ASSERT_NE(b, nullptr);
  expect_vector_near(b->pose.translation(), {50.0, 50.0, 10.0}, 1e-9);
  EXPECT_FALSE(b->is_static);
  // plaza (100, 0) turned 90 degrees, then 1 m along its x: world (100, 1).
  expect_vector_near(find_object(world, "c/link/collision")->pose.translation(), {100.0, 1.0, 10.0},
                     1e-9);
  expect_vector_near(find_object(world, "d/link/collision")->pose.translation(), {-7.0, -7.0, 10.0},
                     1e-9);
  EXPECT_TRUE(has_warning(world, "model://nowhere_to_be_found not found, 2 includes skipped"))
      << all_warnings(world);
  EXPECT_TRUE(has_warning(world, "w.sdf:"));

  // Without the model path the included models are missing too, and the load still succeeds.
  const auto bare = load_sdf_world(path, isolated_options()).value();
  EXPECT_TRUE(bare.objects.empty());
  EXPECT_TRUE(has_warning(bare, "model://tower_block not found"));
}

TEST(WorldSdf, MaterialsFromElementsRulesAndDefaults) {
  const auto dir = test::make_temp_dir("world_sdf_materials");
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf(static_model("facade", "0 0 0 0 0 0", "<box><size>1 1 1</size></box>",
                             "<skytrace:material class=\"glass\"/>") +
                "<model name=\"hedge_row\"><static>true</static><link name=\"link\"><collision "
                "name=\"collision\">"
                "<skytrace:vegetation attenuation_db_per_m=\"1.2\"/><geometry><box><size>10 1 "
                "2</size></box></geometry>"
                "</collision></link></model>\n" +
                static_model("pine_tree_7", "20 0 0 0 0 0",
                             "<cylinder><radius>2</radius><length>8</length></cylinder>") +
                static_model("house_9", "30 0 0 0 0 0", "<box><size>2 2 2</size></box>") +
                static_model("block", "40 0 0 0 0 0", "<box><size>10 10 12</size></box>") +
                static_model("crate", "50 0 0 0 0 0", "<box><size>1 1 1</size></box>") +
                static_model("radio_mast", "60 0 0 0 0 0", "<box><size>1 1 30</size></box>") +
                static_model("odd", "70 0 0 0 0 0", "<box><size>1 1 1</size></box>",
                             "<skytrace:material class=\"metal\" kind=\"building\"/>") +
                static_model("typo", "80 0 0 0 0 0", "<box><size>1 1 1</size></box>",
                             "<skytrace:material class=\"glas\"/>")));
  auto options = isolated_options();
  options.material_rules.push_back({"*mast*", {MaterialClass::kMetal, 0.0}, std::nullopt});
  const auto world = load_sdf_world(path, options).value();

  const auto* facade = find_object(world, "facade/link/collision");
  EXPECT_EQ(facade->material.material_class, MaterialClass::kGlass);
  const auto* hedge = find_object(world, "hedge_row/link/collision");
  EXPECT_TRUE(hedge->material.is_vegetation());
  EXPECT_DOUBLE_EQ(hedge->material.attenuation_db_per_m, 1.2);
  EXPECT_EQ(hedge->kind, ObjectKind::kTree);
  const auto* pine = find_object(world, "pine_tree_7/link/collision");
  EXPECT_TRUE(pine->material.is_vegetation());
  EXPECT_DOUBLE_EQ(pine->material.attenuation_db_per_m, kDefaultVegetationAttenuationDbPerM);
  EXPECT_EQ(pine->kind, ObjectKind::kTree);
  EXPECT_EQ(find_object(world, "house_9/link/collision")->kind, ObjectKind::kBuilding);  // by name
  EXPECT_EQ(find_object(world, "block/link/collision")->kind,
            ObjectKind::kBuilding);  // tall, static, wide
  EXPECT_EQ(find_object(world, "block/link/collision")->material.material_class,
            MaterialClass::kConcrete);
  EXPECT_EQ(find_object(world, "crate/link/collision")->kind, ObjectKind::kOther);
  const auto* mast = find_object(world, "radio_mast/link/collision");
  EXPECT_EQ(mast->material.material_class, MaterialClass::kMetal);  // scenario rule
  EXPECT_EQ(mast->kind, ObjectKind::kOther);                        // tall but thin
  const auto* odd = find_object(world, "odd/link/collision");
  EXPECT_EQ(odd->material.material_class, MaterialClass::kMetal);
  EXPECT_EQ(odd->kind, ObjectKind::kBuilding);
  EXPECT_EQ(find_object(world, "typo/link/collision")->material.material_class,
            MaterialClass::kConcrete);
  EXPECT_TRUE(has_warning(world, "unknown material class 'glas'")) << all_warnings(world);

  // A scenario rule wins over the SDF's own element.
  options.material_rules.insert(options.material_rules.begin(),
                                {"facade*", {MaterialClass::kBrick, 0.0}, std::nullopt});
  const auto overridden = load_sdf_world(path, options).value();
  EXPECT_EQ(find_object(overridden, "facade/link/collision")->material.material_class,
            MaterialClass::kBrick);
}

TEST(WorldSdf, DuplicateNamesPolylinesAndVisuals) {
  const auto dir = test::make_temp_dir("world_sdf_duplicates");
  const std::string square =
      "<polyline><height>3</height><point>0 0</point><point>10 0</point><point>10 10</point>"
      "<point>0 10</point></polyline><polyline><height>3</height><point>2 2</point>"
      "<point>4 2</point><point>4 4</point><point>2 4</point></polyline>";
  const auto path =
      write_file(dir / "w.sdf",
                 world_sdf(static_model("dup", "0 0 0 0 0 0", "<box><size>1 1 1</size></box>") +
                               static_model("dup", "5 0 0 0 0 0", "<box><size>1 1 1</size></box>") +
                               static_model("dup", "9 0 0 0 0 0", "<box><size>1 1 1</size></box>") +
                               static_model("walls", "0 0 1 0 0 0", square) +
                               "<model name=\"deco\"><static>true</static><link name=\"l\"><visual "
                               "name=\"v\"><geometry><box>"
                               "<size>1 1 1</size></box></geometry></visual></link></model>",
                           "1.6"));
  const auto world = load_sdf_world(path, isolated_options()).value();
  ASSERT_NE(find_object(world, "dup_3/link/collision"), nullptr) << all_warnings(world);
  expect_vector_near(find_object(world, "dup_2/link/collision")->pose.translation(),
                     {5.0, 0.0, 0.0}, 1e-9);
  EXPECT_TRUE(has_warning(world, "3 models named 'dup'"));
  const auto* walls = find_object(world, "walls/link/collision");
  ASSERT_NE(walls, nullptr);
  EXPECT_TRUE(is_closed_consistent(walls->mesh));
  EXPECT_NEAR(signed_volume_m3(walls->mesh), (100.0 - 4.0) * 3.0, 1e-4);
  EXPECT_EQ(find_object(world, "deco/l/v"), nullptr);  // visual only: not loaded by default

  auto options = isolated_options();
  options.geometry = GeometrySource::kCollisionElseVisual;
  const auto with_visuals = load_sdf_world(path, options).value();
  EXPECT_NE(find_object(with_visuals, "deco/l/v"), nullptr);
  EXPECT_NE(find_object(with_visuals, "walls/link/collision"), nullptr);
}

TEST(WorldSdf, MalformedFilesAreErrorsNamingTheFile) {
  const auto dir = test::make_temp_dir("world_sdf_malformed");
  const auto broken =
      write_file(dir / "broken.sdf",
                 "<?xml version=\"1.0\"?>\n<sdf version=\"1.6\">\n<world name=\"w\">\n"
                 "<model name=\"a\"><link name=\"l\"></model>\n</world></sdf>\n");
  auto result = load_sdf_world(broken, isolated_options());
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kParse);
  EXPECT_NE(result.error().message.find("broken.sdf:4"), std::string::npos)
      << result.error().message;

  const auto bad_value = write_file(
      dir / "bad_value.sdf",
      world_sdf(static_model("a", "0 0 0 0 0 0", "<box><size>a b c</size></box>"), "1.6"));
  result = load_sdf_world(bad_value, isolated_options());
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("bad_value.sdf"), std::string::npos)
      << result.error().message;
  EXPECT_NE(result.error().message.find("size"), std::string::npos) << result.error().message;

  // "--" in a comment is not XML, but sdformat accepts it (gz-sim's examples have it): no error.
  std::string dashes_text =
      world_sdf(static_model("a", "0 0 0 0 0 0", "<box><size>1 1 1</size></box>"));
  dashes_text.insert(dashes_text.find('\n') + 1, "<!-- run: gz service --timeout 2000 -->\n");
  const auto dashes = write_file(dir / "dashes.sdf", dashes_text);
  const auto dashes_world = load_sdf_world(dashes, isolated_options());
  EXPECT_TRUE(dashes_world.ok()) << dashes_world.error().message;

  const auto urdf = write_file(dir / "robot.urdf", "<?xml version=\"1.0\"?><robot name=\"r\"/>");
  result = load_sdf_world(urdf, isolated_options());
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().message.find("not an SDF file"), std::string::npos);

  result = load_sdf_world(dir / "absent.sdf", isolated_options());
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kIo);
}

// sdformat's element description is built once per process and shared by every load: a load after
// others (an error among them, another SDF version) gives the same world as the first.
TEST(WorldSdf, LoadsShareOneDescriptionWithoutCarryingAnythingOver) {
  const auto dir = test::make_temp_dir("world_sdf_shared_description");
  const auto first = write_file(
      dir / "first.sdf",
      world_sdf(static_model("a", "1 2 0 0 0 0.5", "<box><size>4 6 10</size></box>") +
                static_model("b", "-5 0 0 0 0 0", "<cylinder><radius>1</radius><length>3</length></cylinder>")));
  const auto broken = write_file(dir / "broken.sdf",
                                 "<?xml version=\"1.0\"?>\n<sdf version=\"1.6\">\n<world name=\"w\">\n"
                                 "<model name=\"a\"><link name=\"l\"></model>\n</world></sdf>\n");
  const auto older = write_file(
      dir / "older.sdf", world_sdf(static_model("c", "0 0 0 0 0 0", "<sphere><radius>2</radius></sphere>"), "1.6"));
  const auto before = load_sdf_world(first, isolated_options()).value();
  ASSERT_FALSE(load_sdf_world(broken, isolated_options()).ok());
  ASSERT_EQ(load_sdf_world(older, isolated_options()).value().objects.size(), 1U);
  const auto after = load_sdf_world(first, isolated_options()).value();
  ASSERT_EQ(after.objects.size(), before.objects.size());
  ASSERT_EQ(before.objects.size(), 2U);
  for (size_t i = 0; i < before.objects.size(); ++i) {
    const WorldObject& x = before.objects[i];
    const WorldObject& y = after.objects[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_TRUE(x.pose.matrix() == y.pose.matrix()) << x.name;
    ASSERT_EQ(x.mesh.vertices_m.size(), y.mesh.vertices_m.size()) << x.name;
    for (size_t v = 0; v < x.mesh.vertices_m.size(); ++v) EXPECT_TRUE(x.mesh.vertices_m[v] == y.mesh.vertices_m[v]);
    EXPECT_EQ(x.mesh.triangles, y.mesh.triangles) << x.name;
  }
  EXPECT_EQ(before.warnings, after.warnings);
}

TEST(WorldSdf, SphericalCoordinatesFollowGazebo) {
  const auto dir = test::make_temp_dir("world_sdf_geo");
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf(
          "<spherical_coordinates><surface_model>EARTH_WGS84</surface_model>"
          "<world_frame_orientation>ENU</world_frame_orientation><latitude_deg>48.1</latitude_deg>"
          "<longitude_deg>11.5</longitude_deg><elevation>500</elevation><heading_deg>90</"
          "heading_deg>"
          "</spherical_coordinates>" +
          static_model("a", "0 0 0 0 0 0", "<box><size>1 1 1</size></box>")));
  auto world = load_sdf_world(path, isolated_options()).value();
  ASSERT_TRUE(world.geo_origin.has_value());
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.latitude_deg, 48.1);
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.longitude_deg, 11.5);
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.height_m, 500.0);
  EXPECT_DOUBLE_EQ(world.geo_origin->heading_deg, 90.0);

  // gz-math: heading is the angle from east to the world x axis, counter-clockwise; at 90 degrees
  // the world x axis points north and y west. 1 km north along the tangent plane is 1 km over the
  // meridian's radius of curvature M = a (1 - e2) / (1 - e2 sin2(lat))^1.5, plus the height.
  const Geodetic north = world_point_to_geodetic(*world.geo_origin, {1000.0, 0.0, 0.0});
  const double e2 = 6.69437999014e-3;
  const double sin_lat = std::sin(48.1 * kPi / 180.0);
  const double meridian_m = 6378137.0 * (1.0 - e2) / std::pow(1.0 - e2 * sin_lat * sin_lat, 1.5);
  EXPECT_NEAR(north.latitude_deg - 48.1, std::atan(1000.0 / (meridian_m + 500.0)) * 180.0 / kPi,
              1e-8);
  EXPECT_NEAR(north.longitude_deg, 11.5, 1e-9);
  EXPECT_NEAR(north.height_m, 500.0 + 1000.0 * 1000.0 / (2.0 * 6.37e6),
              0.01);  // the tangent plane rises
  const Geodetic west = world_point_to_geodetic(*world.geo_origin, {0.0, 1000.0, 0.0});
  EXPECT_LT(west.longitude_deg, 11.5);
  const Eigen::Vector3d back = geodetic_to_world_point(*world.geo_origin, north);
  expect_vector_near(back, {1000.0, 0.0, 0.0}, 1e-6);

  // The scenario may override the world's origin.
  auto options = isolated_options();
  options.geo_origin = GeoOrigin{Geodetic{1.0, 2.0, 3.0}, 0.0};
  world = load_sdf_world(path, options).value();
  EXPECT_DOUBLE_EQ(world.geo_origin->origin.latitude_deg, 1.0);
  EXPECT_DOUBLE_EQ(world.geo_origin->heading_deg, 0.0);
  const Geodetic east = world_point_to_geodetic(*world.geo_origin, {1000.0, 0.0, 0.0});
  EXPECT_GT(east.longitude_deg, 2.0);
  EXPECT_NEAR(east.latitude_deg, 1.0, 1e-6);
}

// 3 x 2 grayscale PNG: rows (0, 128, 255) and (255, 0, 64).
const unsigned char kTinyPng[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44,
    0x52, 0x00, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x02, 0x08, 0x00, 0x00, 0x00, 0x00, 0xb8,
    0x1f, 0x39, 0xc6, 0x00, 0x00, 0x00, 0x10, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x60,
    0x68, 0xf8, 0xcf, 0xf0, 0x9f, 0xc1, 0x01, 0x00, 0x0b, 0x40, 0x02, 0xbf, 0x8c, 0xe2, 0x9d,
    0x78, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

TEST(WorldSdf, HeightmapAndMissingHeightmap) {
  const auto dir = test::make_temp_dir("world_sdf_heightmap");
  {
    std::ofstream png(dir / "terrain.png", std::ios::binary);
    png.write(reinterpret_cast<const char*>(kTinyPng), sizeof(kTinyPng));
  }
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf(
          static_model(
              "terrain", "0 0 0 0 0 0",
              "<heightmap><uri>terrain.png</uri><size>20 10 5</size><pos>1 2 3</pos></heightmap>") +
          static_model("lost", "0 0 0 0 0 0",
                       "<heightmap><uri>nothing.png</uri><size>20 10 5</size></heightmap>") +
          // An include skytrace instantiates itself: the rest of the world is then parsed from
          // text, and relative URIs must still start from the world's folder.
          "<include><uri>model://absent_model</uri></include>"));
  const auto world = load_sdf_world(path, isolated_options()).value();
  const auto* terrain = find_object(world, "terrain/link/collision");
  ASSERT_NE(terrain, nullptr) << all_warnings(world);
  EXPECT_EQ(terrain->kind, ObjectKind::kGround);
  ASSERT_EQ(terrain->mesh.vertices_m.size(), 6U);
  // Row 0 (north, +y), column 2 (east): brightness 255 -> pos.z + size.z.
  expect_vector_near(terrain->mesh.vertices_m[2].cast<double>(), {1.0 + 10.0, 2.0 + 5.0, 3.0 + 5.0},
                     1e-5);
  // Row 1, column 2: 64 / 255 of 5 m.
  expect_vector_near(terrain->mesh.vertices_m[5].cast<double>(),
                     {11.0, -3.0, 3.0 + 5.0 * 64.0 / 255.0}, 1e-5);
  EXPECT_EQ(find_object(world, "lost/link/collision"), nullptr);
  EXPECT_TRUE(has_warning(world, "heightmap nothing.png not found")) << all_warnings(world);
}

// ---------------------------------------------------------------------------------------------
// Meshes

// One triangle (0,0,0) (100,0,0) (0,100,0) in centimetres with the given up axis.
std::string collada_triangle(const std::string& up_axis) {
  return R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="centimeter" meter="0.01"/><up_axis>)" +
         up_axis + R"(</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri">
      <mesh>
        <source id="tri-pos">
          <float_array id="tri-pos-array" count="9">0 0 0 100 0 0 0 100 0</float_array>
          <technique_common><accessor source="#tri-pos-array" count="3" stride="3">
            <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
          </accessor></technique_common>
        </source>
        <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
        <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="panel" name="panel"><instance_geometry url="#tri"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
}

Eigen::Vector3d max_corner(const std::vector<MeshPart>& parts) {
  Eigen::Vector3d high = Eigen::Vector3d::Constant(-1e9);
  for (const auto& part : parts) {
    for (const auto& v : part.mesh.vertices_m) high = high.cwiseMax(v.cast<double>());
  }
  return high;
}

TEST(WorldMesh, ColladaUnitAndUpAxis) {
  const auto dir = test::make_temp_dir("world_mesh_collada");
  const auto y_up = read_mesh_file(write_file(dir / "y.dae", collada_triangle("Y_UP"))).value();
  ASSERT_EQ(y_up.size(), 1U);
  EXPECT_EQ(y_up[0].node_name, "panel");
  // Centimetres to metres; the file's y (up) becomes z.
  expect_vector_near(max_corner(y_up), {1.0, 0.0, 1.0}, 1e-6);
  const auto z_up = read_mesh_file(write_file(dir / "z.dae", collada_triangle("Z_UP"))).value();
  expect_vector_near(max_corner(z_up), {1.0, 1.0, 0.0}, 1e-6);
  // An explicit axis overrides the file's declaration.
  const auto forced = read_mesh_file(dir / "y.dae", UpAxis::kZ).value();
  expect_vector_near(max_corner(forced), {1.0, 1.0, 0.0}, 1e-6);
}

const char* kTwoBoxesObj = R"(o tree_crown
v 0 0 0
v 2 0 0
v 2 2 0
v 0 2 0
v 0 0 2
v 2 0 2
v 2 2 2
v 0 2 2
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
o house_block
v 10 0 0
v 14 0 0
v 14 4 0
v 10 4 9
f 9 10 11
f 9 11 12
)";

TEST(WorldMesh, ObjFilesKeepTheirAxesAndSplitByNode) {
  const auto dir = test::make_temp_dir("world_mesh_obj");
  const auto path = write_file(dir / "scene.obj", kTwoBoxesObj);
  const auto parts = read_mesh_file(path).value();
  ASSERT_EQ(parts.size(), 2U);
  expect_vector_near(max_corner(parts), {14.0, 4.0, 9.0}, 1e-6);  // OBJ: z stays up

  MeshLoadOptions options;
  options.pose = Eigen::Translation3d(100.0, 0.0, 0.0) * Eigen::Isometry3d::Identity();
  const GeoOrigin origin{Geodetic{48.0, 11.0, 500.0}, 0.0};
  const auto world = load_mesh_world(path, origin, options).value();
  EXPECT_EQ(world.geo_origin->origin.latitude_deg, 48.0);
  ASSERT_EQ(world.objects.size(), 2U);
  const auto* crown = find_object(world, "scene.obj/tree_crown");
  ASSERT_NE(crown, nullptr);
  EXPECT_EQ(crown->kind, ObjectKind::kTree);
  EXPECT_TRUE(crown->material.is_vegetation());
  // The two open squares become their convex hull: the 2 m cube.
  EXPECT_TRUE(is_closed_consistent(crown->mesh));
  EXPECT_NEAR(signed_volume_m3(crown->mesh), 8.0, 1e-5);
  const auto* house = find_object(world, "scene.obj/house_block");
  ASSERT_NE(house, nullptr);
  EXPECT_EQ(house->kind, ObjectKind::kBuilding);
  EXPECT_NEAR(world_bounds(world).second.x(), 114.0, 1e-5);

  EXPECT_FALSE(read_mesh_file(dir / "absent.obj").ok());
  const auto garbage = read_mesh_file(write_file(dir / "garbage.stl", "this is not a mesh"));
  ASSERT_FALSE(garbage.ok());
  EXPECT_NE(garbage.error().message.find("garbage.stl"), std::string::npos);
}

TEST(WorldMesh, SdfMeshesWithScaleSubmeshAndFailures) {
  const auto dir = test::make_temp_dir("world_mesh_sdf");
  write_file(dir / "models" / "garden" / "meshes" / "scene.obj", kTwoBoxesObj);
  write_file(dir / "models" / "garden" / "meshes" / "broken.dae", "<COLLADA>nope");
  const auto path = write_file(
      dir / "w.sdf",
      world_sdf(
          static_model(
              "scaled", "0 0 0 0 0 0",
              "<mesh><uri>model://garden/meshes/scene.obj</uri><scale>2 1 0.5</scale></mesh>") +
          static_model(
              "crown_only", "0 0 0 0 0 0",
              "<mesh><uri>model://garden/meshes/scene.obj</uri><submesh><name>tree_crown</name>"
              "<center>true</center></submesh></mesh>") +
          static_model("ghost", "0 0 0 0 0 0",
                       "<mesh><uri>model://garden/meshes/ghost.dae</uri></mesh>") +
          static_model("broken", "0 0 0 0 0 0",
                       "<mesh><uri>model://garden/meshes/broken.dae</uri></mesh>")));
  // By default a mesh that exists but cannot be read stops the load, naming it and its place.
  const auto refused = load_sdf_world(path, isolated_options(dir / "models"));
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("broken/link/collision"), std::string::npos) << refused.error().message;
  EXPECT_NE(refused.error().message.find("broken.dae"), std::string::npos) << refused.error().message;
  auto lenient = isolated_options(dir / "models");
  lenient.unreadable_mesh_is_error = false;
  const auto world = load_sdf_world(path, lenient).value();
  const auto* scaled = find_object(world, "scaled/link/collision");
  ASSERT_NE(scaled, nullptr) << all_warnings(world);
  EXPECT_EQ(scaled->mesh.triangles.size(), 6U);
  expect_vector_near(object_bounds(*scaled).second, {28.0, 4.0, 4.5}, 1e-5);
  const auto* crown = find_object(world, "crown_only/link/collision");
  ASSERT_NE(crown, nullptr);
  EXPECT_TRUE(crown->material.is_vegetation());  // the submesh's name says tree
  EXPECT_NEAR(signed_volume_m3(crown->mesh), 8.0, 1e-5);
  const auto [low, high] = object_bounds(*crown);
  expect_vector_near(low, {-1.0, -1.0, -1.0}, 1e-6);  // centred
  EXPECT_EQ(find_object(world, "ghost/link/collision"), nullptr);
  EXPECT_EQ(find_object(world, "broken/link/collision"), nullptr);
  EXPECT_TRUE(
      has_warning(world, "mesh model://garden/meshes/ghost.dae not found, 1 geometry skipped"))
      << all_warnings(world);
  EXPECT_TRUE(has_warning(world, "broken.dae")) << all_warnings(world);
}

// ---------------------------------------------------------------------------------------------
// OpenStreetMap

std::string osm_node(int id, double lat, double lon, const std::string& tags = "") {
  char buffer[200];
  std::snprintf(buffer, sizeof(buffer), "<node id=\"%d\" version=\"1\" lat=\"%.7f\" lon=\"%.7f\"",
                id, lat, lon);
  return std::string(buffer) + (tags.empty() ? "/>\n" : ">" + tags + "</node>\n");
}

std::string osm_way(int id, const std::vector<int>& nodes, const std::string& tags) {
  std::string out = "<way id=\"" + std::to_string(id) + "\" version=\"1\">";
  for (const int n : nodes) out += "<nd ref=\"" + std::to_string(n) + "\"/>";
  return out + tags + "</way>\n";
}

std::string tag(const std::string& k, const std::string& v) {
  return "<tag k=\"" + k + "\" v=\"" + v + "\"/>";
}

// Square of nodes first_id..first_id+3 between two latitudes and longitudes.
std::string osm_square(int first_id, double lat0, double lon0, double lat1, double lon1) {
  return osm_node(first_id, lat0, lon0) + osm_node(first_id + 1, lat0, lon1) +
         osm_node(first_id + 2, lat1, lon1) + osm_node(first_id + 3, lat1, lon0);
}

std::string tiny_osm(bool with_buildings) {
  std::string xml =
      "<?xml version='1.0' encoding='UTF-8'?>\n<osm version=\"0.6\">\n"
      "<bounds minlat=\"47.998\" minlon=\"10.999\" maxlat=\"48.003\" maxlon=\"11.002\"/>\n";
  xml += osm_square(1, 48.0000, 11.0000, 48.0002, 11.0002);
  xml += osm_square(5, 48.0004, 11.0000, 48.0006, 11.0002);
  xml += osm_square(9, 48.0008, 11.0000, 48.0010, 11.0002);
  xml += osm_square(13, 48.0012, 11.0004, 48.0020, 11.0012);
  xml += osm_square(17, 48.0015, 11.0007, 48.0017, 11.0009);
  xml += osm_square(21, 47.9990, 11.0010, 47.9995, 11.0015);
  xml += osm_square(25, 47.9990, 11.0000, 47.9992, 11.0002);
  xml += osm_square(29, 48.0024, 11.0000, 48.0028, 11.0004);
  xml += osm_node(33, 48.0026, 11.0000) + osm_node(34, 48.0027, 11.0000);
  xml += osm_node(40, 47.9985, 11.0000,
                  tag("natural", "tree") + tag("height", "10") + tag("diameter_crown", "4"));
  xml += osm_node(41, 47.9985, 11.0005, tag("natural", "tree"));
  if (with_buildings) {
    xml += osm_way(1, {1, 2, 3, 4, 1}, tag("building", "yes") + tag("height", "12 m"));
    xml +=
        osm_way(2, {5, 6, 7, 8, 5},
                tag("building", "house") + tag("building:levels", "4") + tag("roof:levels", "1"));
    xml +=
        osm_way(3, {9, 10, 11, 12, 9}, tag("building", "yes") + tag("building:material", "glass"));
    xml += osm_way(4, {1}, tag("building", "yes"));
    xml += osm_way(5, {25, 26, 27, 28, 25}, tag("building", "no"));
    // The west side runs down, back up and down again: osmium rejects the overlapping segments,
    // the outline as drawn is still a square.
    xml += osm_way(6, {29, 30, 31, 32, 33, 34, 29}, tag("building", "yes") + tag("height", "5"));
    xml += osm_way(20, {13, 14, 15, 16, 13}, "");
    xml += osm_way(21, {17, 18, 19, 20, 17}, "");
    xml +=
        "<relation id=\"10\" version=\"1\"><member type=\"way\" ref=\"20\" role=\"outer\"/>"
        "<member type=\"way\" ref=\"21\" role=\"inner\"/>" +
        tag("type", "multipolygon") + tag("building", "yes") + tag("height", "20") +
        "</relation>\n";
    xml += "<relation id=\"11\" version=\"1\"><member type=\"way\" ref=\"999\" role=\"outer\"/>" +
           tag("type", "multipolygon") + tag("building", "yes") + "</relation>\n";
  }
  xml += osm_way(30, {21, 22, 23, 24, 21}, tag("natural", "wood"));
  return xml + "</osm>\n";
}

// ENU of a point at the origin's height, through core's frames (independent of GeographicLib's
// LocalCartesian used by the loader).
Eigen::Vector2d enu_of(double lat, double lon, const Geodetic& origin) {
  const Eigen::Vector3d enu =
      ecef_to_enu(geodetic_to_ecef(Geodetic{lat, lon, origin.height_m}), origin);
  return enu.head<2>();
}

double square_area_m2(double lat0, double lon0, double lat1, double lon1, const Geodetic& origin) {
  return std::abs(signed_area_m2({enu_of(lat0, lon0, origin), enu_of(lat0, lon1, origin),
                                  enu_of(lat1, lon1, origin), enu_of(lat1, lon0, origin)}));
}

TEST(WorldOsm, BuildingsMultipolygonTreesAndWoods) {
  const auto dir = test::make_temp_dir("world_osm_tiny");
  const auto path = write_file(dir / "tiny.osm", tiny_osm(true));
  OsmLoadOptions options;
  options.default_building_height_m = 7.0;
  const auto world = load_osm_world(path, options).value();
  ASSERT_TRUE(world.geo_origin.has_value());
  const Geodetic origin = world.geo_origin->origin;
  EXPECT_NEAR(origin.latitude_deg, 48.0005, 1e-9);  // centre of <bounds>
  EXPECT_NEAR(origin.longitude_deg, 11.0005, 1e-9);

  const auto summary = summarize_world(world);
  EXPECT_EQ(summary.buildings, 5U) << all_warnings(world);  // ways 1, 2, 3, 6 and relation 10
  EXPECT_EQ(summary.trees, 3U);                             // two tree nodes and the wood

  const auto height_of = [&](const std::string& name) {
    const auto* object = find_object(world, name);
    EXPECT_NE(object, nullptr) << name;
    if (object == nullptr) return 0.0;
    const auto [low, high] = object_bounds(*object);
    EXPECT_NEAR(low.z(), 0.0, 1e-5) << name;
    return high.z();
  };
  EXPECT_NEAR(height_of("way/1"), 12.0, 1e-5);
  EXPECT_NEAR(height_of("way/2"), 15.0, 1e-5);  // 4 levels + 1 roof level of 3 m
  EXPECT_NEAR(height_of("way/3"), 7.0, 1e-5);   // default from the options
  EXPECT_EQ(find_object(world, "way/3")->material.material_class, MaterialClass::kGlass);
  EXPECT_EQ(find_object(world, "way/1")->material.material_class, MaterialClass::kConcrete);

  // Footprint of way 1 from the prism's volume, against the shoelace area of its corners in ENU.
  const auto* first = find_object(world, "way/1");
  EXPECT_TRUE(is_closed_consistent(first->mesh));
  EXPECT_NEAR(signed_volume_m3(first->mesh) / 12.0,
              square_area_m2(48.0, 11.0, 48.0002, 11.0002, origin), 0.01);
  // The footprint's east-west extent: 0.0002 deg of longitude at 48 deg, N cos(lat) with the prime
  // vertical radius N = a / sqrt(1 - e2 sin2(lat)) = 6390702 m: 14.927 m.
  const auto [low1, high1] = object_bounds(*first);
  EXPECT_NEAR(high1.x() - low1.x(),
              enu_of(48.0, 11.0002, origin).x() - enu_of(48.0, 11.0, origin).x(), 0.01);
  EXPECT_NEAR(high1.x() - low1.x(), 0.0002 * kPi / 180.0 * 6390702.0 * std::cos(48.0 * kPi / 180.0),
              0.01);

  // The multipolygon keeps its hole: volume = (outer - inner) * 20 m.
  const auto* courtyard = find_object(world, "relation/10");
  ASSERT_NE(courtyard, nullptr);
  EXPECT_TRUE(is_closed_consistent(courtyard->mesh));
  const double ring_area = square_area_m2(48.0012, 11.0004, 48.0020, 11.0012, origin) -
                           square_area_m2(48.0015, 11.0007, 48.0017, 11.0009, origin);
  EXPECT_NEAR(signed_volume_m3(courtyard->mesh), ring_area * 20.0, 1e-4 * ring_area * 20.0);

  const auto* tree = find_object(world, "node/40");
  ASSERT_NE(tree, nullptr);
  EXPECT_TRUE(tree->material.is_vegetation());
  const auto [tree_low, tree_high] = object_bounds(*tree);
  EXPECT_NEAR(tree_high.z(), 10.0, 1e-4);
  EXPECT_NEAR(tree_low.z(), 3.0, 1e-4);  // crown from 30 % of the height
  EXPECT_NEAR(tree_high.x() - tree_low.x(), 4.0, 1e-3);
  EXPECT_NEAR(0.5 * (tree_high.y() + tree_low.y()), enu_of(47.9985, 11.0, origin).y(), 0.01);
  EXPECT_NEAR(object_bounds(*find_object(world, "node/41")).second.z(), 8.0, 1e-4);  // defaults

  const auto* wood = find_object(world, "way/30");
  ASSERT_NE(wood, nullptr);
  EXPECT_EQ(wood->kind, ObjectKind::kTree);
  EXPECT_DOUBLE_EQ(wood->material.attenuation_db_per_m, kDefaultVegetationAttenuationDbPerM);
  EXPECT_NEAR(object_bounds(*wood).second.z(), 15.0, 1e-5);

  EXPECT_EQ(find_object(world, "way/5"), nullptr);  // building=no
  const auto* redrawn = find_object(world, "way/6");
  ASSERT_NE(redrawn, nullptr);
  EXPECT_TRUE(is_closed_consistent(redrawn->mesh));
  EXPECT_NEAR(signed_volume_m3(redrawn->mesh) / 5.0,
              square_area_m2(48.0024, 11.0, 48.0028, 11.0004, origin), 0.05);
  EXPECT_TRUE(has_warning(world, "way/6 (building=yes, 7 node(s), closed): osmium rejected it"))
      << all_warnings(world);
  EXPECT_TRUE(has_warning(world, "way/4 (building=yes, 1 node(s), not a closed ring) skipped"))
      << all_warnings(world);
  EXPECT_TRUE(has_warning(world, "relation/11")) << all_warnings(world);
}

TEST(WorldOsm, NoBuildingsIsAnErrorUnlessAllowed) {
  const auto dir = test::make_temp_dir("world_osm_empty");
  const auto path = write_file(dir / "trees_only.osm", tiny_osm(false));
  const auto result = load_osm_world(path);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kNotFound);
  EXPECT_NE(result.error().message.find("no buildings"), std::string::npos);
  EXPECT_NE(result.error().message.find("trees_only.osm"), std::string::npos);
  OsmLoadOptions options;
  options.allow_no_buildings = true;
  const auto world = load_osm_world(path, options).value();
  EXPECT_EQ(summarize_world(world).trees, 3U);

  const auto broken = write_file(dir / "broken.osm",
                                 "<?xml version='1.0'?>\n<osm version=\"0.6\">\n<node id=\"1\"");
  const auto bad = load_osm_world(broken);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("broken.osm"), std::string::npos);
  EXPECT_FALSE(load_osm_world(dir / "absent.osm").ok());
}

// An object seen from above: the convex hull of its posed vertices on the x-y plane, counter-
// clockwise, inner and repeated vertices dropped (an L-shaped prism gives its hull).
TEST(WorldFootprint, ConvexHullOfThePosedVerticesOnTheGround) {
  WorldObject l_shape;
  l_shape.kind = ObjectKind::kBuilding;
  // An L of 10 x 10 m with a 5 x 5 m notch at the north-east, floor and roof, and a point inside.
  for (const float z : {0.0F, 8.0F}) {
    for (const auto& [x, y] : std::vector<std::pair<float, float>>{{0, 0}, {10, 0}, {10, 5}, {5, 5}, {5, 10}, {0, 10}, {2, 2}}) {
      l_shape.mesh.vertices_m.emplace_back(x, y, z);
    }
  }
  l_shape.pose = Eigen::Translation3d(100.0, 50.0, 0.0) * Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ());
  const Footprint f = footprint(l_shape);
  EXPECT_EQ(f.kind, ObjectKind::kBuilding);
  ASSERT_EQ(f.outline_m.size(), 5U);  // the notch's corner (5, 5) is inside the hull
  double twice_area = 0.0;
  for (size_t i = 0; i < f.outline_m.size(); ++i) {
    const auto& a = f.outline_m[i];
    const auto& b = f.outline_m[(i + 1) % f.outline_m.size()];
    twice_area += a.x() * b.y() - b.x() * a.y();
    // Rotated by 90 degrees and moved: x in [90, 100], y in [50, 60].
    EXPECT_GE(a.x(), 90.0 - 1e-9);
    EXPECT_LE(a.x(), 100.0 + 1e-9);
    EXPECT_GE(a.y(), 50.0 - 1e-9);
    EXPECT_LE(a.y(), 60.0 + 1e-9);
  }
  EXPECT_NEAR(twice_area / 2.0, 100.0 - 12.5, 1e-6);  // counter-clockwise: positive
  EXPECT_TRUE(footprint(WorldObject{}).outline_m.empty());
}

}  // namespace
}  // namespace skytrace::world
