// `skytrace position` end to end: on skytrace's own noise-free simulation of the contract scenario
// esbc-open-sky it must land on the antenna (the solver inverts the observation model), and on the
// real ESBC recording it must agree epoch by epoch with RTKLIB's rnx2rtkp, an independent
// implementation of the same single-point models.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

const Eigen::Vector3d kEsbcMarker(3582105.2910, 532589.7313, 5232754.8054);
constexpr double kEsbcAntennaHeight_m = 0.2160;

Eigen::Vector3d esbc_antenna() {
  return kEsbcMarker + kEsbcAntennaHeight_m * ecef_to_enu_rotation(ecef_to_geodetic(kEsbcMarker)).row(2).transpose();
}

struct Row {
  std::string time;  // "2020-06-25T00:00:30.000"
  std::string fix;
  int satellites = 0;
  Eigen::Vector3d ecef_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_enu_mps = Eigen::Vector3d::Zero();
  bool has_velocity = false;
};

// Reads the CSV of `skytrace position`, checking the header names the columns used here.
std::vector<Row> read_position_csv(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  {
    std::stringstream header(line);
    for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  }
  const auto column = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    EXPECT_NE(it, names.end()) << name;
    return static_cast<size_t>(it - names.begin());
  };
  const size_t time = column("time_gpst"), fix = column("fix"), used = column("satellites_used"), x = column("x_m"),
               ve = column("velocity_east_mps");
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string v; std::getline(fields, v, ',');) f.push_back(v);
    if (f.size() <= ve + 2) continue;
    Row r;
    r.time = f[time];
    r.fix = f[fix];
    r.satellites = std::stoi(f[used]);
    if (r.fix == "3d") {
      r.ecef_m = {std::stod(f[x]), std::stod(f[x + 1]), std::stod(f[x + 2])};
      if (!f[ve].empty()) {
        r.velocity_enu_mps = {std::stod(f[ve]), std::stod(f[ve + 1]), std::stod(f[ve + 2])};
        r.has_velocity = true;
      }
    }
    rows.push_back(r);
  }
  return rows;
}

double percentile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  return values.empty() ? std::nan("") : values[static_cast<size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1];
}

std::string skytrace_command() { return test::shell_quote(test::skytrace_executable().string()); }

