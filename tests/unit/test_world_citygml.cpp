// CityGML city models (world/citygml_loader): the CityJSON test's LoD2 house (gable roof, UTM 33N)
// as CityGML 2.0 boundary surfaces beside a LoD1 box, chosen by LoD and giving the CityJSON
// loader's geometry; CityGML 3.0 in WGS84 latitude/longitude order with gml:pos points and a
// roof with a courtyard (a hole); GML 2 coordinates; a TIN relief and a tree; errors naming the
// file and line.
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

// Area of the triangles facing down (floor) and up (roofs), m2.
std::pair<double, double> down_and_up_m2(const WorldObject& o) {
  double down = 0.0, up = 0.0;
  for (const auto& t : o.mesh.triangles) {
    const Eigen::Vector3d a = o.mesh.vertices_m[t[0]].cast<double>();
    const Eigen::Vector3d n = (o.mesh.vertices_m[t[1]].cast<double>() - a).cross(o.mesh.vertices_m[t[2]].cast<double>() - a);
    if (n.z() < -1e-6) down += 0.5 * -n.z();
    if (n.z() > 1e-6) up += 0.5 * n.z();
  }
  return {down, up};
}

// A polygon's posList from corners (x, y, z), closed.
std::string pos_list(const std::vector<std::array<double, 3>>& corners) {
  std::string s;
  for (size_t i = 0; i <= corners.size(); ++i) {
    const auto& c = corners[i % corners.size()];
    char b[96];
    std::snprintf(b, sizeof b, "%s%.3f %.3f %.3f", s.empty() ? "" : " ", c[0], c[1], c[2]);
    s += b;
  }
  return s;
}

std::string polygon(const std::vector<std::array<double, 3>>& corners) {
  return "<gml:Polygon><gml:exterior><gml:LinearRing><gml:posList srsDimension=\"3\">" + pos_list(corners) +
         "</gml:posList></gml:LinearRing></gml:exterior></gml:Polygon>";
}

