// Path finding for multipath: reflections against image geometry worked out by hand (ground plane,
// street canyon of canyon.sdf, second order), knife-edge diffraction against ITU-R P.526 and the
// exact Fresnel integral, Fresnel coefficients against their limits, EmbreeScene against
// BruteForceScene as the ray caster.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/world/loaders.hpp"
#include "skytrace/world/propagation.hpp"
#include "skytrace/world/scene.hpp"

namespace skytrace::world {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kL1WavelengthM = 299792458.0 / 1575.42e6;

WorldObject placed(const std::string& name, TriangleMesh mesh, const Eigen::Vector3d& position_m, MaterialClass material,
                   ObjectKind kind = ObjectKind::kBuilding) {
  WorldObject o;
  o.name = name;
  o.kind = kind;
  o.material = Material{material, 0.0};
  o.mesh = std::move(mesh);
  o.pose = Eigen::Isometry3d(Eigen::Translation3d(position_m));
  return o;
}

WorldObject ground_plane(double size_m = 600.0) {
  return placed("ground", make_plane(Eigen::Vector3d::UnitZ(), {size_m, size_m}), Eigen::Vector3d::Zero(),
                MaterialClass::kGround, ObjectKind::kGround);
}

// The contract canyon (../shared/contract/worlds/canyon.sdf): north wall's south face 9.5 m north
// of the origin, 30 m high; south wall's north face 19.5 m south, 40 m high; both 200 m long.
WorldModel canyon(bool with_ground = true) {
  WorldModel w;
  if (with_ground) w.objects.push_back(ground_plane());
  w.objects.push_back(placed("north", make_box({200, 1, 30}), {0, 10, 15}, MaterialClass::kConcrete));
  w.objects.push_back(placed("south", make_box({200, 1, 40}), {0, -20, 20}, MaterialClass::kConcrete));
  return w;
}

std::unique_ptr<PropagationScene> propagation(const WorldModel& world, bool brute_force = false) {
  std::shared_ptr<const PathQuery> scene;
  if (brute_force) {
    auto b = BruteForceScene::build(world);
    EXPECT_TRUE(b.ok());
    scene = std::make_shared<BruteForceScene>(std::move(*b));
  } else {
    auto e = EmbreeScene::build(world);
    EXPECT_TRUE(e.ok());
    scene = std::shared_ptr<const PathQuery>(std::move(*e));
  }
  auto p = PropagationScene::build(world, scene);
  EXPECT_TRUE(p.ok()) << (p.ok() ? "" : p.error().message);
  return std::move(*p);
}

const SignalPath* find_path(const PathSet& set, PathType type, int reflections = 0) {
  for (const SignalPath& p : set.paths) {
    if (p.type == type && (type != PathType::kReflected || p.reflections == reflections)) return &p;
  }
  return nullptr;
}

TEST(KnifeEdge, LossAtGrazingIsSixDecibels) {
  // ITU-R P.526: the field at grazing (v = 0) is half the free-space field, 6.02 dB.
  EXPECT_NEAR(knife_edge_loss_db(0.0), 20.0 * std::log10(2.0), 0.02);
  EXPECT_EQ(knife_edge_loss_db(-0.78), 0.0);
  EXPECT_EQ(knife_edge_loss_db(-3.0), 0.0);
  // Large v: P.526's asymptote 13 + 20 log10(v).
  EXPECT_NEAR(knife_edge_loss_db(10.0), 13.0 + 20.0 * std::log10(10.0), 0.2);
}

// Exact knife-edge field |F(v)| = |(1 + j)/2 * integral from v to infinity of exp(-j pi t^2 / 2) dt|.
double exact_knife_edge_loss_db(double v) {
  const double upper = 60.0;
  const int steps = 600000;
  const double h = (upper - v) / steps;
  std::complex<double> sum = 0.0;
  for (int i = 0; i <= steps; ++i) {
    const double t = v + h * i;
    const double weight = (i == 0 || i == steps) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += weight * std::polar(1.0, -std::numbers::pi * t * t / 2.0);
  }
  std::complex<double> integral = sum * h / 3.0;
  // Tail beyond `upper`: integration by parts, exp(-j pi u^2/2) / (j pi u).
  integral += std::polar(1.0, -std::numbers::pi * upper * upper / 2.0) / std::complex<double>(0.0, std::numbers::pi * upper);
  const std::complex<double> field = std::complex<double>(0.5, 0.5) * integral;
  return -20.0 * std::log10(std::abs(field));
}

TEST(KnifeEdge, ApproximationFollowsTheFresnelIntegral) {
  // P.526's J(v) approximates the exact knife-edge loss; the ripple of the lit side (v < 0) is
  // smoothed out, so the comparison starts at v = -0.5.
  for (const double v : {-0.5, -0.2, 0.0, 0.5, 1.0, 2.0, 4.0, 8.0}) {
    EXPECT_NEAR(knife_edge_loss_db(v), exact_knife_edge_loss_db(v), 0.6) << "v = " << v;
  }
}

TEST(Fresnel, LimitsOfTheCircularCoefficients) {
  // Perfect conductor: RHCP turns entirely LHCP at every angle.
  const auto metal = complex_permittivity(MaterialClass::kMetal, 1575.42e6);
  for (const double cos_i : {1.0, 0.7, 0.2}) {
    const FresnelCoefficients f = fresnel_coefficients(metal, cos_i);
    EXPECT_LT(std::abs(f.co), 1e-3);
    EXPECT_NEAR(std::abs(f.cross), 1.0, 1e-3);
  }
  // Grazing incidence on any dielectric: the wave is reflected whole with its handedness (-1).
  const auto concrete = complex_permittivity(MaterialClass::kConcrete, 1575.42e6);
  const FresnelCoefficients grazing = fresnel_coefficients(concrete, 1e-9);
  EXPECT_NEAR(grazing.co.real(), -1.0, 1e-6);
  EXPECT_LT(std::abs(grazing.cross), 1e-6);
  // Normal incidence: only cross-polar, |(1 - sqrt(eta)) / (1 + sqrt(eta))|.
  const FresnelCoefficients normal = fresnel_coefficients(concrete, 1.0);
  EXPECT_LT(std::abs(normal.co), 1e-12);
  EXPECT_NEAR(std::abs(normal.cross), std::abs((1.0 - std::sqrt(concrete)) / (1.0 + std::sqrt(concrete))), 1e-12);
  // Glass (nearly lossless): the parallel coefficient vanishes at Brewster's angle atan(sqrt(eps')).
  const auto glass = complex_permittivity(MaterialClass::kGlass, 1575.42e6);
  const double brewster = std::atan(std::sqrt(glass.real()));
  EXPECT_LT(std::abs(fresnel_coefficients(glass, std::cos(brewster)).tm), 0.01);
  EXPECT_GT(std::abs(fresnel_coefficients(glass, std::cos(brewster)).te), 0.5);
}

// A passive surface reflects at most the power that reaches it: the diffuse-scattering search
// bounds a facet's lighting by |Gamma|^2 <= 1 before it works out the coefficients, and would drop
// paths if a material or the coefficients ever made a reflection gain power.
TEST(Fresnel, PassiveSurfacesReflectAtMostTheIncidentPower) {
  for (const MaterialClass m : {MaterialClass::kConcrete, MaterialClass::kBrick, MaterialClass::kGlass, MaterialClass::kMetal,
                                MaterialClass::kWood, MaterialClass::kGround, MaterialClass::kVegetation, MaterialClass::kUnknown}) {
    for (const double f_hz : {1176.45e6, 1207.14e6, 1227.60e6, 1246.0e6, 1268.52e6, 1278.75e6, 1561.098e6, 1575.42e6, 1602.0e6}) {
      const std::complex<double> eta = complex_permittivity(m, f_hz);
      EXPECT_LE(eta.imag(), 0.0);  // eps' - j eps'': a loss, never a gain
      for (int k = 1; k <= 1000; ++k) {  // the searches use cos(incidence) > 1e-6
        const FresnelCoefficients g = fresnel_coefficients(eta, k / 1000.0);
        EXPECT_LE(std::norm(g.te), 1.0 + 1e-12) << static_cast<int>(m) << " " << f_hz << " " << k;
        EXPECT_LE(std::norm(g.tm), 1.0 + 1e-12) << static_cast<int>(m) << " " << f_hz << " " << k;
      }
    }
  }
  // The coefficients the other way up (the receiver's side taken for the material's) would.
  const auto concrete = complex_permittivity(MaterialClass::kConcrete, 1575.42e6);
  const std::complex<double> root = std::sqrt(concrete - 0.91);
  EXPECT_GT(std::norm((0.3 + root) / (0.3 - root)), 1.0);
}

TEST(Fresnel, MaterialTablesOfP2040) {
  // ITU-R P.2040-1 Table 3 at 1 GHz: concrete 5.31 / 0.0326 S/m, brick 3.75 / 0.038, wood 1.99 / 0.0047,
  // glass 6.27 / 0.0043, medium dry ground 15 / 0.035.
  const struct {
    MaterialClass m;
    double eps, sigma;
  } rows[] = {{MaterialClass::kConcrete, 5.31, 0.0326}, {MaterialClass::kBrick, 3.75, 0.038},
              {MaterialClass::kWood, 1.99, 0.0047},     {MaterialClass::kGlass, 6.27, 0.0043},
              {MaterialClass::kGround, 15.0, 0.035}};
  for (const auto& row : rows) {
    const ElectricalProperties e = electrical_properties(row.m, 1e9);
    EXPECT_NEAR(e.relative_permittivity, row.eps, 1e-9);
    EXPECT_NEAR(e.conductivity_s_per_m, row.sigma, 1e-9);
  }
  // eps'' = 17.98 sigma / f_GHz.
  EXPECT_NEAR(complex_permittivity(MaterialClass::kConcrete, 1e9).imag(), -17.98 * 0.0326, 1e-9);
}

TEST(Propagation, FacetsAndEdgesOfTheCanyon) {
  const auto scene = propagation(canyon());
  // Two boxes of 6 faces and the ground plane; the ground has no diffracting edges.
  EXPECT_EQ(scene->facets().size(), 13u);
  EXPECT_EQ(scene->edges().size(), 24u);
  double ground_area = 0.0;
  for (const Facet& f : scene->facets()) {
    if (f.material == MaterialClass::kGround) ground_area = f.area_m2;
  }
  EXPECT_NEAR(ground_area, 600.0 * 600.0, 1e-6);
}

// The triangles' boxes only pass over triangles: a facet of many triangles (a fan of slivers and
// a square) answers every point as the barycentric tests alone do, on the boundary and within the
// slack just beyond it too.
TEST(Propagation, FacetContainsAlikeWithAndWithoutTheTrianglesBoxes) {
  Facet plain;
  plain.normal = Eigen::Vector3d::UnitZ();
  plain.origin_m = Eigen::Vector3d::Zero();
  plain.axis_u = Eigen::Vector3d::UnitX();
  plain.axis_v = Eigen::Vector3d::UnitY();
  const Eigen::Vector2d centre(10.0, 10.0);
  constexpr int kFan = 24;
  for (int k = 0; k < kFan; ++k) {
    const double a0 = 2.0 * std::numbers::pi * k / kFan, a1 = 2.0 * std::numbers::pi * (k + 1) / kFan;
    const double radius_m = k % 3 == 0 ? 8.0 : 5.0;
    plain.triangles_uv.push_back(centre);
    plain.triangles_uv.push_back(centre + radius_m * Eigen::Vector2d(std::cos(a0), std::sin(a0)));
    plain.triangles_uv.push_back(centre + radius_m * Eigen::Vector2d(std::cos(a1), std::sin(a1)));
  }
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(30, 0), Eigen::Vector2d(40, 0), Eigen::Vector2d(40, 10)}) {
    plain.triangles_uv.push_back(corner);
  }
  plain.min_uv = Eigen::Vector2d::Constant(1e300);
  plain.max_uv = Eigen::Vector2d::Constant(-1e300);
  for (const Eigen::Vector2d& uv : plain.triangles_uv) {
    plain.min_uv = plain.min_uv.cwiseMin(uv);
    plain.max_uv = plain.max_uv.cwiseMax(uv);
  }
  Facet boxed = plain;
  boxed.set_triangle_bounds();
  ASSERT_EQ(3 * boxed.triangle_bounds_uv.size(), boxed.triangles_uv.size());
  int inside = 0, tested = 0;
  const auto expect_alike = [&](const Eigen::Vector2d& uv) {
    const Eigen::Vector3d point(uv.x(), uv.y(), 0.0);
    ++tested;
    const bool answer = plain.contains(point);
    inside += answer ? 1 : 0;
    EXPECT_EQ(boxed.contains(point), answer) << "u " << uv.x() << " v " << uv.y();
  };
  for (double u = -1.0; u <= 41.0; u += 0.25) {
    for (double v = -1.0; v <= 21.0; v += 0.25) expect_alike({u, v});
  }
  // Corners and points a hair inside and outside every edge.
  for (std::size_t i = 0; i + 2 < plain.triangles_uv.size(); i += 3) {
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector2d& a = plain.triangles_uv[i + static_cast<std::size_t>(e)];
      const Eigen::Vector2d& b = plain.triangles_uv[i + static_cast<std::size_t>((e + 1) % 3)];
      const Eigen::Vector2d normal = Eigen::Vector2d(b.y() - a.y(), a.x() - b.x()).normalized();
      for (const double along : {0.0, 0.3, 0.5, 1.0}) {
        for (const double off_m : {-1e-6, -1e-9, 0.0, 1e-9, 1e-8, 1e-6}) expect_alike(a + along * (b - a) + off_m * normal);
      }
    }
  }
  EXPECT_GT(inside, 1000);
  EXPECT_LT(inside, tested);
}

