// The RTK engine end to end: the contract pair simulated in one scenario (the rover's fix.csv from
// its base's epochs), the same pair as two RINEX files through `skytrace position --base` beside
// RTKLIB's rnx2rtkp (kinematic, fix-and-hold, same masks), a real GEONET pair beside rnx2rtkp
// (static, L1+L2), and bad base input (a position kilometres off, no common epochs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "rtklib.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

struct FixRow {
  std::string time;  // ISO 8601 to the millisecond
  double tow_s = 0.0;
  std::string fix;
  Eigen::Vector3d ecef_m = Eigen::Vector3d::Zero();
  std::string message;
  std::optional<double> age_s;
};

// fix.csv rows (the columns this test needs; messages hold no commas here).
std::vector<FixRow> read_fix_csv(const std::filesystem::path& path) {
  std::vector<FixRow> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    if (cells.size() < 27) continue;
    FixRow row;
    row.time = cells[0];
    row.tow_s = std::stod(cells[2]);
    row.fix = cells[3];
    if (!cells[8].empty()) row.ecef_m = Eigen::Vector3d(std::stod(cells[8]), std::stod(cells[9]), std::stod(cells[10]));
    row.message = cells[26];
    if (cells.size() > 29 && !cells[29].empty()) row.age_s = std::stod(cells[29]);
    rows.push_back(row);
  }
  return rows;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// RTKLIB solutions by time of day "hh:mm:ss" (its xyz output), quality 1 fix, 2 float.
std::map<std::string, test::RtklibSolution> rtklib_by_time(const std::filesystem::path& path) {
  std::map<std::string, test::RtklibSolution> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '%') continue;
    std::istringstream fields(line);
    std::string date, time;
    test::RtklibSolution s;
    fields >> date >> time >> s.ecef_m.x() >> s.ecef_m.y() >> s.ecef_m.z() >> s.quality;
    if (fields) out[time.substr(0, 8)] = s;
  }
  return out;
}

struct Agreement {
  size_t epochs = 0, same_type = 0, skytrace_fixed = 0, rtklib_fixed = 0;
  std::vector<double> fixed_differences_m;
};

Agreement compare(const std::vector<FixRow>& rows, const std::map<std::string, test::RtklibSolution>& rtklib) {
  Agreement a;
  for (const FixRow& row : rows) {
    ++a.epochs;
    const auto it = rtklib.find(row.time.substr(11, 8));
    const int theirs = it == rtklib.end() ? 0 : it->second.quality;
    const int mine = row.fix == "rtk_fixed" ? 1 : row.fix == "rtk_float" ? 2 : 5;
    if (mine == 1) ++a.skytrace_fixed;
    if (theirs == 1) ++a.rtklib_fixed;
    if (mine == theirs || (theirs == 0 && mine == 5)) ++a.same_type;
    if (mine == 1 && theirs == 1) a.fixed_differences_m.push_back((row.ecef_m - it->second.ecef_m).norm());
  }
  return a;
}

std::string rtklib_config(const std::string& mode, const std::string& armode, int navsys, double mask_deg,
                          const Eigen::Vector3d& base) {
  std::ostringstream c;
  c.precision(4);
  c << std::fixed << "pos1-posmode=" << mode << "\npos1-frequency=l1+2\npos1-soltype=forward\npos1-elmask=" << mask_deg
    << "\npos1-ionoopt=brdc\npos1-tropopt=saas\npos1-sateph=brdc\npos1-navsys=" << navsys << "\npos2-armode=" << armode
    << "\nant2-postype=xyz\nant2-pos1=" << base.x() << "\nant2-pos2=" << base.y() << "\nant2-pos3=" << base.z()
    << "\nout-solformat=xyz\n";
  return c.str();
}

std::filesystem::path contract_dir() { return test::shared_data_dir().parent_path() / "contract"; }

bool contract_available() {
  return std::filesystem::exists(contract_dir() / "rtk-pair.yaml") &&
         std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
}