// The house of test_world_cityjson.cpp (10 m east x 8 m north, walls 6 m, ridge 9 m along x, on
// z = 34 m above mean sea level) at (east, north) of UTM 33N, as CityGML 2.0: a LoD1 box of 6 m and
// the LoD2 ground, wall and roof surfaces; a TIN relief and a tree beside it.
std::string house_citygml(double e, double n, const std::string& srs) {
  using P = std::array<double, 3>;
  const auto at = [&](double x, double y, double z) { return P{e + x, n + y, z}; };
  const P f0 = at(0, 0, 34), f1 = at(10, 0, 34), f2 = at(10, 8, 34), f3 = at(0, 8, 34);
  const P e0 = at(0, 0, 40), e1 = at(10, 0, 40), e2 = at(10, 8, 40), e3 = at(0, 8, 40);
  const P r0 = at(0, 4, 43), r1 = at(10, 4, 43);
  const auto surface = [&](const std::string& type, const std::vector<P>& corners) {
    return "<bldg:boundedBy><bldg:" + type + "><bldg:lod2MultiSurface><gml:MultiSurface><gml:surfaceMember>" +
           polygon(corners) + "</gml:surfaceMember></gml:MultiSurface></bldg:lod2MultiSurface></bldg:" + type +
           "></bldg:boundedBy>";
  };
  std::string box;
  for (const auto& face : std::vector<std::vector<P>>{{f0, f3, f2, f1}, {e0, e1, e2, e3}, {f0, f1, e1, e0},
                                                      {f1, f2, e2, e1}, {f2, f3, e3, e2}, {f3, f0, e0, e3}}) {
    box += "<gml:surfaceMember>" + polygon(face) + "</gml:surfaceMember>";
  }
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<core:CityModel xmlns:core="http://www.opengis.net/citygml/2.0" xmlns:bldg="http://www.opengis.net/citygml/building/2.0"
  xmlns:dem="http://www.opengis.net/citygml/relief/2.0" xmlns:veg="http://www.opengis.net/citygml/vegetation/2.0"
  xmlns:gml="http://www.opengis.net/gml" xmlns:xlink="http://www.w3.org/1999/xlink">
  <gml:boundedBy><gml:Envelope srsName=")" + srs + R"(" srsDimension="3"><gml:lowerCorner>0 0 0</gml:lowerCorner><gml:upperCorner>1 1 1</gml:upperCorner></gml:Envelope></gml:boundedBy>
  <core:cityObjectMember><bldg:Building gml:id="house">
    <bldg:lod1Solid><gml:Solid><gml:exterior><gml:CompositeSurface>)" + box +
         R"(</gml:CompositeSurface></gml:exterior></gml:Solid></bldg:lod1Solid>
    <bldg:lod2Solid><gml:Solid><gml:exterior><gml:CompositeSurface><gml:surfaceMember xlink:href="#wall1"/></gml:CompositeSurface></gml:exterior></gml:Solid></bldg:lod2Solid>)" +
         surface("GroundSurface", {f0, f3, f2, f1}) + surface("WallSurface", {f0, f1, e1, e0}) +
         surface("WallSurface", {f1, f2, e2, r1, e1}) + surface("WallSurface", {f2, f3, e3, e2}) +
         surface("WallSurface", {f3, f0, e0, r0, e3}) + surface("RoofSurface", {e0, e1, r1, r0}) +
         surface("RoofSurface", {e3, r0, r1, e2}) + R"(
  </bldg:Building></core:cityObjectMember>
  <core:cityObjectMember><dem:ReliefFeature gml:id="relief"><dem:lod>1</dem:lod><dem:reliefComponent><dem:TINRelief gml:id="tin"><dem:lod>1</dem:lod>
    <dem:tin><gml:TriangulatedSurface><gml:trianglePatches><gml:Triangle><gml:exterior><gml:LinearRing><gml:posList>)" +
         pos_list({at(-20, -20, 34), at(30, -20, 34), at(5, 30, 34)}) + R"(</gml:posList></gml:LinearRing></gml:exterior></gml:Triangle>
    </gml:trianglePatches></gml:TriangulatedSurface></dem:tin></dem:TINRelief></dem:reliefComponent></dem:ReliefFeature></core:cityObjectMember>
  <core:cityObjectMember><veg:SolitaryVegetationObject gml:id="hedge"><veg:lod1Geometry><gml:MultiSurface><gml:surfaceMember>)" +
         polygon({at(15, 0, 34), at(15, 8, 34), at(15, 8, 36)}) + R"(</gml:surfaceMember></gml:MultiSurface></veg:lod1Geometry>
  <veg:lod2ImplicitRepresentation><core:ImplicitGeometry><core:relativeGMLGeometry>)" +
         polygon({{0, 0, 0}, {1, 0, 0}, {1, 1, 5}}) + R"(</core:relativeGMLGeometry></core:ImplicitGeometry></veg:lod2ImplicitRepresentation>
  </veg:SolitaryVegetationObject></core:cityObjectMember>
</core:CityModel>
)";
}

