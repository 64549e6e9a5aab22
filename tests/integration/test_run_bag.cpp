// `skytrace run` with output.mcap: the rosbag2 folder it writes, read by the libraries Foxglove's
// viewer uses (tests/clients/mcap/check_bag.mjs), carries the same values as the run's other
// outputs: NavSatFix = fix.csv, NMEA = fix.nmea, RTCM frames = obs.rtcm3, observations = obs.rnx,
// one message per epoch and topic. Skips only when the npm packages are not installed.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "process.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

using nlohmann::json;

std::filesystem::path client_dir() { return test::source_dir() / "tests" / "clients" / "mcap"; }

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> cells;
  std::stringstream s(line);
  std::string cell;
  while (std::getline(s, cell, separator)) cells.push_back(cell);
  return cells;
}

TEST(RunBag, FoxgloveReadsTheSameValuesAsTheOtherOutputs) {
  if (!std::filesystem::exists(client_dir() / "node_modules" / "@mcap" / "core")) {
    GTEST_SKIP() << "npm packages not installed in " << client_dir() << " (run scripts/setup)";
  }
  const auto out = test::make_temp_dir("run_bag");
  const auto run = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote((test::source_dir() / "examples" / "quickstart.yaml").string()) +
                                     " --out " + test::shell_quote(out.string()) +
                                     " --quiet --set time.duration_s=30 --set output.mcap=true --set output.nmea=true"
                                     " --set output.rtcm3=true --set output.mcap_compression=lz4 2>&1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  ASSERT_TRUE(std::filesystem::exists(out / "bag" / "metadata.yaml"));
  ASSERT_TRUE(std::filesystem::exists(out / "bag" / "bag_0.mcap"));

  const auto checked = test::run_command("node " + test::shell_quote((client_dir() / "check_bag.mjs").string()) + " " +
                                         test::shell_quote((out / "bag").string()) + " --values 2>&1");
  ASSERT_EQ(checked.exit_code, 0) << checked.output.substr(0, 4000);
  const json summary = json::parse(checked.output.substr(checked.output.find('{')));
  ASSERT_TRUE(summary.value("ok", false)) << summary["errors"].dump(1);
  const json& values = summary["values"];
  EXPECT_EQ(summary["compression"], json::array({"lz4"}));

  // Every topic of the receiver, one message per epoch (31) where the topic is per epoch.
  std::map<std::string, int> counts;
  for (const auto& topic : summary["topics"]) counts[topic["name"]] = topic["count"];
  for (const char* topic : {"/skytrace/fix", "/skytrace/velocity", "/skytrace/time_reference", "/skytrace/gnss/measurements",
                            "/skytrace/observations", "/skytrace/sky", "/skytrace/rays"}) {
    EXPECT_EQ(counts[topic], 31) << topic;
  }
  EXPECT_GT(counts["/skytrace/gnss/ephemeris"], 10);  // the nominal constellation's records in use

  // NavSatFix against fix.csv (9 decimals of a degree, 4 of a metre).
  std::ifstream fix_csv(out / "fix.csv");
  std::string line;
  std::getline(fix_csv, line);
  const auto columns = split(line, ',');
  const auto column = [&](const char* name) {
    return static_cast<size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin());
  };
  size_t row = 0;
  while (std::getline(fix_csv, line)) {
    const auto cells = split(line, ',');
    ASSERT_LT(row, values["/skytrace/fix"].size());
    const json& fix = values["/skytrace/fix"][row];
    EXPECT_NEAR(fix["latitude"].get<double>(), std::stod(cells[column("latitude_deg")]), 1e-9) << row;
    EXPECT_NEAR(fix["longitude"].get<double>(), std::stod(cells[column("longitude_deg")]), 1e-9) << row;
    EXPECT_NEAR(fix["altitude"].get<double>(), std::stod(cells[column("height_m")]), 1e-4) << row;
    EXPECT_EQ(fix["status"]["status"], 0);  // single point: STATUS_FIX
    EXPECT_EQ(fix["position_covariance_type"], 3);
    EXPECT_NEAR(std::sqrt(fix["position_covariance"][0].get<double>()), std::stod(cells[column("sigma_east_m")]), 1e-4);
    ++row;
  }
  EXPECT_EQ(row, 31u);

  // NMEA and RTCM: the same sentences and frames, in order.
  std::string nmea;
  for (const auto& sentence : values["/skytrace/nmea"]) nmea += sentence["sentence"].get<std::string>() + "\r\n";
  EXPECT_EQ(nmea, read_bytes(out / "fix.nmea"));
  std::string rtcm;
  for (const auto& frame : values["/skytrace/rtcm"]) {
    for (const auto& byte : frame["message"]) rtcm += static_cast<char>(byte.get<int>());
  }
  EXPECT_EQ(rtcm, read_bytes(out / "obs.rtcm3"));

  // Observations against obs.rnx (F14.3: within half a millimetre, a thousandth of a cycle).
  auto obs = io::read_rinex_obs(out / "obs.rnx");
  ASSERT_TRUE(obs.ok()) << obs.error().message;
  ASSERT_EQ(obs->epochs.size(), values["/skytrace/observations"].size());
  size_t compared = 0;
  for (size_t k = 0; k < obs->epochs.size(); ++k) {
    const auto& epoch = obs->epochs[k];
    for (const auto& o : values["/skytrace/observations"][k]["observations"]) {
      const auto satellite = SatelliteId::parse(o["satellite"].get<std::string>()).value();
      const auto* record = epoch.find(satellite);
      ASSERT_NE(record, nullptr) << o["satellite"];
      const auto& types = obs->header.observation_types.at(satellite.system);
      for (size_t t = 0; t < types.size() && t < record->values.size(); ++t) {
        if (types[t].code == std::string("C").append(o["signal"].get<std::string>()) && record->values[t].value) {
          EXPECT_NEAR(o["pseudorange_m"].get<double>(), *record->values[t].value, 5e-4);
          ++compared;
        }
        if (types[t].code == std::string("L").append(o["signal"].get<std::string>()) && record->values[t].value) {
          EXPECT_NEAR(o["carrier_phase_cycles"].get<double>(), *record->values[t].value, 5e-4);
        }
      }
    }
  }
  EXPECT_GT(compared, 31u * 10);

  // gnss_comm measurements carry the same pseudoranges (GPS, GLONASS, Galileo, BeiDou satellites).
  const json& first = values["/skytrace/gnss/measurements"][0]["meas"];
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first[0]["time"]["week"], values["/skytrace/observations"][0]["gps_week"]);
  for (const auto& m : first) {
    EXPECT_GE(m["sat"].get<int>(), 1);
    EXPECT_EQ(m["psr"].size(), m["cn0"].size());
    EXPECT_GT(m["psr_std"][0].get<double>(), 0.0);
  }
}

}  // namespace
}  // namespace skytrace
