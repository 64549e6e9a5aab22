// IONEX reader and evaluation on a hand-made file whose interpolated values are computed by hand,
// and the thin-shell geometry against an independent ray-sphere intersection.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/core/signal.hpp"
#include "test_support.hpp"

namespace skytrace::atmosphere {
namespace {

// Two maps one hour apart on a 3 x 3 regional grid (latitudes 50, 45, 40; longitudes 0, 10, 20).
// Map 1 in 0.1 TECU (header EXPONENT -1):   Map 2 in TECU (its own EXPONENT 0):
//   lat 50:  10  12  20                      20  22  24
//   lat 45:  20  22  30                      30  32  34
//   lat 40:  30  32  --  (9999)              40  42  44
// Map 1 is not linear in longitude, so the Earth-rotation correction changes the result.
constexpr const char* kTwoMaps =
    "     1.0            IONOSPHERE MAPS     GPS                 IONEX VERSION / TYPE\n"
    "skytrace-test       skytrace            06-JUN-16 00:00     PGM / RUN BY / DATE\n"
    "hand-made two-map file for the unit tests                   DESCRIPTION\n"
    "  2016     6     6     0     0     0                        EPOCH OF FIRST MAP\n"
    "  2016     6     6     1     0     0                        EPOCH OF LAST MAP\n"
    "  3600                                                      INTERVAL\n"
    "     2                                                      # OF MAPS IN FILE\n"
    "  COSZ                                                      MAPPING FUNCTION\n"
    "     0.0                                                    ELEVATION CUTOFF\n"
    "  6371.0                                                    BASE RADIUS\n"
    "     2                                                      MAP DIMENSION\n"
    "   450.0 450.0   0.0                                        HGT1 / HGT2 / DHGT\n"
    "    50.0  40.0  -5.0                                        LAT1 / LAT2 / DLAT\n"
    "     0.0  20.0  10.0                                        LON1 / LON2 / DLON\n"
    "    -1                                                      EXPONENT\n"
    "TEC values in 0.1 TECU; 9999 if no value available          COMMENT\n"
    "Differential code biases                                    START OF AUX DATA\n"
    "   G01    -7.612     0.004                                  PRN / BIAS / RMS\n"
    "                                                            END OF AUX DATA\n"
    "                                                            END OF HEADER\n"
    "     1                                                      START OF TEC MAP\n"
    "  2016     6     6     0     0     0                        EPOCH OF CURRENT MAP\n"
    "    50.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "  100  120  200\n"
    "    45.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "  200  220  300\n"
    "    40.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "  300  320 9999\n"
    "     1                                                      END OF TEC MAP\n"
    "     2                                                      START OF TEC MAP\n"
    "  2016     6     6     1     0     0                        EPOCH OF CURRENT MAP\n"
    "     0                                                      EXPONENT\n"
    "    50.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "   20   22   24\n"
    "    45.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "   30   32   34\n"
    "    40.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "   40   42   44\n"
    "     2                                                      END OF TEC MAP\n"
    "     1                                                      START OF RMS MAP\n"
    "  2016     6     6     0     0     0                        EPOCH OF CURRENT MAP\n"
    "    50.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "   15   15   15\n"
    "    45.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "   15   15   15\n"
    "    40.0   0.0  20.0  10.0 450.0                            LAT/LON1/LON2/DLON/H\n"
    "   15   15   15\n"
    "     1                                                      END OF RMS MAP\n"
    "                                                            END OF FILE\n";

// One global map: latitudes 87.5, 0, -87.5; longitudes -180, -60, 60, 180 (180 repeats -180).
constexpr const char* kGlobalMap =
    "     1.1            IONOSPHERE MAPS     MIX                 IONEX VERSION / TYPE\n"
    "  2016     6     6    12     0     0                        EPOCH OF FIRST MAP\n"
    "  2016     6     6    12     0     0                        EPOCH OF LAST MAP\n"
    "     0                                                      INTERVAL\n"
    "     1                                                      # OF MAPS IN FILE\n"
    "  NONE                                                      MAPPING FUNCTION\n"
    "  6371.0                                                    BASE RADIUS\n"
    "     2                                                      MAP DIMENSION\n"
    "   350.0 350.0   0.0                                        HGT1 / HGT2 / DHGT\n"
    "    87.5 -87.5 -87.5                                        LAT1 / LAT2 / DLAT\n"
    "  -180.0 180.0 120.0                                        LON1 / LON2 / DLON\n"
    "     0                                                      EXPONENT\n"
    "                                                            END OF HEADER\n"
    "     1                                                      START OF TEC MAP\n"
    "  2016     6     6    12     0     0                        EPOCH OF CURRENT MAP\n"
    "    87.5-180.0 180.0 120.0 350.0                            LAT/LON1/LON2/DLON/H\n"
    "    1    2    3    1\n"
    "     0.0-180.0 180.0 120.0 350.0                            LAT/LON1/LON2/DLON/H\n"
    "   10   20   30   10\n"
    "   -87.5-180.0 180.0 120.0 350.0                            LAT/LON1/LON2/DLON/H\n"
    "    5    5    5    5\n"
    "     1                                                      END OF TEC MAP\n";

constexpr double kTecTolerance_tecu = 1e-9;

GnssTime utc(int hour, int minute, double second) {
  return GnssTime::from_calendar(CalendarTime{2016, 6, 6, hour, minute, second}, TimeScale::kUtc);
}

IonexMaps two_maps() { return parse_ionex("test.16i", kTwoMaps).value(); }

// 1-based line number of the first line containing `text`.
size_t line_of(const std::string& content, const std::string& text) {
  const size_t at = content.find(text);
  return static_cast<size_t>(
             std::count(content.begin(), content.begin() + static_cast<long>(at), '\n')) +
         1;
}

std::string replaced(std::string content, const std::string& from, const std::string& to) {
  const size_t at = content.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return content.replace(at, from.size(), to);
}

TEST(IonexReader, HeaderAndGrid) {
  const IonexMaps maps = two_maps();
  EXPECT_EQ(maps.version, "1.0");
  EXPECT_EQ(maps.satellite_system, "GPS");
  EXPECT_EQ(maps.map_count, 2);
  EXPECT_EQ(maps.interval_s, 3600.0);
  EXPECT_EQ(maps.mapping_function, IonexMappingFunction::kCosZ);
  EXPECT_EQ(maps.base_radius_m, 6371e3);
  EXPECT_EQ(maps.shell_height_m, 450e3);
  EXPECT_EQ(maps.latitude.count(), 3u);
  EXPECT_EQ(maps.longitude.count(), 3u);
  EXPECT_EQ(maps.exponent, -1);
  ASSERT_EQ(maps.comments.size(), 1u);
  ASSERT_EQ(maps.description.size(), 1u);
  // UT epochs on the GPST timeline: 2016-06-06 00:00 UTC is 00:00:17 GPST (GPS - UTC = 17 s).
  EXPECT_EQ(maps.first_epoch,
            GnssTime::from_calendar(CalendarTime{2016, 6, 6, 0, 0, 17.0}, TimeScale::kGpst));
  EXPECT_EQ(maps.last_epoch, utc(1, 0, 0.0));
  ASSERT_EQ(maps.tec_maps.size(), 2u);
  ASSERT_EQ(maps.rms_maps.size(), 1u);
  EXPECT_EQ(maps.tec_maps[1].epoch - maps.tec_maps[0].epoch, 3600.0);
  EXPECT_EQ(maps.tec_maps[0].first_line, line_of(kTwoMaps, "START OF TEC MAP"));
}

TEST(IonexReader, ExponentAndMissingValues) {
  const IonexMaps maps = two_maps();
  const auto& m1 = maps.tec_maps[0].values_tecu;
  const auto& m2 = maps.tec_maps[1].values_tecu;
  // Header EXPONENT -1: 120 -> 12.0 TECU; the second map's EXPONENT 0: 22 -> 22 TECU.
  EXPECT_DOUBLE_EQ(m1[0 * 3 + 1], 12.0);
  EXPECT_DOUBLE_EQ(m1[2 * 3 + 1], 32.0);
  EXPECT_TRUE(std::isnan(m1[2 * 3 + 2]));  // 9999
  EXPECT_DOUBLE_EQ(m2[0 * 3 + 1], 22.0);
  EXPECT_DOUBLE_EQ(m2[2 * 3 + 2], 44.0);
  EXPECT_DOUBLE_EQ(maps.rms_maps[0].values_tecu[4], 1.5);
}

TEST(IonexReader, GzipFile) {
  const auto dir = test::make_temp_dir("ionex_gzip");
  const auto plain = dir / "test.16i";
  {
    std::ofstream out(plain);
    out << kTwoMaps;
  }
  ASSERT_EQ(std::system(("gzip -k " + plain.string()).c_str()), 0);
  auto maps = read_ionex(dir / "test.16i.gz");
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  EXPECT_EQ(maps->tec_maps.size(), 2u);
  EXPECT_DOUBLE_EQ(maps->tec_maps[0].values_tecu[1], 12.0);
  const auto missing = read_ionex(dir / "absent.16i");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
}

TEST(IonexEvaluation, BilinearInSpace) {
  const IonexIonosphere model(two_maps());
  const GnssTime t0 = utc(0, 0, 0.0);
  // Grid points.
  EXPECT_NEAR(model.vertical_tec_tecu(t0, 50.0, 0.0).value(), 10.0, kTecTolerance_tecu);
  EXPECT_NEAR(model.vertical_tec_tecu(t0, 45.0, 20.0).value(), 30.0, kTecTolerance_tecu);
  // Cell centre: (10 + 12 + 20 + 22) / 4.
  EXPECT_NEAR(model.vertical_tec_tecu(t0, 47.5, 5.0).value(), 16.0, kTecTolerance_tecu);
  // lat 48 (q = 0.4 from row 50), lon 12 (p = 0.2 from column 10):
  // 0.6*0.8*12 + 0.6*0.2*20 + 0.4*0.8*22 + 0.4*0.2*30 = 5.76 + 2.4 + 7.04 + 2.4 = 17.6.
  EXPECT_NEAR(model.vertical_tec_tecu(t0, 48.0, 12.0).value(), 17.6, kTecTolerance_tecu);
  // On the last row, next to the missing value but with zero weight on it.
  EXPECT_NEAR(model.vertical_tec_tecu(t0, 40.0, 10.0).value(), 32.0, kTecTolerance_tecu);
  // RMS map: 1.5 everywhere, a single map is only defined at its epoch.
  EXPECT_NEAR(model.vertical_rms_tecu(t0, 47.0, 7.0).value(), 1.5, kTecTolerance_tecu);
  EXPECT_FALSE(model.vertical_rms_tecu(t0 + 60.0, 47.0, 7.0).ok());
}

TEST(IonexEvaluation, MissingValueAndOutsideGridAreErrors) {
  const IonexIonosphere model(two_maps());
  const GnssTime t0 = utc(0, 0, 0.0);
  const auto missing = model.vertical_tec_tecu(t0, 42.0, 15.0);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("test.16i"), std::string::npos) << missing.error().message;
  EXPECT_NE(missing.error().message.find("9999"), std::string::npos) << missing.error().message;
  EXPECT_NE(missing.error().message.find("latitude 40 deg, longitude 20 deg"), std::string::npos)
      << missing.error().message;
  // The second map has the value: at its epoch the interpolation needs only that map.
  EXPECT_NEAR(model.vertical_tec_tecu(utc(1, 0, 0.0), 40.0, 20.0).value(), 44.0,
              kTecTolerance_tecu);

