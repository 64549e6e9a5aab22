// The CAS global ionosphere map of 2016-06-06 (casg1580.16i, smartLoc Berlin data set): header and
// grid as the file states them, vertical TEC over Berlin against the raw grid values read here
// independently, and the slant L1 delay against the broadcast Klobuchar model of brdc1580.16n.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/atmosphere/ionosphere.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::atmosphere {
namespace {

constexpr const char* kIonex = "real/smartloc_berlin_potsdamer_platz_2016158/casg1580.16i";
constexpr const char* kNav = "real/smartloc_berlin_potsdamer_platz_2016158/brdc1580.16n";
// Potsdamer Platz, Berlin (the data set's area), ellipsoidal height.
const Geodetic kBerlin{52.5096, 13.3762, 80.0};

GnssTime utc(int day, int hour, int minute) {
  return GnssTime::from_calendar(CalendarTime{2016, 6, day, hour, minute, 0.0}, TimeScale::kUtc);
}

// The values of the 52.5 N row of every TEC map, in 0.1 TECU, read with a plain token split (not
// the library's fixed-column reader): rows[map][longitude index], longitude -180 + 5 * index.
std::vector<std::vector<int>> raw_rows_52_5(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::vector<std::vector<int>> rows;
  bool in_tec_map = false;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    if (line.find("START OF TEC MAP") != std::string::npos) in_tec_map = true;
    if (line.find("END OF TEC MAP") != std::string::npos) in_tec_map = false;
    if (in_tec_map && line.find("LAT/LON1/LON2/DLON/H") != std::string::npos &&
        line.rfind("    52.5-180.0", 0) == 0) {
      std::istringstream values(lines[i + 1] + " " + lines[i + 2] + " " + lines[i + 3] + " " +
                                lines[i + 4] + " " + lines[i + 5]);
      std::vector<int> row;
      for (int v = 0; values >> v;) row.push_back(v);
      rows.push_back(row);
    }
  }
  return rows;
}

double percentile(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(fraction * static_cast<double>(values.size() - 1) + 0.5)];
}

TEST(IonexRealFile, CasHeaderAndGrid) {
  const auto path = SKYTRACE_SHARED_FILE(kIonex);
  const auto maps = read_ionex(path);
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  EXPECT_EQ(maps->version, "1.0");
  EXPECT_EQ(maps->satellite_system, "MIX");
  EXPECT_EQ(maps->map_count, 49);
  EXPECT_EQ(maps->tec_maps.size(), 49u);
  EXPECT_EQ(maps->rms_maps.size(), 49u);
  EXPECT_EQ(maps->interval_s, 1800.0);
  EXPECT_EQ(maps->mapping_function, IonexMappingFunction::kCosZ);
  EXPECT_DOUBLE_EQ(maps->base_radius_m, 6371.4e3);
  EXPECT_DOUBLE_EQ(maps->shell_height_m, 450e3);
  EXPECT_EQ(maps->exponent, -1);
  EXPECT_EQ(maps->latitude.count(), 71u);   // 87.5 to -87.5 by -2.5
  EXPECT_EQ(maps->longitude.count(), 73u);  // -180 to 180 by 5
  EXPECT_EQ(maps->first_epoch, utc(6, 0, 0));
  EXPECT_EQ(maps->last_epoch, utc(7, 0, 0));
  EXPECT_EQ(maps->tec_maps.front().epoch, maps->first_epoch);
  EXPECT_EQ(maps->tec_maps.back().epoch, maps->last_epoch);
  for (size_t k = 1; k < maps->tec_maps.size(); ++k) {
    EXPECT_EQ(maps->tec_maps[k].epoch - maps->tec_maps[k - 1].epoch, 1800.0);
  }
  // Every TEC value is present in this file (the 9999 are in the RMS maps' edges).
  size_t missing_tec = 0, missing_rms = 0;
  for (const auto& m : maps->tec_maps)
    missing_tec += std::count_if(m.values_tecu.begin(), m.values_tecu.end(),
                                 [](double v) { return std::isnan(v); });
  for (const auto& m : maps->rms_maps)
    missing_rms += std::count_if(m.values_tecu.begin(), m.values_tecu.end(),
                                 [](double v) { return std::isnan(v); });
  EXPECT_EQ(missing_tec, 0u);
  std::printf(
      "[ figures ] casg1580.16i: 49 TEC + 49 RMS maps of 71 x 73 points, %zu RMS values missing "
      "(9999)\n",
      missing_rms);
}

