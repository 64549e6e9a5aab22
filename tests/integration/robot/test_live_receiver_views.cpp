// The robot-facing view of an epoch (live::Receiver, under the ROS node and the Gazebo bridge):
// in the canyon contract with multipath, satellites hidden by one wall and reflected by the other
// are tracked with the NLOS flag set, and open-sky ones are not.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "live_receiver.hpp"
#include "test_support.hpp"

namespace skytrace {
namespace {

TEST(LiveReceiverViews, CanyonReflectionsAreFlaggedNlos) {
  const auto scenario = test::shared_data_dir().parent_path() / "contract" / "canyon.yaml";
  if (!std::filesystem::exists(scenario) ||
      !std::filesystem::exists(test::shared_data_dir() / "real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx")) {
    GTEST_SKIP() << "canyon contract or ESBC data absent (set SKYTRACE_SHARED_DATA)";
  }
  live::ReceiverOptions options;
  options.scenario_path = scenario.string();
  std::string error;
  auto receiver = live::Receiver::create(options, error);
  ASSERT_TRUE(receiver) << error;
  int nlos = 0, direct = 0;
  for (double t = 0.0; t <= 3600.0; t += 600.0) {
    live::EpochView epoch;
    ASSERT_TRUE(receiver->step(t, epoch, error)) << error;
    for (const auto& sat : epoch.satellites) {
      if (sat.status != live::SkyStatus::kTracked) continue;
      EXPECT_FALSE(sat.nlos && sat.multipath) << sat.id;
      (sat.nlos ? nlos : direct) += 1;
    }
  }
  EXPECT_GT(nlos, 0) << "the canyon's reflected-only satellites must be flagged";
  EXPECT_GT(direct, 0);
}

}  // namespace
}  // namespace skytrace