TEST(Propagation, GroundReflectionDelayIsTwoHeightsSineElevation) {
  WorldModel world;
  world.objects.push_back(ground_plane());
  const auto scene = propagation(world);
  const double h = 1.5;
  const Eigen::Vector3d rx(3.0, -2.0, h);
  PathSearchSettings settings;
  for (const double el : {5.0, 15.0, 30.0, 60.0, 85.0}) {
    for (const double az : {0.0, 123.0, 250.0}) {
      const Eigen::Vector3d s = enu_direction(az, el);
      const auto sets = scene->paths(rx, {s}, settings);
      ASSERT_EQ(sets.size(), 1u);
      ASSERT_EQ(sets[0].paths.size(), 2u) << el;
      EXPECT_EQ(sets[0].paths[0].type, PathType::kDirect);
      const SignalPath* g = find_path(sets[0], PathType::kReflected, 1);
      ASSERT_NE(g, nullptr);
      EXPECT_NEAR(g->excess_delay_m, 2.0 * h * std::sin(el * kDeg), 1e-9);
      // The specular point: h / tan(el) ahead of the antenna towards the satellite's azimuth.
      const Eigen::Vector3d expected = rx + Eigen::Vector3d(std::sin(az * kDeg), std::cos(az * kDeg), 0.0) * h / std::tan(el * kDeg) -
                                       Eigen::Vector3d(0, 0, h);
      EXPECT_NEAR((g->point_m - expected).norm(), 0.0, 1e-9);
      EXPECT_NEAR(g->arrival_direction.z(), -std::sin(el * kDeg), 1e-9);
      EXPECT_EQ(g->material, MaterialClass::kGround);
      // Amplitudes are the Fresnel coefficients of medium dry ground at the grazing angle.
      const FresnelCoefficients f = fresnel_coefficients(complex_permittivity(MaterialClass::kGround, 1575.42e6), std::sin(el * kDeg));
      EXPECT_NEAR(std::abs(g->rhcp_amplitude - f.co), 0.0, 1e-12);
      EXPECT_NEAR(std::abs(g->lhcp_amplitude - f.cross), 0.0, 1e-12);
    }
  }
  // Low satellites reflect co-polar (RHCP) off the ground, high ones mostly cross-polar.
  const auto low = scene->paths(rx, {enu_direction(0, 5)}, settings)[0].paths[1];
  const auto high = scene->paths(rx, {enu_direction(0, 80)}, settings)[0].paths[1];
  EXPECT_GT(std::abs(low.rhcp_amplitude), std::abs(low.lhcp_amplitude));
  EXPECT_LT(std::abs(high.rhcp_amplitude), std::abs(high.lhcp_amplitude));
}