  const auto west = model.vertical_tec_tecu(t0, 45.0, -1.0);  // regional map: no wrap-around
  ASSERT_FALSE(west.ok());
  EXPECT_EQ(west.error().code, ErrorCode::kOutOfRange);
  EXPECT_NE(west.error().message.find("longitude -1.000"), std::string::npos)
      << west.error().message;
  const auto north = model.vertical_tec_tecu(t0, 51.0, 5.0);  // 50 deg is far from the pole: no cap
  ASSERT_FALSE(north.ok());
  EXPECT_NE(north.error().message.find("latitude 51.000"), std::string::npos)
      << north.error().message;
}

TEST(IonexEvaluation, TimeInterpolationStrategies) {
  // t = 00:20 UTC: weights 2/3 on map 1 and 1/3 on map 2; point lat 48, lon 12.
  const GnssTime t = utc(0, 20, 0.0);
  const double w0 = 2.0 / 3.0, w1 = 1.0 / 3.0;
  // Map values at (48, 12): map 1 17.6 (see BilinearInSpace); map 2
  // 0.6*0.8*22 + 0.6*0.2*24 + 0.4*0.8*32 + 0.4*0.2*34 = 26.4.
  const double linear = w0 * 17.6 + w1 * 26.4;  // 20.5333
  // Rotated: map 1 at lon 12 + 360 * 1200 / 86400 = 17 (p = 0.7):
  //   0.6*0.3*12 + 0.6*0.7*20 + 0.4*0.3*22 + 0.4*0.7*30 = 21.6;
  // map 2 at lon 12 - 360 * 2400 / 86400 = 2 (p = 0.2):
  //   0.6*0.8*20 + 0.6*0.2*22 + 0.4*0.8*30 + 0.4*0.2*32 = 24.4.
  const double rotated = w0 * 21.6 + w1 * 24.4;  // 22.5333

  const IonexIonosphere nearest(
      two_maps(), {IonexTimeInterpolation::kNearestMap, ThinShellMapping::kSingleLayer});
  const IonexIonosphere plain(two_maps(),
                              {IonexTimeInterpolation::kLinear, ThinShellMapping::kSingleLayer});
  const IonexIonosphere rotating(two_maps());  // the default: rotated maps
  EXPECT_EQ(rotating.options().time_interpolation, IonexTimeInterpolation::kRotatedLinear);
  EXPECT_NEAR(nearest.vertical_tec_tecu(t, 48.0, 12.0).value(), 17.6, kTecTolerance_tecu);
  EXPECT_NEAR(nearest.vertical_tec_tecu(utc(0, 40, 0.0), 48.0, 12.0).value(), 26.4,
              kTecTolerance_tecu);
  EXPECT_NEAR(plain.vertical_tec_tecu(t, 48.0, 12.0).value(), linear, kTecTolerance_tecu);
  EXPECT_NEAR(rotating.vertical_tec_tecu(t, 48.0, 12.0).value(), rotated, kTecTolerance_tecu);
  // At the map epochs every strategy returns the map itself.
  for (const auto* model : {&nearest, &plain, &rotating}) {
    EXPECT_NEAR(model->vertical_tec_tecu(utc(0, 0, 0.0), 48.0, 12.0).value(), 17.6,
                kTecTolerance_tecu);
    EXPECT_NEAR(model->vertical_tec_tecu(utc(1, 0, 0.0), 48.0, 12.0).value(), 26.4,
                kTecTolerance_tecu);
  }
}

TEST(IonexEvaluation, TimeOutsideTheMapsNamesTheSpanInUtc) {
  const IonexIonosphere model(two_maps());
  // 01:00:10 GPST is 00:59:53 UTC: inside. 01:00:18 GPST is 01:00:01 UTC: outside.
  const auto gpst = [](int h, int m, double s) {
    return GnssTime::from_calendar(CalendarTime{2016, 6, 6, h, m, s}, TimeScale::kGpst);
  };
  // (Longitude 5: map 1 rotated by almost 15 degrees stays on the regional grid.)
  EXPECT_TRUE(model.vertical_tec_tecu(gpst(1, 0, 10.0), 45.0, 5.0).ok());
  EXPECT_TRUE(model.vertical_tec_tecu(gpst(1, 0, 17.0), 45.0, 5.0).ok());
  const auto late = model.vertical_tec_tecu(gpst(1, 0, 18.0), 45.0, 10.0);
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().code, ErrorCode::kOutOfRange);
  EXPECT_EQ(late.error().message,
            "IONEX file test.16i covers 2016-06-06T00:00:00 to 2016-06-06T01:00:00 UTC; requested "
            "2016-06-06T01:00:01.000 UTC (2016-06-06T01:00:18.000 GPST)");
  // 00:00:16 GPST is 23:59:59 UTC of the day before.
  EXPECT_FALSE(model.vertical_tec_tecu(gpst(0, 0, 16.0), 45.0, 10.0).ok());
  EXPECT_TRUE(model.covers(utc(0, 0, 0.0), utc(1, 0, 0.0)).ok());
  const auto span = model.covers(utc(0, 30, 0.0), utc(2, 0, 0.0));
  ASSERT_FALSE(span.ok());
  EXPECT_NE(span.error().message.find("requested 2016-06-06T02:00:00.000 UTC"), std::string::npos);
  // The slant delay passes the error on.
  const auto slant =
      model.delay_l1_m(utc(3, 0, 0.0), Geodetic{45.0, 10.0, 0.0}, AzimuthElevation{0.0, 90.0});
  ASSERT_FALSE(slant.ok());
  EXPECT_EQ(slant.error().code, ErrorCode::kOutOfRange);
}

