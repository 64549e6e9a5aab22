// Precise products that do not cover a run: the span check before the run (sim::prepare_resources,
// check_precise_coverage), satellites the products lack or cannot serve (broadcast truth for the
// whole run, reported), and a live session stepped beyond the products (an error, not a switch of
// truth). Small SP3 and RINEX clock files are written by the tests; the navigation data is the
// nominal constellation.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "skytrace/sim/live.hpp"
#include "skytrace/sim/scenario.hpp"
#include "skytrace/sim/setup.hpp"
#include "test_support.hpp"

namespace skytrace::sim {
namespace {

const GnssTime kDay = GnssTime::from_calendar({2020, 6, 25, 0, 0, 0.0}, TimeScale::kGpst);

// An SP3-c file from `first_s` to `last_s` (seconds of 2020-06-25 GPST) every `interval_s`, with
// positions (and clocks) of `satellites` where has(satellite, t_s) says so.
std::string sp3_text(const std::vector<std::string>& satellites, double first_s, double last_s, double interval_s,
                     const std::function<bool(const std::string&, double)>& has = nullptr) {
  const int epochs = static_cast<int>((last_s - first_s) / interval_s + 0.5) + 1;
  const GnssTime t0 = kDay + first_s;
  const WeekTow wt = t0.to_week_tow(TimeScale::kGpst);
  const CalendarTime c = t0.to_calendar(TimeScale::kGpst);
  char line[160];
  std::string s;
  std::snprintf(line, sizeof line, "#cP%4d %2d %2d %2d %2d %11.8f %7d ORBIT IGb14 FIT  TST\n", c.year, c.month, c.day,
                c.hour, c.minute, c.second, epochs);
  s += line;
  std::snprintf(line, sizeof line, "## %4d %15.8f %14.8f 59025 0.0000000000000\n", wt.week, wt.tow_s, interval_s);
  s += line;
  std::string list;
  for (const auto& sat : satellites) list += sat;
  std::snprintf(line, sizeof line, "+  %3zu   %-51s\n", satellites.size(), list.c_str());
  s += line;
  s += "++         5  5  5  0  0  0  0  0  0  0  0  0  0  0  0  0  0\n";
  s += "%c G  cc GPS ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n";
  s += "%c cc cc ccc ccc cccc cccc cccc cccc ccccc ccccc ccccc ccccc\n";
  s += "%f  1.2500000  1.025000000  0.00000000000  0.000000000000000\n";
  s += "%i    0    0    0    0      0      0      0      0         0\n";
  for (int k = 0; k < epochs; ++k) {
    const double t_s = first_s + k * interval_s;
    const CalendarTime e = (kDay + t_s).to_calendar(TimeScale::kGpst);
    std::snprintf(line, sizeof line, "*  %4d %2d %2d %2d %2d %11.8f\n", e.year, e.month, e.day, e.hour, e.minute, e.second);
    s += line;
    for (size_t i = 0; i < satellites.size(); ++i) {
      const bool present = !has || has(satellites[i], t_s);
      // Any smooth path at GNSS height will do: only whether a value exists matters here.
      const double x_km = present ? 15000.0 + 1000.0 * static_cast<double>(i) + 0.5 * t_s / 60.0 : 0.0;
      const double y_km = present ? 10000.0 - 0.3 * t_s / 60.0 : 0.0;
      const double z_km = present ? 18000.0 : 0.0;
      std::snprintf(line, sizeof line, "P%3s%14.6f%14.6f%14.6f%14.6f\n", satellites[i].c_str(), x_km, y_km, z_km,
                    present ? 100.0 : 999999.999999);
      s += line;
    }
  }
  s += "EOF\n";
  return s;
}

std::string header_line(const std::string& content, const std::string& label) {
  std::string line = content;
  line.resize(60, ' ');
  return line + label + "\n";
}

// A RINEX 3.00 clock file from `first_s` to `last_s` every 30 s for `satellites`, leaving out the
// samples has(satellite, t_s) refuses.
std::string clock_text(const std::vector<std::string>& satellites, double first_s, double last_s,
                       const std::function<bool(const std::string&, double)>& has = nullptr) {
  std::string s;
  s += header_line("     3.00           CLOCK DATA          G", "RINEX VERSION / TYPE");
  s += header_line("   GPS", "TIME SYSTEM ID");
  s += header_line("     1    AS", "# OF TYPES OF DATA");
  s += header_line("TST  skytrace tests", "ANALYSIS CENTER");
  std::string list;
  for (const auto& sat : satellites) list += sat + " ";
  s += header_line(list, "PRN LIST");
  s += header_line("", "END OF HEADER");
  char line[160];
  for (double t_s = first_s; t_s <= last_s + 1e-9; t_s += 30.0) {
    const CalendarTime e = (kDay + t_s).to_calendar(TimeScale::kGpst);
    for (const auto& sat : satellites) {
      if (has && !has(sat, t_s)) continue;
      std::snprintf(line, sizeof line, "AS %-3s  %4d %2d %2d %2d %2d %9.6f  1   %19.12E\n", sat.c_str(), e.year, e.month,
                    e.day, e.hour, e.minute, e.second, 1e-4 + 1e-11 * t_s);
      s += line;
    }
  }
  return s;
}

class PreciseCoverage : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("precise_coverage"); }

  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name, std::ios::binary) << text; }

  // A nominal-constellation scenario (GPS L1) starting `start` (2020-06-25) for `duration_s`, with
  // the SP3 and clock files of this folder named.
  Result<Scenario> scenario(const std::string& start, double duration_s, const std::string& sp3,
                            const std::string& clk) const {
    std::string text = "name: coverage\ntime:\n  start: 2020-06-25T" + start + "\n  scale: GPST\n  duration_s: " +
                       std::to_string(duration_s) +
                       "\n  interval_s: 30\nreceiver:\n  position:\n    ecef_m: [3582105.2910, 532589.7313, 5232754.8054]\n"
                       "  signals: [G1C]\nephemeris:\n  nominal: true\n  precise_orbits: [" +
                       sp3 + "]\n";
    if (!clk.empty()) text += "  precise_clocks: [" + clk + "]\n";
    text += "models:\n  ionosphere: none\n";
    return parse_scenario(text, (dir_ / "s.yaml").string(), dir_);
  }

  std::filesystem::path dir_;
};