TEST(WorldCityGml, Lod2HouseReliefAndVegetationInUtmAsCityJsonGivesThem) {
  const auto dir = test::make_temp_dir("world_citygml");
  const double lat = 52.5086, lon = 13.3723;
  int zone = 0;
  bool north = true;
  double x = 0.0, y = 0.0;
  GeographicLib::UTMUPS::Forward(lat, lon, zone, north, x, y, 33);
  const auto path = write_text(dir / "city.gml", house_citygml(x, y, "urn:ogc:def:crs,crs:EPSG::25833,crs:EPSG::7837"));
  CityGmlLoadOptions options;
  options.height_offset_m = 39.6;
  options.origin = Geodetic{lat, lon, 73.6};
  auto world = load_citygml_world(path, options);
  ASSERT_TRUE(world) << world.error().message;
  ASSERT_EQ(world->objects.size(), 3U);
  const WorldObject* house = find_object(*world, "/house");
  ASSERT_NE(house, nullptr);
  EXPECT_EQ(house->name, "city.gml/house");
  EXPECT_EQ(house->kind, ObjectKind::kBuilding);
  // The figures of WorldCityJson.Lod2HouseGroundAndVegetationInUtm: the same geometry.
  const auto [low, high] = object_bounds(*house);
  EXPECT_NEAR(low.z(), 0.0, 0.01);
  EXPECT_NEAR(high.z(), 9.0, 0.01);  // LoD2's ridge, not LoD1's flat 6 m
  EXPECT_NEAR(down_and_up_m2(*house).first, 80.05, 0.03);
  EXPECT_NEAR(low.x(), 0.0, 0.2);
  EXPECT_NEAR(low.y(), 0.0, 0.2);
  EXPECT_EQ(house->mesh.triangles.size(), 16U);
  const WorldObject* relief = find_object(*world, "/relief");
  ASSERT_NE(relief, nullptr);
  EXPECT_EQ(relief->kind, ObjectKind::kGround);
  EXPECT_EQ(relief->mesh.triangles.size(), 1U);
  const WorldObject* hedge = find_object(*world, "/hedge");
  ASSERT_NE(hedge, nullptr);
  EXPECT_EQ(hedge->kind, ObjectKind::kTree);
  EXPECT_TRUE(hedge->material.is_vegetation());
  // The implicit LoD2 geometry (relative coordinates) is left out: the LoD1 panel is the hedge.
  EXPECT_EQ(hedge->mesh.triangles.size(), 1U);
}

// CityGML 3.0 in EPSG:4326 (GML order: latitude first), points as gml:pos, a flat roof of 20 m x 20 m
// with a 6 m x 6 m courtyard; and a GML 2 gml:coordinates polygon.
TEST(WorldCityGml, Version3InLatitudeLongitudeOrderWithACourtyardAndGml2Coordinates) {
  const auto dir = test::make_temp_dir("world_citygml3");
  const double lat0 = 35.6580, lon0 = 139.7016;  // Shibuya
  const double dlat = 1.0 / 111000.0, dlon = 1.0 / (111320.0 * std::cos(lat0 * M_PI / 180.0));  // degrees per metre
  const auto pos = [&](double east_m, double north_m, double h) {
    char b[96];
    std::snprintf(b, sizeof b, "<gml:pos>%.9f %.9f %.3f</gml:pos>", lat0 + north_m * dlat, lon0 + east_m * dlon, h);
    return std::string(b);
  };
  const auto ring = [&](std::vector<std::array<double, 2>> corners) {
    std::string s = "<gml:LinearRing>";
    for (size_t i = 0; i <= corners.size(); ++i) s += pos(corners[i % corners.size()][0], corners[i % corners.size()][1], 50.0);
    return s + "</gml:LinearRing>";
  };
  const std::string roof = "<gml:Polygon><gml:exterior>" + ring({{0, 0}, {20, 0}, {20, 20}, {0, 20}}) +
                           "</gml:exterior><gml:interior>" + ring({{7, 7}, {7, 13}, {13, 13}, {13, 7}}) +
                           "</gml:interior></gml:Polygon>";
  char gml2[256];
  std::snprintf(gml2, sizeof gml2, "%.9f,%.9f,40 %.9f,%.9f,40 %.9f,%.9f,45", lat0 - 10 * dlat, lon0, lat0 - 10 * dlat,
                lon0 + 5 * dlon, lat0 - 10 * dlat, lon0 + 5 * dlon);
  const std::string text = R"(<?xml version="1.0"?>
<CityModel xmlns="http://www.opengis.net/citygml/3.0" xmlns:bldg="http://www.opengis.net/citygml/building/3.0"
  xmlns:gml="http://www.opengis.net/gml/3.2">
  <cityObjectMember><bldg:Building gml:id="block"><bldg:lod2MultiSurface><gml:MultiSurface srsName="http://www.opengis.net/def/crs/EPSG/0/4326" srsDimension="3">
    <gml:surfaceMember>)" + roof + R"(</gml:surfaceMember></gml:MultiSurface></bldg:lod2MultiSurface></bldg:Building></cityObjectMember>
  <cityObjectMember><bldg:Building gml:id="shed"><bldg:lod1MultiSurface><gml:MultiSurface><gml:surfaceMember>
    <gml:Polygon><gml:outerBoundaryIs><gml:LinearRing><gml:coordinates>)" + std::string(gml2) +
                           R"(</gml:coordinates></gml:LinearRing></gml:outerBoundaryIs></gml:Polygon>
  </gml:surfaceMember></gml:MultiSurface></bldg:lod1MultiSurface></bldg:Building></cityObjectMember>