void run_scenario(const std::string& name, const std::filesystem::path& out) {
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote((contract_dir() / (name + ".yaml")).string()) + " --out " +
                                   test::shell_quote(out.string()) + " --quiet --no-truth");
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

TEST(RtkEngineEndToEnd, ContractPairInOneScenarioFixesAndLandsOnTheRover) {
  if (!contract_available()) GTEST_SKIP() << "contract scenarios or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  const auto dir = test::make_temp_dir("rtk_pair");
  run_scenario("rtk-pair", dir / "pair");
  const auto rows = read_fix_csv(dir / "pair/fix_ROVR.csv");
  ASSERT_EQ(rows.size(), 1801u);
  const Eigen::Vector3d rover = geodetic_to_ecef(Geodetic{55.4935, 8.4880, 75.0});
  size_t after_first_minute = 0, fixed = 0;
  std::vector<double> errors_m;
  for (const FixRow& row : rows) {
    if (row.tow_s < rows.front().tow_s + 60.0) continue;
    ++after_first_minute;
    if (row.fix != "rtk_fixed") continue;
    ++fixed;
    errors_m.push_back((row.ecef_m - rover).norm());
  }
  const double fixed_ratio = static_cast<double>(fixed) / static_cast<double>(after_first_minute);
  std::printf("[ figures ] skytrace run rtk-pair: %.1f %% rtk_fixed after the first minute, fixed error median %.4f m\n",
              100.0 * fixed_ratio, median(errors_m));
  EXPECT_GE(fixed_ratio, 0.95);
  EXPECT_LE(median(errors_m), 0.01);
  // The base's own fix.csv stays single-point.
  const auto base_rows = read_fix_csv(dir / "pair/fix_BASE.csv");
  ASSERT_FALSE(base_rows.empty());
  EXPECT_EQ(base_rows.back().fix, "3d");
}

TEST(RtkEngineEndToEnd, ContractRinexPairAgreesWithRnx2rtkpKinematicFixAndHold) {
  if (!contract_available()) GTEST_SKIP() << "contract scenarios or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("rtk_rinex_pair");
  run_scenario("rtk-base", dir / "base");
  run_scenario("rtk-rover", dir / "rover");
  const Eigen::Vector3d base(3582105.2910, 532589.7313, 5232754.8054);
  std::ofstream(dir / "rtk.conf") << rtklib_config("kinematic", "fix-and-hold", 1 + 8, 15.0, base);
  const auto rover_obs = test::shell_quote((dir / "rover/obs.rnx").string());
  const auto base_obs = test::shell_quote((dir / "base/obs.rnx").string());
  const auto nav = test::shell_quote((dir / "rover/nav.rnx").string());
  const auto r = test::run_command("rnx2rtkp -k " + test::shell_quote((dir / "rtk.conf").string()) + " -o " +
                                   test::shell_quote((dir / "rtk.pos").string()) + " " + rover_obs + " " + base_obs +
                                   " " + nav);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The same masks (15 degrees), GPS + Galileo, base position from the header (the marker).
  const auto s = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " position " + rover_obs +
                                   " --nav " + nav + " --base " + base_obs + " --systems G,E --out " +
                                   test::shell_quote((dir / "rtk.csv").string()));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  const Agreement a = compare(read_fix_csv(dir / "rtk.csv"), rtklib_by_time(dir / "rtk.pos"));
  std::printf("[ figures ] rtk-rover/rtk-base, kinematic fix-and-hold G+E: %zu epochs, skytrace fixed %zu, rnx2rtkp "
              "fixed %zu, same type %.1f %%, fixed positions apart median %.4f m max %.4f m\n",
              a.epochs, a.skytrace_fixed, a.rtklib_fixed, 100.0 * a.same_type / a.epochs,
              median(a.fixed_differences_m),
              a.fixed_differences_m.empty() ? NAN : *std::max_element(a.fixed_differences_m.begin(), a.fixed_differences_m.end()));
  EXPECT_EQ(a.epochs, 1801u);
  EXPECT_GE(static_cast<double>(a.same_type) / a.epochs, 0.95);
  ASSERT_GE(a.fixed_differences_m.size(), 1700u);
  EXPECT_LE(*std::max_element(a.fixed_differences_m.begin(), a.fixed_differences_m.end()), 0.01);
}