TEST_F(PreciseCoverage, ARunLongerThanTheProductsStopsNamingTheFileItsSpanAndTheRuns) {
  // Orbits 00:00-02:00 (5 min), clocks 00:30-01:30 (30 s).
  write("orbits.sp3", sp3_text({"G01", "G02"}, 0.0, 7200.0, 300.0));
  write("short.clk", clock_text({"G01", "G02"}, 1800.0, 5400.0));

  auto run = scenario("00:00:00", 3600, "orbits.sp3", "short.clk");
  ASSERT_TRUE(run.ok()) << run.error().message;
  auto resources = prepare_resources(*run);
  ASSERT_FALSE(resources.ok());
  EXPECT_EQ(resources.error().code, ErrorCode::kOutOfRange);  // exit code 4, as any time outside the data
  EXPECT_EQ(resources.error().message,
            "ephemeris.precise_clocks: short.clk covers 2020-06-25 00:30:00 to 01:30:00 GPST; the run needs 00:00:00 "
            "to 01:00:00 GPST (give the neighbouring days' files as well, or shorten the run)");

  // Beyond the end of the orbits; a run into the next day names both dates.
  auto late = prepare_resources(*scenario("01:30:00", 3600, "orbits.sp3", ""));
  ASSERT_FALSE(late.ok());
  EXPECT_EQ(late.error().code, ErrorCode::kOutOfRange);
  EXPECT_EQ(late.error().message,
            "ephemeris.precise_orbits: orbits.sp3 covers 2020-06-25 00:00:00 to 02:00:00 GPST; the run needs 01:30:00 "
            "to 02:30:00 GPST (give the neighbouring days' files as well, or shorten the run)");
  write("late.sp3", sp3_text({"G01", "G02"}, 0.0, 86400.0 - 300.0, 300.0));
  auto next_day = prepare_resources(*scenario("23:30:00", 3600, "late.sp3", ""));
  ASSERT_FALSE(next_day.ok());
  EXPECT_NE(next_day.error().message.find("late.sp3 covers 2020-06-25 00:00:00 to 23:55:00 GPST; the run needs "
                                          "23:30:00 to 2020-06-26 00:30:00 GPST"),
            std::string::npos)
      << next_day.error().message;

  // Exactly the clock file's hour runs: the flight time before the first epoch (a fraction of a
  // second before the first sample) is within the interpolation's one interval of extrapolation.
  auto inside = prepare_resources(*scenario("00:30:00", 3600, "orbits.sp3", "short.clk"));
  ASSERT_TRUE(inside.ok()) << inside.error().message;
  ASSERT_TRUE(inside->precise_coverage.has_value());
  EXPECT_EQ(inside->precise_coverage->gaps.size(), 0u);
  EXPECT_EQ(inside->precise_coverage->lacking.count(SatelliteId{GnssSystem::kGps, 1}), 0u);
  EXPECT_DOUBLE_EQ(inside->precise_coverage->to - inside->precise_coverage->from, 3600.0 + kTransmissionLead_s);

  // SP3 files without clocks and no clock file: nothing to take the clocks from.
  std::string no_clocks = sp3_text({"G01"}, 0.0, 7200.0, 300.0);
  for (size_t at = no_clocks.find("    100.000000\n"); at != std::string::npos; at = no_clocks.find("    100.000000\n")) {
    no_clocks.replace(at, 14, " 999999.999999");
  }
  write("noclk.sp3", no_clocks);
  auto without = prepare_resources(*scenario("00:30:00", 600, "noclk.sp3", ""));
  ASSERT_FALSE(without.ok());
  EXPECT_EQ(without.error().code, ErrorCode::kNotFound);
  EXPECT_EQ(without.error().message,
            "ephemeris.precise_orbits: noclk.sp3 holds no satellite clock and no ephemeris.precise_clocks file is given");
}

