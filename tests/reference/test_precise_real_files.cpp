// Precise products read from real IGS/MGEX files and interpolated against themselves: header and
// record values checked against the text of the files, leave-one-out interpolation errors, and
// the agreement of 30 s clock files with 15-min SP3 clocks.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/precise.hpp"
#include "skytrace/orbits/precise_cache.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

constexpr const char* kGrgDayBefore = "real/esbc_2020177/GRG0MGXFIN_20201760000_01D_15M_ORB.SP3";
constexpr const char* kGrgDay = "real/esbc_2020177/GRG0MGXFIN_20201770000_01D_15M_ORB.SP3";
constexpr const char* kGrgClock = "real/esbc_2020177/GRG0MGXFIN_20201770000_01D_30S_CLK.CLK";
constexpr const char* kCodOrbit = "real/slac_2021118/COD0MGXFIN_20211180000_01D_05M_ORB.SP3";
constexpr const char* kCodClock = "real/slac_2021118/COD0MGXFIN_20211180000_01D_30S_CLK.CLK";
constexpr const char* kEsbcNav = "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
constexpr const char* kGfzOrbit = "real/smartloc_berlin_potsdamer_platz_2016158/gbm19001.sp3";

SatelliteId sat(const char* text) { return SatelliteId::parse(text).value(); }

GnssTime gpst(int year, int month, int day, int hour, int minute, double second) {
  return GnssTime::from_calendar({year, month, day, hour, minute, second}, TimeScale::kGpst);
}

const Sp3Record& record_at(const Sp3Data& data, const char* satellite, const GnssTime& t) {
  const auto it = std::find(data.epochs.begin(), data.epochs.end(), t);
  EXPECT_NE(it, data.epochs.end()) << t.to_iso8601(TimeScale::kGpst);
  const auto* series = data.series(sat(satellite));
  EXPECT_NE(series, nullptr) << satellite;
  return (*series)[static_cast<size_t>(it - data.epochs.begin())];
}

TEST(PreciseRealFiles, GrgSp3cHeaderCountsAndValues) {
  const auto path = SKYTRACE_SHARED_FILE(kGrgDay);
  auto data = read_sp3(path);
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_EQ(data->header.version, 'c');
  EXPECT_EQ(data->header.agency, "GRGS");
  EXPECT_EQ(data->header.coordinate_system, "IGb14");
  EXPECT_EQ(data->header.time_system, "GPS");
  EXPECT_EQ(data->header.declared_epoch_count, 96);
  EXPECT_DOUBLE_EQ(data->interval_s, 900.0);
  EXPECT_EQ(data->header.satellites.size(), 75u);
  // Counts per system from the P records of the text (awk over the file).
  EXPECT_EQ(data->satellite_count(GnssSystem::kGps), 30u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGlonass), 21u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGalileo), 24u);
  ASSERT_EQ(data->epochs.size(), 96u);
  EXPECT_EQ(data->epochs.front(), gpst(2020, 6, 25, 0, 0, 0.0));
  EXPECT_EQ(data->epochs.back(), gpst(2020, 6, 25, 23, 45, 0.0));
  // The "##" line: GPS week 2111, 345600 s.
  EXPECT_EQ(data->header.first_epoch, GnssTime::from_week_tow(TimeScale::kGpst, 2111, 345600.0));
  // "PE01 -11562.163582  14053.114306  23345.128269   -884.707516" at 00:00.
  const Sp3Record& e01 = record_at(*data, "E01", gpst(2020, 6, 25, 0, 0, 0.0));
  EXPECT_NEAR(e01.position_m.x(), -11562163.582, 1e-6);
  EXPECT_NEAR(e01.position_m.y(), 14053114.306, 1e-6);
  EXPECT_NEAR(e01.position_m.z(), 23345128.269, 1e-6);
  EXPECT_NEAR(e01.clock_s, -884.707516e-6, 1e-15);
  // "PG05 -20632.475811   4434.893522  16106.178530    -15.353148" at 12:00.
  const Sp3Record& g05 = record_at(*data, "G05", gpst(2020, 6, 25, 12, 0, 0.0));
  EXPECT_NEAR(g05.position_m.x(), -20632475.811, 1e-6);
  EXPECT_NEAR(g05.clock_s, -15.353148e-6, 1e-15);
}