TEST(Propagation, CanyonNlosOffTheOppositeWall) {
  for (const bool brute : {false, true}) {
    const auto scene = propagation(canyon(), brute);
    const Eigen::Vector3d rx(0.0, 0.0, 1.5);
    PathSearchSettings settings;
    settings.diffraction = false;
    for (const double az : {0.0, 20.0, 340.0, 180.0, 160.0}) {
      // Low enough to be hidden by the near wall, high enough for the reflection to clear it.
      const bool north = std::cos(az * kDeg) > 0.0;
      const double el = north ? 40.0 : 55.0;
      const auto sets = scene->paths(rx, {enu_direction(az, el)}, settings);
      const PathSet& set = sets[0];
      EXPECT_TRUE(set.direct.blocked) << az;
      EXPECT_EQ(find_path(set, PathType::kDirect), nullptr);
      const SignalPath* wall = find_path(set, PathType::kReflected, 1);
      ASSERT_NE(wall, nullptr) << az;
      // Northern satellites reflect off the south wall (19.5 m), southern ones off the north wall (9.5 m).
      const double d = north ? 19.5 : 9.5;
      EXPECT_NEAR(wall->excess_delay_m, 2.0 * d * std::cos(el * kDeg) * std::abs(std::cos(az * kDeg)), 1e-6)
          << az << (brute ? " brute" : " embree");
      EXPECT_EQ(wall->object, north ? "south" : "north");
      EXPECT_NEAR(wall->point_m.y(), north ? -19.5 : 9.5, 1e-6);
      // The ground reflection of a blocked satellite is blocked too.
      for (const SignalPath& p : set.paths) EXPECT_NE(p.material, MaterialClass::kGround);
    }
  }
}

TEST(Propagation, SecondOrderReflectionInTheCanyon) {
  const auto scene = propagation(canyon(false));
  const Eigen::Vector3d rx(0.0, 0.0, 1.5);
  PathSearchSettings settings;
  settings.diffraction = false;
  settings.max_reflection_order = 2;
  const double el = 30.0;
  const auto sets = scene->paths(rx, {enu_direction(0.0, el)}, settings);
  const SignalPath* twice = find_path(sets[0], PathType::kReflected, 2);
  ASSERT_NE(twice, nullptr);
  // Images: receiver in the north face (y = 9.5) at y = 19, that in the south face (y = -19.5) at
  // y = -58; the excess is the image's offset along the satellite direction, 58 cos(el).
  EXPECT_NEAR(twice->excess_delay_m, 58.0 * std::cos(el * kDeg), 1e-6);
  EXPECT_NEAR(twice->point_m.y(), 9.5, 1e-6);
  EXPECT_NEAR(twice->second_point_m.y(), -19.5, 1e-6);
  EXPECT_EQ(twice->object, "north");
  // RHCP -> LHCP -> RHCP: two reflections near normal incidence return mostly co-polar.
  EXPECT_GT(std::abs(twice->rhcp_amplitude), std::abs(twice->lhcp_amplitude));
  // Double bounces only between facets within second_order_radius_m: the south wall (19.5 m) is
  // beyond 15 m, inside 20 m.
  settings.second_order_radius_m = 15.0;
  EXPECT_EQ(find_path(scene->paths(rx, {enu_direction(0.0, el)}, settings)[0], PathType::kReflected, 2), nullptr);
  settings.second_order_radius_m = 20.0;
  EXPECT_NE(find_path(scene->paths(rx, {enu_direction(0.0, el)}, settings)[0], PathType::kReflected, 2), nullptr);
  // Without the second order only the single bounce remains.
  settings.max_reflection_order = 1;
  EXPECT_EQ(find_path(scene->paths(rx, {enu_direction(0.0, el)}, settings)[0], PathType::kReflected, 2), nullptr);
}

// A static antenna's double bounces come from an index of the facet pairs by sky cell, its
// knife edges and its diffractions then reflections from indexes of edges and of facet-edge pairs
// by sky cell and object (each with its band of directions), and its
// view of the scattering patches is traced once, all kept from its second call at the same point
// (a moving antenna searches and traces each time). They must give the same paths, bit for bit: a
// block of buildings turned every way, scattering on, and satellite directions all over the sky.
// Six blocks of different sizes and yaws on a ground plane: streets, corners and courtyards.
WorldModel blocks_world() {
  WorldModel w;
  w.objects.push_back(ground_plane(400.0));
  const struct {
    Eigen::Vector3d size_m, centre_m;
    double yaw_deg;
  } blocks[] = {{{30, 12, 25}, {0, 22, 12.5}, 0.0},   {{20, 20, 40}, {-28, -18, 20}, 20.0},
                {{40, 8, 15}, {25, -20, 7.5}, -35.0}, {{10, 30, 30}, {35, 15, 15}, 60.0},
                {{15, 15, 12}, {-30, 20, 6}, 45.0},   {{6, 6, 18}, {8, -6, 9}, 10.0}};
  int k = 0;
  for (const auto& b : blocks) {
    WorldObject o = placed("block" + std::to_string(k++), make_box(b.size_m), b.centre_m, MaterialClass::kConcrete);
    o.pose.rotate(Eigen::AngleAxisd(b.yaw_deg * kDeg, Eigen::Vector3d::UnitZ()));
    w.objects.push_back(std::move(o));
  }
  return w;
}

// Every path model: double bounces, diffraction with a reflection, directive scattering.
PathSearchSettings nlos_models() {
  PathSearchSettings settings;
  settings.max_reflection_order = 2;
  settings.second_order_radius_m = 60.0;
  settings.scattering_coefficient = 0.4;
  settings.scattering_lobe_exponent = 4;
  settings.min_relative_power_db = -40.0;
  return settings;
}

// A Fibonacci lattice over the whole sphere (satellites below the horizon too).
std::vector<Eigen::Vector3d> fibonacci_sky(int directions) {
  std::vector<Eigen::Vector3d> sky;
  for (int i = 0; i < directions; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / directions;
    const double azimuth = std::numbers::pi * (3.0 - std::sqrt(5.0)) * i;
    sky.emplace_back(std::sqrt(1.0 - z * z) * std::cos(azimuth), std::sqrt(1.0 - z * z) * std::sin(azimuth), z);
  }
  return sky;
}

void expect_same_paths(const PathSet& a_set, const PathSet& b_set, const std::string& what) {
  EXPECT_EQ(a_set.direct.blocked, b_set.direct.blocked) << what;
  ASSERT_EQ(a_set.paths.size(), b_set.paths.size()) << what;
  for (std::size_t j = 0; j < a_set.paths.size(); ++j) {
    const SignalPath& a = a_set.paths[j];
    const SignalPath& b = b_set.paths[j];
    EXPECT_EQ(a.type, b.type) << what;
    EXPECT_EQ(a.reflections, b.reflections) << what;
    EXPECT_EQ(a.excess_delay_m, b.excess_delay_m) << what;
    EXPECT_EQ(a.rhcp_amplitude, b.rhcp_amplitude) << what;
    EXPECT_EQ(a.lhcp_amplitude, b.lhcp_amplitude) << what;
    EXPECT_EQ(a.point_m, b.point_m) << what;
    EXPECT_EQ(a.arrival_direction, b.arrival_direction) << what;
  }
}

