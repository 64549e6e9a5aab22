// Precise products as the truth: the signals come from the GRG orbits and clocks while nav.rnx
// carries the broadcast records. RTKLIB given the same precise products must land on the antenna
// (proving the precise path is exact), and given only nav.rnx must see real broadcast errors.
// Products that do not cover the run stop it (exit 4); satellites they lack or interrupt keep the
// broadcast truth for the whole run, with a warning.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "rtklib.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

double median_error_m(const std::filesystem::path& solution, const Eigen::Vector3d& antenna, size_t& epochs) {
  const std::vector<double> errors = test::sorted_errors_m(test::read_rtklib_xyz(solution), antenna);
  epochs = errors.size();
  return errors.empty() ? NAN : errors[errors.size() / 2];
}

TEST(PreciseTruth, RtklibWithTheSameProductsLandsOnTheAntennaAndBroadcastShowsItsErrors) {
  const auto data = test::shared_data_dir() / "real/esbc_2020177";
  if (!std::filesystem::exists(data / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK")) GTEST_SKIP() << "ESBC data absent";
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("precise_truth");
  const std::string sp3_a = (data / "GRG0MGXFIN_20201760000_01D_15M_ORB.SP3").string();
  const std::string sp3_b = (data / "GRG0MGXFIN_20201770000_01D_15M_ORB.SP3").string();
  const std::string clk = (data / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK").string();
  std::ofstream(dir / "scenario.yaml")
      << "name: precise-truth\ntime: {start: 2020-06-25T00:00:00, scale: GPST, duration_s: 3600, interval_s: 30}\n"
         "receiver:\n  position: {ecef_m: [3582105.2910, 532589.7313, 5232754.8054]}\n  antenna_height_m: 0.2160\n"
         "  signals: [G1C, E1C]\nephemeris:\n  navigation: ["
      << (data / "ESBC00DNK_R_20201770000_01D_MN.rnx").string() << "]\n  precise_orbits: [" << sp3_a << ", " << sp3_b
      << "]\n  precise_clocks: [" << clk << "]\n";
  auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                             test::shell_quote((dir / "scenario.yaml").string()) + " --out " +
                             test::shell_quote((dir / "out").string()) + " --quiet --no-truth");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const Eigen::Vector3d marker(3582105.2910, 532589.7313, 5232754.8054);
  const Eigen::Vector3d antenna = marker + 0.2160 * ecef_to_enu_rotation(ecef_to_geodetic(marker)).row(2).transpose();
  auto solve = [&](const std::string& sateph, const std::string& extra_files, const std::string& name) {
    std::ofstream(dir / (name + ".conf")) << "pos1-posmode=single\npos1-frequency=l1\npos1-elmask=5\npos1-ionoopt=brdc\n"
                                             "pos1-tropopt=saas\npos1-navsys=1\nout-solformat=xyz\npos1-sateph="
                                          << sateph << "\n";
    const auto result = test::run_command("rnx2rtkp -k " + test::shell_quote((dir / (name + ".conf")).string()) + " -o " +
                                          test::shell_quote((dir / (name + ".pos")).string()) + " " +
                                          test::shell_quote((dir / "out/obs.rnx").string()) + " " +
                                          test::shell_quote((dir / "out/nav.rnx").string()) + " " + extra_files);
    EXPECT_EQ(result.exit_code, 0) << result.output;
    size_t epochs = 0;
    const double median = median_error_m(dir / (name + ".pos"), antenna, epochs);
    std::printf("[ figures ] precise truth, rnx2rtkp GPS single point with %s ephemerides: %zu epochs, median %.4f m\n",
                sateph.c_str(), epochs, median);
    EXPECT_GE(epochs, 115u);
    return median;
  };
  const double with_precise = solve("precise", test::shell_quote(sp3_a) + " " + test::shell_quote(sp3_b) + " " +
                                                   test::shell_quote(clk), "precise");
  const double with_broadcast = solve("brdc", "", "broadcast");
  EXPECT_LE(with_precise, 0.01);
  // Real broadcast orbit and clock errors (about a metre each) now reach the position.
  EXPECT_GE(with_broadcast, 0.3);
  EXPECT_LE(with_broadcast, 6.0);
}

// The GRG clock file of the ESBC day rewritten by `keep(satellite, seconds of the day)`: records
// it refuses are left out (with their continuation lines); the header is kept.
std::filesystem::path filtered_clock_file(const std::filesystem::path& source, const std::filesystem::path& target,
                                          const std::function<bool(const std::string&, int)>& keep) {
  std::ifstream in(source);
  std::ofstream out(target);
  std::string line;
  bool header = true, keeping = true;
  while (std::getline(in, line)) {
    if (header) {
      out << line << "\n";
      header = line.find("END OF HEADER") == std::string::npos;
      continue;
    }
    if (line.rfind("AS ", 0) == 0) {  // "AS G07  2020  6 25  0  0 30.000000  2 ..."
      const int seconds = std::stoi(line.substr(18, 3)) * 3600 + std::stoi(line.substr(21, 3)) * 60 +
                          static_cast<int>(std::stod(line.substr(24, 10)));
      keeping = keep(line.substr(3, 3), seconds);
    } else if (line.size() > 3 && line[2] == ' ' && std::isupper(static_cast<unsigned char>(line[0]))) {
      keeping = true;  // another record type (AR, ...)
    }
    if (keeping) out << line << "\n";
  }
  return target;
}

// One row of truth.csv(.zst) per (satellite, signal) of an epoch: the columns by name.
std::map<std::string, std::vector<std::string>> truth_rows(const std::filesystem::path& truth, const std::string& epoch) {
  std::istringstream in(test::read_zst_text(truth));
  std::string line;
  std::map<std::string, std::vector<std::string>> rows;
  while (std::getline(in, line)) {
    if (line.rfind(epoch, 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    if (cells.size() > 3) rows[cells[2] + " " + cells[3]] = cells;
  }
  return rows;
}

class PreciseCoverageCli : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = test::shared_data_dir() / "real/esbc_2020177";
    if (!std::filesystem::exists(data_ / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK")) GTEST_SKIP() << "ESBC data absent";
    dir_ = test::make_temp_dir("precise_coverage_cli");
  }
  // The ESBC hour with GPS L1 (noise-free) from the GRG orbits and `clk`; extra lines appended.
  std::filesystem::path scenario(const std::filesystem::path& clk, const std::string& name) const {
    const auto path = dir_ / (name + ".yaml");
    std::ofstream(path) << "name: " << name
                        << "\ntime: {start: 2020-06-25T00:00:00, scale: GPST, duration_s: 3600, interval_s: 30}\n"
                           "receiver:\n  position: {ecef_m: [3582105.2910, 532589.7313, 5232754.8054]}\n"
                           "  signals: [G1C]\nephemeris:\n  navigation: ["
                        << (data_ / "ESBC00DNK_R_20201770000_01D_MN.rnx").string() << "]\n  precise_orbits: ["
                        << (data_ / "GRG0MGXFIN_20201760000_01D_15M_ORB.SP3").string() << ", "
                        << (data_ / "GRG0MGXFIN_20201770000_01D_15M_ORB.SP3").string() << "]\n  precise_clocks: ["
                        << clk.string() << "]\n";
    return path;
  }
  test::ProcessResult run(const std::filesystem::path& scenario, const std::filesystem::path& out,
                          const std::string& extra = "") const {
    return test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                             test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                             " --quiet " + extra);
  }
  std::filesystem::path data_, dir_;
};

TEST_F(PreciseCoverageCli, AClockFileShorterThanTheRunStopsItWithExitCode4AndNoOutputs) {
  const auto clk = filtered_clock_file(data_ / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK", dir_ / "cut.clk",
                                       [](const std::string&, int s) { return s >= 600 && s <= 3000; });
  const auto out = dir_ / "out";
  const auto r = run(scenario(clk, "cut"), out);
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("skytrace: error: ephemeris.precise_clocks: cut.clk covers 2020-06-25 00:10:00 to "
                          "00:50:00 GPST; the run needs 00:00:00 to 01:00:00 GPST"),
            std::string::npos)
      << r.output;
  // Nothing half-written: the check runs before the output folder is touched.
  EXPECT_FALSE(std::filesystem::exists(out / "obs.rnx"));
  EXPECT_FALSE(std::filesystem::exists(out / "summary.json"));
}

TEST_F(PreciseCoverageCli, SatellitesTheClockFileLacksOrInterruptsKeepTheBroadcastTruthWithAWarning) {
  // G05 left out of the clock file, G07's samples from 00:20:30 to 00:29:30 left out.
  const auto clk = filtered_clock_file(data_ / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK", dir_ / "holes.clk",
                                       [](const std::string& sat, int s) {
                                         return sat != "G05" && !(sat == "G07" && s > 1200 && s < 1800);
                                       });
  const auto precise = dir_ / "precise";
  const auto r = run(scenario(clk, "holes"), precise);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // GRG has no G04 (GPS III) on this day; G05 is left with its SP3 orbit but no clock.
  EXPECT_NE(r.output.find("skytrace run: warning: the precise products lack 2 satellites of the navigation data, "
                          "which keep the broadcast truth: G04 G05 (no clock)\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("skytrace run: warning: the precise products cannot serve 1 satellite over the whole run, "
                          "which keeps the broadcast truth for all of it: G07 (clock 2020-06-25 00:20:00 to 00:30:00 "
                          "GPST)"),
            std::string::npos)
      << r.output;
  std::ifstream summary_in(precise / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(summary_in);
  EXPECT_EQ(summary.at("precise_truth").at("broadcast_truth_satellites"), nlohmann::json({"G04", "G05", "G07"}));
  EXPECT_EQ(summary.at("precise_truth").at("gaps").at("G07").at("clock"),
            nlohmann::json::parse(R"([["2020-06-25 00:20:00", "2020-06-25 00:30:00"]])"));
  EXPECT_EQ(summary.at("warnings").size(), 2u);

  // G05 and G07 have the broadcast run's truth at every epoch (no switch at the gap's ends), G08
  // the precise one.
  const auto broadcast = dir_ / "broadcast";
  ASSERT_EQ(run(scenario(clk, "holes"), broadcast, "--set ephemeris.precise_orbits=[] --set ephemeris.precise_clocks=[]")
                .exit_code,
            0);
  int compared = 0;
  for (const char* epoch : {"2020-06-25T00:00:00", "2020-06-25T00:25:00", "2020-06-25T01:00:00"}) {
    const auto p = truth_rows(precise / "truth.csv.zst", epoch);
    const auto b = truth_rows(broadcast / "truth.csv.zst", epoch);
    for (const char* key : {"G05 G1C", "G07 G1C"}) {
      if (p.count(key) == 0) continue;
      ASSERT_EQ(b.count(key), 1u) << key;
      EXPECT_EQ(p.at(key)[7], b.at(key)[7]) << key << " range at " << epoch;
      EXPECT_EQ(p.at(key)[9], b.at(key)[9]) << key << " sat_clock_m at " << epoch;
      ++compared;
    }
    ASSERT_EQ(p.count("G08 G1C"), 1u);
    EXPECT_NE(p.at("G08 G1C")[9], b.at("G08 G1C")[9]);
  }
  EXPECT_GE(compared, 4);
}

}  // namespace
}  // namespace skytrace