TEST(PreciseRealFiles, GrgDayBeforeAndDayMergeIntoOneSeries) {
  const auto before = SKYTRACE_SHARED_FILE(kGrgDayBefore);
  const auto day = SKYTRACE_SHARED_FILE(kGrgDay);
  auto merged = read_sp3({before, day});
  ASSERT_TRUE(merged.ok()) << merged.error().message;
  ASSERT_EQ(merged->epochs.size(), 192u);
  EXPECT_EQ(merged->epochs.front(), gpst(2020, 6, 24, 0, 0, 0.0));
  EXPECT_EQ(merged->epochs.back(), gpst(2020, 6, 25, 23, 45, 0.0));
  for (size_t k = 1; k < merged->epochs.size(); ++k) {
    ASSERT_DOUBLE_EQ(merged->epochs[k] - merged->epochs[k - 1], 900.0) << k;
  }
  // Merging the same files again (in the other order) adds no epoch.
  auto twice = read_sp3({day, before, day});
  ASSERT_TRUE(twice.ok());
  EXPECT_EQ(twice->epochs.size(), 192u);

  // Across midnight the interpolation uses both days. The day-before file extrapolated 15 min
  // beyond its end, against the day file's first epoch (a different orbit arc, so this also shows
  // the day-boundary discontinuity of the product).
  auto alone = read_sp3(before);
  ASSERT_TRUE(alone.ok());
  auto extrapolating = PreciseEphemerides::create(std::move(*alone));
  auto joined = PreciseEphemerides::create(std::move(*merged));
  ASSERT_TRUE(extrapolating.ok() && joined.ok());
  const GnssTime midnight = gpst(2020, 6, 25, 0, 0, 0.0);
  std::vector<double> differences_m;
  for (const auto& satellite : joined->satellites()) {
    auto extrapolated = extrapolating->orbit(satellite, midnight);
    auto tabulated = joined->orbit(satellite, midnight);
    ASSERT_TRUE(extrapolated.ok() && tabulated.ok()) << satellite.to_string();
    differences_m.push_back((extrapolated->position_m - tabulated->position_m).norm());
  }
  std::sort(differences_m.begin(), differences_m.end());
  const double median_m = differences_m[differences_m.size() / 2];
  std::printf("[ measured ] GRG 2020-06-24 extrapolated 15 min to midnight vs 2020-06-25 00:00: median %.3f m, "
              "max %.3f m over %zu satellites\n",
              median_m, differences_m.back(), differences_m.size());
  EXPECT_EQ(differences_m.size(), 75u);
  EXPECT_LT(median_m, 0.5);
  EXPECT_LT(differences_m.back(), 5.0);
}

TEST(PreciseRealFiles, CodSp3dTrimmedFile) {
  const auto path = SKYTRACE_SHARED_FILE(kCodOrbit);
  auto data = read_sp3(path);
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_EQ(data->header.version, 'd');
  EXPECT_EQ(data->header.agency, "AIUB");
  EXPECT_EQ(data->header.satellites.size(), 116u);
  EXPECT_EQ(data->header.declared_epoch_count, 289);  // trimmed: fewer epochs are present
  EXPECT_DOUBLE_EQ(data->interval_s, 300.0);
  ASSERT_EQ(data->epochs.size(), 73u);
  EXPECT_EQ(data->epochs.front(), gpst(2021, 4, 28, 18, 0, 0.0));
  EXPECT_EQ(data->epochs.back(), gpst(2021, 4, 29, 0, 0, 0.0));
  EXPECT_EQ(data->satellite_count(GnssSystem::kGps), 31u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGlonass), 21u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGalileo), 24u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kBeiDou), 37u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kQzss), 3u);
  // "PG05 -15882.664746  -4653.022319 -20963.310614    -40.403829" at 19:30.
  const Sp3Record& g05 = record_at(*data, "G05", gpst(2021, 4, 28, 19, 30, 0.0));
  EXPECT_NEAR(g05.position_m.z(), -20963310.614, 1e-6);
  EXPECT_NEAR(g05.clock_s, -40.403829e-6, 1e-15);
  // "PC08 -13545.491808  17230.175165 -35950.044144 999999.999999" at 00:00: clock missing.
  const Sp3Record& c08 = record_at(*data, "C08", gpst(2021, 4, 29, 0, 0, 0.0));
  EXPECT_TRUE(c08.has_position);
  EXPECT_FALSE(c08.has_clock);
  EXPECT_NEAR(c08.position_m.x(), -13545491.808, 1e-6);
}

