// Precise products as the truth: the signals come from the GRG orbits and clocks while nav.rnx
// carries the broadcast records. RTKLIB given the same precise products must land on the antenna
// (proving the precise path is exact), and given only nav.rnx must see real broadcast errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <vector>

#include "process.hpp"
#include "rtklib.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

double median_error_m(const std::filesystem::path& solution, const Eigen::Vector3d& antenna, size_t& epochs) {
  const std::vector<double> errors = test::sorted_errors_m(test::read_rtklib_xyz(solution), antenna);
  epochs = errors.size();
  return errors.empty() ? NAN : errors[errors.size() / 2];
}

TEST(PreciseTruth, RtklibWithTheSameProductsLandsOnTheAntennaAndBroadcastShowsItsErrors) {
  const auto data = test::shared_data_dir() / "real/esbc_2020177";
  if (!std::filesystem::exists(data / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK")) GTEST_SKIP() << "ESBC data absent";
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("precise_truth");
  const std::string sp3_a = (data / "GRG0MGXFIN_20201760000_01D_15M_ORB.SP3").string();
  const std::string sp3_b = (data / "GRG0MGXFIN_20201770000_01D_15M_ORB.SP3").string();
  const std::string clk = (data / "GRG0MGXFIN_20201770000_01D_30S_CLK.CLK").string();
  std::ofstream(dir / "scenario.yaml")
      << "name: precise-truth\ntime: {start: 2020-06-25T00:00:00, scale: GPST, duration_s: 3600, interval_s: 30}\n"
         "receiver:\n  position: {ecef_m: [3582105.2910, 532589.7313, 5232754.8054]}\n  antenna_height_m: 0.2160\n"
         "  signals: [G1C, E1C]\nephemeris:\n  navigation: ["
      << (data / "ESBC00DNK_R_20201770000_01D_MN.rnx").string() << "]\n  precise_orbits: [" << sp3_a << ", " << sp3_b
      << "]\n  precise_clocks: [" << clk << "]\n";
  auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                             test::shell_quote((dir / "scenario.yaml").string()) + " --out " +
                             test::shell_quote((dir / "out").string()) + " --quiet --no-truth");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const Eigen::Vector3d marker(3582105.2910, 532589.7313, 5232754.8054);
  const Eigen::Vector3d antenna = marker + 0.2160 * ecef_to_enu_rotation(ecef_to_geodetic(marker)).row(2).transpose();
  auto solve = [&](const std::string& sateph, const std::string& extra_files, const std::string& name) {
    std::ofstream(dir / (name + ".conf")) << "pos1-posmode=single\npos1-frequency=l1\npos1-elmask=5\npos1-ionoopt=brdc\n"
                                             "pos1-tropopt=saas\npos1-navsys=1\nout-solformat=xyz\npos1-sateph="
                                          << sateph << "\n";
    const auto result = test::run_command("rnx2rtkp -k " + test::shell_quote((dir / (name + ".conf")).string()) + " -o " +
                                          test::shell_quote((dir / (name + ".pos")).string()) + " " +
                                          test::shell_quote((dir / "out/obs.rnx").string()) + " " +
                                          test::shell_quote((dir / "out/nav.rnx").string()) + " " + extra_files);
    EXPECT_EQ(result.exit_code, 0) << result.output;
    size_t epochs = 0;
    const double median = median_error_m(dir / (name + ".pos"), antenna, epochs);
    std::printf("[ figures ] precise truth, rnx2rtkp GPS single point with %s ephemerides: %zu epochs, median %.4f m\n",
                sateph.c_str(), epochs, median);
    EXPECT_GE(epochs, 115u);
    return median;
  };
  const double with_precise = solve("precise", test::shell_quote(sp3_a) + " " + test::shell_quote(sp3_b) + " " +
                                                   test::shell_quote(clk), "precise");
  const double with_broadcast = solve("brdc", "", "broadcast");
  EXPECT_LE(with_precise, 0.01);
  // Real broadcast orbit and clock errors (about a metre each) now reach the position.
  EXPECT_GE(with_broadcast, 0.3);
  EXPECT_LE(with_broadcast, 6.0);
}

}  // namespace
}  // namespace skytrace
