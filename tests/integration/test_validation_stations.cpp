// Receiver realism acceptance on the independent stations (docs/validation.md): NYA1 2024-124 and
// SLAC 2021-118, both Trimble NetR9, simulated with the profile constants fitted on ESBC only
// (ESBC itself: Reproducibility.EsbcRealismAcceptanceOnL1). GPS and Galileo L1, satellites above
// 10 degrees. Limits: overlap >= 95 % both ways, pseudorange p68 <= 2.0 m, Doppler p68 <= 0.10
// m/s, epoch-differenced phase p68 <= 1 cm, C/N0 mean absolute difference <= 2.5 dB-Hz.
// What physics cannot meet here is asserted at its measured size, so that it cannot grow unseen:
// the phase at NYA1 (the real ionosphere's 30-s changes that Klobuchar does not follow, and the
// GPS IIR clocks' short-term noise, absent from broadcast clocks). SLAC, simulated over the hour
// its precise clocks cover, meets every limit.
// NYA1 also checks the NetR9's output rule (tracking.output_requires_ephemeris): rising satellites
// appear only once their first record has been transmitted (docs/validation.md).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <map>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

struct Limits {
  double sim_in_real = 0.95;
  double phase_m = 0.01;
};

class ValidationStations : public ::testing::Test {
 protected:
  // The scenarios name the data as ../../../shared/data from their folder.
  static std::filesystem::path data_in_scenario() {
    return (test::source_dir() / "examples/validation/../../../shared/data").lexically_normal();
  }

  // Runs `scenario` (examples/validation) into a fresh folder, returned.
  static std::filesystem::path run_scenario(const std::string& scenario) {
    const auto scenario_path = test::source_dir() / "examples/validation" / scenario;
    const auto out = test::make_temp_dir("validation_" + scenario);
    auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                               test::shell_quote(scenario_path.string()) + " --out " +
                               test::shell_quote(out.string()) + " --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return out;
  }

  // Runs `scenario` (examples/validation) and compares it with `real`; the JSON rows by signal.
  std::map<std::string, nlohmann::json> run_and_compare(const std::string& scenario, const std::string& real,
                                                        const std::vector<std::string>& navs,
                                                        const std::string& signals) {
    if (!std::filesystem::exists(data_in_scenario() / real)) {
      return {};
    }
    const auto out = run_scenario(scenario);
    std::string command = test::shell_quote(test::skytrace_executable().string()) + " compare " +
                          test::shell_quote((data_in_scenario() / real).string()) + " " +
                          test::shell_quote((out / "obs.rnx").string());
    for (const auto& nav : navs) command += " --nav " + test::shell_quote((data_in_scenario() / nav).string());
    command += " --min-elevation-deg 10 --signals " + signals + " --json " + test::shell_quote((out / "c.json").string());
    const auto r = test::run_command(command);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(out / "c.json");
    std::map<std::string, nlohmann::json> rows;
    const nlohmann::json report = nlohmann::json::parse(in);
    for (const auto& row : report.at("signals")) rows[row.at("signal").get<std::string>()] = row;
    return rows;
  }

  static void check(const nlohmann::json& row, bool has_doppler, const Limits& limits) {
    SCOPED_TRACE(row.dump(1));
    EXPECT_GE(row.at("overlap").at("real_in_sim").get<double>(), 0.95);
    EXPECT_GE(row.at("overlap").at("sim_in_real").get<double>(), limits.sim_in_real);
    EXPECT_LE(row.at("pseudorange_m").at("abs_p68").get<double>(), 2.0);
    if (has_doppler) {
      EXPECT_GT(row.at("doppler_mps").at("count").get<int>(), 500);
      EXPECT_LE(row.at("doppler_mps").at("abs_p68").get<double>(), 0.10);
    }
    EXPECT_LE(row.at("phase_difference_m").at("abs_p68").get<double>(), limits.phase_m);
    EXPECT_GT(row.at("cn0_dbhz").at("count").get<int>(), 500);
    EXPECT_LE(row.at("cn0_dbhz").at("mean_abs_difference").get<double>(), 2.5);
  }
};

TEST_F(ValidationStations, Nya1NetR9WithEsbcConstants) {
  const auto rows = run_and_compare("nya1-realistic.yaml",
                                    "real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx",
                                    {"real/nya1_2024124/NYA100NOR_S_20241240000_01D_GN.rnx",
                                     "real/nya1_2024124/NYA100NOR_S_20241240000_01D_EN.rnx"},
                                    "G1C,E1X");
  if (rows.empty()) GTEST_SKIP() << "NYA1 data absent (../shared/data beside the checkout)";
  ASSERT_EQ(rows.size(), 2u);
  // Measured: G1C phase 0.019 m, E1X 0.0115 m. E1X sim in real 99.9 % (87.3 % before the profile
  // output satellites only with a decoded ephemeris): the acceptance limit holds.
  check(rows.at("G1C"), true, Limits{0.95, 0.022});
  check(rows.at("E1X"), true, Limits{0.95, 0.013});
}

