// `skytrace compare` end to end: the real ESBC first hour against itself (all zero, full overlap)
// and against the open-sky contract simulation of the same hour (sane figures, printed), plus the
// exit codes of bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::filesystem::path esbc_dir() { return test::shared_data_dir() / "real/esbc_2020177"; }
std::filesystem::path esbc_obs() {
  return esbc_dir() / "ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx";
}
std::filesystem::path esbc_nav() { return esbc_dir() / "ESBC00DNK_R_20201770000_01D_MN.rnx"; }
std::filesystem::path contract_scenario() {
  return test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
}
std::string skytrace_cmd() { return test::shell_quote(test::skytrace_executable().string()); }
std::string q(const std::filesystem::path& p) { return test::shell_quote(p.string()); }

nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

const nlohmann::json* find_row(const nlohmann::json& report, const std::string& signal) {
  for (const auto& row : report["signals"]) {
    if (row["signal"] == signal) return &row;
  }
  return nullptr;
}

double number(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::nan("");
}

class CompareCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(esbc_obs()) || !std::filesystem::exists(esbc_nav())) {
      GTEST_SKIP() << "ESBC data absent (set SKYTRACE_SHARED_DATA): " << esbc_obs();
    }
    dir_ = test::make_temp_dir(std::string("compare_cli_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  std::filesystem::path dir_;
};

TEST_F(CompareCli, RealFileAgainstItselfIsZeroWithFullOverlap) {
  const auto json_path = dir_ / "self.json";
  const auto r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " +
                                   q(esbc_obs()) + " --json " + q(json_path));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("elevation mask: none"), std::string::npos) << r.output;
  const auto report = read_json(json_path);
  EXPECT_EQ(report["common_epochs"], 120);
  ASSERT_NE(find_row(report, "G1C"), nullptr);
  ASSERT_NE(find_row(report, "E1C"), nullptr);
  for (const auto& row : report["signals"]) {
    const std::string name = row["signal"];
    const auto& overlap = row["overlap"];
    if (overlap["real_tracked"].get<int>() == 0) continue;  // listed in the header, never observed
    EXPECT_EQ(number(overlap["real_in_sim"]), 1.0) << name;
    EXPECT_EQ(number(overlap["sim_in_real"]), 1.0) << name;
    for (const char* quantity : {"pseudorange_m", "doppler_mps", "phase_difference_m"}) {
      if (row[quantity]["count"].get<int>() == 0) continue;
      EXPECT_EQ(number(row[quantity]["rms"]), 0.0) << name << " " << quantity;
    }
    if (row["cn0_dbhz"]["count"].get<int>() > 0) {
      EXPECT_EQ(number(row["cn0_dbhz"]["mean_abs_difference"]), 0.0) << name;
    }
  }
  EXPECT_GT((*find_row(report, "G1C"))["pseudorange_m"]["count"].get<int>(), 800);
  EXPECT_GT((*find_row(report, "G1C"))["phase_difference_m"]["count"].get<int>(), 800);
}

