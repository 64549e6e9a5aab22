// End to end: skytrace simulates the contract scenario esbc-open-sky (noise-free), RTKLIB's
// rnx2rtkp positions the output with broadcast Klobuchar and Saastamoinen, and every epoch must land
// on the antenna reference point. RTKLIB is an independent implementation of the same models, so
// this checks orbits, clocks, group delays, Sagnac, light time, atmosphere and the RINEX writers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "process.hpp"
#include "rtklib.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

const Eigen::Vector3d kEsbcMarker(3582105.2910, 532589.7313, 5232754.8054);
constexpr double kEsbcAntennaHeight_m = 0.2160;

// The folder with the simulated esbc-open-sky outputs, simulated once for all tests here.
class RtklibSinglePoint : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto scenario = test::shared_data_dir().parent_path() / "contract" / "esbc-open-sky.yaml";
    if (!std::filesystem::exists(scenario) ||
        !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
      skip_reason_ = "contract scenario or ESBC data absent (set SKYTRACE_SHARED_DATA)";
      return;
    }
    if (!test::program_available("rnx2rtkp")) {
      skip_reason_ = "rnx2rtkp (Debian package rtklib) is not installed: run scripts/setup";
      return;
    }
    // One folder per process: CTest runs the tests of this suite in parallel processes.
    out_dir_ = test::make_temp_dir("rtklib_single_point_" + std::to_string(getpid()));
    const auto run = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                       test::shell_quote(scenario.string()) + " --out " +
                                       test::shell_quote(out_dir_.string()) + " --quiet");
    run_exit_code_ = run.exit_code;
    run_output_ = run.output;
  }

  static void TearDownTestSuite() {
    std::error_code ignored;
    if (!out_dir_.empty() && !::testing::Test::HasFailure()) std::filesystem::remove_all(out_dir_, ignored);
  }

  void SetUp() override {
    if (!skip_reason_.empty()) GTEST_SKIP() << skip_reason_;
    ASSERT_EQ(run_exit_code_, 0) << run_output_;
  }

  // The navigation file for RTKLIB for the epochs after `window_start` (GPST "YYYY MM DD hh mm ss"):
  // - only Galileo I/NAV records (data-source bit 1 clear), as rtklib-notes.md advises for E1;
  // - no Galileo record older than the one in force at window_start. RTKLIB takes a satellite's
  //   group delay from its earliest record whatever record it uses for orbit and clock, while the
  //   broadcast BGD changes with new uploads (E13 and E24 change by 0.2 ns at 00:40 on 2020-06-25);
  //   skytrace applies the BGD of the record in force, as a receiver does. Within a window of one
  //   Galileo update interval (10 min) the earliest remaining record is the one in force.
  static std::filesystem::path navigation_for_window(const std::string& window_start, const std::string& name) {
    std::ifstream in(out_dir_ / "nav.rnx");
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    struct Record {
      std::vector<std::string> lines;
      std::string satellite, toe;
    };
    std::vector<std::string> header;
    std::vector<Record> records;
    size_t i = 0;
    for (; i < lines.size(); ++i) {
      header.push_back(lines[i]);
      if (lines[i].find("END OF HEADER") != std::string::npos) break;
    }
    for (++i; i < lines.size();) {
      if (lines[i].empty()) {
        ++i;
        continue;
      }
      const char system = lines[i][0];
      const size_t count = (system == 'R' || system == 'S') ? 4 : 8;
      Record r{{}, lines[i].substr(0, 3), lines[i].substr(4, 19)};
      for (size_t k = 0; k < count && i < lines.size(); ++k, ++i) r.lines.push_back(lines[i]);
      if (system == 'E' && r.lines.size() > 5 && (static_cast<int>(std::stod(r.lines[5].substr(23, 19))) & 2) != 0) {
        continue;  // F/NAV
      }
      records.push_back(std::move(r));
    }
    std::map<std::string, std::string> in_force;  // Galileo satellite -> latest toe before the window
    for (const auto& r : records) {
      if (r.satellite[0] == 'E' && r.toe < window_start && r.toe > in_force[r.satellite]) in_force[r.satellite] = r.toe;
    }
    const auto path = out_dir_ / name;
    std::ofstream out(path);
    for (const auto& line : header) out << line << "\n";
    for (const auto& r : records) {
      if (r.satellite[0] == 'E' && r.toe < in_force[r.satellite]) continue;
      for (const auto& line : r.lines) out << line << "\n";
    }
    return path;
  }

  struct Errors {
    size_t epochs = 0;
    double median_m = 0.0, p95_m = 0.0, max_m = 0.0;
  };

  // Runs rnx2rtkp in single-point mode for a system mask, one 10-minute window at a time (see
  // navigation_for_window), and returns the 3D errors of all epochs.
  static Errors position(int navsys, const std::string& label) {
    const auto config = out_dir_ / ("spp_" + label + ".conf");
    std::ofstream(config) << "pos1-posmode=single\npos1-frequency=l1\npos1-soltype=forward\npos1-elmask=5\n"
                             "pos1-ionoopt=brdc\npos1-tropopt=saas\npos1-sateph=brdc\npos1-navsys="
                          << navsys << "\nout-solformat=xyz\nout-outhead=on\n";
    const auto solution = out_dir_ / ("spp_" + label + ".pos");
    std::filesystem::remove(solution);
    for (int window = 0; window < 6; ++window) {
      // Epochs (window*10 min, (window+1)*10 min], the first window from 00:00:00.
      const int first_s = window == 0 ? 0 : window * 600 + 30;
      const int last_s = (window + 1) * 600;
      auto stamp = [](int seconds, const char* date_sep, const char* sep) {
        char text[32];
        std::snprintf(text, sizeof text, "2020%s06%s25%s%02d%s%02d%s%02d", date_sep, date_sep, " ", seconds / 3600,
                      sep, seconds / 60 % 60, sep, seconds % 60);
        return std::string(text);
      };
      const auto nav = navigation_for_window(stamp(first_s, " ", " "), "nav_window.rnx");
      const auto part = out_dir_ / "window.pos";
      const auto result = test::run_command(
          "rnx2rtkp -k " + test::shell_quote(config.string()) + " -ts " + stamp(first_s, "/", ":") + " -te " +
          stamp(last_s, "/", ":") + " -o " + test::shell_quote(part.string()) + " " +
          test::shell_quote((out_dir_ / "obs.rnx").string()) + " " + test::shell_quote(nav.string()));
      EXPECT_EQ(result.exit_code, 0) << result.output;
      std::ifstream in(part);
      std::ofstream out(solution, std::ios::app);
      for (std::string line; std::getline(in, line);) {
        if (!line.empty() && line[0] != '%') out << line << "\n";
      }
    }
    const Geodetic site = ecef_to_geodetic(kEsbcMarker);
    const Eigen::Vector3d up = ecef_to_enu_rotation(site).row(2).transpose();
    const Eigen::Vector3d antenna = kEsbcMarker + kEsbcAntennaHeight_m * up;
    const std::vector<double> errors = test::sorted_errors_m(test::read_rtklib_xyz(solution), antenna);
    Errors e;
    e.epochs = errors.size();
    if (errors.empty()) return e;
    e.median_m = errors[errors.size() / 2];
    e.p95_m = errors[static_cast<size_t>(std::ceil(0.95 * static_cast<double>(errors.size()))) - 1];
    e.max_m = errors.back();
    std::printf("[ figures ] rnx2rtkp single point, %s: %zu epochs, median %.4f m, p95 %.4f m, max %.4f m\n",
                label.c_str(), e.epochs, e.median_m, e.p95_m, e.max_m);
    return e;
  }

  static inline std::string skip_reason_;
  static inline std::filesystem::path out_dir_;
  static inline int run_exit_code_ = -1;
  static inline std::string run_output_;
};

