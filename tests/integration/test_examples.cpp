// Every example in examples/ runs as the README shows it, cut short (CI time): each scenario for a
// few seconds of its time into a temporary folder, checking its outputs; the scripts with their
// smallest arguments. Examples that read ../shared/data skip when it is absent.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

std::filesystem::path skytrace_binary() { return test::binary_dir() / "bin" / "skytrace"; }
bool shared_data_beside_the_checkout() {
  return std::filesystem::exists(test::source_dir().parent_path() / "shared" / "data" / "real");
}

struct Example {
  const char* scenario;   // relative to examples/
  double duration_s;      // time.duration_s for the test
  bool needs_shared_data;
  std::vector<const char*> outputs;
};

class Examples : public ::testing::TestWithParam<Example> {};

TEST_P(Examples, RunsAndWritesItsOutputs) {
  const Example& e = GetParam();
  if (e.needs_shared_data && !shared_data_beside_the_checkout()) GTEST_SKIP() << "../shared/data absent";
  const auto scenario = test::source_dir() / "examples" / e.scenario;
  ASSERT_TRUE(std::filesystem::exists(scenario)) << scenario;
  std::string name = e.scenario;
  for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  const auto out = test::make_temp_dir("example_" + name) / "out";
  const auto r = test::run_command(test::shell_quote(skytrace_binary().string()) + " run " +
                                   test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                                   " --quiet --set time.duration_s=" + std::to_string(e.duration_s) + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* file : e.outputs) EXPECT_TRUE(std::filesystem::exists(out / file)) << file << "\n" << r.output;
  // The report shows the fix of every example.
  std::ifstream report(out / "report.html");
  std::stringstream html;
  html << report.rdbuf();
  EXPECT_NE(html.str().find("id=\"fix-errors\""), std::string::npos);
  // Every example has a world, drawn from above with the receivers' tracks.
  EXPECT_NE(html.str().find("id=\"world-map\""), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(
    EveryScenario, Examples,
    ::testing::Values(
        Example{"quickstart.yaml", 20, false, {"obs.rnx", "nav.rnx", "truth.csv.zst", "fix.csv", "report.html"}},
        Example{"citysim-drive.yaml", 10, true, {"obs.rnx", "truth.csv.zst", "paths.csv.zst", "report.html"}},
        Example{"osm-city.yaml", 20, true, {"obs.rnx", "report.html"}},
        Example{"berlin-city-model.yaml", 20, true, {"obs.rnx", "report.html"}},
        Example{"under-trees.yaml", 20, true, {"obs.rnx", "report.html"}},
        Example{"ros2-bag.yaml", 5, false, {"obs.rnx", "fix.nmea", "bag/metadata.yaml", "report.html"}},
        Example{"rtk/rtk-yard.yaml", 20, true, {"obs_BASE.rnx", "obs_ROVR.rnx", "fix_ROVR.csv", "report.html"}}),
    [](const ::testing::TestParamInfo<Example>& example) {
      std::string name = example.param.scenario;
      std::string out;
      for (const char c : name.substr(0, name.rfind('.'))) out += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
      return out;
    });

// skytrace serve feeding gpsd: gpsd reports 3D fixes from the simulated receiver.
TEST(ExampleScripts, ServeGpsd) {
  if (!std::filesystem::exists("/usr/sbin/gpsd") || test::run_command("command -v gpspipe").exit_code != 0) {
    GTEST_SKIP() << "gpsd and gpspipe (Debian packages gpsd, gpsd-clients) are not installed";
  }
  const auto r = test::run_command("SKYTRACE=" + test::shell_quote(skytrace_binary().string()) + " " +
                                   test::shell_quote((test::source_dir() / "examples/serve-gpsd.sh").string()) +
                                   " 12 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"class\":\"TPV\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"mode\":3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"altMSL\""), std::string::npos) << r.output;
}

// The Monte Carlo sweep of the quick start, its points cut to 3 s: 40 done, one row each in the table.
TEST(ExampleScripts, SweepMonteCarlo) {
  const auto out = test::make_temp_dir("example_sweep") / "out";
  const auto r = test::run_command(test::shell_quote(skytrace_binary().string()) + " sweep " +
                                   test::shell_quote((test::source_dir() / "examples/sweeps/courtyard-monte-carlo.yaml").string()) +
                                   " --out " + test::shell_quote(out.string()) + " --set time.duration_s=3 --no-truth 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("40 points: 40 done, 0 failed, 0 pending"), std::string::npos) << r.output;
  std::ifstream table(out / "summaries.csv");
  std::string line;
  int rows = 0;
  while (std::getline(table, line)) ++rows;
  EXPECT_EQ(rows, 41);
}

// Comparing against a real recording: the table has the station's signals.
TEST(ExampleScripts, CompareReal) {
  if (!shared_data_beside_the_checkout()) GTEST_SKIP() << "../shared/data absent";
  const auto out = test::make_temp_dir("example_compare_real") / "out";
  const auto r = test::run_command("SKYTRACE=" + test::shell_quote(skytrace_binary().string()) + " " +
                                   test::shell_quote((test::source_dir() / "examples/compare-real.sh").string()) + " " +
                                   test::shell_quote(out.string()) + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\nG1C "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\nE1X "), std::string::npos) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out / "compare.json"));
}