TEST(IonexRealFile, BerlinVerticalTecFromTheRawGrid) {
  const auto path = SKYTRACE_SHARED_FILE(kIonex);
  const IonexIonosphere model(read_ionex(path).value());
  const auto rows = raw_rows_52_5(path);
  ASSERT_EQ(rows.size(), 49u);
  ASSERT_EQ(rows.front().size(), 73u);
  const auto raw_tecu = [&](size_t map, double longitude_deg) {
    return 0.1 * rows[map][static_cast<size_t>(std::lround((longitude_deg + 180.0) / 5.0))];
  };
  // Berlin's longitude 13.3762 lies between grid columns 10 and 15 at fraction 0.67524; latitude
  // 52.5 is a grid row, so at the map epochs the value is a linear mix of two raw values.
  const double lon_deg = 13.3762;
  const double f = (lon_deg - 10.0) / 5.0;
  double min_tecu = 1e9, max_tecu = -1e9;
  for (size_t k = 0; k < rows.size(); ++k) {
    const GnssTime t = model.maps().tec_maps[k].epoch;
    const double expected = (1.0 - f) * raw_tecu(k, 10.0) + f * raw_tecu(k, 15.0);
    EXPECT_NEAR(model.vertical_tec_tecu(t, 52.5, lon_deg).value(), expected, 1e-9)
        << "map " << k + 1;
    min_tecu = std::min(min_tecu, expected);
    max_tecu = std::max(max_tecu, expected);
  }
  // Half-way between maps, the rotated maps (IONEX strategy 3): map k read 3.75 deg east, map k+1
  // 3.75 deg west, each bilinear between its two raw columns, then averaged.
  const auto mix = [&](size_t map, double longitude_deg) {
    const double column = std::floor(longitude_deg / 5.0) * 5.0;
    const double g = (longitude_deg - column) / 5.0;
    return (1.0 - g) * raw_tecu(map, column) + g * raw_tecu(map, column + 5.0);
  };
  double worst_tecu = 0.0;
  for (size_t k = 0; k + 1 < rows.size(); ++k) {
    const GnssTime t = model.maps().tec_maps[k].epoch + 900.0;
    const double expected = 0.5 * mix(k, lon_deg + 3.75) + 0.5 * mix(k + 1, lon_deg - 3.75);
    const double got = model.vertical_tec_tecu(t, 52.5, lon_deg).value();
    worst_tecu = std::max(worst_tecu, std::abs(got - expected));
  }
  EXPECT_LT(worst_tecu, 1e-9);
  // A June 2016 day (declining solar cycle 24) at mid-latitude: a few TECU at night, low teens at
  // noon.
  EXPECT_GT(min_tecu, 3.0);
  EXPECT_LT(max_tecu, 25.0);
  EXPECT_GT(max_tecu - min_tecu, 3.0);  // a visible diurnal cycle
  // Grid point (52.5, 15) of the noon map, against the value read by eye from the file: 13.3 TECU.
  EXPECT_NEAR(model.vertical_tec_tecu(utc(6, 12, 0), 52.5, 15.0).value(), 13.3, 1e-9);
  std::printf(
      "[ figures ] VTEC over Berlin (52.5 N, 13.38 E) on 2016-06-06: min %.2f TECU, max %.2f TECU "
      "(zenith L1 %.2f to %.2f m)\n",
      min_tecu, max_tecu, ionosphere_group_delay_m(min_tecu, kIonosphereReferenceFrequency_hz),
      ionosphere_group_delay_m(max_tecu, kIonosphereReferenceFrequency_hz));
}

TEST(IonexRealFile, OutsideTheDayIsAnErrorInUtc) {
  const auto path = SKYTRACE_SHARED_FILE(kIonex);
  const IonexIonosphere model(read_ionex(path).value());
  const auto late = model.delay_l1_m(utc(7, 1, 0), kBerlin, AzimuthElevation{0.0, 45.0});
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().code, ErrorCode::kOutOfRange);
  EXPECT_NE(late.error().message.find("IONEX file casg1580.16i covers 2016-06-06T00:00:00 to "
                                      "2016-06-07T00:00:00 UTC; requested "
                                      "2016-06-07T01:00:00.000 UTC"),
            std::string::npos)
      << late.error().message;
  // Midnight GPST of the 7th is 23:59:43 UTC of the 6th: inside.
  EXPECT_TRUE(model
                  .delay_l1_m(GnssTime::from_calendar(CalendarTime{2016, 6, 7, 0, 0, 0.0},
                                                      TimeScale::kGpst),
                              kBerlin, AzimuthElevation{0.0, 45.0})
                  .ok());
}