TEST(PreciseRealFiles, GfzSp3cWithTrailingBlanks) {
  const auto path = SKYTRACE_SHARED_FILE(kGfzOrbit);
  auto data = read_sp3(path);
  ASSERT_TRUE(data.ok()) << data.error().message;
  EXPECT_EQ(data->header.agency, "GFZ");
  EXPECT_EQ(data->header.satellites.size(), 78u);
  ASSERT_EQ(data->epochs.size(), 288u);
  EXPECT_EQ(data->epochs.front(), gpst(2016, 6, 6, 0, 0, 0.0));
  EXPECT_EQ(data->epochs.back(), gpst(2016, 6, 6, 23, 55, 0.0));
  EXPECT_EQ(data->header.first_epoch, GnssTime::from_week_tow(TimeScale::kGpst, 1900, 86400.0));
  EXPECT_EQ(data->satellite_count(GnssSystem::kBeiDou), 13u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGalileo), 11u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGps), 31u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kQzss), 1u);
  EXPECT_EQ(data->satellite_count(GnssSystem::kGlonass), 22u);
  // "PJ01 -19853.929460  30190.307961 -17027.887870   -216.618586" at 00:00.
  const Sp3Record& j01 = record_at(*data, "J01", gpst(2016, 6, 6, 0, 0, 0.0));
  EXPECT_NEAR(j01.position_m.y(), 30190307.961, 1e-6);
  EXPECT_NEAR(j01.clock_s, -216.618586e-6, 1e-15);
  ASSERT_EQ(data->header.accuracy_exponents.size(), 78u);
  EXPECT_EQ(data->header.accuracy_exponents[0], 10);  // C01
}

TEST(PreciseRealFiles, ClockFilesVersion300And304) {
  const auto grg_path = SKYTRACE_SHARED_FILE(kGrgClock);
  const auto cod_path = SKYTRACE_SHARED_FILE(kCodClock);
  auto grg = read_rinex_clock(grg_path);
  ASSERT_TRUE(grg.ok()) << grg.error().message;
  EXPECT_DOUBLE_EQ(grg->version, 3.0);
  EXPECT_EQ(grg->time_scale, TimeScale::kGpst);
  EXPECT_EQ(grg->listed_satellites.size(), 75u);
  EXPECT_EQ(grg->satellite_clocks.size(), 75u);
  size_t full_days = 0;
  for (const auto& [satellite, samples] : grg->satellite_clocks) full_days += samples.size() == 2880 ? 1 : 0;
  EXPECT_EQ(full_days, 74u);  // one satellite misses one sample (awk over the file)
  const auto* g05 = grg->series(sat("G05"));
  ASSERT_NE(g05, nullptr);
  EXPECT_EQ(g05->front().time, gpst(2020, 6, 25, 0, 0, 0.0));
  EXPECT_EQ(g05->back().time, gpst(2020, 6, 25, 23, 59, 30.0));
  // "AS G05  2020  6 25 12  0 30.000000  2   -0.153531461860E-04  0.573890373401E-11"
  EXPECT_EQ((*g05)[1441].time, gpst(2020, 6, 25, 12, 0, 30.0));
  EXPECT_DOUBLE_EQ((*g05)[1441].bias_s, -0.153531461860E-04);
  EXPECT_DOUBLE_EQ((*g05)[1441].sigma_s, 0.573890373401E-11);

  auto cod = read_rinex_clock(cod_path);
  ASSERT_TRUE(cod.ok()) << cod.error().message;
  EXPECT_DOUBLE_EQ(cod->version, 3.04);
  EXPECT_EQ(cod->analysis_center, "COM  CODE MGEX");
  EXPECT_EQ(cod->listed_satellites.size(), 116u);
  EXPECT_EQ(cod->satellite_clocks.size(), 116u);
  std::map<GnssSystem, int> per_system;
  for (const auto& [satellite, samples] : cod->satellite_clocks) {
    ++per_system[satellite.system];
    EXPECT_EQ(samples.size(), 121u) << satellite.to_string();
  }
  EXPECT_EQ(per_system[GnssSystem::kBeiDou], 37);
  EXPECT_EQ(per_system[GnssSystem::kQzss], 3);
  const auto* cod_g05 = cod->series(sat("G05"));
  ASSERT_NE(cod_g05, nullptr);
  EXPECT_EQ(cod_g05->front().time, gpst(2021, 4, 28, 19, 30, 0.0));
  EXPECT_DOUBLE_EQ(cod_g05->front().bias_s, -0.404037984480E-04);
  EXPECT_DOUBLE_EQ((*cod_g05)[1].bias_s, -0.404037740176E-04);
  EXPECT_LT((*cod_g05)[1].sigma_s, 0.0);  // only one value on that line
  EXPECT_EQ(cod_g05->back().time, gpst(2021, 4, 28, 20, 30, 0.0));
}