TEST(IonexEvaluation, GlobalMapWrapsLongitudeAndCapsThePoles) {
  const IonexIonosphere model(parse_ionex("global.16i", kGlobalMap).value());
  const GnssTime t = utc(12, 0, 0.0);
  EXPECT_EQ(model.maps().version, "1.1");
  EXPECT_EQ(model.maps().mapping_function, IonexMappingFunction::kNone);
  // Equator row 10, 20, 30, (10). Lon 170: between 60 (30) and 180 (10): 30 + (110/120) * (10 -
  // 30).
  EXPECT_NEAR(model.vertical_tec_tecu(t, 0.0, 170.0).value(), 30.0 - 20.0 * 110.0 / 120.0,
              kTecTolerance_tecu);
  // Lon -175 and 185 are the same place: 10 + (5/120) * 10.
  EXPECT_NEAR(model.vertical_tec_tecu(t, 0.0, -175.0).value(), 10.0 + 10.0 * 5.0 / 120.0,
              kTecTolerance_tecu);
  EXPECT_NEAR(model.vertical_tec_tecu(t, 0.0, 185.0).value(), 10.0 + 10.0 * 5.0 / 120.0,
              kTecTolerance_tecu);
  EXPECT_NEAR(model.vertical_tec_tecu(t, 0.0, 540.0).value(), 10.0, kTecTolerance_tecu);
  // Beyond 87.5 deg the edge row's value.
  EXPECT_NEAR(model.vertical_tec_tecu(t, 89.0, -60.0).value(), 2.0, kTecTolerance_tecu);
  EXPECT_NEAR(model.vertical_tec_tecu(t, -90.0, 100.0).value(), 5.0, kTecTolerance_tecu);
  // Half-way between rows 87.5 (value 2 at -60) and 0 (20): 11.
  EXPECT_NEAR(model.vertical_tec_tecu(t, 43.75, -60.0).value(), 11.0, kTecTolerance_tecu);
}