// The NetR9 outputs a satellite only once it holds a broadcast ephemeris for it. The station's own
// navigation file dates the first records: E10 transmitted 00:33:25 (real observations from
// 00:34:00), E30 01:01:25 and E11 01:28:25 (none in the first hour), G10 00:45:36 (from 00:46:00),
// G22 00:34:12 (from 00:34:30). Satellites tracked at the start are output at once.
TEST_F(ValidationStations, Nya1NetR9OutputsRisingSatellitesOnceTheirEphemerisIsTransmitted) {
  const std::string real_name = "real/nya1_2024124/NYA100NOR_S_20241240000_01D_30S_MO_first1h.rnx";
  if (!std::filesystem::exists(data_in_scenario() / real_name)) {
    GTEST_SKIP() << "NYA1 data absent (../shared/data beside the checkout)";
  }
  const auto out = run_scenario("nya1-realistic.yaml");
  const auto sim = io::read_rinex_obs(out / "obs.rnx");
  ASSERT_TRUE(sim) << sim.error().message;
  const auto real = io::read_rinex_obs(data_in_scenario() / real_name);
  ASSERT_TRUE(real) << real.error().message;
  const GnssTime start = GnssTime::parse_iso8601("2024-05-03T00:00:00", TimeScale::kGpst).value();
  const GnssTime end = start + 3600.0;
  // First epoch (before `end`) at which a satellite is in the file.
  const auto first = [&](const io::ObservationFile& file, const char* name) -> std::optional<GnssTime> {
    const SatelliteId sat = SatelliteId::parse(name).value();
    for (const auto& epoch : file.epochs) {
      if (epoch.time < end && epoch.find(sat) != nullptr) return epoch.time;
    }
    return std::nullopt;
  };
  const auto at = [&](const char* hms) {
    return GnssTime::parse_iso8601(std::string("2024-05-03T") + hms, TimeScale::kGpst).value();
  };
  EXPECT_FALSE(first(*sim, "E11")) << "E11's first record was transmitted at 01:28:25";
  EXPECT_FALSE(first(*sim, "E30")) << "E30's first record was transmitted at 01:01:25";
  EXPECT_FALSE(first(*real, "E11"));
  EXPECT_FALSE(first(*real, "E30"));
  const auto e10 = first(*sim, "E10");
  ASSERT_TRUE(e10);
  EXPECT_GE(*e10, at("00:33:25"));
  EXPECT_LE(*e10 - at("00:33:25"), 30.0) << e10->to_iso8601(TimeScale::kGpst);  // within one epoch
  EXPECT_LE(*e10 - *first(*real, "E10"), 30.0);
  EXPECT_GE(*e10 - *first(*real, "E10"), -30.0);
  // GPS: the epochs of the real receiver exactly.
  EXPECT_EQ(first(*sim, "G10"), at("00:46:00"));
  EXPECT_EQ(first(*real, "G10"), at("00:46:00"));
  EXPECT_EQ(first(*sim, "G22"), at("00:34:30"));
  EXPECT_EQ(first(*real, "G22"), at("00:34:30"));
  // Tracked from the start: output from the first epoch, as in the real file.
  for (const char* name : {"G05", "E02"}) {
    EXPECT_EQ(first(*sim, name), start) << name;
    EXPECT_EQ(first(*real, name), start) << name;
  }
  // The first output of a satellite that waited starts its arc for the user (LLI 1), as the
  // NetR9 does.
  const SatelliteId g10 = SatelliteId::parse("G10").value();
  for (const auto& epoch : sim->epochs) {
    if (const auto* record = epoch.find(g10)) {
      ASSERT_GE(record->values.size(), 2u);
      EXPECT_EQ(record->values[1].lli & 1, 1);  // L1C
      break;
    }
  }
}

TEST_F(ValidationStations, SlacNetR9WithEsbcConstants) {
  const auto rows = run_and_compare("slac-realistic.yaml", "real/slac_2021118/slac1180.21o",
                                    {"real/slac_2021118/brdc1180.21n"}, "G1C");
  if (rows.empty()) GTEST_SKIP() << "SLAC data absent (../shared/data beside the checkout)";
  ASSERT_EQ(rows.size(), 1u);
  // RINEX 2.11 without Doppler. The run is 19:30-20:30, the hour CODE's clock file covers: phase
  // 0.0083 m, the acceptance limit holds (0.0114 m over 19:00-21:00, when the half hours outside the
  // clock file silently had broadcast truth).
  EXPECT_EQ(rows.at("G1C").at("doppler_mps").at("count").get<int>(), 0);
  EXPECT_GT(rows.at("G1C").at("phase_difference_m").at("count").get<int>(), 1000);
  check(rows.at("G1C"), false, Limits{0.95, 0.01});
}

}  // namespace
}  // namespace skytrace