// Errors of one class of leave-out points.
struct ErrorStats {
  double sum_m2 = 0.0, max_m = 0.0;
  size_t count = 0;
  std::map<GnssSystem, std::pair<double, size_t>> per_system;  // sum of squares, count

  void add(GnssSystem system, double error_m) {
    sum_m2 += error_m * error_m;
    max_m = std::max(max_m, error_m);
    ++count;
    per_system[system].first += error_m * error_m;
    ++per_system[system].second;
  }
  [[nodiscard]] double rms_m() const { return count > 0 ? std::sqrt(sum_m2 / static_cast<double>(count)) : 0.0; }
  [[nodiscard]] double rms_m(GnssSystem system) const {
    const auto it = per_system.find(system);
    return it == per_system.end() ? 0.0 : std::sqrt(it->second.first / static_cast<double>(it->second.second));
  }
};

struct LeaveOut {
  ErrorStats centred;       // 10-point window centred on the point
  ErrorStats edge;          // within the data but near its ends: one-sided window
  ErrorStats extrapolated;  // after the last kept epoch
};

// Keeps every `keep`-th epoch, interpolates at the others and compares with the tabulated
// positions (a check that includes the products' own noise of a few mm).
LeaveOut leave_out(const Sp3Data& full, size_t keep, const PreciseOptions& options) {
  Sp3Data thinned = full;
  thinned.epochs.clear();
  for (auto& series : thinned.records) series.clear();
  for (size_t e = 0; e < full.epochs.size(); e += keep) {
    thinned.epochs.push_back(full.epochs[e]);
    for (size_t s = 0; s < full.records.size(); ++s) thinned.records[s].push_back(full.records[s][e]);
  }
  const size_t kept = thinned.epochs.size();
  thinned.interval_s = full.interval_s * static_cast<double>(keep);
  const auto half = static_cast<size_t>(options.interpolation_points / 2);
  auto source = PreciseEphemerides::create(std::move(thinned), std::nullopt, options);
  EXPECT_TRUE(source.ok());
  LeaveOut out;
  if (!source.ok()) return out;
  for (size_t s = 0; s < full.satellites.size(); ++s) {
    for (size_t e = 0; e < full.epochs.size(); ++e) {
      if (e % keep == 0 || !full.records[s][e].has_position) continue;
      auto orbit = source->orbit(full.satellites[s], full.epochs[e]);
      if (!orbit.ok()) continue;  // next to missing samples
      const double error_m = (orbit->position_m - full.records[s][e].position_m).norm();
      const size_t lower = e / keep;  // kept sample before the point
      ErrorStats& stats = lower + 1 >= kept ? out.extrapolated
                          : (lower + 1 >= half && lower + half < kept) ? out.centred
                                                                       : out.edge;
      stats.add(full.satellites[s].system, error_m);
    }
  }
  return out;
}

const PreciseOptions kTwoBody{};
const PreciseOptions kInertialPlain = [] {
  PreciseOptions o;
  o.two_body_reference = false;
  return o;
}();
const PreciseOptions kEarthFixed = [] {
  PreciseOptions o;
  o.frame = InterpolationFrame::kEarthFixed;
  return o;
}();

void report(const std::string& what, const ErrorStats& r) {
  std::printf("[ measured ] %s: RMS %.4f m, max %.4f m over %zu points; RMS per system:", what.c_str(), r.rms_m(),
              r.max_m, r.count);
  for (const auto& [system, sums] : r.per_system) std::printf(" %c %.4f", system_letter(system), r.rms_m(system));
  std::printf("\n");
}

