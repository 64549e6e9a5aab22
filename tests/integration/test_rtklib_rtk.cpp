// Carrier phase end to end: the contract base/rover pair (2 km baseline, noise and a realistic
// receiver clock) processed by RTKLIB's rnx2rtkp as static RTK with GPS L1+L2 must fix the integer
// ambiguities and recover the rover's position.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "process.hpp"
#include "rtklib.hpp"
#include "skytrace/core/frames.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

TEST(RtklibRtk, ContractBaseRoverPairFixesAndLandsOnTheRover) {
  const auto contract = test::shared_data_dir().parent_path() / "contract";
  if (!std::filesystem::exists(contract / "rtk-base.yaml") ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "contract scenarios or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  }
  if (!test::program_available("rnx2rtkp")) GTEST_SKIP() << "rnx2rtkp (Debian package rtklib) is not installed";
  const auto dir = test::make_temp_dir("rtklib_rtk");
  for (const char* name : {"rtk-base", "rtk-rover"}) {
    const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                     test::shell_quote((contract / (std::string(name) + ".yaml")).string()) + " --out " +
                                     test::shell_quote((dir / name).string()) + " --quiet --no-truth");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const Eigen::Vector3d base(3582105.2910, 532589.7313, 5232754.8054);
  const Eigen::Vector3d rover = geodetic_to_ecef(Geodetic{55.4935, 8.4880, 75.0});
  std::ofstream(dir / "rtk.conf") << "pos1-posmode=static\npos1-frequency=l1+l2\npos1-soltype=forward\npos1-elmask=10\n"
                                     "pos1-ionoopt=brdc\npos1-tropopt=saas\npos1-sateph=brdc\npos1-navsys=1\n"
                                     "pos2-armode=continuous\nant2-postype=xyz\n"
                                  << "ant2-pos1=" << std::to_string(base.x()) << "\nant2-pos2=" << std::to_string(base.y())
                                  << "\nant2-pos3=" << std::to_string(base.z()) << "\nout-solformat=xyz\n";
  const auto r = test::run_command("rnx2rtkp -k " + test::shell_quote((dir / "rtk.conf").string()) + " -o " +
                                   test::shell_quote((dir / "rtk.pos").string()) + " " +
                                   test::shell_quote((dir / "rtk-rover/obs.rnx").string()) + " " +
                                   test::shell_quote((dir / "rtk-base/obs.rnx").string()) + " " +
                                   test::shell_quote((dir / "rtk-rover/nav.rnx").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto solutions = test::read_rtklib_xyz(dir / "rtk.pos");
  const size_t epochs = solutions.size();
  size_t fixed = 0;
  std::vector<double> fixed_errors_m;
  for (const auto& solution : solutions) {
    if (solution.quality != 1) continue;
    ++fixed;
    fixed_errors_m.push_back((solution.ecef_m - rover).norm());
  }
  ASSERT_GT(epochs, 0u);
  const double fix_ratio = static_cast<double>(fixed) / static_cast<double>(epochs);
  std::sort(fixed_errors_m.begin(), fixed_errors_m.end());
  const double final_error_m = fixed_errors_m.empty() ? NAN : fixed_errors_m.back();
  const double p95_m = fixed_errors_m.empty() ? NAN : fixed_errors_m[fixed_errors_m.size() * 95 / 100];
  std::printf("[ figures ] rnx2rtkp static RTK GPS L1+L2, 2 km: %zu epochs, fixed %.1f %%, fixed-epoch error p95 %.4f m, "
              "max %.4f m\n",
              epochs, 100.0 * fix_ratio, p95_m, final_error_m);
  EXPECT_GE(epochs, 1800u);
  EXPECT_GE(fix_ratio, 0.90);
  EXPECT_LE(p95_m, 0.01);
}

}  // namespace
}  // namespace skytrace