TEST(IonexRealFile, SlantL1DelayAgainstBroadcastKlobucharOverBerlin) {
  const auto ionex_path = SKYTRACE_SHARED_FILE(kIonex);
  const auto nav_path = SKYTRACE_SHARED_FILE(kNav);
  const IonexIonosphere ionex(read_ionex(ionex_path).value());
  auto nav = orbits::read_rinex_nav(nav_path);
  ASSERT_TRUE(nav.ok()) << nav.error().message;
  ASSERT_TRUE(nav->ionosphere.gps.has_value());
  const KlobucharIonosphere klobuchar(*nav->ionosphere.gps);
  const orbits::BroadcastEphemerides ephemerides(std::move(*nav));

  const Eigen::Vector3d receiver_ecef_m = geodetic_to_ecef(kBerlin);
  std::vector<double> ionex_m, klobuchar_m, difference_m;
  std::vector<double> ionex_high_m, klobuchar_high_m;  // above 60 degrees
  // Every 5 minutes of the map day (UTC), every GPS satellite above 10 degrees.
  for (GnssTime t = ionex.maps().first_epoch; t <= ionex.maps().last_epoch; t += 300.0) {
    for (const SatelliteId& satellite : ephemerides.satellites()) {
      if (satellite.system != GnssSystem::kGps) continue;
      const auto state = ephemerides.state(satellite, t);
      if (!state.ok()) continue;
      const AzimuthElevation direction =
          azimuth_elevation(receiver_ecef_m, kBerlin, state->position_m);
      if (direction.elevation_deg < 10.0) continue;
      const auto from_map = ionex.delay_l1_m(t, kBerlin, direction);
      ASSERT_TRUE(from_map.ok()) << from_map.error().message;
      const auto broadcast = klobuchar.delay_l1_m(t, kBerlin, direction);
      ASSERT_TRUE(broadcast.ok() && broadcast->has_value());
      ionex_m.push_back(**from_map);
      klobuchar_m.push_back(**broadcast);
      difference_m.push_back(**broadcast - **from_map);
      if (direction.elevation_deg > 60.0) {
        ionex_high_m.push_back(**from_map);
        klobuchar_high_m.push_back(**broadcast);
      }
    }
  }
  ASSERT_GT(ionex_m.size(), 2000u);
  const auto mean = [](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  };
  const auto rms = [](const std::vector<double>& v) {
    return std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0) /
                     static_cast<double>(v.size()));
  };
  std::vector<double> abs_difference_m(difference_m.size());
  std::transform(difference_m.begin(), difference_m.end(), abs_difference_m.begin(),
                 [](double d) { return std::abs(d); });
  // How much of the map's delay a receiver applying Klobuchar removes: 1 - RMS(residual) /
  // RMS(delay).
  const double removed = 1.0 - rms(difference_m) / rms(ionex_m);
  const double mean_x = mean(ionex_m), mean_y = mean(klobuchar_m);
  double sxy = 0.0, sxx = 0.0, syy = 0.0;
  for (size_t k = 0; k < ionex_m.size(); ++k) {
    sxy += (ionex_m[k] - mean_x) * (klobuchar_m[k] - mean_y);
    sxx += (ionex_m[k] - mean_x) * (ionex_m[k] - mean_x);
    syy += (klobuchar_m[k] - mean_y) * (klobuchar_m[k] - mean_y);
  }
  const double correlation = sxy / std::sqrt(sxx * syy);
  std::printf(
      "[ figures ] Berlin 2016-06-06, GPS above 10 deg every 5 min, %zu satellite-epochs: slant L1 "
      "delay "
      "IONEX (CAS) mean %.2f m (max %.2f m), Klobuchar mean %.2f m (max %.2f m); Klobuchar - IONEX "
      "mean %.2f m, "
      "RMS %.2f m, |.| p95 %.2f m, max %.2f m; correlation %.2f; Klobuchar removes %.0f %% (RMS); "
      "above 60 deg "
      "IONEX %.2f m, Klobuchar %.2f m\n",
      ionex_m.size(), mean_x, *std::max_element(ionex_m.begin(), ionex_m.end()), mean_y,
      *std::max_element(klobuchar_m.begin(), klobuchar_m.end()), mean(difference_m),
      rms(difference_m), percentile(abs_difference_m, 0.95),
      *std::max_element(abs_difference_m.begin(), abs_difference_m.end()), correlation,
      100.0 * removed, mean(ionex_high_m), mean(klobuchar_high_m));

  // Two models of the same ionosphere: same size and same elevation and daily dependence, within a
  // few metres of each other (the broadcast model is known to be good to 50-60 % RMS).
  EXPECT_GT(mean_x, 1.0);
  EXPECT_LT(mean_x, 8.0);
  EXPECT_LT(std::abs(mean(difference_m)), 3.0);
  EXPECT_LT(percentile(abs_difference_m, 0.95), 5.0);
  EXPECT_GT(correlation, 0.5);
  EXPECT_GT(removed, 0.0);
}

}  // namespace
}  // namespace skytrace::atmosphere