void report(const std::string& what, const LeaveOut& r) {
  report(what + ", centred", r.centred);
  report(what + ", edge intervals", r.edge);
  report(what + ", extrapolated", r.extrapolated);
}

TEST(PreciseRealFiles, LeaveOneOutOnGrg15MinuteOrbits) {
  const auto path = SKYTRACE_SHARED_FILE(kGrgDay);
  auto data = read_sp3(path);
  ASSERT_TRUE(data.ok());
  // Every second epoch dropped: 10 points spaced 30 min, evaluated at the dropped epochs.
  const LeaveOut inertial = leave_out(*data, 2, kTwoBody);
  const LeaveOut plain = leave_out(*data, 2, kInertialPlain);
  const LeaveOut fixed = leave_out(*data, 2, kEarthFixed);
  report("GRG 2020-06-25 at 30 min, inertial with two-body reference", inertial);
  report("GRG 2020-06-25 at 30 min, inertial", plain);
  report("GRG 2020-06-25 at 30 min, Earth-fixed", fixed);
  EXPECT_EQ(inertial.centred.count + inertial.edge.count + inertial.extrapolated.count, 75u * 48u);
  EXPECT_LT(inertial.centred.rms_m(), 0.05);
  EXPECT_LT(inertial.centred.rms_m(GnssSystem::kGps), 0.01);
  EXPECT_LT(inertial.centred.rms_m(GnssSystem::kGlonass), 0.01);
  EXPECT_LT(inertial.centred.rms_m(GnssSystem::kGps), fixed.centred.rms_m(GnssSystem::kGps));
  EXPECT_LT(inertial.centred.rms_m(GnssSystem::kGlonass), fixed.centred.rms_m(GnssSystem::kGlonass));
}

TEST(PreciseRealFiles, LeaveOutAt15MinutesOn5MinuteOrbits) {
  // The 5-min products thinned to 15 min: the error of interpolating real 15-min products.
  const auto cod_path = SKYTRACE_SHARED_FILE(kCodOrbit);
  const auto gfz_path = SKYTRACE_SHARED_FILE(kGfzOrbit);
  for (const auto& path : {cod_path, gfz_path}) {
    auto data = read_sp3(path);
    ASSERT_TRUE(data.ok());
    const LeaveOut inertial = leave_out(*data, 3, kTwoBody);
    const LeaveOut plain = leave_out(*data, 3, kInertialPlain);
    const LeaveOut fixed = leave_out(*data, 3, kEarthFixed);
    const std::string name = path.filename().string();
    report(name + " at 15 min, inertial with two-body reference", inertial);
    report(name + " at 15 min, inertial", plain);
    report(name + " at 15 min, Earth-fixed", fixed);
    EXPECT_GT(inertial.centred.count, 1000u);
    EXPECT_LT(inertial.centred.rms_m(), 0.01) << name;
    EXPECT_LT(inertial.centred.rms_m(GnssSystem::kGps), 0.005) << name;
  }
}

// Statistics of |a - b| per system.
struct ClockComparison {
  std::map<GnssSystem, std::vector<double>> differences_s;
};

double percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(fraction * static_cast<double>(values.size() - 1))];
}

