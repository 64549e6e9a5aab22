// The command line: exit codes, messages naming what is wrong, and no partial outputs.
#include <gtest/gtest.h>

#include <fstream>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::string skytrace_cmd() { return test::shell_quote(test::skytrace_executable().string()); }

std::filesystem::path esbc_nav() { return test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx"; }

// A scenario file in `dir` built from the open-sky contract with one line replaced.
std::filesystem::path write_scenario(const std::filesystem::path& dir, const std::string& replace_from,
                                     const std::string& replace_to) {
  std::string text = "name: cli\ntime:\n  start: 2020-06-25T00:00:00\n  scale: GPST\n  duration_s: 300\n  interval_s: 30\n"
                     "receiver:\n  position:\n    ecef_m: [3582105.2910, 532589.7313, 5232754.8054]\n"
                     "  signals: [G1C, E1C]\nephemeris:\n  navigation:\n    - " +
                     esbc_nav().string() + "\n";
  if (!replace_from.empty()) {
    const auto pos = text.find(replace_from);
    EXPECT_NE(pos, std::string::npos);
    text.replace(pos, replace_from.size(), replace_to);
  }
  const auto path = dir / "scenario.yaml";
  std::ofstream(path) << text;
  return path;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(esbc_nav())) GTEST_SKIP() << "ESBC navigation file absent: " << esbc_nav();
    dir_ = test::make_temp_dir(std::string("cli_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  test::ProcessResult run(const std::filesystem::path& scenario) {
    return test::run_command(skytrace_cmd() + " run " + test::shell_quote(scenario.string()) + " --out " +
                             test::shell_quote((dir_ / "out").string()) + " --quiet");
  }
  bool out_is_empty() const {
    const auto out = dir_ / "out";
    return !std::filesystem::exists(out) || std::filesystem::is_empty(out);
  }
  std::filesystem::path dir_;
};

TEST_F(Cli, HelpAndVersion) {
  EXPECT_EQ(test::run_command(skytrace_cmd() + " --help").exit_code, 0);
  EXPECT_EQ(test::run_command(skytrace_cmd() + " run --help").exit_code, 0);
  const auto r = test::run_command(skytrace_cmd() + " --version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("skytrace"), std::string::npos);
  EXPECT_EQ(test::run_command(skytrace_cmd() + " no-such-command").exit_code, 2);
}

TEST_F(Cli, GoodScenarioWritesAllOutputs) {
  const auto r = run(write_scenario(dir_, "", ""));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"obs.rnx", "nav.rnx", "truth.csv.zst", "fix.csv", "summary.json", "report.html", "skyplot.svg"}) {
    EXPECT_TRUE(std::filesystem::exists(dir_ / "out" / name)) << name;
  }
  // Nothing else (no staging folder) is left behind.
  size_t entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir_ / "out")) ++entries;
  EXPECT_EQ(entries, 7u);
}

TEST_F(Cli, TimeOutsideTheNavigationData) {
  const auto r = run(write_scenario(dir_, "2020-06-25T00:00:00", "2020-07-25T00:00:00"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("no valid GPS ephemeris"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cover"), std::string::npos) << r.output;
  EXPECT_TRUE(out_is_empty());
}

TEST_F(Cli, SignalTheSystemDoesNotHave) {
  const auto r = run(write_scenario(dir_, "[G1C, E1C]", "[G1C, E2C]"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("receiver.signals[1]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("E2C"), std::string::npos) << r.output;
  EXPECT_TRUE(out_is_empty());
}

TEST_F(Cli, PositionBelowTheEarthsSurface) {
  const auto r = run(write_scenario(dir_, "ecef_m: [3582105.2910, 532589.7313, 5232754.8054]", "lla_deg_m: [55.5, 8.5, -3000]"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("below the Earth's surface"), std::string::npos) << r.output;
  EXPECT_TRUE(out_is_empty());
}

TEST_F(Cli, MissingFiles) {
  auto r = run(write_scenario(dir_, esbc_nav().string(), "/nonexistent/brdc.rnx"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("file not found: /nonexistent/brdc.rnx"), std::string::npos) << r.output;
  r = run(dir_ / "missing.yaml");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("missing.yaml"), std::string::npos) << r.output;
  EXPECT_TRUE(out_is_empty());
}

TEST_F(Cli, CorruptNavigationFileNamesFileAndLine) {
  // The real file cut in the middle of a record.
  std::ifstream in(esbc_nav());
  std::ofstream out(dir_ / "cut.rnx");
  std::string line;
  for (int i = 0; i < 40 && std::getline(in, line); ++i) out << line << "\n";
  out.close();
  const auto r = test::run_command(skytrace_cmd() + " orbits --nav " + test::shell_quote((dir_ / "cut.rnx").string()) +
                                   " --csv " + test::shell_quote((dir_ / "o.csv").string()));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("cut.rnx:"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "o.csv"));
}

TEST_F(Cli, OrbitsOutsideEveryEphemeris) {
  const auto r = test::run_command(skytrace_cmd() + " orbits --nav " + test::shell_quote(esbc_nav().string()) +
                                   " --start 2021-01-01T00:00:00 --csv " + test::shell_quote((dir_ / "o.csv").string()));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("2021-01-01T00:00:00"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "o.csv"));
}

TEST_F(Cli, NominalConstellationNeedsNoFiles) {
  const auto r = test::run_command(skytrace_cmd() + " orbits --duration-s 3600 --csv " +
                                   test::shell_quote((dir_ / "o.csv").string()));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir_ / "o.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "time_gpst,sat,x_m,y_m,z_m,clock_s");
}

}  // namespace
}  // namespace skytrace