// A city model without terrain heights placed at the wrong height: the receiver hovers 75 m above
// the streets, and the run says so, naming the heights (issue #15); placed right, not a word.
TEST(WorldHeights, AReceiverHighAboveTheGroundOverNoObjectIsWarnedAbout) {
  if (!shared_data_beside_the_checkout()) GTEST_SKIP() << "../shared/data absent";
  const auto dir = test::make_temp_dir("world_heights");
  const std::string run = test::shell_quote(skytrace_binary().string()) + " run " +
                          test::shell_quote((test::source_dir() / "examples/berlin-city-model.yaml").string()) +
                          " --set time.duration_s=2 --out ";
  const auto wrong = test::run_command(run + test::shell_quote((dir / "wrong").string()) + " --set world.elevation_m=0 2>&1");
  ASSERT_EQ(wrong.exit_code, 0) << wrong.output;
  EXPECT_NE(wrong.output.find("warning: receiver 'BERL' starts 75.4 m above the world's ground (0.0 m above the "
                              "ellipsoid) over no object"),
            std::string::npos)
      << wrong.output;
  const auto right = test::run_command(run + test::shell_quote((dir / "right").string()) + " 2>&1");
  ASSERT_EQ(right.exit_code, 0) << right.output;
  EXPECT_EQ(right.output.find("above the world's ground"), std::string::npos) << right.output;
}

// A receiver that tracks nothing in the whole run says so (console, summary.json, report); one that
// tracks does not.
TEST(RunWarnings, AReceiverThatTrackedNothingIsWarnedAbout) {
  const auto dir = test::make_temp_dir("tracked_nothing");
  const std::string run = test::shell_quote(skytrace_binary().string()) + " run " +
                          test::shell_quote((test::source_dir() / "examples/quickstart.yaml").string()) +
                          " --set time.duration_s=5 --out ";
  const auto masked = test::run_command(run + test::shell_quote((dir / "masked").string()) +
                                        " --set receiver.elevation_mask_deg=89.9 2>&1");
  ASSERT_EQ(masked.exit_code, 0) << masked.output;
  const std::string expected = "receiver 'QUICK' tracked no signal in the whole run (signals G1C, ";
  EXPECT_NE(masked.output.find("warning: " + expected), std::string::npos) << masked.output;
  const auto text_of = [](const std::filesystem::path& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_NE(text_of(dir / "masked" / "summary.json").find(expected), std::string::npos);
  EXPECT_NE(text_of(dir / "masked" / "report.html").find("tracked no signal"), std::string::npos);
  const auto open = test::run_command(run + test::shell_quote((dir / "open").string()) + " 2>&1");
  ASSERT_EQ(open.exit_code, 0) << open.output;
  EXPECT_EQ(open.output.find("tracked no signal"), std::string::npos) << open.output;
}

}  // namespace
}  // namespace skytrace