TEST(PreciseRealFiles, ClockFileAgreesWithInterpolatedSp3Clocks) {
  const auto orbit_path = SKYTRACE_SHARED_FILE(kGrgDay);
  const auto clock_path = SKYTRACE_SHARED_FILE(kGrgClock);
  auto orbits = read_sp3(orbit_path);
  auto clocks = read_rinex_clock(clock_path);
  ASSERT_TRUE(orbits.ok() && clocks.ok());
  auto sp3_only = PreciseEphemerides::create(*orbits);
  auto with_file = PreciseEphemerides::create(*orbits, *clocks);
  ASSERT_TRUE(sp3_only.ok() && with_file.ok());
  // At the 15-min epochs both products hold the same solution (to the 1e-12 s of SP3's format).
  // In between, the 30 s clock file against the SP3 clock interpolated linearly over 15 min.
  std::map<GnssSystem, std::vector<double>> on_epochs_s, between_s;
  std::map<SatelliteId, double> worst_between_s;
  for (const auto& [satellite, samples] : clocks->satellite_clocks) {
    for (const auto& sample : samples) {
      if (sample.time > orbits->epochs.back()) continue;  // SP3 would extrapolate there
      auto interpolated = sp3_only->clock(satellite, sample.time);
      if (!interpolated.ok()) continue;
      const double difference_s = std::abs(interpolated->bias_s - sample.bias_s);
      const double offset_s = sample.time - orbits->epochs.front();
      const bool on_epoch = std::fmod(offset_s, 900.0) == 0.0;
      (on_epoch ? on_epochs_s : between_s)[satellite.system].push_back(difference_s);
      if (!on_epoch) worst_between_s[satellite] = std::max(worst_between_s[satellite], difference_s);
      // The state source built with the clock file returns the file's samples.
      if (satellite.number % 7 == 0 && std::fmod(offset_s, 3600.0) == 30.0) {
        auto from_file = with_file->clock(satellite, sample.time);
        ASSERT_TRUE(from_file.ok()) << from_file.error().message;
        EXPECT_DOUBLE_EQ(from_file->bias_s, sample.bias_s);
      }
    }
  }
  for (const auto& [system, values] : between_s) {
    std::printf("[ measured ] GRG clock file vs SP3 clock interpolated over 15 min, %s: median %.3f ns, 95%% %.3f ns, "
                "max %.3f ns (%zu samples); at the SP3 epochs max %.4f ns\n",
                std::string(system_name(system)).c_str(), percentile(values, 0.5) * 1e9,
                percentile(values, 0.95) * 1e9, percentile(values, 1.0) * 1e9, values.size(),
                percentile(on_epochs_s[system], 1.0) * 1e9);
    EXPECT_LT(percentile(on_epochs_s[system], 1.0), 1e-12);
  }
  size_t gps_below_1ns = 0, gps_total = 0;
  for (const auto& [satellite, worst_s] : worst_between_s) {
    if (satellite.system != GnssSystem::kGps) continue;
    ++gps_total;
    gps_below_1ns += worst_s < 1e-9 ? 1 : 0;
  }
  std::printf("[ measured ] GPS satellites whose 15-min linear clock stays within 1 ns of the 30 s clock all day: %zu of %zu\n",
              gps_below_1ns, gps_total);
  EXPECT_EQ(gps_total, 30u);
  EXPECT_GE(gps_below_1ns, 24u);
  EXPECT_LT(percentile(between_s[GnssSystem::kGps], 0.95), 1e-9);
}

TEST(PreciseRealFiles, StateFromSp3AndClockFile) {
  const auto orbit_path = SKYTRACE_SHARED_FILE(kCodOrbit);
  const auto clock_path = SKYTRACE_SHARED_FILE(kCodClock);
  auto orbits = read_sp3(orbit_path);
  auto clocks = read_rinex_clock(clock_path);
  ASSERT_TRUE(orbits.ok() && clocks.ok());
  auto source = PreciseEphemerides::create(std::move(*orbits), std::move(*clocks));
  ASSERT_TRUE(source.ok());
  EXPECT_EQ(source->satellites().size(), 116u);
  // G05 at 19:30:30: on a 30 s clock sample, between 5-min orbit samples.
  const GnssTime t = gpst(2021, 4, 28, 19, 30, 30.0);
  auto state = source->state(sat("G05"), t);
  ASSERT_TRUE(state.ok()) << state.error().message;
  EXPECT_DOUBLE_EQ(state->clock_bias_s, -0.404037740176E-04);
  const double radius_m = state->position_m.norm();
  EXPECT_GT(radius_m, 26.0e6);  // a = 26560 km, e < 0.02
  EXPECT_LT(radius_m, 27.1e6);
  // Velocity against the position difference over +-0.5 s.
  auto before = source->orbit(sat("G05"), t - 0.5);
  auto after = source->orbit(sat("G05"), t + 0.5);
  ASSERT_TRUE(before.ok() && after.ok());
  EXPECT_LT((state->velocity_mps - (after->position_m - before->position_m)).norm(), 1e-4);
  // GPS orbits are nearly circular: the relativistic term stays within about 25 ns.
  EXPECT_LT(std::abs(state->relativistic_s), 25e-9);
  // Beyond the clock file (20:30): refused, the orbit alone still works.
  const GnssTime late = gpst(2021, 4, 28, 21, 0, 0.0);
  EXPECT_TRUE(source->orbit(sat("G05"), late).ok());
  auto no_clock = source->state(sat("G05"), late);
  ASSERT_FALSE(no_clock.ok());
  EXPECT_NE(no_clock.error().message.find("no precise clock for G05 at 2021-04-28T21:00:00 GPST"), std::string::npos)
      << no_clock.error().message;
  // Beyond the orbits: the message names the satellite, the time and the coverage.
  auto beyond = source->state(sat("G05"), gpst(2021, 4, 29, 0, 30, 0.0));
  ASSERT_FALSE(beyond.ok());
  EXPECT_EQ(beyond.error().message,
            "no precise orbit for G05 at 2021-04-29T00:30:00 GPST (the SP3 data cover 2021-04-28T18:00:00 to "
            "2021-04-29T00:00:00 GPST)");
}