TEST(IonexReader, BadFieldsNameFileLineAndField) {
  const std::string good = kTwoMaps;
  const auto expect_error = [](const std::string& content, const std::string& where,
                               const std::string& what) {
    const auto r = parse_ionex("test.16i", content);
    ASSERT_FALSE(r.ok()) << where;
    EXPECT_NE(r.error().message.find(where), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
  };
  {
    const auto bad = replaced(good, "    50.0  40.0  -5.0  ", "    50.0  4x.0  -5.0  ");
    expect_error(bad, "test.16i:" + std::to_string(line_of(good, "LAT1 / LAT2 / DLAT")) + ":",
                 "LAT1 / LAT2 / DLAT");
  }
  {
    const auto bad = replaced(good, "  100  120  200", "  100  1x0  200");
    expect_error(bad, "test.16i:" + std::to_string(line_of(good, "  100  120  200")) + ":",
                 "field value 2 of latitude 50 (longitude 10)");
  }
  {
    const auto bad = replaced(
        good, "  2016     6     6     1     0     0                        EPOCH OF CURRENT MAP",
        "  2016    13     6     1     0     0                        EPOCH OF CURRENT MAP");
    expect_error(bad,
                 "test.16i:" +
                     std::to_string(line_of(good,
                                            "     2                                                "
                                            "      START OF TEC MAP") +
                                    1) +
                     ":",
                 "EPOCH OF CURRENT MAP");
  }
  {
    const auto bad =
        replaced(good, "    45.0   0.0  20.0  10.0 450.0", "    47.0   0.0  20.0  10.0 450.0");
    expect_error(
        bad, "test.16i:" + std::to_string(line_of(good, "    45.0   0.0  20.0  10.0 450.0")) + ":",
        "field LAT: 47 is not on the header's grid");
  }
  {
    const auto bad = replaced(
        good, "     2                                                      # OF MAPS IN FILE",
        "     3                                                      # OF MAPS IN FILE");
    expect_error(bad, "test.16i", "says 3 but the file holds 2 TEC maps");
  }
  {
    const auto bad = replaced(
        good, "  6371.0                                                    BASE RADIUS\n", "");
    expect_error(bad, "test.16i", "BASE RADIUS missing");
  }
  {
    const auto bad = replaced(good, "   40   42   44\n", "");  // the row's values are missing
    expect_error(bad, "test.16i:", "expected an integer");
  }
  {
    const auto bad =
        replaced(good, "     1.0            IONOSPHERE", "     2.0            IONOSPHERE");
    const auto r = parse_ionex("test.16i", bad);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
  }
  {
    const auto bad = replaced(good, "   450.0 450.0   0.0", "   250.0 450.0  50.0");
    const auto r = parse_ionex("test.16i", bad);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
    EXPECT_NE(r.error().message.find("3-D maps"), std::string::npos) << r.error().message;
  }
  expect_error("some text\n", "test.16i:1:", "not an IONEX file");
}

// The pierce point by an independent construction: ray from a point of the sphere of radius R
// intersected with the sphere of radius R + H, in Cartesian vectors.
struct RayPierce {
  double latitude_deg, longitude_deg, mapping_factor;
};
RayPierce ray_sphere(const Geodetic& receiver, const AzimuthElevation& direction, double radius_m,
                     double height_m) {
  constexpr double d2r = std::numbers::pi / 180.0;
  const double lat = receiver.latitude_deg * d2r, lon = receiver.longitude_deg * d2r;
  const double az = direction.azimuth_deg * d2r, el = direction.elevation_deg * d2r;
  const Eigen::Vector3d up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
                           std::sin(lat));
  const Eigen::Vector3d east(-std::sin(lon), std::cos(lon), 0.0);
  const Eigen::Vector3d north = up.cross(east);
  const Eigen::Vector3d d =
      std::cos(el) * std::sin(az) * east + std::cos(el) * std::cos(az) * north + std::sin(el) * up;
  const Eigen::Vector3d r = radius_m * up;
  const double b = r.dot(d);
  const double shell_m = radius_m + height_m;
  const double s = -b + std::sqrt(b * b - (r.squaredNorm() - shell_m * shell_m));
  const Eigen::Vector3d p = r + s * d;
  const double cos_zp = p.normalized().dot(d);
  return {std::asin(p.z() / p.norm()) / d2r, std::atan2(p.y(), p.x()) / d2r, 1.0 / cos_zp};
}

