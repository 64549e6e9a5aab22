// The positioning engine on real recordings of geodetic stations (RINEX 2.11, 3.05, 4.00) with
// their broadcast navigation files: the fixes must land on the published station coordinates as a
// single-frequency code solution does (a few metres), and the velocity of the static antenna at 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "skytrace/io/rinex_measurements.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/positioning/spp.hpp"
#include "test_support.hpp"

namespace skytrace::positioning {
namespace {

struct Statistics {
  size_t epochs = 0, fixes = 0;
  double median_m = 0.0, p95_m = 0.0, speed_p95_mps = 0.0;
  std::map<GnssSystem, size_t> clock_epochs;  // epochs with a clock of the system
};

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const double index = q * static_cast<double>(values.size() - 1);
  const auto low = static_cast<size_t>(std::floor(index));
  const size_t high = std::min(low + 1, values.size() - 1);
  return values[low] + (index - static_cast<double>(low)) * (values[high] - values[low]);
}

Statistics position_file(const std::filesystem::path& obs, const std::vector<std::filesystem::path>& navs,
                         const Eigen::Vector3d& antenna_m, SolverSettings settings) {
  orbits::NavigationData data;
  for (const auto& nav : navs) data.merge(orbits::read_rinex_nav(nav).value());
  const auto klobuchar = data.ionosphere.gps;
  const orbits::BroadcastEphemerides ephemerides(std::move(data));
  const io::ObservationFile file = io::read_rinex_obs(obs).value();
  const io::MeasurementExtractor extractor(file.header);
  SinglePointSolver solver(ephemerides, settings, klobuchar);
  Statistics s;
  std::vector<double> errors, speeds;
  for (const auto& epoch : file.epochs) {
    if (epoch.flag != io::EpochFlag::kOk) continue;
    ++s.epochs;
    const PositionFix fix = solver.solve(extractor.measurements(epoch)).value();
    if (fix.type != FixType::kFix3D) continue;
    ++s.fixes;
    errors.push_back((fix.position_ecef_m - antenna_m).norm());
    if (fix.velocity_valid) speeds.push_back(fix.velocity_enu_mps.norm());
    for (const auto& [system, bias] : fix.clock_bias_m) ++s.clock_epochs[system];
  }
  s.median_m = percentile(errors, 0.5);
  s.p95_m = percentile(errors, 0.95);
  s.speed_p95_mps = percentile(speeds, 0.95);
  return s;
}

SolverSettings only(std::vector<GnssSystem> systems) {
  SolverSettings s;
  s.systems = std::move(systems);
  return s;
}

// ESBC00DNK: marker XYZ from the data README, antenna reference point 0.2160 m above it.
Eigen::Vector3d esbc_antenna() {
  const Eigen::Vector3d marker(3582105.2910, 532589.7313, 5232754.8054);
  return marker + 0.2160 * ecef_to_enu_rotation(ecef_to_geodetic(marker)).row(2).transpose();
}

TEST(SppRealRecordings, EsbcGpsOnly) {
  const auto obs = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
  const auto nav = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  const Statistics s = position_file(obs, {nav}, esbc_antenna(), only({GnssSystem::kGps}));
  EXPECT_EQ(s.epochs, 120u);
  EXPECT_EQ(s.fixes, s.epochs);
  EXPECT_LT(s.p95_m, 5.0);
  EXPECT_LT(s.speed_p95_mps, 0.05);
  RecordProperty("median_m", std::to_string(s.median_m));
  RecordProperty("p95_m", std::to_string(s.p95_m));
}

TEST(SppRealRecordings, EsbcFourSystemsWithOneClockEach) {
  const auto obs = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
  const auto nav = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  SolverSettings settings = only({GnssSystem::kGps, GnssSystem::kGlonass, GnssSystem::kGalileo, GnssSystem::kBeiDou});
  Statistics s = position_file(obs, {nav}, esbc_antenna(), settings);
  EXPECT_EQ(s.fixes, s.epochs);
  EXPECT_LT(s.p95_m, 5.0);
  EXPECT_LT(s.speed_p95_mps, 0.05);
  for (GnssSystem system : settings.systems) EXPECT_EQ(s.clock_epochs[system], s.fixes) << system_name(system);

  // The residual test must not cost a real station in the open any epoch, nor its accuracy.
  settings.reject_outliers = true;
  const Statistics robust = position_file(obs, {nav}, esbc_antenna(), settings);
  EXPECT_EQ(robust.fixes, robust.epochs);
  EXPECT_LT(robust.p95_m, 5.0);
}

TEST(SppRealRecordings, Kms3Rinex4) {
  const auto obs = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_30S_MO.rnx");
  const auto nav = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_MN.rnx");
  const Statistics s = position_file(obs, {nav}, Eigen::Vector3d(3516213.4380, 781859.8595, 5246037.9660), SolverSettings{});
  EXPECT_EQ(s.epochs, 19u);
  EXPECT_EQ(s.fixes, s.epochs);
  EXPECT_LT(s.p95_m, 5.0);
}

TEST(SppRealRecordings, Nya1HighLatitudeSeparateNavigationFiles) {
  const auto obs = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx");
  const auto gps = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_GN.rnx");
  const auto galileo = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_EN.rnx");
  const auto beidou = SKYTRACE_SHARED_FILE("real/nya1_2024124/NYA100NOR_S_20241240000_01D_CN.rnx");
  const Statistics s = position_file(obs, {gps, galileo, beidou}, Eigen::Vector3d(1202434.1303, 252632.2212, 6237772.4351),
                                     SolverSettings{});
  EXPECT_EQ(s.fixes, s.epochs);
  EXPECT_LT(s.p95_m, 5.0);
  EXPECT_EQ(s.clock_epochs.count(GnssSystem::kGlonass), 0u);  // no GLONASS navigation data
}

TEST(SppRealRecordings, SlacRinex2WithoutDoppler) {
  const auto obs = SKYTRACE_SHARED_FILE("real/slac_2021118/slac1180.21o");
  const auto nav = SKYTRACE_SHARED_FILE("real/slac_2021118/brdc1180.21n");
  const Statistics s = position_file(obs, {nav}, Eigen::Vector3d(-2703115.2660, -4291768.3440, 3854247.9550),
                                     only({GnssSystem::kGps}));
  EXPECT_EQ(s.fixes, s.epochs);
  // RTKLIB's rnx2rtkp (single, brdc iono, saas) gives 3.9 m median and 6.2 m p95 on these two hours.
  EXPECT_LT(s.median_m, 5.0);
  EXPECT_LT(s.p95_m, 7.5);
  EXPECT_TRUE(std::isnan(s.speed_p95_mps));  // no Doppler in the file: no velocity
}

}  // namespace
}  // namespace skytrace::positioning