// The per-interval Chebyshev fits a run's generator evaluates against the full interpolation they
// replace, every satellite of a 15-minute (two days merged) and a 5-minute product, forward in
// steps of 17.3 s and at a few earlier times (the light-time guess steps back): positions within
// 1 um, velocities within 10 nm/s (10 um/s on sample times), the same clocks, and the same errors where the full
// interpolation refuses (beyond the data's extrapolation, gaps).
TEST(PreciseRealFiles, OrbitCacheAgreesWithFullInterpolation) {
  struct Product {
    std::vector<std::filesystem::path> orbits;
    std::optional<std::filesystem::path> clock;
  };
  const auto grg_before = SKYTRACE_SHARED_FILE(kGrgDayBefore);
  const auto grg_day = SKYTRACE_SHARED_FILE(kGrgDay);
  const auto grg_clock = SKYTRACE_SHARED_FILE(kGrgClock);
  const auto cod_orbit = SKYTRACE_SHARED_FILE(kCodOrbit);
  const auto cod_clock = SKYTRACE_SHARED_FILE(kCodClock);
  const std::vector<Product> products = {{{grg_before, grg_day}, grg_clock}, {{cod_orbit}, cod_clock}};
  for (const auto& product : products) {
    auto orbits = read_sp3(product.orbits);
    ASSERT_TRUE(orbits.ok()) << orbits.error().message;
    auto clocks = read_rinex_clock(*product.clock);
    ASSERT_TRUE(clocks.ok()) << clocks.error().message;
    auto precise = PreciseEphemerides::create(std::move(*orbits), std::move(*clocks));
    ASSERT_TRUE(precise.ok()) << precise.error().message;
    const auto view = precise->sequential_view();
    ASSERT_NE(view, nullptr);
    const auto& cache = dynamic_cast<const PreciseOrbitCache&>(*view);
    const GnssTime first = precise->orbit_span().first - 60.0;
    const GnssTime last = precise->orbit_span().last + 1000.0;  // beyond the one interval served
    double worst_position_m = 0.0, worst_velocity_mps = 0.0, worst_velocity_on_sample_mps = 0.0;
    int compared = 0, refused = 0;
    for (const auto& satellite : precise->satellites()) {
      for (GnssTime t = first; t < last; t += 17.3) {
        for (const double back_s : {0.0, -0.08}) {
          const GnssTime at = t + back_s;
          auto exact = precise->orbit(satellite, at);
          auto cached = cache.orbit(satellite, at);
          ASSERT_EQ(exact.ok(), cached.ok()) << satellite.to_string() << " " << at.to_iso8601(TimeScale::kGpst, 3);
          if (!exact.ok()) {
            EXPECT_EQ(exact.error().message, cached.error().message);
            ++refused;
            continue;
          }
          worst_position_m = std::max(worst_position_m, (exact->position_m - cached->position_m).norm());
          // On a sample time the full interpolation centres its window on that sample: another
          // polynomial, whose velocity differs by a few um/s from the neighbouring interval's.
          const auto& epochs = precise->orbits().epochs;
          const auto next = std::lower_bound(epochs.begin(), epochs.end(), at - 1e-3);
          const bool on_sample = next != epochs.end() && std::abs(*next - at) < 1e-3;
          double& worst = on_sample ? worst_velocity_on_sample_mps : worst_velocity_mps;
          worst = std::max(worst, (exact->velocity_mps - cached->velocity_mps).norm());
          ++compared;
        }
      }
      // The state: the same clock and relativistic terms from the same orbit.
      const GnssTime middle = precise->orbit_span().first + 3333.0;
      auto exact_state = precise->state(satellite, middle);
      auto cached_state = cache.state(satellite, middle);
      ASSERT_EQ(exact_state.ok(), cached_state.ok()) << satellite.to_string();
      if (exact_state.ok()) {
        EXPECT_EQ(exact_state->clock_bias_s, cached_state->clock_bias_s);
        EXPECT_NEAR(exact_state->relativistic_s, cached_state->relativistic_s, 1e-18);
      }
    }
    EXPECT_GT(compared, 100000);
    EXPECT_GT(refused, 0);
    EXPECT_LT(worst_position_m, 1e-6);
    EXPECT_LT(worst_velocity_mps, 1e-8);
    EXPECT_LT(worst_velocity_on_sample_mps, 1e-5);
    std::printf("orbit cache: %d times compared, %d refused alike; worst %.3g m, %.3g m/s (%.3g m/s on samples)\n",
                compared, refused, worst_position_m, worst_velocity_mps, worst_velocity_on_sample_mps);
  }
}