TEST(Propagation, StaticAntennaIndexGivesTheSamePathsAsTheFullSearch) {
  const WorldModel w = blocks_world();
  const PathSearchSettings settings = nlos_models();
  const std::vector<Eigen::Vector3d> sky = fibonacci_sky(3000);
  int reflections = 0, double_bounces = 0, diffracted_reflections = 0, knife_edges = 0;
  for (const Eigen::Vector3d& rx : {Eigen::Vector3d(2.0, 3.0, 1.5), Eigen::Vector3d(-12.0, 1.0, 1.5), Eigen::Vector3d(10.0, -8.0, 20.0)}) {
    const auto full = propagation(w)->paths(rx, sky, settings);
    const auto scene = propagation(w);
    (void)scene->paths(rx, sky, settings);                      // first call at the point: full search
    (void)scene->paths(rx, sky, settings);                      // second: builds the index
    const auto indexed = scene->paths(rx, sky, settings);       // third: from the index
    ASSERT_EQ(full.size(), indexed.size());
    for (std::size_t i = 0; i < full.size(); ++i) {
      ASSERT_EQ(full[i].paths.size(), indexed[i].paths.size()) << "direction " << i;
      for (std::size_t j = 0; j < full[i].paths.size(); ++j) {
        const SignalPath& a = full[i].paths[j];
        const SignalPath& b = indexed[i].paths[j];
        EXPECT_EQ(a.type, b.type);
        EXPECT_EQ(a.reflections, b.reflections);
        EXPECT_EQ(a.excess_delay_m, b.excess_delay_m);
        EXPECT_EQ(a.rhcp_amplitude, b.rhcp_amplitude);
        EXPECT_EQ(a.point_m, b.point_m);
        EXPECT_EQ(a.second_point_m, b.second_point_m);
        EXPECT_EQ(a.diffraction_v, b.diffraction_v);
        reflections += a.type == PathType::kReflected && a.reflections == 1 ? 1 : 0;
        double_bounces += a.type == PathType::kReflected && a.reflections == 2 ? 1 : 0;
        diffracted_reflections += a.type == PathType::kDiffracted && a.reflections == 1 ? 1 : 0;
        knife_edges += a.type == PathType::kDiffracted && a.reflections == 0 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(reflections, 100);  // enough to mean something
  EXPECT_GT(double_bounces, 100);
  EXPECT_GT(diffracted_reflections, 100);
  EXPECT_GT(knife_edges, 100);
}

// Sky cells (static_sky_cell_deg) rest on this: a direction's paths do not depend on the other
// directions searched with it.
TEST(Propagation, EachDirectionGetsThePathsItGetsAlone) {
  const WorldModel w = blocks_world();
  const PathSearchSettings settings = nlos_models();
  const std::vector<Eigen::Vector3d> sky = fibonacci_sky(400);
  const Eigen::Vector3d rx(2.0, 3.0, 1.5);
  const auto together = propagation(w)->paths(rx, sky, settings);
  const auto scene = propagation(w);
  int with_paths = 0;
  for (std::size_t i = 0; i < sky.size(); i += 3) {
    const auto alone = scene->paths(rx, {sky[i]}, settings);
    expect_same_paths(together[i], alone[0], "direction " + std::to_string(i));
    with_paths += together[i].direct.blocked && !together[i].paths.empty() ? 1 : 0;
  }
  EXPECT_GT(with_paths, 10);  // blocked directions with paths: the searches that matter
}

// A static antenna's sky cells: each direction gets the paths searched at its cell's centre, the
// excess delays carried to it by their gradients: exact for reflections (their excess is linear in
// the direction), within micrometres for diffractions at the default 0.05 deg.
TEST(Propagation, StaticSkyCellsGiveTheirCentresPathsCarriedToTheDirection) {
  const WorldModel w = blocks_world();
  PathSearchSettings exact = nlos_models();
  PathSearchSettings celled = exact;
  celled.static_sky_cell_deg = 0.05;
  const std::vector<Eigen::Vector3d> sky = fibonacci_sky(600);
  const Eigen::Vector3d rx(2.0, 3.0, 1.5);
  const auto scene = propagation(w);
  const auto by_cell = scene->paths(rx, sky, celled);
  const auto at_direction = propagation(w)->paths(rx, sky, exact);
  std::vector<Eigen::Vector3d> centres;
  for (const Eigen::Vector3d& s : sky) centres.push_back(sky_cell_centre(s, celled.static_sky_cell_deg));
  const auto at_centre = propagation(w)->paths(rx, centres, exact);
  int compared_reflections = 0, compared_diffractions = 0;
  for (std::size_t i = 0; i < sky.size(); ++i) {
    const std::string what = "direction " + std::to_string(i);
    EXPECT_LT(std::acos(std::min(1.0, sky[i].dot(centres[i]))), 0.05 * kDeg) << what;
    ASSERT_EQ(by_cell[i].paths.size(), at_centre[i].paths.size()) << what;
    for (std::size_t j = 0; j < by_cell[i].paths.size(); ++j) {
      const SignalPath& carried = by_cell[i].paths[j];
      const SignalPath& centre = at_centre[i].paths[j];
      EXPECT_EQ(carried.type, centre.type) << what;
      EXPECT_EQ(carried.rhcp_amplitude, centre.rhcp_amplitude) << what;
      if (carried.type == PathType::kDirect) {
        EXPECT_EQ(carried.arrival_direction, sky[i]) << what;
        continue;
      }
      EXPECT_DOUBLE_EQ(carried.excess_delay_m,
                       std::max(centre.excess_delay_m + centre.delay_gradient_direction.dot(sky[i] - centres[i]), 0.0))
          << what;
      // The same path searched at the direction itself: of the same kind, off the same object, the
      // nearest point.
      const SignalPath* own = nullptr;
      for (const SignalPath& p : at_direction[i].paths) {
        if (p.type != carried.type || p.reflections != carried.reflections || p.object != carried.object) continue;
        if (own == nullptr || (p.point_m - carried.point_m).norm() < (own->point_m - carried.point_m).norm()) own = &p;
      }
      if (own == nullptr || (own->point_m - carried.point_m).norm() > 1.0) continue;
      if (carried.type == PathType::kReflected) {
        EXPECT_NEAR(carried.excess_delay_m, own->excess_delay_m, 1e-9) << what;
        ++compared_reflections;
      } else if (carried.type == PathType::kDiffracted) {
        EXPECT_NEAR(carried.excess_delay_m, own->excess_delay_m, 1e-4) << what;  // 6 um at most
        ++compared_diffractions;
      } else {
        // A scattered path's excess is the power-weighted mean over 2 m patches, which steps as
        // patches are lit or shadowed: up to 0.15 m between the centre and the direction here.
        EXPECT_NEAR(carried.excess_delay_m, own->excess_delay_m, 0.25) << what;
      }
    }
  }
  EXPECT_GT(compared_reflections, 100);
  EXPECT_GT(compared_diffractions, 100);
}

bool is_far_kind(const SignalPath& p) {  // what a moving antenna takes from its cube's centre
  return p.type == PathType::kScattered || (p.type == PathType::kReflected && p.reflections == 2) ||
         (p.type == PathType::kDiffracted && p.reflections == 1);
}

// A moving antenna's cubes (moving_cell_m): the direct paths, single reflections and knife edges are
// those of the search at the antenna itself, the same values; the second-order and scattered paths
// are those searched at the cube's centre for the directions' sky-cell centres, their excess delays
// carried to the antenna and the direction by their gradients (scattering kept for a satellite
// hidden from the antenna, as the search at the antenna keeps it).
TEST(Propagation, MovingCellsTakeNearPathsAtTheAntennaAndTheRestFromTheCubesCentre) {
  const WorldModel w = blocks_world();
  const PathSearchSettings exact = nlos_models();
  PathSearchSettings celled = exact;
  celled.moving_cell_m = 3.0;
  const std::vector<Eigen::Vector3d> sky = fibonacci_sky(600);
  int near = 0, far = 0, carried_off_centre = 0;
  for (const Eigen::Vector3d& rx : {Eigen::Vector3d(2.0, 3.0, 1.5), Eigen::Vector3d(-12.0, 1.0, 1.5), Eigen::Vector3d(0.7, -8.2, 2.4)}) {
    const auto by_cell = propagation(w)->paths(rx, sky, celled);
    const auto at_antenna = propagation(w)->paths(rx, sky, exact);
    const Eigen::Vector3d centre = moving_cell_centre(rx, celled.moving_cell_m);
    EXPECT_LE((centre - rx).cwiseAbs().maxCoeff(), 1.5);
    std::vector<Eigen::Vector3d> centres;
    for (const Eigen::Vector3d& s : sky) centres.push_back(sky_cell_centre(s, PathSearchSettings::kMovingSkyCell_deg));
    const auto at_centre = propagation(w)->paths(centre, centres, exact);
    for (std::size_t i = 0; i < sky.size(); ++i) {
      const std::string what = "direction " + std::to_string(i);
      EXPECT_EQ(by_cell[i].direct.blocked, at_antenna[i].direct.blocked) << what;
      // Per kind in power order, as each search lists them.
      for (const bool far_kind : {false, true}) {
        std::vector<SignalPath> got, want;
        for (const SignalPath& p : by_cell[i].paths) {
          if (is_far_kind(p) == far_kind) got.push_back(p);
        }
        for (const SignalPath& p : far_kind ? at_centre[i].paths : at_antenna[i].paths) {
          if (is_far_kind(p) != far_kind) continue;
          if (far_kind && p.type == PathType::kScattered && !at_antenna[i].direct.blocked) continue;
          want.push_back(p);
        }
        ASSERT_EQ(got.size(), want.size()) << what << (far_kind ? " far" : " near");
        for (std::size_t j = 0; j < got.size(); ++j) {
          EXPECT_EQ(got[j].type, want[j].type) << what;
          EXPECT_EQ(got[j].reflections, want[j].reflections) << what;
          EXPECT_EQ(got[j].rhcp_amplitude, want[j].rhcp_amplitude) << what;
          EXPECT_EQ(got[j].point_m, want[j].point_m) << what;
          if (!far_kind) {
            EXPECT_EQ(got[j].excess_delay_m, want[j].excess_delay_m) << what;
            ++near;
            continue;
          }
          const double carried = std::max(want[j].excess_delay_m + want[j].delay_gradient_direction.dot(sky[i] - centres[i]), 0.0);
          EXPECT_DOUBLE_EQ(got[j].excess_delay_m, std::max(carried + want[j].delay_gradient_origin.dot(rx - centre), 0.0)) << what;
          carried_off_centre += got[j].excess_delay_m != want[j].excess_delay_m ? 1 : 0;
          ++far;
        }
      }
    }
  }
  EXPECT_GT(near, 300);  // enough of each to mean something
  EXPECT_GT(far, 100);
  EXPECT_GT(carried_off_centre, 100);
}

// A double bounce's excess is linear in the antenna's position (its image in both planes): carried
// from the cube's centre it is the excess searched at the antenna, wherever the path exists at both.
TEST(Propagation, MovingCellsCarryDoubleBouncesExactly) {
  const WorldModel w = blocks_world();
  PathSearchSettings exact = nlos_models();
  exact.scattering_coefficient = 0.0;
  PathSearchSettings celled = exact;
  celled.moving_cell_m = 2.0;
  // Directions at their sky cells' centres: only the antenna's offset is carried.
  std::vector<Eigen::Vector3d> sky;
  for (const Eigen::Vector3d& s : fibonacci_sky(600)) sky.push_back(sky_cell_centre(s, PathSearchSettings::kMovingSkyCell_deg));
  int compared = 0;
  for (const Eigen::Vector3d& rx : {Eigen::Vector3d(2.0, 3.0, 1.5), Eigen::Vector3d(-12.0, 1.0, 1.5)}) {
    const auto by_cell = propagation(w)->paths(rx, sky, celled);
    const auto at_antenna = propagation(w)->paths(rx, sky, exact);
    for (std::size_t i = 0; i < sky.size(); ++i) {
      for (const SignalPath& carried : by_cell[i].paths) {
        if (carried.type != PathType::kReflected || carried.reflections != 2) continue;
        // The same two facets: the same object and material, the points within the antenna's offset.
        for (const SignalPath& own : at_antenna[i].paths) {
          if (own.type != carried.type || own.reflections != 2 || own.object != carried.object) continue;
          if ((own.point_m - carried.point_m).norm() > 2.0 || (own.second_point_m - carried.second_point_m).norm() > 2.0) continue;
          if ((own.delay_gradient_origin - carried.delay_gradient_origin).norm() > 1e-9) continue;  // another pair of planes
          EXPECT_NEAR(carried.excess_delay_m, own.excess_delay_m, 1e-9) << "direction " << i;
          ++compared;
          break;
        }
      }
    }
  }
  EXPECT_GT(compared, 20);
}

// The sky turned by step_deg more at each of `epochs` epochs, about a fixed axis.
std::vector<std::vector<Eigen::Vector3d>> turning_sky(const std::vector<Eigen::Vector3d>& sky, int epochs, double step_deg) {
  std::vector<std::vector<Eigen::Vector3d>> out;
  for (int k = 0; k < epochs; ++k) {
    const Eigen::AngleAxisd turn(step_deg * k * kDeg, Eigen::Vector3d(0.3, -0.2, 1.0).normalized());
    std::vector<Eigen::Vector3d> turned;
    for (const Eigen::Vector3d& s : sky) turned.push_back(turn * s);
    out.push_back(std::move(turned));
  }
  return out;
}

// Two scenes asked the same epochs (antenna k, directions k) in opposite orders, as threads sharing
// a scene may ask them, answer alike.
void expect_alike_in_either_order(const WorldModel& w, const PathSearchSettings& settings, const std::vector<Eigen::Vector3d>& antenna,
                                  const std::vector<std::vector<Eigen::Vector3d>>& epochs) {
  const auto forwards = propagation(w);
  const auto backwards = propagation(w);
  std::vector<std::vector<PathSet>> first(epochs.size()), second(epochs.size());
  for (std::size_t k = 0; k < epochs.size(); ++k) first[k] = forwards->paths(antenna[k], epochs[k], settings);
  for (std::size_t k = epochs.size(); k-- > 0;) second[k] = backwards->paths(antenna[k], epochs[k], settings);
  for (std::size_t k = 0; k < epochs.size(); ++k) {
    for (std::size_t i = 0; i < epochs[k].size(); ++i) {
      expect_same_paths(first[k][i], second[k][i], "epoch " + std::to_string(k) + " direction " + std::to_string(i));
    }
  }
}

// What a cube answers depends on the cube and the sky cells alone.
TEST(Propagation, MovingCellsAnswerAlikeWhateverWasAskedBefore) {
  PathSearchSettings settings = nlos_models();
  settings.moving_cell_m = 3.0;
  std::vector<Eigen::Vector3d> antenna;
  for (int k = 0; k < 8; ++k) antenna.emplace_back(-14.0 + 1.1 * k, 1.0, 1.5);  // 1.1 m per epoch: cubes met more than once
  expect_alike_in_either_order(blocks_world(), settings, antenna, turning_sky(fibonacci_sky(150), 8, 0.4));
}

// What a cell answers depends on the cell alone.
TEST(Propagation, StaticSkyCellsAnswerAlikeWhateverWasAskedBefore) {
  PathSearchSettings settings = nlos_models();
  settings.static_sky_cell_deg = 0.05;
  const std::vector<Eigen::Vector3d> antenna(6, Eigen::Vector3d(-12.0, 1.0, 1.5));
  expect_alike_in_either_order(blocks_world(), settings, antenna, turning_sky(fibonacci_sky(150), 6, 0.02));
}

// The excess delay of the path diffracted once and reflected once, moved a little from the
// receiver and the satellite direction, against its gradients (the Doppler's excess-delay rate).
void expect_diffracted_reflection_gradients(const PropagationScene& scene, const Eigen::Vector3d& rx,
                                            const Eigen::Vector3d& s, const PathSearchSettings& settings,
                                            const SignalPath& path) {
  const auto excess_at = [&](const Eigen::Vector3d& at, const Eigen::Vector3d& towards) {
    const std::vector<PathSet> sets = scene.paths(at, {towards}, settings);
    for (const SignalPath& p : sets[0].paths) {
      if (p.type == PathType::kDiffracted && p.reflections == 1) return p.excess_delay_m;
    }
    ADD_FAILURE() << "path lost";
    return 0.0;
  };
  const double step = 1e-4;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d dr = Eigen::Vector3d::Unit(axis) * step;
    EXPECT_NEAR(excess_at(rx + dr, s) - path.excess_delay_m, path.delay_gradient_origin.dot(dr), 1e-7) << axis;
    const Eigen::Vector3d turned = (s + Eigen::Vector3d::Unit(axis) * step).normalized();
    EXPECT_NEAR(excess_at(rx, turned) - path.excess_delay_m, path.delay_gradient_direction.dot(turned - s), 1e-6) << axis;
  }
}

TEST(Propagation, OverTheRoofAcrossTheStreetThenOffTheFacadeBehind) {
  // A satellite low in the north, hidden by the north wall (30 m, its south face at y = 9.5):
  // over that wall's top edge, down onto the south wall's face (y = -19.5) and back to the
  // receiver. Seen from the receiver's image in the south face (y = -39) the edge point is the
  // knife edge's; the reflection point is where the line from it to the image crosses the face.
  const auto scene = propagation(canyon(false));
  const Eigen::Vector3d rx(0.0, 0.0, 1.5);
  const double el = 25.0;
  const Eigen::Vector3d s = enu_direction(0.0, el);
  PathSearchSettings settings;
  settings.max_reflection_order = 2;
  const PathSet set = scene->paths(rx, {s}, settings)[0];
  ASSERT_TRUE(set.direct.blocked);
  // The image's own line to the satellite passes below the edge (1.5 + 48.5 tan 25 = 24.1 m < 30):
  // no plain reflection off the south wall.
  EXPECT_EQ(find_path(set, PathType::kReflected, 1), nullptr);
  const SignalPath* over_and_back = nullptr;
  for (const SignalPath& p : set.paths) {
    if (p.type == PathType::kDiffracted && p.reflections == 1) over_and_back = &p;
  }
  ASSERT_NE(over_and_back, nullptr);
  const Eigen::Vector3d image(0.0, -39.0, 1.5);
  const Eigen::Vector3d edge(0.0, 9.5, 30.0);  // the top of the south face (the north one is hidden behind it)
  EXPECT_NEAR((over_and_back->second_point_m - edge).norm(), 0.0, 1e-6);
  EXPECT_EQ(over_and_back->object, "south");
  EXPECT_NEAR(over_and_back->point_m.y(), -19.5, 1e-6);
  const double t = (edge.y() + 19.5) / (edge.y() - image.y());
  EXPECT_NEAR(over_and_back->point_m.z(), edge.z() + t * (image.z() - edge.z()), 1e-6);
  EXPECT_NEAR(over_and_back->excess_delay_m, (edge - image).norm() - s.dot(edge - rx), 1e-6);
  const double v = std::sqrt(4.0 * ((edge - image).norm() - s.dot(edge - image)) / kL1WavelengthM);
  EXPECT_NEAR(over_and_back->diffraction_v, v, 1e-6);
  EXPECT_NEAR(over_and_back->diffraction_loss_db, knife_edge_loss_db(v), 1e-9);
  // Weaker than the knife edge alone by the reflection (concrete, incidence from the edge).
  EXPECT_LT(over_and_back->power_linear(), std::pow(10.0, -knife_edge_loss_db(v) / 10.0));
  EXPECT_GT(over_and_back->power_linear(), std::pow(10.0, -(knife_edge_loss_db(v) + 15.0) / 10.0));
  // Its delay gradients against finite differences (the Doppler's excess-delay rate).
  expect_diffracted_reflection_gradients(*scene, rx, s, settings, *over_and_back);
  // A first-order search does not look for it.
  settings.max_reflection_order = 1;
  const std::vector<PathSet> first_order = scene->paths(rx, {s}, settings);
  for (const SignalPath& p : first_order[0].paths) {
    EXPECT_FALSE(p.type == PathType::kDiffracted && p.reflections == 1);
  }
}

TEST(Propagation, OffTheFacadeThenOverTheLowBlockInBetween) {
  // A satellite low in the south (in view), its reflection off a tall wall 29.5 m north hidden from
  // the receiver by an 8 m block between them (y = 10-11): the reflected wave, a plane wave from the
  // satellite's direction mirrored in the wall (north, 20 deg), bends over the block's near top
  // edge down to the receiver.
  WorldModel w;
  w.objects.push_back(placed("wall", make_box({200, 1, 60}), {0, 30, 30}, MaterialClass::kConcrete));
  w.objects.push_back(placed("block", make_box({200, 1, 8}), {0, 10.5, 4}, MaterialClass::kConcrete));
  const auto scene = propagation(w);
  const Eigen::Vector3d rx(0.0, 0.0, 1.5);
  const Eigen::Vector3d s = enu_direction(180.0, 20.0);
  PathSearchSettings settings;
  settings.max_reflection_order = 2;
  const PathSet set = scene->paths(rx, {s}, settings)[0];
  ASSERT_FALSE(set.direct.blocked);
  for (const SignalPath& p : set.paths) {
    EXPECT_FALSE(p.type == PathType::kReflected && p.object == "wall");  // that reflection is hidden
  }
  const SignalPath* round = nullptr;
  for (const SignalPath& p : set.paths) {
    if (p.type == PathType::kDiffracted && p.reflections == 1) round = &p;
  }
  ASSERT_NE(round, nullptr);
  const Eigen::Vector3d edge(0.0, 10.0, 8.0);  // the block's top edge on the receiver's side
  const Eigen::Vector3d mirrored = enu_direction(0.0, 20.0);
  EXPECT_NEAR((round->point_m - edge).norm(), 0.0, 1e-6);
  EXPECT_EQ(round->object, "block");
  // Back from the edge along the mirrored direction to the wall's face (y = 29.5).
  const double back = (29.5 - edge.y()) / mirrored.y();
  EXPECT_NEAR((round->second_point_m - (edge + back * mirrored)).norm(), 0.0, 1e-6);
  const double edge_excess = (edge - rx).norm() - mirrored.dot(edge - rx);
  EXPECT_NEAR(round->excess_delay_m, edge_excess + 2.0 * 29.5 * std::cos(20.0 * kDeg), 1e-6);
  EXPECT_NEAR(round->diffraction_v, std::sqrt(4.0 * edge_excess / kL1WavelengthM), 1e-6);
  EXPECT_LT(round->power_linear(), std::pow(10.0, -round->diffraction_loss_db / 10.0));
  // Its delay gradients against finite differences (the Doppler's excess-delay rate).
  expect_diffracted_reflection_gradients(*scene, rx, s, settings, *round);
  // A first-order search does not look for it.
  settings.max_reflection_order = 1;
  const std::vector<PathSet> first_order = scene->paths(rx, {s}, settings);
  for (const SignalPath& p : first_order[0].paths) {
    EXPECT_FALSE(p.type == PathType::kDiffracted && p.reflections == 1);
  }
}

TEST(Propagation, ReflectionPointMustLieOnTheFacet) {
  // A 4 m wide wall 10 m east: satellites to the east-north-east reflect only while the specular
  // point stays within the wall's 4 m.
  WorldModel world;
  world.objects.push_back(placed("wall", make_box({1, 4, 10}), {10.5, 0, 5}, MaterialClass::kBrick));
  const auto scene = propagation(world);
  const Eigen::Vector3d rx(0.0, 0.0, 1.5);
  PathSearchSettings settings;
  settings.diffraction = false;
  // The satellite is west so the east wall's west face is lit; specular point y = 10 tan(az offset).
  for (const double az : {270.0, 280.0, 290.0}) {
    const auto sets = scene->paths(rx, {enu_direction(az, 20.0)}, settings);
    const double y = 10.0 * std::tan((270.0 - az) * kDeg);
    const SignalPath* r = find_path(sets[0], PathType::kReflected, 1);
    if (std::abs(y) <= 2.0) {
      ASSERT_NE(r, nullptr) << az;
      EXPECT_NEAR(r->point_m.y(), -y, 1e-6);
    } else {
      EXPECT_EQ(r, nullptr) << az;
    }
  }
}

TEST(Propagation, DelayGradientsMatchFiniteDifferences) {
  const auto scene = propagation(canyon());
  const Eigen::Vector3d rx(1.0, 2.0, 1.5);
  PathSearchSettings settings;
  settings.max_reflection_order = 2;
  const Eigen::Vector3d s = enu_direction(10.0, 40.0);
  const auto base = scene->paths(rx, {s}, settings)[0];
  ASSERT_GE(base.paths.size(), 2u);
  const double step = 1e-4;
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d dr = Eigen::Vector3d::Unit(axis) * step;
    const auto moved = scene->paths(rx + dr, {s}, settings)[0];
    const Eigen::Vector3d ds = (s + Eigen::Vector3d::Unit(axis) * step).normalized() - s;
    const auto turned = scene->paths(rx, {(s + Eigen::Vector3d::Unit(axis) * step).normalized()}, settings)[0];
    ASSERT_EQ(moved.paths.size(), base.paths.size());
    ASSERT_EQ(turned.paths.size(), base.paths.size());
    for (std::size_t k = 0; k < base.paths.size(); ++k) {
      const SignalPath& p = base.paths[k];
      EXPECT_NEAR(moved.paths[k].excess_delay_m - p.excess_delay_m, p.delay_gradient_origin.dot(dr), 1e-7) << k;
      EXPECT_NEAR(turned.paths[k].excess_delay_m - p.excess_delay_m, p.delay_gradient_direction.dot(ds), 1e-6) << k;
    }
  }
}

TEST(Propagation, DiffractionOverTheRoofEdge) {
  const auto scene = propagation(canyon(false));
  const Eigen::Vector3d rx(0.0, 0.0, 1.5);
  PathSearchSettings settings;
  settings.max_reflection_order = 0;
  // Roof edge of the north wall's south face: y = 9.5, z = 30, seen at atan(28.5 / 9.5) = 71.57 deg.
  const Eigen::Vector3d edge_point(0.0, 9.5, 30.0);
  const double edge_el = std::atan2(28.5, 9.5) / kDeg;
  for (const double el : {edge_el - 8.0, edge_el - 3.0, edge_el - 0.5}) {
    const Eigen::Vector3d s = enu_direction(0.0, el);
    const auto set = scene->paths(rx, {s}, settings)[0];
    ASSERT_TRUE(set.direct.blocked);
    const SignalPath* d = find_path(set, PathType::kDiffracted);
    ASSERT_NE(d, nullptr) << el;
    EXPECT_NEAR((d->point_m - edge_point).norm(), 0.0, 1e-6);
    // P.526 in its small-angle form: v = h sqrt(2 / (lambda d)), h the edge's clearance above the
    // direct ray, d the distance along it (the satellite at infinity).
    const Eigen::Vector3d to_edge = edge_point - rx;
    const double along = s.dot(to_edge);
    const double h = (to_edge - along * s).norm();
    const double v = h * std::sqrt(2.0 / (kL1WavelengthM * along));
    EXPECT_NEAR(d->diffraction_v, v, 0.01 * v) << el;
    EXPECT_NEAR(d->diffraction_loss_db, knife_edge_loss_db(v), 0.1);
    EXPECT_NEAR(d->relative_power_db(), -knife_edge_loss_db(d->diffraction_v), 1e-9);
    EXPECT_NEAR(d->excess_delay_m, to_edge.norm() - along, 1e-9);
  }
  // Line of sight just clearing the edge (1 cm): about 6 dB lost; well clear: nothing.
  const double grazing_el = std::atan2(28.5 + 0.01 / std::cos(edge_el * kDeg), 9.5) / kDeg;
  const auto grazing = scene->paths(rx, {enu_direction(0.0, grazing_el)}, settings)[0];
  ASSERT_FALSE(grazing.direct.blocked);
  ASSERT_EQ(grazing.paths.front().type, PathType::kDirect);
  EXPECT_NEAR(grazing.paths.front().diffraction_loss_db, 6.0, 0.1);
  EXPECT_NEAR(grazing.paths.front().relative_power_db(), -grazing.paths.front().diffraction_loss_db, 1e-9);
  const auto clear = scene->paths(rx, {enu_direction(0.0, 80.0)}, settings)[0];
  EXPECT_EQ(clear.paths.front().diffraction_loss_db, 0.0);
  EXPECT_NEAR(clear.paths.front().relative_power_db(), 0.0, 1e-12);
}

TEST(Propagation, DefaultPathQueryGivesTheDirectPathOnly) {
  const WorldModel world = canyon();
  auto embree = EmbreeScene::build(world);
  ASSERT_TRUE(embree.ok());
  const PathQuery& plain = **embree;
  const auto sets = plain.paths({0, 0, 1.5}, {enu_direction(0, 30), enu_direction(90, 30)}, PathSearchSettings{});
  ASSERT_EQ(sets.size(), 2u);
  EXPECT_TRUE(sets[0].paths.empty());
  ASSERT_EQ(sets[1].paths.size(), 1u);
  EXPECT_EQ(sets[1].paths[0].type, PathType::kDirect);
}

}  // namespace
}  // namespace skytrace::world

