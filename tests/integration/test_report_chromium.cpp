// The run report rendered by a real browser: headless Chromium loads report.html from disk (no
// network), its DOM holds the plots, and a screenshot of the page is a real picture.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "process.hpp"
#include "skytrace/io/report.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

constexpr const char* kChromium = "/usr/bin/chromium";

size_t count_of(const std::string& text, std::string_view what) {
  size_t n = 0;
  for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

std::string read_all(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Eight satellites of three systems over two hours at 30 s, some blocked by a wall to the east,
// some through vegetation to the south-west; a sky mask with the wall.
io::ReportBuilder synthetic_run(io::ReportMeta& meta) {
  const auto start = GnssTime::from_calendar({2020, 6, 25, 6, 0, 0.0}, TimeScale::kGpst);
  meta.scenario_name = "courtyard <synthetic> & trees";
  meta.receiver_name = "rover";
  meta.start = start;
  meta.end = start + 7200.0;
  meta.interval_s = 30.0;
  meta.summary_rows = {{"world", "courtyard.sdf (12 buildings, 30 trees)"}, {"signals", "G1C E1C C2I"}};
  for (int i = 0; i < 72; ++i) {
    const double azimuth_deg = 5.0 * i;
    meta.sky_mask_elevation_deg.push_back(azimuth_deg >= 60.0 && azimuth_deg <= 120.0 ? 35.0 : 8.0);
  }
  meta.sky_mask_azimuth_step_deg = 5.0;
  meta.warnings = {"model tree_7 skipped: mesh not found"};
  // A building north of the rover's circle and a tree crown inside it, seen from above.
  meta.world_outlines.push_back({io::ReportMeta::MapOutline::Kind::kBuilding, {{-30, 30}, {30, 30}, {30, 45}, {-30, 45}}});
  meta.world_outlines.push_back({io::ReportMeta::MapOutline::Kind::kTree, {{-4, -3}, {4, -3}, {4, 3}, {-4, 3}}});

  io::ReportBuilder builder;
  const char* satellites[] = {"G02", "G05", "G13", "E11", "E24", "C20", "C29", "G30"};
  for (int k = 0; k <= 240; ++k) {
    const double f = k / 240.0;
    for (int s = 0; s < 8; ++s) {
      io::ReportSample sample;
      sample.time = start + 30.0 * k;
      sample.satellite = SatelliteId::parse(satellites[s]).value();
      sample.azimuth_deg = std::fmod(45.0 * s + 70.0 * f, 360.0);
      sample.elevation_deg = 5.0 + 70.0 * std::sin(std::numbers::pi * (0.15 + 0.7 * f)) * (0.4 + 0.08 * s);
      const bool behind_wall = sample.azimuth_deg >= 60.0 && sample.azimuth_deg <= 120.0 && sample.elevation_deg < 35.0;
      const bool in_trees = sample.azimuth_deg >= 200.0 && sample.azimuth_deg <= 250.0;
      if (sample.elevation_deg < 8.0) {
        sample.status = "below_mask";
      } else if (behind_wall) {
        sample.status = "blocked";
      } else {
        sample.status = "tracked";
        sample.vegetation_attenuation_db = in_trees ? 7.0 : 0.0;
        sample.cn0_dbhz = 30.0 + 0.25 * sample.elevation_deg - sample.vegetation_attenuation_db;
      }
      builder.add(sample);
    }
    // The rover drives a circle of 20 m; its fix scatters by decimetres, RTK fixed after 10 min.
    io::ReportBuilder::FixError error;
    const double angle = 2.0 * std::numbers::pi * f;
    error.truth_east_m = 20.0 * std::cos(angle);
    error.truth_north_m = 20.0 * std::sin(angle);
    error.east_m = 0.3 * std::sin(7.0 * k);
    error.north_m = 0.2 * std::cos(5.0 * k);
    error.up_m = 0.4 * std::sin(3.0 * k);
    if (k >= 20) error.east_m *= 0.02, error.north_m *= 0.02, error.up_m *= 0.02;
    error.fix_east_m = error.truth_east_m + error.east_m;
    error.fix_north_m = error.truth_north_m + error.north_m;
    error.satellites_used = 6;
    error.hdop = 1.1;
    builder.add_fix("rover", start + 30.0 * k, k >= 20 ? "rtk_fixed" : "3d", &error);
  }
  return builder;
}

class ReportChromium : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kChromium)) GTEST_SKIP() << kChromium << " absent (installed by scripts/setup)";
    dir_ = test::make_temp_dir(std::string("report_chromium_") +
                               ::testing::UnitTest::GetInstance()->current_test_info()->name());
    io::ReportMeta meta;
    const auto builder = synthetic_run(meta);
    report_ = dir_ / "report.html";
    std::ofstream(report_) << builder.html(meta);
    std::ofstream(dir_ / "skyplot.svg") << builder.sky_plot_svg(meta);
  }
  // Headless Chromium with everything that could reach the network switched off.
  std::string chromium(const std::string& profile, const std::string& arguments, const std::filesystem::path& log) const {
    return "timeout 60 " + std::string(kChromium) +
           " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking"
           " --disable-component-update --disable-sync --user-data-dir=" +
           test::shell_quote((dir_ / profile).string()) + " " + arguments + " 2>" + test::shell_quote(log.string());
  }
  std::filesystem::path dir_;
  std::filesystem::path report_;
};