TEST(RtkEngineEndToEnd, RealGeonetPairAgreesWithRnx2rtkpStatic) {
  const auto data = test::shared_data_dir() / "real/gsi_0759_3040_2005092";
  if (!std::filesystem::exists(data / "07590920.05o")) GTEST_SKIP() << "GEONET data absent (set SKYTRACE_SHARED_DATA)";
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("rtk_geonet");
  const Eigen::Vector3d base(-3978242.4348, 3382841.1715, 3649902.7667);  // 3040's header position
  std::ofstream(dir / "rtk.conf") << rtklib_config("static", "continuous", 1, 15.0, base);
  const auto rover_obs = test::shell_quote((data / "07590920.05o").string());
  const auto base_obs = test::shell_quote((data / "30400920.05o").string());
  const auto nav = test::shell_quote((data / "07590920.05n").string());
  const auto r = test::run_command("rnx2rtkp -k " + test::shell_quote((dir / "rtk.conf").string()) + " -o " +
                                   test::shell_quote((dir / "rtk.pos").string()) + " " + rover_obs + " " + base_obs +
                                   " " + nav);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " position " + rover_obs +
                                   " --nav " + nav + " --base " + base_obs +
                                   " --dynamics static --ambiguity-mode continuous --out " +
                                   test::shell_quote((dir / "rtk.csv").string()));
  ASSERT_EQ(s.exit_code, 0) << s.output;
  auto rows = read_fix_csv(dir / "rtk.csv");
  ASSERT_GE(rows.size(), 120u);
  rows.resize(120);
  const Agreement a = compare(rows, rtklib_by_time(dir / "rtk.pos"));
  std::printf("[ figures ] GEONET 0759/3040 static L1+L2, first 120 epochs: skytrace fixed %zu, rnx2rtkp fixed %zu, "
              "both fixed %zu, apart median %.4f m max %.4f m\n",
              a.skytrace_fixed, a.rtklib_fixed, a.fixed_differences_m.size(), median(a.fixed_differences_m),
              a.fixed_differences_m.empty() ? NAN : *std::max_element(a.fixed_differences_m.begin(), a.fixed_differences_m.end()));
  EXPECT_GE(a.skytrace_fixed, 110u);
  ASSERT_GE(a.fixed_differences_m.size(), 100u);
  EXPECT_LE(*std::max_element(a.fixed_differences_m.begin(), a.fixed_differences_m.end()), 0.02);
}