TEST(ThinShell, PiercePointMatchesRaySphereIntersection) {
  const double radius_m = 6371e3, height_m = 450e3;
  double worst_deg = 0.0, worst_factor = 0.0;
  for (const double latitude_deg : {52.5, -33.9, 79.0, 0.0}) {
    const Geodetic receiver{latitude_deg, 13.4, 80.0};
    for (double el = 5.0; el <= 90.0; el += 5.0) {
      for (double az = 0.0; az < 360.0; az += 30.0) {
        const AzimuthElevation direction{az, el};
        const auto p = thin_shell_pierce_point(receiver, direction, radius_m, height_m);
        ASSERT_TRUE(p.has_value());
        const RayPierce expected = ray_sphere(receiver, direction, radius_m, height_m);
        double dlon = std::remainder(p->longitude_deg - expected.longitude_deg, 360.0);
        worst_deg =
            std::max({worst_deg, std::abs(p->latitude_deg - expected.latitude_deg),
                      std::abs(dlon) * std::cos(expected.latitude_deg * std::numbers::pi / 180.0)});
        worst_factor =
            std::max(worst_factor, std::abs(p->mapping_factor / expected.mapping_factor - 1.0));
      }
    }
  }
  EXPECT_LT(worst_deg, 1e-9);
  EXPECT_LT(worst_factor, 1e-12);
  // From 79 N looking north at 10 deg the path crosses the pole: latitude beyond 90 - 79.
  const auto polar = thin_shell_pierce_point(Geodetic{79.0, 12.0, 0.0}, AzimuthElevation{0.0, 5.0},
                                             radius_m, height_m);
  ASSERT_TRUE(polar.has_value());
  EXPECT_GT(polar->latitude_deg, 79.0);
}