TEST_F(ReportChromium, DomHoldsThePlots) {
  const auto log = dir_ / "dump.log";
  const auto result =
      test::run_command(chromium("profile-dom", "--dump-dom " + test::shell_quote("file://" + report_.string()), log));
  ASSERT_EQ(result.exit_code, 0) << read_all(log);
  const std::string& dom = result.output;
  for (const char* id : {"id=\"skyplot\"", "id=\"satellite-count\"", "id=\"cn0-chart\"", "id=\"summary\"",
                         "id=\"path-timeline\"", "id=\"solution-type\"", "id=\"fix-errors\"", "id=\"fix-horizontal-error\"",
                         "id=\"fix-error-cdf\"", "id=\"fix-top-view-1\"", "id=\"world-map\""}) {
    EXPECT_EQ(count_of(dom, id), 1U) << id << "\n" << read_all(log);
  }
  // The browser parsed the SVG: tracks, markers and chart lines are elements of the DOM.
  EXPECT_GE(count_of(dom, "<polyline"), 8U + 4U + 8U);
  EXPECT_GE(count_of(dom, "<circle"), 8U + 3U);
  EXPECT_NE(dom.find("courtyard &lt;synthetic&gt; &amp; trees"), std::string::npos);
  EXPECT_NE(dom.find("model tree_7 skipped"), std::string::npos);
  EXPECT_EQ(dom.find("<script"), std::string::npos);
}

TEST_F(ReportChromium, ScreenshotIsAPicture) {
  const auto png = dir_ / "report.png";
  const auto log = dir_ / "screenshot.log";
  const auto result = test::run_command(chromium("profile-shot",
                                                 "--screenshot=" + test::shell_quote(png.string()) +
                                                     " --window-size=1200,1600 " +
                                                     test::shell_quote("file://" + report_.string()),
                                                 log));
  ASSERT_EQ(result.exit_code, 0) << result.output << read_all(log);
  ASSERT_TRUE(std::filesystem::exists(png)) << read_all(log);
  const auto bytes = read_all(png);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // A blank page compresses to about 1 kB; plots with lines and text take tens of kB.
  EXPECT_GT(bytes.size(), 20'000U);
}

TEST_F(ReportChromium, StandaloneSkyPlotRenders) {
  const auto png = dir_ / "skyplot.png";
  const auto log = dir_ / "skyplot.log";
  const auto result = test::run_command(chromium("profile-svg",
                                                 "--screenshot=" + test::shell_quote(png.string()) +
                                                     " --window-size=520,620 " +
                                                     test::shell_quote("file://" + (dir_ / "skyplot.svg").string()),
                                                 log));
  ASSERT_EQ(result.exit_code, 0) << result.output << read_all(log);
  ASSERT_TRUE(std::filesystem::exists(png)) << read_all(log);
  EXPECT_GT(std::filesystem::file_size(png), 8'000U);
}

}  // namespace
}  // namespace skytrace
