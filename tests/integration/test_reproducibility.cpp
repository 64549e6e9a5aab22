// Reproducibility: the same scenario and seed give byte-identical files (noise, cycle slips and
// a profile clock included); the RINEX header date is the scenario's start or SOURCE_DATE_EPOCH.
// Also the ESBC realism acceptance on GPS/Galileo L1 against the real PolaRx5 hour.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class Reproducibility : public ::testing::Test {
 protected:
  void SetUp() override {
    scenario_ = test::shared_data_dir().parent_path() / "contract" / "esbc-realistic.yaml";
    if (!std::filesystem::exists(scenario_) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      GTEST_SKIP() << "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
    }
  }
  std::filesystem::path run(const std::string& name, const std::string& environment = "",
                            const std::filesystem::path& scenario = {}) {
    const auto out = test::make_temp_dir("reproducibility_" + name);
    const auto r = test::run_command(environment + test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote((scenario.empty() ? scenario_ : scenario).string()) +
                                     " --out " + test::shell_quote(out.string()) + " --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return out;
  }
  std::filesystem::path scenario_;
};

TEST_F(Reproducibility, SameScenarioAndSeedGiveIdenticalBytes) {
  const auto a = run("a");
  const auto b = run("b");
  for (const char* file : {"obs.rnx", "nav.rnx", "truth.csv.zst"}) {
    const std::string first = read_bytes(a / file);
    ASSERT_GT(first.size(), 1000u) << file;
    EXPECT_TRUE(first == read_bytes(b / file)) << file << " differs between two runs";
  }
  // The header date is the scenario's start (2020-06-25 00:00:00 GPST = 23:59:42 UTC the day before).
  const std::string obs = read_bytes(a / "obs.rnx");
  EXPECT_NE(obs.find("20200624 235942 UTC PGM / RUN BY / DATE"), std::string::npos) << obs.substr(0, 300);
  // SOURCE_DATE_EPOCH wins: 1700000000 = 2023-11-14 22:13:20 UTC.
  const auto c = run("c", "SOURCE_DATE_EPOCH=1700000000 ");
  EXPECT_NE(read_bytes(c / "obs.rnx").find("20231114 221320 UTC PGM / RUN BY / DATE"), std::string::npos);
  EXPECT_NE(read_bytes(c / "nav.rnx").find("20231114 221320 UTC"), std::string::npos);
}

TEST_F(Reproducibility, AnotherSeedChangesTheNoise) {
  const auto a = run("seed7");
  std::ifstream in(scenario_);
  std::ostringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto at = yaml.find("seed: 7");
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, 7, "seed: 8");
  // Same folder as the contract so that its relative data paths hold.
  const auto other = scenario_.parent_path() / ".reproducibility-seed8.yaml";
  std::ofstream(other) << yaml;
  const auto b = run("seed8", "", other);
  std::filesystem::remove(other);
  EXPECT_FALSE(read_bytes(a / "obs.rnx") == read_bytes(b / "obs.rnx"));
}

TEST_F(Reproducibility, EsbcRealismAcceptanceOnL1) {
  const auto out = run("compare");
  const auto real = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx";
  const auto nav = test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx";
  const auto json_path = out / "compare.json";
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " compare " +
                                   test::shell_quote(real.string()) + " " + test::shell_quote((out / "obs.rnx").string()) +
                                   " --nav " + test::shell_quote(nav.string()) +
                                   " --min-elevation-deg 10 --signals G1C,E1C --json " + test::shell_quote(json_path.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json_path);
  const nlohmann::json j = nlohmann::json::parse(in);
  SCOPED_TRACE(j.dump(1));
  int checked = 0;
  for (const auto& row : j.at("signals")) {
    const std::string signal = row.at("signal");
    SCOPED_TRACE(signal);
    EXPECT_GE(row.at("overlap").at("real_in_sim").get<double>(), 0.95);
    EXPECT_GE(row.at("overlap").at("sim_in_real").get<double>(), 0.95);
    EXPECT_LE(row.at("pseudorange_m").at("abs_p68").get<double>(), 2.0);
    EXPECT_LE(row.at("doppler_mps").at("abs_p68").get<double>(), 0.10);
    EXPECT_LE(row.at("phase_difference_m").at("abs_p68").get<double>(), 0.01);
    EXPECT_LE(row.at("cn0_dbhz").at("mean_abs_difference").get<double>(), 2.5);
    ++checked;
  }
  EXPECT_EQ(checked, 2);
}

}  // namespace
}  // namespace skytrace