TEST(ThinShell, ZenithHorizonAndMappingFunctions) {
  const Geodetic receiver{52.5, 13.4, 35.0};
  const auto zenith =
      thin_shell_pierce_point(receiver, AzimuthElevation{123.0, 90.0}, 6371e3, 450e3);
  ASSERT_TRUE(zenith.has_value());
  EXPECT_NEAR(zenith->latitude_deg, 52.5, 1e-12);
  EXPECT_NEAR(zenith->longitude_deg, 13.4, 1e-12);
  EXPECT_NEAR(zenith->mapping_factor, 1.0, 1e-15);
  EXPECT_FALSE(
      thin_shell_pierce_point(receiver, AzimuthElevation{0.0, 0.0}, 6371e3, 450e3).has_value());
  EXPECT_FALSE(
      thin_shell_pierce_point(receiver, AzimuthElevation{0.0, -3.0}, 6371e3, 450e3).has_value());
  // SLM at 30 deg elevation: sin z' = 6371 / 6821 * sin 60 deg = 0.808891, factor 1 / cos z'
  // = 1.700801.
  const auto slm = thin_shell_pierce_point(receiver, AzimuthElevation{0.0, 30.0}, 6371e3, 450e3);
  EXPECT_NEAR(slm->mapping_factor, 1.700801, 1e-6);
  // MSLM: sin z' = 6371 / 6877.7 * sin(0.9782 * 60 deg) = 0.791441, factor 1.636004.
  const auto mslm = thin_shell_pierce_point(receiver, AzimuthElevation{0.0, 30.0}, 6371e3, 450e3,
                                            ThinShellMapping::kModifiedSingleLayer);
  EXPECT_NEAR(mslm->mapping_factor, 1.636004, 1e-6);
  // Same pierce point (the map's shell height), different factor.
  EXPECT_EQ(mslm->latitude_deg, slm->latitude_deg);
}