// An independent check of the state as a whole: broadcast ephemerides of the same day (another
// implementation, another product) must agree at the broadcast accuracy, and the relativistic
// term -2 r.v / c^2 must match the Keplerian F e sqrt(A) sin E of the broadcast evaluation.
TEST(PreciseRealFiles, AgreesWithBroadcastEphemerides) {
  const auto orbit_path = SKYTRACE_SHARED_FILE(kGrgDay);
  const auto clock_path = SKYTRACE_SHARED_FILE(kGrgClock);
  const auto nav_path = SKYTRACE_SHARED_FILE(kEsbcNav);
  auto precise = PreciseEphemerides::create(read_sp3(orbit_path).value(), read_rinex_clock(clock_path).value());
  ASSERT_TRUE(precise.ok());
  auto navigation = read_rinex_nav(nav_path);
  ASSERT_TRUE(navigation.ok()) << navigation.error().message;
  const BroadcastEphemerides broadcast(std::move(*navigation));
  std::map<GnssSystem, std::vector<double>> position_m, clock_s, relativistic_s;
  for (int hour = 1; hour < 24; hour += 3) {
    const GnssTime t = gpst(2020, 6, 25, hour, 7, 30.0);
    for (const auto& satellite : precise->satellites()) {
      auto p = precise->state(satellite, t);
      auto b = broadcast.state(satellite, t);
      if (!p.ok() || !b.ok()) continue;
      position_m[satellite.system].push_back((p->position_m - b->position_m).norm());
      if (satellite.system == GnssSystem::kGlonass) continue;  // broadcast clock holds the term
      clock_s[satellite.system].push_back(std::abs(p->clock_bias_s - b->clock_bias_s));
      relativistic_s[satellite.system].push_back(std::abs(p->relativistic_s - b->relativistic_s));
    }
  }
  for (const auto& [system, values] : position_m) {
    const auto& clocks = clock_s[system];
    const auto& relativistic = relativistic_s[system];
    std::printf("[ measured ] precise vs broadcast, %s: position median %.2f m, max %.2f m (CoM vs APC "
                "uncorrected)",
                std::string(system_name(system)).c_str(), percentile(values, 0.5), percentile(values, 1.0));
    if (!clocks.empty()) {
      std::printf("; clock median %.2f ns, max %.2f ns; relativistic term max %.3f ns", percentile(clocks, 0.5) * 1e9,
                  percentile(clocks, 1.0) * 1e9, percentile(relativistic, 1.0) * 1e9);
    }
    std::printf("\n");
    EXPECT_GT(values.size(), 50u);
    // GLONASS broadcast orbits are a few metres (measured median 2.8 m), GPS and Galileo about 1 m.
    const bool glonass = system == GnssSystem::kGlonass;
    EXPECT_LT(percentile(values, 0.5), glonass ? 5.0 : 2.0) << system_name(system);
    EXPECT_LT(percentile(values, 1.0), glonass ? 15.0 : 10.0) << system_name(system);
    if (glonass) continue;
    EXPECT_LT(percentile(clocks, 0.5), 3e-9) << system_name(system);
    EXPECT_LT(percentile(clocks, 1.0), 15e-9) << system_name(system);
    EXPECT_LT(percentile(relativistic, 1.0), 0.2e-9) << system_name(system);
  }
  EXPECT_EQ(position_m.size(), 3u);
}

}  // namespace
}  // namespace skytrace::orbits