TEST(RtkEngineEndToEnd, BadBaseInputGivesAClearStateNeverAWrongFix) {
  const auto data = test::shared_data_dir() / "real/gsi_0759_3040_2005092";
  if (!std::filesystem::exists(data / "07590920.05o")) GTEST_SKIP() << "GEONET data absent (set SKYTRACE_SHARED_DATA)";
  const auto dir = test::make_temp_dir("rtk_bad_base");
  const std::string position = test::shell_quote(test::skytrace_executable().string()) + " position " +
                               test::shell_quote((data / "07590920.05o").string()) + " --nav " +
                               test::shell_quote((data / "07590920.05n").string());
  // The base position 3 km off: single-point fixes that say why.
  auto r = test::run_command(position + " --base " + test::shell_quote((data / "30400920.05o").string()) +
                             " --base-position=-3980242.4348,3384841.1715,3649902.7667 --out " +
                             test::shell_quote((dir / "off.csv").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const FixRow& row : read_fix_csv(dir / "off.csv")) {
    ASSERT_EQ(row.fix, "3d") << row.time;
    ASSERT_NE(row.message.find("base position"), std::string::npos) << row.message;
  }
  // A "base" that is the rover's own file shifted by a day: no base epoch near any rover epoch.
  std::ifstream in(data / "30400920.05o");
  std::stringstream text;
  text << in.rdbuf();
  std::string shifted = text.str();
  for (size_t at = 0; (at = shifted.find("\n 05  4  2 ", at)) != std::string::npos; ++at) shifted.replace(at, 11, "\n 05  4  1 ");
  std::ofstream(dir / "old.05o") << shifted;
  r = test::run_command(position + " --base " + test::shell_quote((dir / "old.05o").string()) + " --out " +
                        test::shell_quote((dir / "old.csv").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const FixRow& row : read_fix_csv(dir / "old.csv")) {
    ASSERT_EQ(row.fix, "3d") << row.time;
    ASSERT_NE(row.message.find("base observations"), std::string::npos) << row.message;
  }
  // A malformed --base-position is an option error.
  r = test::run_command(position + " --base " + test::shell_quote((data / "30400920.05o").string()) +
                        " --base-position 1,2 --out " + test::shell_quote((dir / "x.csv").string()));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--base-position"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// A base as an RTCM 3 stream (1006 and MSM7 from `output.rtcm3`, with garbage between frames as a
// serial line or NTRIP relay delivers it): the same fixes as with the base's RINEX file, positions
// within the fields' resolution; without 1005/1006 the base position must be given.
TEST(RtkEngineEndToEnd, BaseAsAnRtcmStreamFixesAsItsRinexFile) {
  if (!contract_available()) GTEST_SKIP() << "contract scenarios or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  const auto dir = test::make_temp_dir("rtk_rtcm_base");
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote((contract_dir() / "rtk-pair.yaml").string()) + " --out " +
                                   test::shell_quote((dir / "pair").string()) +
                                   " --quiet --no-truth --set output.rtcm3=true --set time.duration_s=300");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Garbage (with a false preamble) after every frame.
  std::ifstream in(dir / "pair/obs_BASE.rtcm3", std::ios::binary);
  const std::string clean((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string noisy;
  for (size_t i = 0; i + 3 <= clean.size();) {
    const size_t length = ((static_cast<unsigned char>(clean[i + 1]) & 0x03) << 8) | static_cast<unsigned char>(clean[i + 2]);
    noisy += clean.substr(i, length + 6) + "\xD3\x01garbage";
    i += length + 6;
  }
  std::ofstream(dir / "noisy.rtcm3", std::ios::binary) << noisy;

  const std::string position = test::shell_quote(test::skytrace_executable().string()) + " position " +
                               test::shell_quote((dir / "pair/obs_ROVR.rnx").string()) + " --nav " +
                               test::shell_quote((dir / "pair/nav.rnx").string());
  const auto with_rinex = test::run_command(position + " --base " + test::shell_quote((dir / "pair/obs_BASE.rnx").string()) +
                                            " --out " + test::shell_quote((dir / "rinex.csv").string()) + " 2>&1");
  ASSERT_EQ(with_rinex.exit_code, 0) << with_rinex.output;
  const auto with_rtcm = test::run_command(position + " --base " + test::shell_quote((dir / "noisy.rtcm3").string()) +
                                           " --out " + test::shell_quote((dir / "rtcm.csv").string()) + " 2>&1");
  ASSERT_EQ(with_rtcm.exit_code, 0) << with_rtcm.output;
  EXPECT_NE(with_rtcm.output.find("bytes outside valid frames"), std::string::npos) << with_rtcm.output;
  const auto a = read_fix_csv(dir / "rinex.csv");
  const auto b = read_fix_csv(dir / "rtcm.csv");
  ASSERT_EQ(a.size(), b.size());
  size_t both_fixed = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].fix, b[k].fix) << k;
    if (a[k].fix == "rtk_fixed" && b[k].fix == "rtk_fixed") {
      ++both_fixed;
      EXPECT_LT((a[k].ecef_m - b[k].ecef_m).norm(), 0.003) << k;
    }
  }
  EXPECT_GT(both_fixed, 280u);

  // The real GMSD stream carries no 1005/1006: the base position is required.
  const auto gmsd = test::shared_data_dir() / "real/gsi_0759_3040_2005092/GMSD7_20121014.rtcm3";
  if (std::filesystem::exists(gmsd)) {
    const auto no_position = test::run_command(position + " --base " + test::shell_quote(gmsd.string()) + " 2>&1");
    EXPECT_EQ(no_position.exit_code, 2) << no_position.output;
    EXPECT_NE(no_position.output.find("no station position (message 1005 or 1006)"), std::string::npos)
        << no_position.output;
  }
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// Corrections that arrive late, every few seconds, and stop for a minute (rtk.latency_s,
// rtk.interval_s, rtk.outages_s): the age of corrections follows, the rover falls back to its own
// fix once they are older than the engine's limit (30 s) and fixes again when they return.
TEST(RtkEngineEndToEnd, LateSparseAndInterruptedCorrectionsShowInAgeAndSolutionType) {
  if (!contract_available()) GTEST_SKIP() << "contract scenarios or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  const auto dir = test::make_temp_dir("rtk_link");
  const auto r = test::run_command(
      test::shell_quote(test::skytrace_executable().string()) + " run " +
      test::shell_quote((contract_dir() / "rtk-pair.yaml").string()) + " --out " + test::shell_quote((dir / "pair").string()) +
      " --quiet --no-truth --set time.duration_s=300 --set receivers.1.rtk.latency_s=2 --set receivers.1.rtk.interval_s=5"
      " --set 'receivers.1.rtk.outages_s=[[100, 160]]' 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rows = read_fix_csv(dir / "pair/fix_ROVR.csv");
  ASSERT_EQ(rows.size(), 301u);
  const double t0 = rows.front().tow_s;
  size_t fixed_before = 0, single_in_outage = 0, fixed_after = 0;
  for (const auto& row : rows) {
    const double t = row.tow_s - t0;
    if (t >= 60.0 && t < 100.0) {
      ASSERT_TRUE(row.age_s.has_value()) << row.time;
      EXPECT_GE(*row.age_s, 2.0 - 1e-6) << row.time;
      EXPECT_LE(*row.age_s, 7.0 + 1e-6) << row.time;
      fixed_before += row.fix == "rtk_fixed";
    }
    if (t >= 130.0 && t < 160.0) {
      EXPECT_TRUE(row.fix == "3d") << row.time << " " << row.fix;
      single_in_outage += row.fix == "3d";
    }
    if (t >= 200.0) fixed_after += row.fix == "rtk_fixed";
  }
  EXPECT_GE(fixed_before, 38u);
  EXPECT_EQ(single_in_outage, 30u);
  EXPECT_GE(fixed_after, 95u);
}

// The yard example's rover under the lime tree's crown (examples/rtk/rtk-yard.yaml, 10 minutes):
// the crown's fades (models.foliage_fading) break the phase lock of most signals and the fix;
// without them the mean attenuation alone leaves it fixed (a few weak signals, reacquired near the
// threshold, lose lock all the same); 10 m from the trunk, where few rays cross the crown, the
// C/N0-weighted engine keeps its fix. The report shows the solution types.
TEST(RtkEngineEndToEnd, UnderATreeCrownTheFoliageFadesBreakTheFix) {
  if (!contract_available()) GTEST_SKIP() << "contract scenarios or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  const auto dir = test::make_temp_dir("rtk_tree");
  const auto fixed_share = [&](const std::string& name, const std::string& where, const std::string& sets) {
    const auto out = dir / name;
    const auto r = test::run_command(
        test::shell_quote(test::skytrace_executable().string()) + " run " +
        test::shell_quote((test::source_dir() / "examples/rtk/rtk-yard.yaml").string()) + " --out " +
        test::shell_quote(out.string()) + " --quiet --no-truth --set time.duration_s=600 --set " +
        test::shell_quote("receivers.1.position.world_enu_m=" + where) + " " + sets + " 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const auto rows = read_fix_csv(out / "fix_ROVR.csv");
    EXPECT_EQ(rows.size(), 601u);
    size_t fixed = 0;
    for (const FixRow& row : rows) fixed += row.fix == "rtk_fixed";
    // The rover's signals that lose lock after the first epoch (RINEX LLI bit 0), counted once
    // each: a weak signal the receiver reacquires and loses again counts as one.
    std::set<std::pair<std::string, size_t>> slipped;
    std::ifstream obs(out / "obs_ROVR.rnx");
    std::string line;
    bool header = true;
    int epochs = 0;
    while (std::getline(obs, line)) {
      if (header) {
        header = line.find("END OF HEADER") == std::string::npos;
        continue;
      }
      if (line.starts_with(">")) {
        ++epochs;
        continue;
      }
      if (epochs <= 1) continue;
      for (size_t field = 3; field + 15 <= line.size(); field += 16) {
        const char lli = line[field + 14];
        if (lli == '1' || lli == '3' || lli == '5' || lli == '7') slipped.emplace(line.substr(0, 3), field);
      }
    }
    const size_t slips = slipped.size();
    const double share = static_cast<double>(fixed) / static_cast<double>(rows.size());
    std::printf("[ figures ] rtk-yard %s: %.1f %% rtk_fixed, %zu signals lost lock\n", name.c_str(), 100.0 * share, slips);
    EXPECT_NE(test::run_command("grep -c 'Solution type' " + test::shell_quote((out / "report.html").string())).output, "0\n");
    return std::make_pair(share, slips);
  };
  const auto [faded, faded_slips] = fixed_share("crown", "[-30.0, 12.0, 1.5]", "");
  const auto [still, still_slips] = fixed_share("crown_without_fading", "[-30.0, 12.0, 1.5]", "--set models.foliage_fading=false");
  const auto [near, near_slips] = fixed_share("ten_metres_away", "[-20.0, 12.0, 1.5]", "");
  EXPECT_LT(faded, 0.2);
  EXPECT_GT(still, 0.9);
  EXPECT_GT(near, 0.9);
  EXPECT_GT(faded_slips, 3 * still_slips);
}

}  // namespace
}  // namespace skytrace

namespace skytrace {
namespace {

// Two antennas on one body, 1.4 m apart at azimuth 30 degrees and level: the moving-base rover's
// fixed baseline gives the heading and pitch (fix.csv, NMEA HDT/THS), its sigma from the baseline
// covariance.
TEST(RtkEngineEndToEnd, MovingBaseGivesTheHeadingOfTheBaseline) {
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  if (!std::filesystem::exists(nav)) GTEST_SKIP() << "ESBC navigation file absent";
  const auto dir = test::make_temp_dir("rtk_heading");
  std::ofstream(dir / "heading.yaml") << test::moving_base_scenario_yaml(nav, "0.7, 1.2124356, 1.5", 120);
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote((dir / "heading.yaml").string()) + " --out " +
                                   test::shell_quote((dir / "out").string()) + " --quiet --no-truth --set output.nmea=true 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "out/fix_ANT2.csv");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> columns;
  for (std::stringstream s(line); std::getline(s, line, ',');) columns.push_back(line);
  const auto at = [&](const char* name) { return static_cast<size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin()); };
  size_t with_heading = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    for (std::stringstream s(line); std::getline(s, line, ',');) cells.push_back(line);
    cells.resize(columns.size());
    if (cells[at("heading_deg")].empty()) continue;
    ++with_heading;
    EXPECT_EQ(cells[at("fix")], "rtk_fixed");
    EXPECT_NEAR(std::stod(cells[at("heading_deg")]), 30.0, 0.3);
    EXPECT_NEAR(std::stod(cells[at("pitch_deg")]), 0.0, 0.5);
    const double sigma = std::stod(cells[at("heading_sigma_deg")]);
    EXPECT_GT(sigma, 0.0);
    EXPECT_LT(sigma, 0.5);
  }
  EXPECT_GT(with_heading, 100u);
  std::ifstream nmea(dir / "out/fix_ANT2.nmea");
  const std::string text((std::istreambuf_iterator<char>(nmea)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("$GNHDT,30.0"), std::string::npos);
  EXPECT_NE(text.find(",A*"), std::string::npos);
  EXPECT_NE(text.find("THS,"), std::string::npos);
}

}  // namespace
}  // namespace skytrace