TEST(ThinShell, SlantDelayScalesAsVtecTimesFactorOverFrequencySquared) {
  const IonexIonosphere model(parse_ionex("global.16i", kGlobalMap).value());
  const GnssTime t = utc(12, 0, 0.0);
  const Geodetic receiver{-89.9, 0.0, 0.0};  // polar cap: 5 TECU everywhere nearby
  const auto zenith_l1 = model.delay_l1_m(t, receiver, AzimuthElevation{0.0, 90.0}).value();
  ASSERT_TRUE(zenith_l1.has_value());
  // 1 TECU is 0.1624 m on L1: 40.3e16 / 1575.42e6^2 = 0.162372 m.
  EXPECT_NEAR(*zenith_l1, 5.0 * 0.162372, 5e-6);
  EXPECT_NEAR(*zenith_l1, ionosphere_group_delay_m(5.0, 1575.42e6), 1e-12);
  const double f_l5_hz = 1176.45e6;
  const auto zenith_l5 =
      model.slant_delay_m(t, receiver, AzimuthElevation{0.0, 90.0}, f_l5_hz).value();
  EXPECT_NEAR(*zenith_l5 / *zenith_l1, std::pow(1575.42 / 1176.45, 2), 1e-12);
  // Slant: VTEC at the pierce point (file height 350 km, radius 6371 km) times the mapping factor.
  const AzimuthElevation low{45.0, 20.0};
  const auto stec = model.slant_tec_tecu(t, receiver, low).value();
  const auto pierce = thin_shell_pierce_point(receiver, low, 6371e3, 350e3).value();
  const double vtec_tecu =
      model.vertical_tec_tecu(t, pierce.latitude_deg, pierce.longitude_deg).value();
  EXPECT_GT(vtec_tecu, 5.0);  // 7 degrees from the pole, inside the grid
  EXPECT_NEAR(*stec, vtec_tecu * pierce.mapping_factor, 1e-9);
  EXPECT_GT(pierce.mapping_factor, 2.0);
  EXPECT_FALSE(model.delay_l1_m(t, receiver, AzimuthElevation{0.0, -1.0}).value().has_value());
}

