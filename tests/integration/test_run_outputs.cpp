// The outputs of `skytrace run` read back: skytrace's own RINEX reader finds exactly the values of
// truth.csv, RTKLIB reads both files without a single warning, and summary.json counts agree.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

class RunOutputs : public ::testing::Test {
 protected:
  void SetUp() override {
    scenario_ = test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
    if (!std::filesystem::exists(scenario_) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
    }
    out_ = test::make_temp_dir(std::string("run_outputs_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote(scenario_.string()) + " --out " + test::shell_quote(out_.string()) +
                                     " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  std::filesystem::path scenario_, out_;
};

TEST_F(RunOutputs, ObservationFileReadsBackToTheTruth) {
  auto file = io::read_rinex_obs(out_ / "obs.rnx");
  ASSERT_TRUE(file.ok()) << file.error().message;
  const auto& header = file->header;
  EXPECT_EQ(file->epochs.size(), 121u);
  ASSERT_TRUE(header.approx_position_ecef_m.has_value());
  EXPECT_NEAR((*header.approx_position_ecef_m)[0], 3582105.2910, 1e-4);
  EXPECT_NEAR(header.antenna_delta_hen_m[0], 0.2160, 1e-4);
  EXPECT_EQ(header.signal_strength_unit, "DBHZ");
  ASSERT_TRUE(header.interval_s.has_value());
  EXPECT_DOUBLE_EQ(*header.interval_s, 30.0);
  EXPECT_EQ(header.leap_seconds.value_or(0), 18);
  EXPECT_FALSE(header.glonass_slots.empty());
  EXPECT_EQ(header.observation_types.size(), 5u);  // G R E C J

  // truth.csv: pseudorange and phase per (time, satellite, signal).
  std::map<std::string, std::pair<double, double>> truth;
  std::istringstream in(test::read_zst_text(out_ / "truth.csv.zst"));
  std::string line;
  std::getline(in, line);
  size_t tracked_rows = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    if (cells.size() < 23 || cells[4] != "tracked" || cells[3].empty()) continue;
    ++tracked_rows;
    truth[cells[0].substr(0, 19) + cells[2] + cells[3]] = {std::stod(cells[19]), std::stod(cells[20])};
  }
  size_t compared = 0;
  for (const auto& epoch : file->epochs) {
    const std::string time = epoch.time.to_iso8601(TimeScale::kGpst, 0);
    for (const auto& sat : epoch.satellites) {
      const auto& types = header.observation_types.at(sat.satellite.system);
      for (size_t i = 0; i < sat.values.size() && i < types.size(); ++i) {
        if (!sat.values[i].value || types[i].kind() != 'C') continue;
        const std::string signal = std::string(1, system_letter(sat.satellite.system)) + types[i].code.substr(1);
        const auto it = truth.find(time + sat.satellite.to_string() + signal);
        ASSERT_NE(it, truth.end()) << time << " " << sat.satellite.to_string() << " " << signal;
        EXPECT_NEAR(*sat.values[i].value, it->second.first, 0.0006);
        ASSERT_TRUE(sat.values[i + 1].value.has_value());
        EXPECT_NEAR(*sat.values[i + 1].value, it->second.second, 0.0006);
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, tracked_rows);
  EXPECT_GT(compared, 9000u);

  std::ifstream summary_in(out_ / "summary.json");
  const auto summary = nlohmann::json::parse(summary_in);
  EXPECT_EQ(summary["epochs"].get<size_t>(), 121u);
  EXPECT_EQ(summary["signal_observations"].get<size_t>(), compared);
  EXPECT_EQ(summary["configuration"]["seed"].get<int>(), 1);
}

// A satellite the navigation data holds no valid ephemeris for has no geometry: truth.csv says so
// in one row when it enters that state, not at every epoch (the contract's file: several BeiDou
// and Galileo satellites all along).
TEST_F(RunOutputs, SatellitesWithoutEphemerisHaveOneTruthRowNotOnePerEpoch) {
  const std::string truth = test::read_zst_text(out_ / "truth.csv.zst");
  std::map<std::string, int> rows_without_ephemeris;
  std::set<std::string> epochs;
  std::istringstream lines(truth);
  std::string line;
  std::getline(lines, line);  // header
  for (; std::getline(lines, line);) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    ASSERT_GE(cells.size(), 6U);
    epochs.insert(cells[0]);
    if (cells[4] == "no_ephemeris") ++rows_without_ephemeris[cells[2]];
  }
  ASSERT_GT(epochs.size(), 100U);
  EXPECT_GE(rows_without_ephemeris.size(), 5U);
  for (const auto& [satellite, rows] : rows_without_ephemeris) EXPECT_LE(rows, 2) << satellite;
}

TEST_F(RunOutputs, NavigationFileHoldsOnlyRecordsUsedAndReadsBack) {
  auto nav = orbits::read_rinex_nav(out_ / "nav.rnx");
  ASSERT_TRUE(nav.ok()) << nav.error().message;
  EXPECT_TRUE(nav->ionosphere.gps.has_value());
  // One hour of a 24 h merged file: far fewer records than the source.
  auto source = orbits::read_rinex_nav(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  ASSERT_TRUE(source.ok());
  EXPECT_GT(nav->record_count(), 50u);
  EXPECT_LT(nav->record_count(), source->record_count() / 4);
}

TEST_F(RunOutputs, RtklibReadsTheFilesWithoutAWarning) {
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  std::ofstream(out_ / "spp.conf") << "pos1-posmode=single\npos1-navsys=61\npos1-ionoopt=brdc\npos1-tropopt=saas\n";
  const auto r = test::run_command("rnx2rtkp -k " + test::shell_quote((out_ / "spp.conf").string()) + " -x 2 -o " +
                                   test::shell_quote((out_ / "spp.pos").string()) + " " +
                                   test::shell_quote((out_ / "obs.rnx").string()) + " " +
                                   test::shell_quote((out_ / "nav.rnx").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Trace level 2 holds RTKLIB's warnings (the real ESBC navigation file gives "rinex nav toc error").
  std::ifstream trace(out_ / "spp.pos.trace");
  std::string warnings, line;
  while (std::getline(trace, line)) warnings += line + "\n";
  EXPECT_TRUE(warnings.empty()) << warnings;
}

// --threads changes who computes and writes, never what: every output of a run with all its sinks
// (truth, bag, RTCM, NMEA, fix CSV, report) is the same file for 1, 2 and 4 threads. The quick start
// needs no shared data.
TEST(RunThreads, OutputsAreTheSameBytesForAnyNumberOfThreads) {
  const auto scenario = test::source_dir() / "examples" / "quickstart.yaml";
  const auto dir = test::make_temp_dir("run_threads");
  std::map<std::string, std::string> first;
  for (const int threads : {1, 2, 4}) {
    const auto out = dir / ("t" + std::to_string(threads));
    const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                                     " --quiet --threads " + std::to_string(threads) +
                                     " --set time.duration_s=600 --set output.mcap=true --set output.rtcm3=true"
                                     " --set output.nmea=true 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::map<std::string, std::string> files;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(out)) {
      if (!entry.is_regular_file() || entry.path().filename() == "summary.json") continue;  // it holds the wall time
      std::ifstream in(entry.path(), std::ios::binary);
      std::stringstream bytes;
      bytes << in.rdbuf();
      files[std::filesystem::relative(entry.path(), out).string()] = bytes.str();
    }
    EXPECT_TRUE(files.count("truth.csv.zst") && files.count("bag/bag_0.mcap") && files.count("obs.rtcm3")) << threads;
    if (first.empty()) {
      first = std::move(files);
      continue;
    }
    ASSERT_EQ(files.size(), first.size()) << threads;
    for (const auto& [name, bytes] : first) EXPECT_TRUE(files[name] == bytes) << name << " differs with " << threads << " threads";
  }
}

// Receivers observed side by side (from 3 threads with fixes, 2 without) give the same files as one
// thread: a base, its RTK rover and a third receiver in the quick start's courtyard with multipath
// (the world's path caches shared by the threads), with the default outputs and with neither truth
// nor fixes (the single writing thread's path).
TEST(RunThreads, ReceiversObservedSideBySideGiveTheSameBytes) {
  const auto dir = test::make_temp_dir("run_threads_receivers");
  const auto scenario = dir / "receivers.yaml";
  std::ofstream(scenario) << "name: threads-receivers\n"
                             "time: {start: 2026-03-01T12:00:00, scale: GPST, duration_s: 300, interval_s: 1}\n"
                             "receivers:\n"
                             "  - {name: BASE, position: {world_enu_m: [-5.0, 0.0, 1.5]}, profile: septentrio-polarx5,"
                             " signals: [G1C, G2W, E1C, E7Q, C2I]}\n"
                             "  - {name: ROVR, position: {world_enu_m: [5.0, 3.0, 1.5]}, profile: ublox-f9p,"
                             " signals: [G1C, G2L, E1C, E7Q, C2I, C7I], rtk: {base: BASE}}\n"
                             "  - {name: THIRD, position: {world_enu_m: [0.0, -8.0, 1.5]}, profile: septentrio-polarx5,"
                             " signals: [G1C, R1C, E1C]}\n"
                             "world: {sdf: " << (test::source_dir() / "examples" / "worlds" / "courtyard.sdf").string() << "}\n"
                             "ephemeris: {nominal: true}\n"
                             "models: {ionosphere: klobuchar, troposphere: saastamoinen, receiver_clock: profile, noise: true,"
                             " multipath: true}\n"
                             "seed: 5\n";
  for (const std::string outputs : {"", " --no-truth --set output.fix=false"}) {
    std::map<std::string, std::string> first;
    for (const int threads : {1, 2, 3, 4}) {
      const auto out = dir / ("t" + std::to_string(threads));
      std::filesystem::remove_all(out);
      const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                       test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                                       " --quiet --threads " + std::to_string(threads) + outputs + " 2>&1");
      ASSERT_EQ(r.exit_code, 0) << r.output;
      std::map<std::string, std::string> files;
      for (const auto& entry : std::filesystem::directory_iterator(out)) {
        if (!entry.is_regular_file() || entry.path().filename() == "summary.json") continue;
        std::ifstream in(entry.path(), std::ios::binary);
        std::stringstream bytes;
        bytes << in.rdbuf();
        files[entry.path().filename().string()] = bytes.str();
      }
      EXPECT_TRUE(files.count("obs_THIRD.rnx")) << threads;
      if (first.empty()) {
        first = std::move(files);
        continue;
      }
      ASSERT_EQ(files.size(), first.size()) << threads << outputs;
      for (const auto& [name, bytes] : first) {
        EXPECT_TRUE(files[name] == bytes) << name << " differs with " << threads << " threads" << outputs;
      }
    }
  }
}

}  // namespace
}  // namespace skytrace