</CityModel>
)";
  CityGmlLoadOptions options;
  options.height_offset_m = 36.7;
  auto world = load_citygml_world(write_text(dir / "block.gml", text), options);
  ASSERT_TRUE(world) << world.error().message;
  ASSERT_TRUE(world->geo_origin.has_value());
  EXPECT_NEAR(world->geo_origin->origin.latitude_deg, lat0, 3e-4);  // not swapped with the longitude
  EXPECT_NEAR(world->geo_origin->origin.longitude_deg, lon0, 3e-4);
  const WorldObject* block = find_object(*world, "/block");
  ASSERT_NE(block, nullptr);
  const auto [down, up] = down_and_up_m2(*block);
  EXPECT_NEAR(down + up, 400.0 - 36.0, 1.0);  // the roof less its courtyard
  const auto [low, high] = object_bounds(*block);
  EXPECT_NEAR(high.x() - low.x(), 20.0, 0.05);
  EXPECT_NEAR(high.y() - low.y(), 20.0, 0.05);
  const WorldObject* shed = find_object(*world, "/shed");
  ASSERT_NE(shed, nullptr);
  EXPECT_EQ(shed->mesh.triangles.size(), 1U);
}

TEST(WorldCityGml, BadFilesNameTheFileLineAndWhat) {
  const auto dir = test::make_temp_dir("world_citygml_bad");
  auto message = [](const std::filesystem::path& p) {
    auto w = load_citygml_world(p);
    return w ? std::string() : w.error().message;
  };
  EXPECT_NE(message(dir / "absent.gml").find("absent.gml: CityGML file not found"), std::string::npos);
  EXPECT_NE(message(write_text(dir / "broken.gml", "<CityModel>\n<a></b>")).find("broken.gml:2:"), std::string::npos)
      << message(dir / "broken.gml");
  EXPECT_NE(message(dir / "broken.gml").find("malformed XML"), std::string::npos);
  EXPECT_NE(message(write_text(dir / "sdf.gml", "<sdf version=\"1.9\"/>")).find("sdf.gml:1: not a CityGML file (root element <sdf>"),
            std::string::npos)
      << message(dir / "sdf.gml");
  const std::string house = house_citygml(390000, 5800000, "EPSG:25833");
  std::string odd = house;
  odd.replace(odd.find("<gml:posList srsDimension=\"3\">") + 30, 0, "1 ");
  EXPECT_NE(message(write_text(dir / "odd.gml", odd)).find("numbers are not points of 3 coordinates"), std::string::npos)
      << message(dir / "odd.gml");
  std::string letters = house;
  letters.replace(letters.find("<gml:posList srsDimension=\"3\">") + 30, 0, "x ");
  EXPECT_NE(message(write_text(dir / "letters.gml", letters)).find("letters.gml:7: expected numbers in <posList>"), std::string::npos)
      << message(dir / "letters.gml");
  EXPECT_NE(message(write_text(dir / "crs.gml", house_citygml(390000, 5800000, "EPSG:999999"))).find("crs.gml: srsName: EPSG:999999 is unknown to PROJ"),
            std::string::npos)
      << message(dir / "crs.gml");
  std::string no_srs = house;
  no_srs.replace(no_srs.find("srsName=\"EPSG:25833\""), std::string("srsName=\"EPSG:25833\"").size(), "");
  EXPECT_NE(message(write_text(dir / "nosrs.gml", no_srs)).find("nosrs.gml: no srsName"), std::string::npos) << message(dir / "nosrs.gml");
  EXPECT_NE(message(write_text(dir / "empty.gml", "<CityModel><cityObjectMember><Building/></cityObjectMember></CityModel>"))
                .find("empty.gml: no city object with surfaces"),
            std::string::npos)
      << message(dir / "empty.gml");
}

}  // namespace
}  // namespace skytrace::world