TEST(IonosphereModel, KlobucharAndIonexBehindTheInterface) {
  orbits::KlobucharCoefficients k;
  k.alpha = {0.6519e-08, 0.2235e-07, -0.5960e-07, -0.1192e-06};  // brdc1580.16n
  k.beta = {0.8602e+05, 0.9830e+05, -0.6554e+05, -0.5243e+06};
  std::unique_ptr<IonosphereModel> klobuchar = std::make_unique<KlobucharIonosphere>(k);
  std::unique_ptr<IonosphereModel> ionex = std::make_unique<IonexIonosphere>(two_maps());
  const GnssTime t = utc(0, 30, 0.0);
  // Pierce point near 49.2 N 10 E: the rotated maps are read at 17.5 E and 2.5 E.
  const Geodetic receiver{47.0, 10.0, 0.0};
  const AzimuthElevation direction{0.0, 60.0};
  EXPECT_EQ(klobuchar->name(), "klobuchar");
  EXPECT_EQ(ionex->name(), "ionex");
  EXPECT_EQ(klobuchar->delay_l1_m(t, receiver, direction).value(),
            klobuchar_delay_l1_m(k, t, receiver, direction));
  EXPECT_FALSE(klobuchar->delay_l1_m(t, receiver, AzimuthElevation{0.0, -5.0}).value().has_value());
  const auto delay = ionex->delay_l1_m(t, receiver, direction);
  ASSERT_TRUE(delay.ok()) << delay.error().message;
  EXPECT_GT(**delay, 1.0);  // ~16 TECU at 60 deg elevation: ~3 m
  EXPECT_LT(**delay, 10.0);
}

}  // namespace
}  // namespace skytrace::atmosphere
