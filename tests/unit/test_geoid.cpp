// The geoid grid of NMEA heights (core/geoid): GTX reading, bilinear interpolation with longitude
// wrap-around, errors that name the file; and EGM96 from Debian's proj-data against the NGA's
// published EGM96 test values (computed from the spherical-harmonic model, so they check the grid
// and the interpolation independently).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>

#include "skytrace/core/geoid.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

void put_big_endian(std::ofstream& out, std::uint64_t raw, int bytes) {
  for (int i = bytes - 1; i >= 0; --i) out.put(static_cast<char>((raw >> (8 * i)) & 0xff));
}

// A GTX file: origin (south, west), spacing, rows x columns, then values row by row from the south.
std::filesystem::path write_gtx(const std::filesystem::path& path, double south, double west, double step_lat,
                                double step_lon, int rows, int columns, const std::vector<float>& values) {
  std::ofstream out(path, std::ios::binary);
  for (double d : {south, west, step_lat, step_lon}) put_big_endian(out, std::bit_cast<std::uint64_t>(d), 8);
  put_big_endian(out, static_cast<std::uint32_t>(rows), 4);
  put_big_endian(out, static_cast<std::uint32_t>(columns), 4);
  for (float v : values) put_big_endian(out, std::bit_cast<std::uint32_t>(v), 4);
  return path;
}

TEST(Geoid, BilinearOnTheGridWrappingAroundTheAntimeridian) {
  const auto dir = test::make_temp_dir("geoid");
  // 3 rows (-90, 0, 90) x 4 columns (-180, -90, 0, 90): covers 360 degrees, so longitudes wrap.
  const auto path = write_gtx(dir / "g.gtx", -90.0, -180.0, 90.0, 90.0, 3, 4,
                              {0, 0, 0, 0, /* equator */ 10, 20, 30, 40, /* north pole */ 5, 5, 5, 5});
  const auto grid = GeoidGrid::load_gtx(path);
  ASSERT_TRUE(grid) << grid.error().message;
  EXPECT_EQ(grid.value().name(), "g.gtx");
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(0.0, -180.0), 10.0);
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(0.0, 45.0), 35.0);
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(0.0, 135.0), 25.0);   // between 90 (40) and 180 = -180 (10)
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(0.0, -225.0), 25.0);  // the same meridian
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(45.0, -180.0), 7.5);
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(-45.0, -90.0), 10.0);
  EXPECT_DOUBLE_EQ(grid.value().undulation_m(90.0, 10.0), 5.0);
  EXPECT_TRUE(std::isnan(grid.value().undulation_m(std::nan(""), 0.0)));
}

TEST(Geoid, BadFilesAreRefusedNamingTheFile) {
  const auto dir = test::make_temp_dir("geoid_bad");
  auto message = [](const std::filesystem::path& p) {
    auto g = GeoidGrid::load_gtx(p);
    return g ? std::string() : g.error().message;
  };
  EXPECT_NE(message(dir / "absent.gtx").find("absent.gtx: cannot open"), std::string::npos);
  {
    std::ofstream(dir / "short.gtx") << "GTX";
  }
  EXPECT_NE(message(dir / "short.gtx").find("short.gtx: not a GTX geoid grid"), std::string::npos);
  // One value missing.
  const auto truncated = write_gtx(dir / "truncated.gtx", -90, -180, 90, 90, 3, 4, std::vector<float>(11, 1.0f));
  EXPECT_NE(message(truncated).find("truncated.gtx: 84 bytes, expected 88 for 3 x 4"), std::string::npos)
      << message(truncated);
  const auto huge = write_gtx(dir / "huge.gtx", -90, -180, 90, 90, 2000000, 4, {});
  EXPECT_NE(message(huge).find("huge.gtx: GTX header out of range"), std::string::npos) << message(huge);
  const auto zero_step = write_gtx(dir / "zero.gtx", -90, -180, 0, 90, 3, 4, std::vector<float>(12, 1.0f));
  EXPECT_NE(message(zero_step).find("GTX header out of range"), std::string::npos);
}

// NGA's EGM96 test values (lat, lon, N in m; their F477 program's output for the full model). The
// 15' grid with bilinear interpolation stays within 6 cm of them.
TEST(Geoid, Egm96FromProjDataAgreesWithTheNgaTestValues) {
  auto grid = GeoidGrid::load_gtx("/usr/share/proj/egm96_15.gtx");
  if (!grid) GTEST_SKIP() << "proj-data's EGM96 grid not installed (scripts/setup)";
  struct Point {
    double latitude_deg, longitude_deg, n_m;
  };
  for (const Point& p : {Point{38.6281550, 269.7791550, -31.628}, Point{-14.6212170, 305.0211140, -2.969},
                         Point{46.8743190, 102.4487290, -43.575}, Point{-23.6174460, 133.8747120, 15.871},
                         Point{38.6254730, 359.9995000, 50.066}, Point{-0.4667440, 0.0023000, 17.329}}) {
    EXPECT_NEAR(grid.value().undulation_m(p.latitude_deg, p.longitude_deg), p.n_m, 0.07)
        << p.latitude_deg << " " << p.longitude_deg;
    // East longitudes as negative west ones: the same point.
    EXPECT_DOUBLE_EQ(grid.value().undulation_m(p.latitude_deg, p.longitude_deg - 360.0),
                     grid.value().undulation_m(p.latitude_deg, p.longitude_deg));
  }
}

}  // namespace
}  // namespace skytrace