constexpr size_t kEpochs = 121;  // one hour at 30 s

TEST_F(RtklibSinglePoint, GpsAloneWithinFiveCentimetres) {
  const Errors e = position(1, "GPS");
  EXPECT_GE(e.epochs, kEpochs * 95 / 100);
  EXPECT_LE(e.p95_m, 0.05);
}

TEST_F(RtklibSinglePoint, GalileoAloneWithinFiveCentimetres) {
  const Errors e = position(8, "Galileo");
  EXPECT_GE(e.epochs, kEpochs * 95 / 100);
  EXPECT_LE(e.p95_m, 0.05);
}

TEST_F(RtklibSinglePoint, GlonassAloneWithinFiveCentimetres) {
  const Errors e = position(4, "GLONASS");
  EXPECT_GE(e.epochs, kEpochs * 95 / 100);
  EXPECT_LE(e.p95_m, 0.05);
}

TEST_F(RtklibSinglePoint, BeiDouAloneWithinFiveCentimetres) {
  const Errors e = position(32, "BeiDou");
  EXPECT_GE(e.epochs, kEpochs * 95 / 100);
  EXPECT_LE(e.p95_m, 0.05);
}

TEST_F(RtklibSinglePoint, FourSystemsWithinTenCentimetres) {
  const Errors e = position(1 + 4 + 8 + 32, "GPS+GLONASS+Galileo+BeiDou");
  EXPECT_GE(e.epochs, kEpochs * 95 / 100);
  EXPECT_LE(e.p95_m, 0.10);
}

}  // namespace
}  // namespace skytrace