TEST_F(PreciseCoverage, SatellitesTheProductsLackOrCannotServeKeepTheBroadcastTruthAndAreReported) {
  // G03 has orbits but no clocks; G02's clocks miss 00:40:30-00:49:30; G04 has a missing SP3
  // position at 01:00 (its neighbours' intervals cannot be interpolated); the nominal
  // constellation's other satellites are in neither product.
  write("orbits.sp3", sp3_text({"G01", "G02", "G03", "G04"}, 0.0, 7200.0, 300.0,
                               [](const std::string& sat, double t_s) { return !(sat == "G04" && t_s == 3600.0); }));
  write("gaps.clk", clock_text({"G01", "G02", "G04"}, 0.0, 7200.0, [](const std::string& sat, double t_s) {
          return !(sat == "G02" && t_s > 2400.0 && t_s < 3000.0);
        }));
  auto s = scenario("00:30:00", 3600, "orbits.sp3", "gaps.clk");
  ASSERT_TRUE(s.ok()) << s.error().message;
  auto resources = prepare_resources(*s);
  ASSERT_TRUE(resources.ok()) << resources.error().message;
  const PreciseTruthCoverage& c = *resources->precise_coverage;
  const SatelliteId g01{GnssSystem::kGps, 1}, g02{GnssSystem::kGps, 2}, g03{GnssSystem::kGps, 3},
      g04{GnssSystem::kGps, 4}, g05{GnssSystem::kGps, 5};
  EXPECT_EQ(c.lacking.count(g01) + c.gaps.count(g01), 0u);
  ASSERT_EQ(c.lacking.count(g03), 1u);
  EXPECT_TRUE(c.lacking.at(g03).in_orbits);
  EXPECT_FALSE(c.lacking.at(g03).in_clocks);
  ASSERT_EQ(c.lacking.count(g05), 1u);
  EXPECT_FALSE(c.lacking.at(g05).in_orbits);
  ASSERT_EQ(c.gaps.count(g02), 1u);
  ASSERT_EQ(c.gaps.at(g02).clock_gaps.size(), 1u);
  EXPECT_TRUE(c.gaps.at(g02).orbit_gaps.empty());
  EXPECT_DOUBLE_EQ(c.gaps.at(g02).clock_gaps[0].first - kDay, 2400.0);
  EXPECT_DOUBLE_EQ(c.gaps.at(g02).clock_gaps[0].last - kDay, 3000.0);
  ASSERT_EQ(c.gaps.count(g04), 1u);
  ASSERT_EQ(c.gaps.at(g04).orbit_gaps.size(), 1u);
  EXPECT_DOUBLE_EQ(c.gaps.at(g04).orbit_gaps[0].first - kDay, 3300.0);
  EXPECT_DOUBLE_EQ(c.gaps.at(g04).orbit_gaps[0].last - kDay, 3900.0);

  // One warning line for each kind, naming the satellites (and what a partly held one lacks).
  ASSERT_EQ(resources->warnings.size(), 2u);
  EXPECT_EQ(resources->warnings[0].rfind("the precise products lack ", 0), 0u) << resources->warnings[0];
  EXPECT_NE(resources->warnings[0].find("which keep the broadcast truth: G03 (no clock) G05 G06"), std::string::npos)
      << resources->warnings[0];
  EXPECT_EQ(resources->warnings[1],
            "the precise products cannot serve 2 satellites over the whole run, which keep the broadcast truth for all "
            "of it: G02 (clock 2020-06-25 00:40:00 to 00:50:00 GPST), G04 (orbit 2020-06-25 00:55:00 to 01:05:00 GPST)");

  // The generators get them as broadcast-truth satellites; G01 keeps the precise truth.
  Eigen::Vector3d marker;
  auto kinematics = make_kinematics(*s, s->receivers[0], std::nullopt, marker);
  ASSERT_TRUE(kinematics.ok());
  auto generator = make_generator(*s, *resources, 0, *kinematics);
  ASSERT_TRUE(generator.ok()) << generator.error().message;
  const auto& broadcast = (*generator)->settings().broadcast_truth;
  EXPECT_EQ(broadcast.count(g01), 0u);
  EXPECT_EQ(broadcast.count(g02) + broadcast.count(g03) + broadcast.count(g04) + broadcast.count(g05), 4u);

  // summary.json's object lists them too.
  const std::string json = c.to_json();
  EXPECT_NE(json.find("\"G02\":{\"clock\":[[\"2020-06-25 00:40:00\",\"2020-06-25 00:50:00\"]],\"orbit\":[]}"),
            std::string::npos)
      << json;
}