TEST_F(CompareCli, RealAgainstOpenSkySimulation) {
  if (!std::filesystem::exists(contract_scenario()))
    GTEST_SKIP() << "contract scenario absent: " << contract_scenario();
  const auto out = dir_ / "sim";
  const auto run = test::run_command(skytrace_cmd() + " run " + q(contract_scenario()) + " --out " +
                                     q(out) + " --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto json_path = dir_ / "compare.json";
  const auto r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " +
                                   q(out / "obs.rnx") + " --nav " + q(esbc_nav()) +
                                   " --min-elevation-deg 10 --json " + q(json_path));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::cout << r.output;
  EXPECT_NE(r.output.find("elevation mask: 10.0 deg"), std::string::npos) << r.output;
  bool g1c_row = false, e1c_row = false;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);) {
    g1c_row = g1c_row || line.rfind("G1C ", 0) == 0;
    e1c_row = e1c_row || line.rfind("E1C ", 0) == 0;
  }
  EXPECT_TRUE(g1c_row && e1c_row) << r.output;

  const auto report = read_json(json_path);
  EXPECT_EQ(report["common_epochs"], 120);
  EXPECT_TRUE(report["elevation_mask"]["applied"].get<bool>());
  for (const char* name : {"G1C", "E1C"}) {
    const auto* row = find_row(report, name);
    ASSERT_NE(row, nullptr) << name;
    const double pr_p68_m = number((*row)["pseudorange_m"]["abs_p68"]);
    const double pr_p95_m = number((*row)["pseudorange_m"]["abs_p95"]);
    const double dop_p68_mps = number((*row)["doppler_mps"]["abs_p68"]);
    const double dphi_p68_m = number((*row)["phase_difference_m"]["abs_p68"]);
    const double cn0_mad_dbhz = number((*row)["cn0_dbhz"]["mean_abs_difference"]);
    const double real_in_sim = number((*row)["overlap"]["real_in_sim"]);
    const double sim_in_real = number((*row)["overlap"]["sim_in_real"]);
    std::cout << "[ figures ] " << name << " ESBC real vs open-sky sim, >= 10 deg: pseudorange p68 "
              << pr_p68_m << " m, p95 " << pr_p95_m << " m; Doppler p68 " << dop_p68_mps
              << " m/s; phase step p68 " << dphi_p68_m << " m; C/N0 mean |diff| " << cn0_mad_dbhz
              << " dB-Hz; overlap real in sim " << 100.0 * real_in_sim << " %, sim in real "
              << 100.0 * sim_in_real << " %\n";
    // Sanity only (the receiver-realism work tunes the figures): finite, a few metres at most for
    // the pseudorange (ionosphere and troposphere model errors, broadcast orbits, multipath).
    EXPECT_TRUE(std::isfinite(pr_p68_m) && std::isfinite(pr_p95_m)) << name;
    EXPECT_LT(pr_p68_m, 10.0) << name;
    EXPECT_TRUE(std::isfinite(dop_p68_mps) && std::isfinite(dphi_p68_m)) << name;
    EXPECT_TRUE(std::isfinite(cn0_mad_dbhz)) << name;
    EXPECT_GT(real_in_sim, 0.5) << name;
    EXPECT_GT(sim_in_real, 0.5) << name;
  }
}

TEST_F(CompareCli, BadInputExitCodes) {
  // Unreadable file: input error, the file named.
  auto r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " +
                             q(dir_ / "missing.rnx"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("missing.rnx"), std::string::npos) << r.output;

  // No common epochs: a one-epoch file a day later; both spans in the message, coverage exit code.
  auto real = io::read_rinex_obs(esbc_obs());
  ASSERT_TRUE(real.ok()) << real.error().message;
  std::vector<io::ObservationEpoch> later = {real->epochs.front()};
  later.front().time += 86400.0;
  auto header = real->header;
  header.version = 3.04;
  header.phase_shifts.clear();
  header.other_records.clear();
  const auto later_path = dir_ / "later.rnx";
  const auto written = io::write_rinex_obs(later_path, header, later);
  ASSERT_TRUE(written.ok()) << written.error().message;
  r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " + q(later_path));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(
      r.output.find(
          "REAL covers 2020-06-25T00:00:00 to 2020-06-25T00:59:30, SIM covers 2020-06-26T00:00:00"),
      std::string::npos)
      << r.output;

  // A signal the files do not have, a bad system letter.
  r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " + q(esbc_obs()) +
                        " --signals G1Z");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " + q(esbc_obs()) +
                        " --signals I5A");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("I5A"), std::string::npos) << r.output;
  r = test::run_command(skytrace_cmd() + " compare " + q(esbc_obs()) + " " + q(esbc_obs()) +
                        " --systems GQ");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
}  // namespace skytrace