TEST(PositionCli, SimulatedOpenSkyLandsOnTheAntenna) {
  const auto scenario = test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
  const auto nav = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  if (!std::filesystem::exists(scenario)) GTEST_SKIP() << "contract scenario absent: " << scenario;
  const auto dir = test::make_temp_dir("position_cli_sim_" + std::to_string(getpid()));
  const auto run = test::run_command(skytrace_command() + " run " + test::shell_quote(scenario.string()) + " --out " +
                                     test::shell_quote(dir.string()) + " --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto csv = dir / "position.csv";
  const auto position = test::run_command(skytrace_command() + " position " + test::shell_quote((dir / "obs.rnx").string()) +
                                          " --nav " + test::shell_quote((dir / "nav.rnx").string()) + " --out " +
                                          test::shell_quote(csv.string()) + " --elevation-mask-deg 5");
  ASSERT_EQ(position.exit_code, 0) << position.output;
  const std::vector<Row> rows = read_position_csv(csv);
  ASSERT_EQ(rows.size(), 121u);  // one hour at 30 s, both ends
  double worst_m = 0.0, worst_mps = 0.0;
  for (const Row& r : rows) {
    ASSERT_EQ(r.fix, "3d") << r.time;
    EXPECT_GE(r.satellites, 20) << r.time;  // G, R, E, C (+ J when two are up) at 5 degrees
    worst_m = std::max(worst_m, (r.ecef_m - esbc_antenna()).norm());
    ASSERT_TRUE(r.has_velocity) << r.time;
    worst_mps = std::max(worst_mps, r.velocity_enu_mps.norm());
  }
  // The only error left is the 1 mm resolution of RINEX code and the 1 mHz of Doppler.
  EXPECT_LT(worst_m, 0.02);
  EXPECT_LT(worst_mps, 0.01);
  std::printf("[ figures ] skytrace position on esbc-open-sky: worst 3D error %.4f m, worst speed %.5f m/s\n", worst_m,
              worst_mps);
  std::filesystem::remove_all(dir);
}

TEST(PositionCli, RealEsbcAgreesWithRtklibGpsOnly) {
  const auto obs = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
  const auto nav = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx");
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("position_cli_rtklib_" + std::to_string(getpid()));
  const auto csv = dir / "position.csv";
  const auto position = test::run_command(skytrace_command() + " position " + test::shell_quote(obs.string()) + " --nav " +
                                          test::shell_quote(nav.string()) + " --systems G --elevation-mask-deg 10 --out " +
                                          test::shell_quote(csv.string()));
  ASSERT_EQ(position.exit_code, 0) << position.output;

  // RTKLIB with the same models (rtklib-notes.md): L1 code, broadcast Klobuchar, Saastamoinen.
  const auto config = dir / "spp.conf";
  std::ofstream(config) << "pos1-posmode=single\npos1-frequency=l1\npos1-soltype=forward\npos1-elmask=10\n"
                           "pos1-ionoopt=brdc\npos1-tropopt=saas\npos1-sateph=brdc\npos1-navsys=1\n"
                           "out-solformat=xyz\nout-outhead=on\n";
  const auto solution = dir / "rtklib.pos";
  const auto rtklib = test::run_command("rnx2rtkp -k " + test::shell_quote(config.string()) + " -o " +
                                        test::shell_quote(solution.string()) + " " + test::shell_quote(obs.string()) +
                                        " " + test::shell_quote(nav.string()) + " 2>&1");
  ASSERT_EQ(rtklib.exit_code, 0) << rtklib.output;
  std::map<std::string, Eigen::Vector3d> reference;  // "00:00:30" -> ECEF
  std::ifstream in(solution);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '%') continue;
    std::istringstream fields(line);
    std::string date, time;
    Eigen::Vector3d x;
    int quality = 0;
    fields >> date >> time >> x.x() >> x.y() >> x.z() >> quality;
    if (fields && quality == 5) reference[time.substr(0, 8)] = x;
  }
  const std::vector<Row> rows = read_position_csv(csv);
  ASSERT_EQ(rows.size(), 120u);
  std::vector<double> differences, errors;
  for (const Row& r : rows) {
    ASSERT_EQ(r.fix, "3d") << r.time;
    errors.push_back((r.ecef_m - esbc_antenna()).norm());
    const auto it = reference.find(r.time.substr(11, 8));
    if (it != reference.end()) differences.push_back((r.ecef_m - it->second).norm());
  }
  EXPECT_GE(differences.size(), 115u);
  const double agreement_p95_m = percentile(differences, 0.95);
  const double error_p95_m = percentile(errors, 0.95);
  EXPECT_LT(agreement_p95_m, 1.0);
  EXPECT_LT(error_p95_m, 5.0);
  std::printf("[ figures ] skytrace position vs rnx2rtkp, ESBC GPS L1: %zu epochs, difference median %.3f m, p95 %.3f m; "
              "error from the antenna median %.3f m, p95 %.3f m\n",
              differences.size(), percentile(differences, 0.5), agreement_p95_m, percentile(errors, 0.5), error_p95_m);
  std::filesystem::remove_all(dir);
}

TEST(PositionCli, BadInputsFailClearlyWithoutOutput) {
  const auto obs = SKYTRACE_SHARED_FILE("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx");
  const auto other_day = SKYTRACE_SHARED_FILE("real/kms3_rinex4_2022159/KMS300DNK_R_20221591000_01H_MN.rnx");
  const auto dir = test::make_temp_dir("position_cli_bad_" + std::to_string(getpid()));
  const auto csv = dir / "position.csv";
  const std::string base = skytrace_command() + " position " + test::shell_quote(obs.string());

  const auto missing = test::run_command(base + " --nav " + test::shell_quote((dir / "absent.rnx").string()) + " --out " +
                                         test::shell_quote(csv.string()));
  EXPECT_EQ(missing.exit_code, 3) << missing.output;
  EXPECT_NE(missing.output.find("absent.rnx"), std::string::npos) << missing.output;

  const auto systems = test::run_command(base + " --nav " + test::shell_quote(other_day.string()) + " --systems GX");
  EXPECT_EQ(systems.exit_code, 2) << systems.output;
  EXPECT_NE(systems.output.find("--systems"), std::string::npos) << systems.output;

  // Ephemerides of 2022 for observations of 2020: no epoch can be positioned, and the message says
  // why with both spans.
  const auto uncovered = test::run_command(base + " --nav " + test::shell_quote(other_day.string()) + " --out " +
                                           test::shell_quote(csv.string()));
  EXPECT_EQ(uncovered.exit_code, 4) << uncovered.output;
  EXPECT_NE(uncovered.output.find("the navigation data does not cover"), std::string::npos) << uncovered.output;
  EXPECT_NE(uncovered.output.find("its records serve 2022-06-07T23:53:44.0 to 2022-06-08"), std::string::npos) << uncovered.output;
  EXPECT_NE(uncovered.output.find("the observations run from 2020-06-25T00:00:00.0"), std::string::npos) << uncovered.output;
  EXPECT_FALSE(std::filesystem::exists(csv));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace skytrace