TEST_F(PreciseCoverage, ALiveSessionSteppedBeyondTheProductsFailsInsteadOfSwitchingTruth) {
  write("orbits.sp3", sp3_text({"G01"}, 0.0, 7200.0, 300.0));
  write("short.clk", clock_text({"G01"}, 1800.0, 5400.0));
  auto s = scenario("00:30:00", 3600, "orbits.sp3", "short.clk");
  ASSERT_TRUE(s.ok());
  LiveOptions options;
  options.solve_position = false;
  auto session = LiveSession::create(*s, options);
  ASSERT_TRUE(session.ok()) << session.error().message;
  EXPECT_TRUE((*session)->step(kDay + 3000.0).ok());
  // 01:31 is a minute past the clock file (30 s of extrapolation are allowed): an error naming the
  // satellite and the clock file's span, never the broadcast truth for this epoch.
  auto beyond = (*session)->step(kDay + 5460.0);
  ASSERT_FALSE(beyond.ok());
  EXPECT_EQ(beyond.error().code, ErrorCode::kOutOfRange);
  EXPECT_NE(beyond.error().message.find("precise truth at epoch 2020-06-25T01:31:00 GPST: no precise clock for G01"),
            std::string::npos)
      << beyond.error().message;
  EXPECT_NE(beyond.error().message.find("the clocks cover 2020-06-25T00:30:00 to 2020-06-25T01:30:00 GPST"),
            std::string::npos)
      << beyond.error().message;
}

}  // namespace
}  // namespace skytrace::sim