namespace skytrace::world {
namespace {

// A concrete wall of the given size centred at `centre` (its south face at y = 10 m when 1 m thick
// at y = 10.5), and a 10 m high block 5 m south of the origin that hides satellites low in the south.
std::unique_ptr<PropagationScene> wall_behind_block(const Eigen::Vector3d& wall_size, const Eigen::Vector3d& centre) {
  WorldModel w;
  w.objects.push_back(placed("wall", make_box(wall_size), centre, MaterialClass::kConcrete));
  w.objects.push_back(placed("block", make_box({40, 1, 10}), {0, -5, 5}, MaterialClass::kConcrete));
  return propagation(w);
}

// Diffuse scattering only, as the scattering tests search.
PathSearchSettings scattering_only() {
  PathSearchSettings settings;
  settings.diffraction = false;
  settings.max_reflection_order = 1;
  settings.scattering_coefficient = 0.4;
  return settings;
}

// Diffuse scattering (effective roughness, Lambertian): a satellite hidden by a low block to the
// south lights a 40 x 20 m wall 10 m north of the receiver from above the block; the wall's
// scattered power is the integral of S^2 |Gamma|^2 cos(theta_i) cos(theta_s) / (pi d^2) over its
// lit part, here summed on a 0.1 m grid independently of the 2 m patches of the model.
TEST(Propagation, DiffuseScatteringOffALitWallMatchesTheLambertianIntegral) {
  const auto scene = wall_behind_block({40, 1, 20}, {0, 10.5, 10});
  const Eigen::Vector3d rx(0.0, 0.0, 1.5);
  const Eigen::Vector3d s = enu_direction(180.0, 30.0);
  PathSearchSettings settings = scattering_only();
  settings.min_relative_power_db = -60.0;
  const PathSet set = scene->paths(rx, {s}, settings)[0];
  ASSERT_TRUE(set.direct.blocked);
  const SignalPath* scattered = find_path(set, PathType::kScattered);
  ASSERT_NE(scattered, nullptr);
  EXPECT_EQ(scattered->object, "wall");
  EXPECT_NEAR(std::norm(scattered->rhcp_amplitude), std::norm(scattered->lhcp_amplitude), 1e-15);  // depolarised

  const FresnelCoefficients gamma = fresnel_coefficients(complex_permittivity(MaterialClass::kConcrete, 1575.42e6), s.dot(-Eigen::Vector3d::UnitY()));
  const double reradiated = 0.5 * (std::norm(gamma.te) + std::norm(gamma.tm));
  const double cos_i = -s.y();
  double power = 0.0, weighted_excess = 0.0;
  constexpr double kStep = 0.1;
  for (double x = -20.0 + kStep / 2; x < 20.0; x += kStep) {
    for (double z = kStep / 2; z < 20.0; z += kStep) {
      // Lit when the ray towards the satellite clears the block's 10 m top at its north face (y = -4.5).
      if (z + 14.5 * std::tan(30.0 * kDeg) <= 10.0) continue;
      const Eigen::Vector3d p(x, 10.0, z);
      const Eigen::Vector3d to_p = p - rx;
      const double d = to_p.norm();
      const double cos_s = to_p.y() / d;
      const double dp = 0.16 * reradiated * kStep * kStep * cos_i * cos_s / (std::numbers::pi * d * d);
      power += dp;
      weighted_excess += dp * (d - s.dot(to_p));
    }
  }
  EXPECT_NEAR(scattered->power_linear() / power, 1.0, 0.05) << 10 * std::log10(power) << " dB expected";
  EXPECT_NEAR(scattered->excess_delay_m, weighted_excess / power, 1.0);
  EXPECT_GT(scattered->arrival_direction.y(), 0.5);  // from the wall

  // The directive lobe (n = 4) sends more towards the receiver here, which sees the wall's patches
  // near their specular direction, and less far from it (a receiver 20 m east sees them obliquely).
  PathSearchSettings directive = settings;
  directive.scattering_lobe_exponent = 4;
  const PathSet directive_set = scene->paths(rx, {s}, directive)[0];  // kept: find_path points into it
  const SignalPath* lobe = find_path(directive_set, PathType::kScattered);
  ASSERT_NE(lobe, nullptr);
  EXPECT_GT(lobe->power_linear(), 1.2 * scattered->power_linear());  // 1.4x here

  // Without scattering: no such path, and the specular reflection keeps sqrt(1 - S^2) of its amplitude.
  settings.scattering_coefficient = 0.0;
  const PathSet plain = scene->paths(rx, {s}, settings)[0];
  EXPECT_EQ(find_path(plain, PathType::kScattered), nullptr);
  const SignalPath* specular = find_path(plain, PathType::kReflected, 1);
  const SignalPath* reduced = find_path(set, PathType::kReflected, 1);
  ASSERT_NE(specular, nullptr);
  ASSERT_NE(reduced, nullptr);
  EXPECT_NEAR(reduced->power_linear() / specular->power_linear(), 1.0 - 0.16, 1e-9);
  // A satellite in view gets no scattered path (the model is for NLOS reception).
  settings.scattering_coefficient = 0.4;
  const PathSet open = scene->paths(rx, {enu_direction(0.0, 80.0)}, settings)[0];
  EXPECT_FALSE(open.direct.blocked);
  EXPECT_EQ(find_path(open, PathType::kScattered), nullptr);
}

// The receiver traces no ray to the patches of a facet whose scattered power cannot reach the
// threshold: a bound on each patch's power, summed over the facet. A 4 x 2 m wall (two patches of
// 2 m) lit over a block keeps its path with the threshold just below its power, with and without the
// directive lobe, and the path the same to the bit; just above, none.
TEST(Propagation, ScatteringKeepsAFacetWhosePowerJustReachesTheThreshold) {
  const auto scene = wall_behind_block({4, 1, 2}, {0, 10.5, 9});
  const Eigen::Vector3d rx(0.3, 0.0, 1.5);
  const Eigen::Vector3d s = enu_direction(180.0, 30.0);
  PathSearchSettings settings = scattering_only();
  for (const int exponent : {0, 4}) {
    settings.scattering_lobe_exponent = exponent;
    settings.min_relative_power_db = -90.0;
    const PathSet reference = scene->paths(rx, {s}, settings)[0];
    ASSERT_TRUE(reference.direct.blocked);
    const SignalPath* full = find_path(reference, PathType::kScattered);
    ASSERT_NE(full, nullptr) << "exponent " << exponent;
    EXPECT_EQ(full->object, "wall");
    settings.min_relative_power_db = 10.0 * std::log10(full->power_linear()) - 0.001;
    const PathSet below = scene->paths(rx, {s}, settings)[0];
    const SignalPath* kept = find_path(below, PathType::kScattered);
    ASSERT_NE(kept, nullptr) << "exponent " << exponent;
    EXPECT_EQ(kept->power_linear(), full->power_linear());
    EXPECT_EQ(kept->excess_delay_m, full->excess_delay_m);
    settings.min_relative_power_db += 0.002;
    EXPECT_EQ(find_path(scene->paths(rx, {s}, settings)[0], PathType::kScattered), nullptr) << "exponent " << exponent;
  }
}

// A facet's scattering patches are the points of its grid that lie in one of its triangles: a
// wall's face cut into 1,600 triangles scatters what the same face as two triangles does (the
// search tries, per grid row, only the triangles that reach it; dropping one that holds a point
// would take that patch's power away).
TEST(Propagation, ScatteringPatchesOfAFaceOfManyTrianglesAreThoseOfTwo) {
  // The wall's south face, 40 x 20 m at y = 10 facing the receiver, as columns x rows squares.
  const auto south_face = [](int columns, int rows) {
    TriangleMesh mesh;
    for (int row = 0; row <= rows; ++row) {
      for (int column = 0; column <= columns; ++column) {
        mesh.vertices_m.emplace_back(-20.0F + 40.0F * static_cast<float>(column) / static_cast<float>(columns), 10.0F,
                                     20.0F * static_cast<float>(row) / static_cast<float>(rows));
      }
    }
    const auto at = [&](int column, int row) { return row * (columns + 1) + column; };
    for (int row = 0; row < rows; ++row) {
      for (int column = 0; column < columns; ++column) {  // counter-clockwise seen from the south (-y)
        mesh.triangles.emplace_back(at(column, row), at(column + 1, row), at(column, row + 1));
        mesh.triangles.emplace_back(at(column + 1, row), at(column + 1, row + 1), at(column, row + 1));
      }
    }
    return mesh;
  };
  const auto scattered_off = [&](int columns, int rows) {
    WorldModel w;
    w.objects.push_back(placed("wall", south_face(columns, rows), Eigen::Vector3d::Zero(), MaterialClass::kConcrete));
    w.objects.push_back(placed("block", make_box({40, 1, 10}), {0, -5, 5}, MaterialClass::kConcrete));
    const auto scene = propagation(w);
    PathSearchSettings settings = scattering_only();
    settings.min_relative_power_db = -60.0;
    const PathSet set = scene->paths(Eigen::Vector3d(0.0, 0.0, 1.5), {enu_direction(180.0, 30.0)}, settings)[0];
    EXPECT_TRUE(set.direct.blocked);
    const SignalPath* path = find_path(set, PathType::kScattered);
    return path != nullptr ? std::optional<SignalPath>(*path) : std::nullopt;
  };
  const std::optional<SignalPath> two = scattered_off(1, 1);
  const std::optional<SignalPath> many = scattered_off(40, 20);
  ASSERT_TRUE(two.has_value());
  ASSERT_TRUE(many.has_value());
  EXPECT_NEAR(many->power_linear() / two->power_linear(), 1.0, 1e-9);
  EXPECT_NEAR(many->excess_delay_m, two->excess_delay_m, 1e-6);
  EXPECT_LT((many->point_m - two->point_m).norm(), 1e-6);
}

}  // namespace
}  // namespace skytrace::world
